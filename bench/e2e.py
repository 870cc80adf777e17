"""End to end, as a user runs it: files in, files out, a batch of frames.

python e2e.py AUREOLE BENCH_CODEC WORKDIR WORKLOAD_DIR   prints the markdown
sections of bench/RESULTS.md. For each workload (the demo night street at
4K and 1080p with a `camera-f8-7blade` kernel file; the issue-5 workload
scene at 4K with its kernel, from WORKLOAD_DIR/*.npy) it times, in this
run:

- aureole: `aureole apply s.%04d.exr --frames … --kernel K -o out/ --half`,
  a batch of 1 and of FRAMES + 1 frames; the steady-state time per frame is
  the difference over FRAMES, the per-stage medians come from its summary
  lines, the peak memory is that of the whole batch (`/usr/bin/time`), the
  fresh memory per frame its minor faults (batches of FRAMES + 1 against
  1, and of 2 FRAMES + 1 against FRAMES + 1: the steady state);
- the peer: the `OpenEXR` package reading each frame, scipy.signal's
  fftconvolve with 2 workers per channel (f32, mode "same"), and OpenEXR
  writing half floats with the input's compression (ZIP), frame by frame in
  one process; the kernel is read once.

Both read the same input files and the same kernel file, and their first
results are compared (relative L2 over the image).

Then the kernels: the 4K lens kernel written by `psf` and read back as
`apply --kernel` reads it (`bench_codec kernel`), one frame with the kernel
file against one frame building it, and the issue-5 bloom + corona kernel
built at 7679x4319; a still (one 4K frame through the default camera, the
kernel built in the run, against the peer given that kernel); and four
issue-5 PFM frames with the kernel built from
bench/issue5.toml in the same run, against scipy given the kernel ready.
"""

import json
import os
import pathlib
import re
import resource
import shutil
import statistics
import subprocess
import sys
import time

import numpy as np

FRAMES = 4
RUNS = 3
ISSUE5 = str(pathlib.Path(__file__).resolve().parent / "issue5.toml")


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


def read_pfm(path):
    with open(path, "rb") as f:
        magic = f.readline().strip()
        width, height = map(int, f.readline().split())
        scale = float(f.readline())
        data = np.frombuffer(f.read(), dtype="<f4" if scale < 0 else ">f4")
    channels = 3 if magic == b"PF" else 1
    return data.reshape(height, width, channels)[::-1].transpose(2, 0, 1).astype(np.float32)


def pfm_peer(pattern, frames, kernel_npy, out_pattern):
    """scipy's fftconvolve (2 workers) on PFM frames, the kernel ready-made
    (loaded before the clock starts); prints one JSON line."""
    import scipy.fft
    import scipy.signal

    kernel = np.load(kernel_npy).astype(np.float32)
    start = time.perf_counter()
    for n in frames:
        planes = read_pfm(pattern % n)
        with scipy.fft.set_workers(2):
            out = [scipy.signal.fftconvolve(p, kernel, mode="same") for p in planes]
        write_pfm(out_pattern % n, out)
    print(json.dumps({"total": time.perf_counter() - start}))


def run(command):
    return subprocess.run(command, check=True, capture_output=True, text=True)


def aureole_batch(aureole, work, kernel, count, ext="exr", any_width=False):
    """`any_width`: the kernel is one numpy wrote, in pixels, without the
    image width `psf` records."""
    out = os.path.join(work, f"out{count}")
    shutil.rmtree(out, ignore_errors=True)
    os.makedirs(out)
    half = ["--half"] if ext == "exr" else []
    start = time.perf_counter()
    done = run(["/usr/bin/time", "-f", "peak %M faults %R", aureole, "apply",
                os.path.join(work, f"s.%04d.{ext}"), "--frames", f"1-{count}",
                "--kernel", kernel, "-o", out + "/"] + half
               + (["--kernel-any-width"] if any_width else []))
    wall = time.perf_counter() - start
    stages = [tuple(map(float, m)) for m in re.findall(
        r"read ([\d.]+) s, camera ([\d.]+) s, write ([\d.]+) s", done.stderr)]
    peak = int(re.search(r"peak (\d+)", done.stderr).group(1)) / 1024
    faults = int(re.search(r"faults (\d+)", done.stderr).group(1))
    return wall, stages, peak, out, faults


def read_rgb(path):
    import OpenEXR

    with OpenEXR.File(path, separate_channels=True) as f:
        channels = f.channels()
        return np.stack([channels[c].pixels.astype(np.float64) for c in ("R", "G", "B")])


def fresh_mib(faults_before, faults_after):
    """Fresh memory per frame between two batches FRAMES frames apart, in
    MiB: their minor page faults, 4 KiB each."""
    return (faults_after - faults_before) / FRAMES * 4096 / 2**20


def workload(name, aureole, work, kernel, any_width=False):
    for n in range(2, 2 * FRAMES + 2):
        shutil.copyfile(os.path.join(work, "s.0001.exr"), os.path.join(work, f"s.{n:04d}.exr"))
    batch = lambda count: aureole_batch(aureole, work, kernel, count, any_width=any_width)
    one, _, _, _, faults_one = batch(1)
    many, stages, peak, out, faults_many = batch(FRAMES + 1)
    faults_more = batch(2 * FRAMES + 1)[4]
    fresh = (f"{fresh_mib(faults_one, faults_many):.0f} MiB, "
             f"{fresh_mib(faults_many, faults_more):.1f} MiB")
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
    print(f"| {name} | aureole | {per_frame:.2f} s | {read:.2f} s | {camera:.2f} s | {write:.2f} s | {peak:.0f} MB | {fresh} | 1.0 | reference |")
    print(f"| {name} | OpenEXR + scipy fftconvolve (2 workers) | {theirs['frame']:.2f} s | {theirs['read']:.2f} s | {theirs['convolve']:.2f} s | {theirs['write']:.2f} s | {theirs['peak_mb']:.0f} MB | | {theirs['frame'] / per_frame:.1f} | {difference:.1e} |")


def pfm_batch(name, aureole, work, kernel, any_width=False):
    """aureole alone, PFM in and out (float32, no compression)."""
    for n in range(2, FRAMES + 2):
        shutil.copyfile(os.path.join(work, "s.0001.pfm"), os.path.join(work, f"s.{n:04d}.pfm"))
    one, _, _, _, faults_one = aureole_batch(aureole, work, kernel, 1, "pfm", any_width)
    many, stages, peak, _, faults_many = aureole_batch(aureole, work, kernel, FRAMES + 1, "pfm",
                                                       any_width)
    steady = stages[1:]
    read, camera, write = (statistics.median(s[i] for s in steady) for i in range(3))
    print(f"| {name} | aureole | {(many - one) / FRAMES:.2f} s | {read:.2f} s | {camera:.2f} s | {write:.2f} s | {peak:.0f} MB | {fresh_mib(faults_one, faults_many):.0f} MiB | | |")


def timed(command):
    start = time.perf_counter()
    done = run(command)
    return time.perf_counter() - start, done


def kernels(aureole, bench_codec, work):
    """The kernel rows: a lens kernel file written, read and applied, and
    the issue-5 kernel built."""
    dir = os.path.join(work, "street-4K")
    kernel = os.path.join(dir, "lens.exr")
    psf = ["psf", "--preset", "camera-f8-7blade", "--size", "7679x4319", "--image-width", "3840"]
    writes = [timed([aureole, *psf, "-o", kernel])[0] for _ in range(RUNS)]
    read = json.loads(run([bench_codec, "kernel", kernel, str(RUNS)]).stdout)["kernel_read"]
    frame = os.path.join(dir, "s.0001.exr")
    out = os.path.join(dir, "one.exr")
    given = [timed([aureole, "apply", frame, "--kernel", kernel, "--half", "-o", out, "-q"])[0]
             for _ in range(RUNS)]
    built = [timed([aureole, "apply", frame, "--preset", "camera-f8-7blade", "--half", "-o", out,
                    "-q"])[0] for _ in range(RUNS)]
    builds = []
    for _ in range(RUNS):
        done = run([aureole, "psf", "--config", ISSUE5, "--size", "7679x4319",
                    "-o", os.path.join(work, "issue5.pfm")])
        builds.append(float(re.search(r"built in ([\d.]+) s", done.stderr).group(1)))
    median = statistics.median
    print("## Kernels: written, read, built\n")
    print(f"Medians of {RUNS}. The 4K lens kernel is `camera-f8-7blade` at 7679x4319 for")
    print("3840-px frames (3 planes, float, stored uncompressed); one frame is the")
    print("night street, EXR in, half EXR out.\n")
    print("| what | time |")
    print("|---|---|")
    print(f"| `psf` of the 4K lens kernel to .exr, build and write | {median(writes):.2f} s "
          f"({os.path.getsize(kernel) / 1e6:.0f} MB) |")
    print(f"| reading it as `apply --kernel` does (file, planes, checks, normalisation) | {read:.2f} s |")
    print(f"| `apply` of one 4K frame with `--kernel lens.exr` | {median(given):.2f} s |")
    print(f"| `apply` of one 4K frame with `--preset camera-f8-7blade` (building the kernel) | {median(built):.2f} s |")
    print(f"| the issue-5 bloom + corona kernel, 7679x4319, built (`psf`'s figure) | {median(builds):.2f} s |")
    print()


def still(aureole, work):
    """One 4K frame through the default camera, file to file, the kernel
    built in the run, against OpenEXR + scipy given that camera's kernel
    ready-made (its second, warm frame: read, fftconvolve with 2 workers
    per channel, half ZIP write)."""
    dir = os.path.join(work, "street-4K")
    frame = os.path.join(dir, "s.0001.exr")
    shutil.copyfile(frame, os.path.join(dir, "s.0002.exr"))
    out = os.path.join(dir, "still.exr")
    ours = [timed([aureole, "apply", frame, "--half", "-o", out, "-q"])[0] for _ in range(RUNS)]
    kernel = os.path.join(dir, "default.exr")
    run([aureole, "psf", "--preset", "paper-fig5-both", "--for-image", frame, "-o", kernel, "-q"])
    peer_out = os.path.join(dir, "still-peer")
    os.makedirs(peer_out, exist_ok=True)
    theirs = [json.loads(run([sys.executable, __file__, "peer", os.path.join(dir, "s.%04d.exr"), "2",
                              kernel, os.path.join(peer_out, "s.%04d.exr")]).stdout)["frame"]
              for _ in range(RUNS)]
    a = read_rgb(out)
    b = read_rgb(os.path.join(peer_out, "s.0001.exr"))
    difference = np.linalg.norm(a - b) / np.linalg.norm(a)
    median = statistics.median
    print("## A still: one 4K night street through the default camera, file to file\n")
    print(f"Medians of {RUNS}: `aureole apply s.0001.exr --half -o still.exr` builds the default")
    print("camera's kernel (paper-fig5-both) in the run; the peer is given that kernel")
    print("(`psf --for-image`) before its clock starts.\n")
    print("| implementation | time | ratio to the peer | agreement |")
    print("|---|---|---|---|")
    print(f"| aureole, kernel built in the run | {median(ours):.2f} s | "
          f"{median(ours) / median(theirs):.2f} | reference |")
    print(f"| OpenEXR + scipy fftconvolve (2 workers), kernel given | {median(theirs):.2f} s | 1.0 | "
          f"{difference:.1e} |")
    print()


def pfm_built(aureole, work, workload_dir):
    """Four issue-5 PFM frames, the kernel built from the config in the
    same run, against scipy given the kernel ready."""
    dir = os.path.join(work, "workload-4K")
    for n in range(2, FRAMES + 1):
        shutil.copyfile(os.path.join(dir, "s.0001.pfm"), os.path.join(dir, f"s.{n:04d}.pfm"))
    out = os.path.join(dir, "built")
    ours = []
    for _ in range(RUNS):
        shutil.rmtree(out, ignore_errors=True)
        os.makedirs(out)
        ours.append(timed([aureole, "apply", os.path.join(dir, "s.%04d.pfm"), "--frames",
                           f"1-{FRAMES}", "--config", ISSUE5, "-o", out + "/", "-q"])[0])
    peer_out = os.path.join(dir, "peer")
    os.makedirs(peer_out, exist_ok=True)
    theirs = [json.loads(run([sys.executable, __file__, "pfm-peer", os.path.join(dir, "s.%04d.pfm"),
                              str(FRAMES), os.path.join(workload_dir, "kernel.npy"),
                              os.path.join(peer_out, "s.%04d.pfm")]).stdout)["total"]
              for _ in range(RUNS)]
    a = read_pfm(os.path.join(out, "s.0001.pfm")).astype(np.float64)
    b = read_pfm(os.path.join(peer_out, "s.0001.pfm")).astype(np.float64)
    difference = np.linalg.norm(a - b) / np.linalg.norm(a)
    median = statistics.median
    print(f"## The issue-5 workload: {FRAMES} PFM frames, the kernel built in the same run\n")
    print(f"Medians of {RUNS} whole runs: aureole builds the kernel from bench/issue5.toml,")
    print("transforms it and applies it to every frame, files in and out; scipy's")
    print("fftconvolve (2 workers) is given the kernel ready-made (read before its clock")
    print("starts) and reads and writes the same PFM files with numpy.\n")
    print("| implementation | total | per frame | ratio to aureole | agreement |")
    print("|---|---|---|---|---|")
    print(f"| aureole (`apply --config`, kernel built) | {median(ours):.2f} s | "
          f"{median(ours) / FRAMES:.2f} s | 1.0 | reference |")
    print(f"| scipy.signal.fftconvolve (2 workers), kernel given | {median(theirs):.2f} s | "
          f"{median(theirs) / FRAMES:.2f} s | {median(theirs) / median(ours):.1f} | {difference:.1e} |")
    print()


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


def main(aureole, bench_codec, work, workload_dir):
    print(f"## End to end: EXR in, half EXR out, a batch of {FRAMES} frames after the first\n")
    print("Per frame in the batch (the first frame, which loads the kernel file and")
    print("transforms it, is left out); the stages are medians over the frames, and")
    print("aureole's overlap (it reads the next frame and writes the last while one")
    print("is convolved), so they add up to more than its time per frame. Both write")
    print("half floats with ZIP, the input's compression. Agreement: relative L2")
    print("between the two results. Fresh memory per frame: `/usr/bin/time`'s")
    print(f"minor faults, batches of {FRAMES + 1} against 1 (the frames in flight fill")
    print(f"up: one read ahead, one being written), then {2 * FRAMES + 1} against {FRAMES + 1} (the steady state).\n")
    print("| workload | implementation | per frame | read | convolve | write | peak memory | fresh memory per frame | ratio to aureole | agreement |")
    print("|---|---|---|---|---|---|---|---|---|---|")
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
    workload("issue-5 workload 4K", aureole, dir, kernel, any_width=True)
    write_pfm(os.path.join(dir, "s.0001.pfm"), list(image))
    pfm_batch("issue-5 workload 4K, PFM in and out", aureole, dir, kernel, any_width=True)
    print()
    kernels(aureole, bench_codec, work)
    still(aureole, work)
    pfm_built(aureole, work, workload_dir)


if __name__ == "__main__":
    if sys.argv[1] == "peer":
        _, _, pattern, count, kernel, out = sys.argv
        peer(pattern, range(1, int(count) + 1), kernel, out)
    elif sys.argv[1] == "pfm-peer":
        _, _, pattern, count, kernel, out = sys.argv
        pfm_peer(pattern, range(1, int(count) + 1), kernel, out)
    else:
        main(*sys.argv[1:5])
