#!/usr/bin/env python3
"""Render an EXR frame sequence through an aureole camera on a Dask cluster.

    python examples/python/dask_frames.py 'plates/shot.%04d.exr' 'out/shot.%04d.exr' \\
        --frames 1001-1096 --preset camera-f8-7blade --threshold 500

The camera (presets and config files composed in order, as on the command
line) is sent to the workers once; each worker builds its plan (kernel and
spectra) for the first frame and keeps it for the rest. Every frame is read,
applied and written on a worker, the result written atomically into a copy
of the input (other layers, parts and attributes kept), byte for byte what
`aureole apply` writes. A failing frame is reported and the others go on;
the exit status is 1 if any failed. Outputs that exist already are skipped,
so a run that was stopped resumes where it was.

By default a LocalCluster of worker processes on this machine; with
`--scheduler tcp://HOST:8786` the workers of a running cluster (they need
`aureole` installed and the same paths to the frames).
"""

import argparse
import os
import sys
import time


def frame_numbers(text):
    """'1-4,7,10-12' as a sorted list of numbers."""
    numbers = set()
    for part in text.split(","):
        first, _, last = part.partition("-")
        first, last = int(first), int(last or first)
        if last < first:
            raise argparse.ArgumentTypeError(f"frames {part!r}: the range runs backwards")
        numbers.update(range(first, last + 1))
    return sorted(numbers)


def arguments(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("input", help="input pattern with a printf number, e.g. shot.%%04d.exr")
    parser.add_argument("output", help="output pattern, e.g. out/shot.%%04d.exr")
    parser.add_argument("--frames", required=True, type=frame_numbers, help="e.g. 1-96 or 1,3,5-9")
    parser.add_argument("--preset", action="append", default=[], help="a built-in preset (repeatable)")
    parser.add_argument("--config", action="append", default=[], help="a TOML config file (repeatable)")
    parser.add_argument("--threshold", type=float, help="cd/m²: pixels at or below it stay")
    parser.add_argument("--knee", type=float, default=0.0)
    parser.add_argument("--half", action="store_true", default=None, help="write half samples")
    parser.add_argument("--compression", help="OpenEXR compression of the outputs")
    parser.add_argument("--scheduler", help="address of a running Dask scheduler (default: a LocalCluster)")
    parser.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes (default 2)")
    return parser.parse_args(argv)


def render_frame(camera_toml, source, target, options):
    """On a worker: one frame through the camera this worker keeps."""
    import aureole
    from distributed import get_worker

    # One camera per worker and TOML: its sessions keep the plan between
    # frames, so the kernel is built once per worker.
    worker = get_worker()
    cameras = getattr(worker, "_aureole_cameras", None)
    if cameras is None:
        cameras = worker._aureole_cameras = {}
    camera = cameras.get(camera_toml)
    if camera is None:
        camera = cameras[camera_toml] = aureole.Camera.from_toml(camera_toml, "the camera")
    start = time.perf_counter()
    report = camera.apply_file(source, target, **options)
    report["seconds"] = time.perf_counter() - start
    report["worker"] = worker.address
    return report


def main(argv=None):
    args = arguments(argv)
    import aureole
    from distributed import Client, LocalCluster, as_completed

    parts = [aureole.Camera.preset(name) for name in args.preset]
    parts += [aureole.Camera.from_file(path) for path in args.config]
    if not parts:
        print("dask_frames: give at least one --preset or --config", file=sys.stderr)
        return 2
    camera_toml = aureole.Camera.compose(*parts).toml()
    options = {"threshold": args.threshold, "knee": args.knee, "half": args.half,
               "compression": args.compression}

    jobs = [(n, args.input % n, args.output % n) for n in args.frames]
    todo = [job for job in jobs if not os.path.exists(job[2])]
    if len(todo) < len(jobs):
        print(f"dask_frames: {len(jobs) - len(todo)} frame(s) already written, skipped")
    if not todo:
        return 0

    if args.scheduler:
        client = Client(args.scheduler)
    else:
        # The workers share the cores: each computes on its part of them.
        os.environ.setdefault("RAYON_NUM_THREADS", str(max(1, (os.cpu_count() or 1) // args.workers)))
        client = Client(LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True))
    failed = 0
    with client:
        camera = client.scatter(camera_toml, broadcast=True)
        futures = {client.submit(render_frame, camera, source, target, options, pure=False): number
                   for number, source, target in todo}
        for future in as_completed(futures):
            number = futures[future]
            error = future.exception()
            if error is not None:
                failed += 1
                print(f"dask_frames: frame {number}: error: {error}", file=sys.stderr)
                continue
            report = future.result()
            print(f"dask_frames: frame {number}: {report['seconds']:.2f} s on {report['worker']}")
        if not args.scheduler:
            client.cluster.close()
    print(f"dask_frames: {len(todo) - failed} written, {failed} failed")
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
