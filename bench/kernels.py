#!/usr/bin/env python3
"""Kernel build times: `aureole psf` on the lens kernels users build (every
preset, the dusty lens and issue 42's bloom with corona at 4K, and a few
apertures), each binary given on the command line run in turn, `--runs`
times, medians.

    python3 bench/kernels.py target/release/aureole [OTHER_BINARY ...] [--only NAME] [--devices cpu,gpu]

The time is the whole command (building and writing a PFM into a temporary
folder), as a user waits for it, and the build alone as `psf` reports it
("built in X s"). With `--devices`, each binary runs once per device
(`psf --device`), a column each.
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


BLOOM_CORONA = """
[[effect]]
type = "bloom"
epsilon = 0.05
beta = 2.0
radius = "10 px"
[[effect]]
type = "corona"
epsilon = 0.05
rays = 14
length = "400 px"
"""


def presets(binary):
    listed = subprocess.run([binary, "presets"], capture_output=True, text=True, check=True)
    return [line.split()[0] for line in listed.stdout.splitlines() if line.strip()]


def cases(folder, binary):
    (folder / "mono8.toml").write_text(lens("blades = 8\nspectral = false"))
    (folder / "rounded7.toml").write_text(lens("blades = 7\nroundness = 0.3"))
    (folder / "mirror.toml").write_text(lens("blades = 0\nobstruction = 0.3\nvanes = 4"))
    (folder / "bloom-corona.toml").write_text(BLOOM_CORONA)
    k4 = ["--size", "7679x4319", "--image-width", "3840"]
    k720 = ["--size", "2559x1439", "--image-width", "1280"]
    every = [(f"4K {name}", ["--preset", name, *k4]) for name in presets(binary)]
    return every + [
        ("4K bloom + corona (issue 42: ε 0.05 each, 14 rays of 400 px)",
         ["--config", str(folder / "bloom-corona.toml"), *k4]),
        ("4K configs/dusty-lens.toml", ["--config", str(ROOT / "configs/dusty-lens.toml"), *k4]),
        ("4K 7 rounded blades (0.3)", ["--config", str(folder / "rounded7.toml"), *k4]),
        ("4K 8 blades, 550 nm", ["--config", str(folder / "mono8.toml"), *k4]),
        ("4K mirror lens (obstruction 0.3, 4 vanes)", ["--config", str(folder / "mirror.toml"), *k4]),
        ("720p camera-f8-7blade", ["--preset", "camera-f8-7blade", *k720]),
        ("720p configs/night-street.toml", ["--config", str(ROOT / "configs/night-street.toml"), *k720]),
    ]


def run(binary, args, output, device):
    extra = ["--device", device] if device else []
    done = subprocess.run([binary, "psf", *args, *extra, "-o", str(output)], capture_output=True,
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
    parser.add_argument("--devices", default="", help="cpu,gpu: a column per binary and device")
    args = parser.parse_args()
    devices = [d for d in args.devices.split(",") if d] or [None]
    columns = [(b, d) for b in args.binaries for d in devices]
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        names = [f"{b} ({d})" if d else b for b, d in columns]
        print("| kernel | " + " | ".join(names) + " |")
        print("|---|" + "---|" * len(columns))
        for name, case in cases(folder, args.binaries[0]):
            if args.only not in name:
                continue
            times = {c: [] for c in columns}
            for _ in range(args.runs):
                for b, d in columns:
                    times[(b, d)].append(run(b, case, folder / "k.pfm", d))
            cells = []
            for c in columns:
                total = statistics.median(t for t, _ in times[c])
                built = [x for _, x in times[c] if x is not None]
                cells.append(f"{total:.2f} s" + (f" (built {statistics.median(built):.2f} s)" if built else ""))
            print(f"| {name} | " + " | ".join(cells) + " |", flush=True)


if __name__ == "__main__":
    main()
