"""The codec table: one 4K frame written and read as half and float, ZIP
and PIZ, by aureole (tools/src/bin/bench_codec.rs, through aureole-io as
`apply` does) and by the reference library (OpenEXR 3.x through its
Python package), in one run on this machine.

python codec.py BENCH_CODEC FRAME.exr WORKDIR   prints the markdown section
of bench/RESULTS.md. Both read the files OpenEXR wrote; medians of RUNS.
"""

import json
import os
import resource
import statistics
import subprocess
import sys
import time

import numpy as np

RUNS = 5


def cpu():
    usage = resource.getrusage(resource.RUSAGE_SELF)
    return usage.ru_utime + usage.ru_stime


def openexr_rows(frame, work):
    import OpenEXR

    with OpenEXR.File(frame, separate_channels=True) as f:
        planes = {c: f.channels()[c].pixels.astype(np.float32) for c in ("R", "G", "B")}
    rows = []
    for kind, dtype in (("half", np.float16), ("float", np.float32)):
        data = {c: np.clip(p, -65504, 65504).astype(dtype) if kind == "half" else p
                for c, p in planes.items()}
        for name, compression in (("zip", OpenEXR.ZIP_COMPRESSION), ("piz", OpenEXR.PIZ_COMPRESSION)):
            path = os.path.join(work, f"openexr-{kind}-{name}.exr")
            header = {"compression": compression, "type": OpenEXR.scanlineimage}
            writes, cpus, reads = [], [], []
            for _ in range(RUNS):
                start, cpu_start = time.perf_counter(), cpu()
                with OpenEXR.File(header, data) as f:
                    f.write(path)
                writes.append(time.perf_counter() - start)
                cpus.append(cpu() - cpu_start)
            for _ in range(RUNS):
                start = time.perf_counter()
                with OpenEXR.File(path, separate_channels=True) as f:
                    [f.channels()[c].pixels for c in ("R", "G", "B")]
                reads.append(time.perf_counter() - start)
            rows.append({"tool": "openexr", "samples": kind, "compression": name,
                         "write": statistics.median(writes), "write_cpu": statistics.median(cpus),
                         "read": statistics.median(reads), "bytes": os.path.getsize(path)})
    return rows


def main(bench_codec, frame, work):
    import OpenEXR

    os.makedirs(work, exist_ok=True)
    theirs = openexr_rows(frame, work)
    done = subprocess.run([bench_codec, frame, work, str(RUNS)], check=True,
                          capture_output=True, text=True)
    ours = [json.loads(line) for line in done.stdout.splitlines() if line.strip()]
    print("## EXR codecs: one 4K frame written and read\n")
    print(f"The night street through the camera (3840x2160 RGB), medians of {RUNS}; both")
    print("read the files OpenEXR wrote. OpenEXR "
          f"{OpenEXR.__version__} through its Python package; aureole through aureole-io")
    print("(`bench_codec`), as `apply` writes and reads frames, on every core.\n")
    print("| samples | compression | aureole write | CPU | OpenEXR write | CPU | write ratio | aureole read | OpenEXR read | read ratio | aureole size | OpenEXR size |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for a in ours:
        b = next(r for r in theirs if r["samples"] == a["samples"] and r["compression"] == a["compression"])
        print(f"| {a['samples']} | {a['compression'].upper()} | {a['write']:.3f} s | {a['write_cpu']:.2f} s "
              f"| {b['write']:.3f} s | {b['write_cpu']:.2f} s | {a['write'] / b['write']:.2f} "
              f"| {a['read']:.3f} s | {b['read']:.3f} s | {a['read'] / b['read']:.2f} "
              f"| {a['bytes'] / 1e6:.1f} MB | {b['bytes'] / 1e6:.1f} MB |")
    print()


if __name__ == "__main__":
    main(*sys.argv[1:4])
