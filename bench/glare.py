#!/usr/bin/env python3
"""Glare figures (issue 46's workload): `aureole glare` against Radiance's
`evalglare` on the same fisheye pictures, file in, figures out: a 1000²
office with a sunlit window and a view towards the low sun, and a 4096²
view towards the low sun (aureole alone: evalglare's manual advises at
most about 1000² pixels). Medians of `--runs` runs of each command, the
ratio, and the two tools' DGP and UGR side by side. The scenes are
rendered first by Radiance's rpict (crates/aureole-py/tests/glare_scenes.py).

    target/pyvenv/bin/python bench/glare.py target/release/aureole [--runs 5]

It needs the PyPI `pyradiance` wheel (1.3.1) for Radiance's binaries.
"""

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "crates" / "aureole-py" / "tests"))
from glare_scenes import _env, radiance_bin, render  # noqa: E402


def timed(command, runs, env=None):
    times, out = [], b""
    for _ in range(runs):
        start = time.perf_counter()
        done = subprocess.run(command, capture_output=True, env=env, check=True)
        times.append(time.perf_counter() - start)
        out = done.stdout
    return statistics.median(times), out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("aureole")
    parser.add_argument("--runs", type=int, default=5)
    args = parser.parse_args()
    bindir = radiance_bin()
    if bindir is None:
        sys.exit("bench/glare.py needs Radiance: pip install pyradiance==1.3.1")

    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        cases = [("office-sun", 1000), ("low-sun", 1000), ("low-sun", 4096)]
        print("| picture | aureole glare | evalglare | ratio | DGP aureole / evalglare | UGR aureole / evalglare |")
        print("|---|---|---|---|---|---|")
        for name, size in cases:
            sub = work / f"{size}"
            sub.mkdir(exist_ok=True)
            path = render(bindir, name, sub, size)
            ours, out = timed([args.aureole, "-q", "glare", str(path), "--json"], args.runs)
            mine = json.loads(out)
            if size <= 1000:
                theirs, text = timed([str(bindir / "evalglare"), str(path)], args.runs, _env(bindir))
                values = [float(v) for v in text.decode().split(":")[1].split()]
                their = f"{theirs * 1000:.0f} ms"
                ratio = f"{theirs / ours:.0f}×"
                dgp = f"{mine['dgp']:.3f} / {values[0]:.3f}"
                ugr = f"{mine['ugr']:.2f} / {values[2]:.2f}"
            else:
                their, ratio = "not run (advised ≤ 1000²)", "–"
                dgp, ugr = f"{mine['dgp']:.3f}", f"{mine['ugr']:.2f}"
            print(f"| {name} {size}² | {ours * 1000:.0f} ms | {their} | {ratio} | {dgp} | {ugr} |")


if __name__ == "__main__":
    main()
