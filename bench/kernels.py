#!/usr/bin/env python3
"""Kernel build times: `aureole psf` on the lens kernels users build, each
binary given on the command line run in turn, `--runs` times, medians.

    python3 bench/kernels.py target/release/aureole [OTHER_BINARY ...] [--only NAME]

The time is the whole command (building and writing a PFM into a temporary
folder), as a user waits for it; a binary that reports its build time
apart ("built in X s") has that printed too.
"""

import argparse
import re
import statistics
import subprocess
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def lens(aperture):
    """A 50 mm lens at f/8 on full frame with one aperture effect."""
    return f"""
[camera]
sensor_width_mm = 36.0
focal_length_mm = 50.0
f_number = 8.0
[[effect]]
type = "aperture"
{aperture}
"""


def cases(folder):
    (folder / "mono8.toml").write_text(lens("blades = 8\nspectral = false"))
    (folder / "rounded7.toml").write_text(lens("blades = 7\nroundness = 0.3"))
    (folder / "mirror.toml").write_text(lens("blades = 0\nobstruction = 0.3\nvanes = 4"))
    k4 = ["--size", "7679x4319", "--image-width", "3840"]
    k720 = ["--size", "2559x1439", "--image-width", "1280"]
    return [
        ("4K camera-f8-7blade", ["--preset", "camera-f8-7blade", *k4]),
        ("4K 7 rounded blades (0.3)", ["--config", str(folder / "rounded7.toml"), *k4]),
        ("4K 8 blades, 550 nm", ["--config", str(folder / "mono8.toml"), *k4]),
        ("4K mirror lens (obstruction 0.3, 4 vanes)", ["--config", str(folder / "mirror.toml"), *k4]),
        ("4K star-filter-4pt", ["--preset", "star-filter-4pt", *k4]),
        ("720p camera-f8-7blade", ["--preset", "camera-f8-7blade", *k720]),
        ("720p configs/night-street.toml", ["--config", str(ROOT / "configs/night-street.toml"), *k720]),
    ]


def run(binary, args, output):
    done = subprocess.run([binary, "psf", *args, "-o", str(output)], capture_output=True,
                          text=True, check=True)
    line = done.stderr.strip().splitlines()[-1]
    built = re.search(r"built in ([0-9.]+) s", line)
    total = re.search(r"([0-9.]+) s(?: in all)?$", line)
    return float(total.group(1)), float(built.group(1)) if built else None


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("binaries", nargs="+")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--only", default="", help="run the kernels whose name holds this")
    args = parser.parse_args()
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        print("| kernel | " + " | ".join(args.binaries) + " |")
        print("|---|" + "---|" * len(args.binaries))
        for name, case in cases(folder):
            if args.only not in name:
                continue
            times = {b: [] for b in args.binaries}
            for _ in range(args.runs):
                for b in args.binaries:
                    times[b].append(run(b, case, folder / "k.pfm"))
            cells = []
            for b in args.binaries:
                total = statistics.median(t for t, _ in times[b])
                built = [x for _, x in times[b] if x is not None]
                cells.append(f"{total:.2f} s" + (f" (built {statistics.median(built):.2f} s)" if built else ""))
            print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
