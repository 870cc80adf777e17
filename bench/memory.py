#!/usr/bin/env python3
"""The --max-memory estimate against the measured peak of whole runs.

    python3 bench/memory.py [target/release/aureole]

For each workload (the 4K demo street through the default camera and
others, a 12000x8000 frame with a capped kernel) it reads the estimate from
the refusal `apply` gives under a limit below it, then runs `apply` with no
limit under /usr/bin/time and reports the peak resident memory. The
estimate is meant to lie above every peak, by at most about a quarter.
"""

import array
import os
import re
import subprocess
import sys
import tempfile

AUREOLE = sys.argv[1] if len(sys.argv) > 1 else "target/release/aureole"
UNITS = {"KiB": 2**10, "MiB": 2**20, "GiB": 2**30}

WORKLOADS = [
    ("4K street, camera-f8-7blade", "3840x2160", ["--preset", "camera-f8-7blade"]),
    ("4K street, paper-fig5-both", "3840x2160", ["--preset", "paper-fig5-both"]),
    ("4K street, paper-fig4-bloom", "3840x2160", ["--preset", "paper-fig4-bloom"]),
    ("4K street, human-eye-vos", "3840x2160", ["--preset", "human-eye-vos"]),
    ("4K street, paper-fig4-bloom + camera-f8-7blade", "3840x2160",
     ["--preset", "paper-fig4-bloom", "--preset", "camera-f8-7blade"]),
    ("1080p street, camera-f8-7blade", "1920x1080", ["--preset", "camera-f8-7blade"]),
    # A star filter's orders fill the same millimetres of the sensor at
    # any size: a thumbnail holds as many as 4K.
    ("64x36 thumbnail, star-filter-8pt", "64x36", ["--preset", "star-filter-8pt"]),
    ("320x180 street, star-filter-6pt", "320x180", ["--preset", "star-filter-6pt"]),
    ("12000x8000, paper-fig4-bloom, --max-kernel 101", "12000x8000",
     ["--preset", "paper-fig4-bloom", "--max-kernel", "101"]),
]


def big_frame(path, width, height):
    """A dim plate with a lamp every 500 px, as a PFM (the demo street
    builds its own uncapped kernel, which a frame this large cannot have)."""
    dim = array.array("f", [0.05] * (3 * width))
    lit = array.array("f", dim)
    for x in range(250, width, 500):
        lit[3 * x:3 * x + 3] = array.array("f", [5e4] * 3)
    with open(path, "wb") as f:
        f.write(f"PF\n{width} {height}\n-1.0\n".encode())
        for y in range(height):
            f.write((lit if y % 500 == 250 else dim).tobytes())


def estimate(frame, out, camera):
    """The largest estimate apply gives: under a limit between the f32
    route's estimate and the f64 engine's, it names the f64 one."""
    said = None
    for limit in ["200M", "400M", "800M", "1200M", "1600M", "2400M", "3200M", "4800M", "6400M",
                  "8000M"]:
        done = subprocess.run([AUREOLE, "apply", "-q", frame, "-o", out, *camera,
                               "--max-memory", limit], capture_output=True, text=True)
        found = re.search(r"needs about ([\d.]+) (KiB|MiB|GiB) \(peak while (.*)\) but",
                          done.stderr)
        if done.returncode == 0:
            return said
        if found:
            said = (float(found.group(1)) * UNITS[found.group(2)], found.group(3))
    return said


def peak(frame, out, camera):
    done = subprocess.run(["/usr/bin/time", "-f", "%M", AUREOLE, "apply", "-q", frame, "-o", out,
                           *camera], capture_output=True, text=True, check=True)
    return int(done.stderr.strip().splitlines()[-1]) * 1024


def main():
    print(f"load: {os.getloadavg()}")
    print("| workload | estimate (its peak stage) | measured peak | peak below the estimate |")
    print("|---|---|---|---|")
    with tempfile.TemporaryDirectory() as work:
        frames = {}
        for name, size, camera in WORKLOADS:
            if size not in frames and size == "12000x8000":
                frames[size] = os.path.join(work, "plate.pfm")
                big_frame(frames[size], 12000, 8000)
            elif size not in frames:
                frames[size] = os.path.join(work, f"street-{size}.exr")
                subprocess.run([AUREOLE, "demo", "-q", "--size", size, "--hdr", frames[size],
                                "-o", os.path.join(work, "street.png")], check=True)
            out = os.path.join(work, "out.exr")
            guess, stage = estimate(frames[size], out, camera)
            measured = peak(frames[size], out, camera)
            below = f"{100 * (1 - measured / guess):.0f} %"
            print(f"| {name} | {guess / 2**30:.2f} GiB ({stage}) | {measured / 2**30:.2f} GiB "
                  f"| {below} |")


if __name__ == "__main__":
    main()
