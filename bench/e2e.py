"""End to end, as a user runs it: files in, files out, a batch of frames.

python e2e.py AUREOLE WORKDIR WORKLOAD_DIR   prints the markdown section of
bench/RESULTS.md. For each workload (the demo night street at 4K and 1080p
with a `camera-f8-7blade` kernel file; the issue-5 workload scene at 4K
with its kernel, from WORKLOAD_DIR/*.npy) it times, in this run:

- aureole: `aureole apply s.%04d.exr --frames … --kernel K -o out/ --half`,
  a batch of 1 and of FRAMES + 1 frames; the steady-state time per frame is
  the difference over FRAMES, the per-stage medians come from its summary
  lines, the peak memory is that of the whole batch (`/usr/bin/time`);
- the peer: the `OpenEXR` package reading each frame, scipy.signal's
  fftconvolve with 2 workers per channel (f32, mode "same"), and OpenEXR
  writing half floats with the input's compression (ZIP), frame by frame in
  one process; the kernel is read once.

Both read the same input files and the same kernel file, and their first
results are compared (relative L2 over the image).
"""

import json
import os
import re
import resource
import shutil
import statistics
import subprocess
import sys
import time

import numpy as np

FRAMES = 4


def peer(pattern, frames, kernel_path, out_pattern):
    """The OpenEXR + scipy pipeline; prints one JSON line."""
    import OpenEXR
    import scipy.fft
    import scipy.signal

    with OpenEXR.File(kernel_path, separate_channels=True) as f:
        channels = f.channels()
        names = [c for c in ("R", "G", "B", "Y") if c in channels]
        kernel = [channels[c].pixels.astype(np.float32) for c in names]
    stages = {"read": [], "convolve": [], "write": [], "frame": []}
    for n in frames:
        t0 = time.perf_counter()
        with OpenEXR.File(pattern % n, separate_channels=True) as f:
            channels = f.channels()
            planes = [channels[c].pixels.astype(np.float32) for c in ("R", "G", "B")]
        t1 = time.perf_counter()
        with scipy.fft.set_workers(2):
            out = [
                scipy.signal.fftconvolve(p, kernel[min(i, len(kernel) - 1)], mode="same")
                for i, p in enumerate(planes)
            ]
        t2 = time.perf_counter()
        header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
        # Clamped to the largest half, as aureole writes them.
        written = {c: np.clip(o, -65504, 65504).astype(np.float16) for c, o in zip(("R", "G", "B"), out)}
        with OpenEXR.File(header, written) as f:
            f.write(out_pattern % n)
        t3 = time.perf_counter()
        for key, value in zip(stages, (t1 - t0, t2 - t1, t3 - t2, t3 - t0)):
            stages[key].append(value)
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    # The first frame pays for planning and caches: the rest are the batch.
    print(json.dumps({k: statistics.median(v[1:]) for k, v in stages.items()} | {"peak_mb": peak}))


def run(command):
    return subprocess.run(command, check=True, capture_output=True, text=True)


def aureole_batch(aureole, work, kernel, count, ext="exr"):
    out = os.path.join(work, f"out{count}")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    half = ["--half"] if ext == "exr" else []
    start = time.perf_counter()
    done = run(["/usr/bin/time", "-f", "peak %M", aureole, "apply",
                os.path.join(work, f"s.%04d.{ext}"), "--frames", f"1-{count}",
                "--kernel", kernel, "-o", out + "/"] + half)
    wall = time.perf_counter() - start
    stages = [tuple(map(float, m)) for m in re.findall(
        r"read ([\d.]+) s, camera ([\d.]+) s, write ([\d.]+) s", done.stderr)]
    peak = int(re.search(r"peak (\d+)", done.stderr).group(1)) / 1024
    return wall, stages, peak, out


def read_rgb(path):
    import OpenEXR

    with OpenEXR.File(path, separate_channels=True) as f:
        channels = f.channels()
        return np.stack([channels[c].pixels.astype(np.float64) for c in ("R", "G", "B")])


def workload(name, aureole, work, kernel):
    for n in range(2, FRAMES + 2):
        shutil.copyfile(os.path.join(work, "s.0001.exr"), os.path.join(work, f"s.{n:04d}.exr"))
    one, _, _, _ = aureole_batch(aureole, work, kernel, 1)
    many, stages, peak, out = aureole_batch(aureole, work, kernel, FRAMES + 1)
    per_frame = (many - one) / FRAMES
    steady = stages[1:]
    read, camera, write = (statistics.median(s[i] for s in steady) for i in range(3))
    peer_out = os.path.join(work, "peer")
    os.makedirs(peer_out, exist_ok=True)
    result = run([sys.executable, __file__, "peer", os.path.join(work, "s.%04d.exr"),
                  str(FRAMES + 1), kernel, os.path.join(peer_out, "s.%04d.exr")])
    theirs = json.loads(result.stdout)
    a = read_rgb(os.path.join(out, "s.0001.exr"))
    b = read_rgb(os.path.join(peer_out, "s.0001.exr"))
    difference = np.linalg.norm(a - b) / np.linalg.norm(a)
    print(f"| {name} | aureole | {per_frame:.2f} s | {read:.2f} s | {camera:.2f} s | {write:.2f} s | {peak:.0f} MB | 1.0 | reference |")
    print(f"| {name} | OpenEXR + scipy fftconvolve (2 workers) | {theirs['frame']:.2f} s | {theirs['read']:.2f} s | {theirs['convolve']:.2f} s | {theirs['write']:.2f} s | {theirs['peak_mb']:.0f} MB | {theirs['frame'] / per_frame:.1f} | {difference:.1e} |")


def pfm_batch(name, aureole, work, kernel):
    """aureole alone, PFM in and out (float32, no compression)."""
    for n in range(2, FRAMES + 2):
        shutil.copyfile(os.path.join(work, "s.0001.pfm"), os.path.join(work, f"s.{n:04d}.pfm"))
    one, _, _, _ = aureole_batch(aureole, work, kernel, 1, "pfm")
    many, stages, peak, _ = aureole_batch(aureole, work, kernel, FRAMES + 1, "pfm")
    steady = stages[1:]
    read, camera, write = (statistics.median(s[i] for s in steady) for i in range(3))
    print(f"| {name} | aureole | {(many - one) / FRAMES:.2f} s | {read:.2f} s | {camera:.2f} s | {write:.2f} s | {peak:.0f} MB | | |")


def write_pfm(path, planes):
    """Three planes (top row first) as a little-endian PF file."""
    data = np.stack(planes, axis=-1)[::-1].astype("<f4")
    with open(path, "wb") as f:
        f.write(f"PF\n{data.shape[1]} {data.shape[0]}\n-1.0\n".encode())
        f.write(data.tobytes())


def write_exr(path, planes, names):
    import OpenEXR

    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    with OpenEXR.File(header, {n: p.astype(np.float32) for n, p in zip(names, planes)}) as f:
        f.write(path)


def main(aureole, work, workload_dir):
    print(f"## End to end: EXR in, half EXR out, a batch of {FRAMES} frames after the first\n")
    print("Per frame in the batch (the first frame, which loads the kernel file and")
    print("transforms it, is left out); the stages are medians over the frames, and")
    print("aureole's overlap (it reads the next frame and writes the last while one")
    print("is convolved), so they add up to more than its time per frame. Both write")
    print("half floats with ZIP, the input's compression. Agreement: relative L2")
    print("between the two results.\n")
    print("| workload | implementation | per frame | read | convolve | write | peak memory | ratio to aureole | agreement |")
    print("|---|---|---|---|---|---|---|---|---|")
    for size, (w, h) in (("4K", (3840, 2160)), ("1080p", (1920, 1080))):
        dir = os.path.join(work, f"street-{size}")
        os.makedirs(dir, exist_ok=True)
        run([aureole, "demo", "--size", f"{w}x{h}", "--hdr", os.path.join(dir, "s.0001.exr"),
             "-o", os.path.join(dir, "demo.png"), "-q"])
        kernel = os.path.join(dir, "lens.exr")
        run([aureole, "psf", "--preset", "camera-f8-7blade", "--size", f"{2 * w - 1}x{2 * h - 1}",
             "--image-width", str(w), "-o", kernel])
        workload(f"night street {size}, camera-f8-7blade", aureole, dir, kernel)
    dir = os.path.join(work, "workload-4K")
    os.makedirs(dir, exist_ok=True)
    image = np.load(os.path.join(workload_dir, "image.npy"))
    write_exr(os.path.join(dir, "s.0001.exr"), image, ("R", "G", "B"))
    kernel = os.path.join(dir, "kernel.exr")
    write_exr(kernel, [np.load(os.path.join(workload_dir, "kernel.npy"))], ("Y",))
    workload("issue-5 workload 4K", aureole, dir, kernel)
    write_pfm(os.path.join(dir, "s.0001.pfm"), list(image))
    pfm_batch("issue-5 workload 4K, PFM in and out", aureole, dir, kernel)
    print()


if __name__ == "__main__":
    if sys.argv[1] == "peer":
        _, _, pattern, count, kernel, out = sys.argv
        peer(pattern, range(1, int(count) + 1), kernel, out)
    else:
        main(*sys.argv[1:4])
