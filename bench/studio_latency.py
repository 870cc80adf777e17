#!/usr/bin/env python3
"""How long the studio takes from a changed parameter to the new picture.

Starts `target/release/aureole studio` on a free port, then for each chain
(bloom, corona, Vos, a spectral aperture) renders a 1280-wide preview of the
demo street five times, changing one parameter each time, and prints the
median of the last four (the first also loads the image). Then the same
camera with only the exposure changed. Standard library only:

    cargo build --release && python3 bench/studio_latency.py
"""
import json
import os
import statistics
import subprocess
import sys
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.path.join(ROOT, "target", "release", "aureole")


def main():
    server = subprocess.Popen([BINARY, "studio", "--no-browser", "-q", "--root", ROOT],
                              stdout=subprocess.PIPE, text=True)
    try:
        url = server.stdout.readline().strip()
        presets = {p["name"]: p["toml"] for p in json.load(urllib.request.urlopen(url + "api/presets"))}

        def render(config, **extra):
            # As the page asks: the linear preview, which it tone-maps itself.
            body = json.dumps({"image": "demo", "config": config, "width": 1280,
                               "format": "linear", **extra}).encode()
            request = urllib.request.Request(url + "api/render", data=body,
                                             headers={"content-type": "application/json"})
            start = time.time()
            with urllib.request.urlopen(request) as reply:
                reply.read()
            return (time.time() - start) * 1e3

        bloom = '[[effect]]\ntype = "bloom"\nradius = "10.4px"\nbeta = 2\nepsilon = {}\n'
        chains = {
            "bloom": lambda k: bloom.format(0.005 + 0.001 * k),
            "corona": lambda k: presets["paper-fig5-corona"].replace(
                "rays = 14", f"rays = {12 + 2 * (k % 3)}"),
            "vos": lambda k: presets["human-eye-vos"].replace(
                "epsilon = 0.05", f"epsilon = {0.04 + 0.005 * k}"),
            "aperture, spectral": lambda k: presets["camera-f8-7blade"].replace(
                "blades = 7", f"blades = {6 + k % 3}"),
        }
        print("1280x720 preview of the demo street, median of 4 changes (ms):")
        for name, make in chains.items():
            times = [render(make(k)) for k in range(5)]
            print(f"  {name:20s} {statistics.median(times[1:]):6.0f}")
        camera = presets["camera-f8-7blade"]
        render(camera)
        times = [render(camera, exposure=ev) for ev in (1, 2, 3, 4)]
        print(f"  {'exposure only':20s} {statistics.median(times):6.0f}")
    finally:
        server.terminate()


if __name__ == "__main__":
    sys.exit(main())
