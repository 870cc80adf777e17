#!/usr/bin/env python3
"""How long the studio takes from a changed parameter to the new picture.

Starts `target/release/aureole studio` on a free port, then for each chain
(bloom, corona, Vos, a spectral aperture, configs/dusty-lens.toml, the
lens ghosts traced anew and kept) renders a 1280-wide preview of the
demo street five times, changing one parameter each time, and prints the
median of the last four (the first also loads the image). Then the same
camera with only the exposure changed. Then, where Chromium is installed,
the page's own redraw when only the exposure moves (tone mapping in WebGL2,
and on a 2D canvas): the median of 60 redraws, each waited for, driven over
the DevTools protocol. Standard library only:

    cargo build --release && python3 bench/studio_latency.py
    python3 bench/studio_latency.py --device gpu --width 3840   # a 4K preview on the GPU
    python3 bench/studio_latency.py --binary OTHER/aureole      # another build

`--device` is the studio's (auto, cpu or gpu); a `--width` beyond the
built-in 1280x720 street renders the street `aureole demo` writes at that
width (16:9) instead.
"""
import argparse
import base64
import json
import os
import re
import shutil
import socket
import struct
import tempfile
import statistics
import subprocess
import sys
import time
import urllib.request

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
BINARY = os.path.join(ROOT, "target", "release", "aureole")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--device", default="auto", choices=["auto", "cpu", "gpu"])
    parser.add_argument("--width", type=int, default=1280)
    parser.add_argument("--binary", default=BINARY, help="the aureole to time (another build, to compare)")
    args = parser.parse_args()
    binary = args.binary
    width, height = args.width, args.width * 9 // 16
    folder = tempfile.mkdtemp()
    image = "demo"
    if width > 1280:
        image = os.path.join(folder, "street.exr")
        subprocess.run([binary, "demo", "-q", "--size", f"{width}x{height}", "--hdr", image,
                        "-o", os.path.join(folder, "street.png")], check=True)
    server = subprocess.Popen([binary, "studio", "--no-browser", "-q", "--root", ROOT,
                               "--root", folder, "--device", args.device],
                              stdout=subprocess.PIPE, text=True)
    try:
        # http://127.0.0.1:PORT/?token=TOKEN: scripts send the token as a header.
        opened = server.stdout.readline().strip()
        url, token = opened.split("?token=")
        auth = {"authorization": f"Bearer {token}"}
        presets = {p["name"]: p["toml"] for p in json.load(urllib.request.urlopen(
            urllib.request.Request(url + "api/presets", headers=auth)))}

        def render(config, **extra):
            # As the page asks: the linear preview, which it tone-maps itself.
            body = json.dumps({"image": image, "config": config, "width": width,
                               "format": "linear", **extra}).encode()
            request = urllib.request.Request(url + "api/render", data=body,
                                             headers={"content-type": "application/json", **auth})
            start = time.time()
            with urllib.request.urlopen(request) as reply:
                reply.read()
            return (time.time() - start) * 1e3

        with open(os.path.join(ROOT, "configs", "dusty-lens.toml")) as f:
            dusty = f.read()
        bloom = '[[effect]]\ntype = "bloom"\nradius = "10.4px"\nbeta = 2\nepsilon = {}\n'
        chains = {
            "bloom": lambda k: bloom.format(0.005 + 0.001 * k),
            "corona": lambda k: presets["paper-fig5-corona"].replace(
                "rays = 14", f"rays = {12 + 2 * k}"),
            "vos": lambda k: presets["human-eye-vos"].replace(
                "epsilon = 0.05", f"epsilon = {0.04 + 0.005 * k}"),
            "aperture, spectral": lambda k: presets["camera-f8-7blade"].replace(
                "blades = 7", f"blades = {5 + k}"),
            "dusty lens": lambda k: dusty.replace("dust = 60", f"dust = {58 + k}"),
            # The lens's ghosts traced anew (the stop's blades shape them)
            # and kept (a bloom they do not depend on).
            "ghosts, retraced": lambda k: presets["camera-f8-7blade-ghosts"].replace(
                "blades = 7", f"blades = {5 + k}"),
            "ghosts, kept": lambda k: presets["camera-f8-7blade-ghosts"] + bloom.format(
                0.005 + 0.001 * k),
        }
        print(f"{width}x{height} preview of the demo street on device {args.device}, "
              "median of 4 changes (ms):")
        for name, make in chains.items():
            # Every change a camera not seen before: the studio keeps the
            # last cameras' kernels, and a repeated one would be a cache hit.
            times = [render(make(k)) for k in range(5)]
            print(f"  {name:20s} {statistics.median(times[1:]):6.0f}")
        camera = presets["camera-f8-7blade"]
        render(camera)
        times = [render(camera, exposure=ev) for ev in (1, 2, 3, 4)]
        print(f"  {'exposure only':20s} {statistics.median(times):6.0f}")
        browser = shutil.which("chromium") or shutil.which("google-chrome")
        if browser:
            print("In the page, exposure only (no server), median of 60 redraws (ms):")
            for display in ("webgl2", "2d"):
                ms = page_redraw(browser, f"{opened}&drawbench=1&display={display}")
                print(f"  {display:20s} {ms:6.2f}")
    finally:
        server.terminate()
        shutil.rmtree(folder, ignore_errors=True)


def page_redraw(browser, url):
    """The page's data-draw-ms, read over the DevTools protocol: the page's
    clocks must run in real time, which --dump-dom's virtual time does not."""
    profile = tempfile.mkdtemp()
    chrome = subprocess.Popen(
        [browser, "--headless=new", "--no-sandbox", "--enable-unsafe-swiftshader",
         "--window-size=1400,860", "--remote-debugging-port=0", f"--user-data-dir={profile}",
         url], stderr=subprocess.PIPE, text=True)
    try:
        for line in chrome.stderr:
            found = re.search(r"ws://127.0.0.1:(\d+)/", line)
            if found:
                port = int(found.group(1))
                break
        pages = json.load(urllib.request.urlopen(f"http://127.0.0.1:{port}/json/list"))
        page = next(p for p in pages if p["type"] == "page")
        socket_ = devtools(page["webSocketDebuggerUrl"])
        for _ in range(120):
            value = evaluate(socket_, "document.body.dataset.drawMs || ''")
            if value:
                return float(value)
            time.sleep(0.5)
        raise RuntimeError(f"{url}: the page never reported its redraw time")
    finally:
        chrome.terminate()
        chrome.wait()
        shutil.rmtree(profile, ignore_errors=True)


def devtools(address):
    """A WebSocket to a DevTools target (RFC 6455, client side, text only)."""
    host, port, path = re.match(r"ws://([^:/]+):(\d+)(/.*)", address).groups()
    connection = socket.create_connection((host, int(port)))
    key = base64.b64encode(os.urandom(16)).decode()
    connection.sendall((f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\n"
                        f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                        "Sec-WebSocket-Version: 13\r\n\r\n").encode())
    reply = b""
    while b"\r\n\r\n" not in reply:
        reply += connection.recv(4096)
    return connection


def evaluate(connection, expression, ids=iter(range(1, 1 << 30))):
    message = json.dumps({"id": next(ids), "method": "Runtime.evaluate",
                          "params": {"expression": expression, "returnByValue": True}}).encode()
    mask = os.urandom(4)
    length = len(message)
    header = struct.pack("!BB", 0x81, 0x80 | length) if length < 126 else \
        struct.pack("!BBH", 0x81, 0x80 | 126, length)
    connection.sendall(header + mask + bytes(b ^ mask[i % 4] for i, b in enumerate(message)))
    while True:
        first, second = struct.unpack("!BB", receive(connection, 2))
        length = second & 0x7F
        if length == 126:
            length = struct.unpack("!H", receive(connection, 2))[0]
        elif length == 127:
            length = struct.unpack("!Q", receive(connection, 8))[0]
        reply = json.loads(receive(connection, length))
        if "id" in reply:
            return reply["result"]["result"].get("value")


def receive(connection, count):
    data = b""
    while len(data) < count:
        chunk = connection.recv(count - len(data))
        if not chunk:
            raise ConnectionError("DevTools closed the connection")
        data += chunk
    return data


if __name__ == "__main__":
    sys.exit(main())
