#!/usr/bin/env python3
"""Lens ghosts (issue 45's workload): a 4K night frame with 16 lamps through
a lens of 15 reflecting surfaces (105 two-reflection paths), at R, G and B,
the ghosts alone in the chain: `aureole apply` file to file, `--runs`
times, medians of the whole command and of the camera's part ("camera X s"
in its summary: the ghost stage, no kernel).

    python3 bench/ghosts.py target/release/aureole [--runs 3] [--size 3840x2160]
        [--lens portrait-90mm-f2] [--f-number 8] [--sources 16]

The frame is written here (a PFM, no dependency beyond Python): a dim
street of 0.05 cd/m² with 16 lamps of 5×5 pixels from 2·10⁴ to 3.2·10⁵
cd/m², spread over the frame.
"""

import argparse
import re
import statistics
import subprocess
import sys
import tempfile
import time
from array import array
from pathlib import Path


def frame(path, width, height, lamps):
    """The night frame as a PFM (rows bottom first, as the format has them)."""
    pixels = array("f", [0.05]) * (width * height * 3)
    for k in range(lamps):
        x = int(200 + (width - 400) * ((k * 0.618) % 1))
        y = int(200 + (height - 400) * ((k * 0.382 + 0.1) % 1))
        for row in range(y - 2, y + 3):
            for column in range(x - 2, x + 3):
                at = 3 * ((height - 1 - row) * width + column)
                pixels[at:at + 3] = array("f", [2e4 * (1 + k)] * 3)
    with open(path, "wb") as out:
        out.write(b"PF\n%d %d\n-1.0\n" % (width, height))
        if sys.byteorder == "big":
            pixels.byteswap()
        out.write(pixels.tobytes())


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("binary")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--size", default="3840x2160")
    parser.add_argument("--lens", default="portrait-90mm-f2")
    parser.add_argument("--f-number", type=float, default=8.0)
    parser.add_argument("--sources", type=int, default=16)
    args = parser.parse_args()
    width, height = map(int, args.size.split("x"))
    with tempfile.TemporaryDirectory() as folder:
        folder = Path(folder)
        frame(folder / "lamps.pfm", width, height, args.sources)
        config = folder / "ghosts.toml"
        config.write_text(
            f"[camera]\nsensor_width_mm = 36.0\nf_number = {args.f_number}\n"
            f"[[effect]]\ntype = \"ghosts\"\nlens = \"{args.lens}\"\nsources = {args.sources}\n")
        whole, camera, said = [], [], ""
        for _ in range(args.runs):
            start = time.perf_counter()
            done = subprocess.run(
                [args.binary, "apply", folder / "lamps.pfm", "-o", folder / "out.exr",
                 "--config", config], capture_output=True, text=True, check=True)
            whole.append(time.perf_counter() - start)
            camera.append(float(re.search(r"camera ([0-9.]+) s", done.stderr).group(1)))
            said = done.stderr.strip().splitlines()[-1].strip()
    print(f"{args.size}, {args.sources} sources, {args.lens} at f/{args.f_number:g}: "
          f"camera {statistics.median(camera):.2f} s, file to file "
          f"{statistics.median(whole):.2f} s (medians of {args.runs})")
    print(said)


if __name__ == "__main__":
    main()
