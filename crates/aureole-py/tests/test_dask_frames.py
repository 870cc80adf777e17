"""Dask: arrays sent to the worker processes of a real LocalCluster come
back equal to a direct call, and examples/python/dask_frames.py on one
writes what the command line's batch writes byte for byte, reports a
broken frame while the others are written, and resumes."""

import subprocess
import sys

import numpy as np
import pytest

import aureole

from conftest import ROOT, run

pytest.importorskip("distributed")

SCRIPT = ROOT / "examples" / "python" / "dask_frames.py"


def frames(folder, count):
    """A lamp moving over a dim street, one EXR per frame."""
    for n in range(1, count + 1):
        image = np.full((90, 160, 3), 0.05, np.float32)
        image[40:50, 100:110] = 0.4
        image[45, 20 + 25 * n] = 5e4
        aureole.write(folder / f"in.{n:04d}.exr", image)


def test_arrays_sent_to_workers_come_back_equal_to_a_direct_call():
    from distributed import Client, LocalCluster

    camera = aureole.Camera.preset("paper-fig5-both")
    images = []
    for n in range(4):
        image = np.full((90, 160, 3), 0.05, np.float32)
        image[45, 20 + 30 * n] = 5e4
        images.append(image)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        # The arrays travel to the workers (pickle protocol 5 buffers, which
        # arrive unaligned), the camera as its TOML.
        sent = client.scatter(images)
        futures = client.map(camera.apply, sent, threshold=100.0)
        results = client.gather(futures)
        where = client.who_has(futures)
    assert len({worker for workers in where.values() for worker in workers}) == 2, where
    for image, result in zip(images, results):
        assert np.array_equal(result, camera.apply(image, threshold=100.0))


def dask(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)],
                          capture_output=True, text=True, timeout=300)


def test_frames_on_a_local_cluster_equal_the_cli_batch_and_resume(cli, tmp_path):
    frames(tmp_path, 4)
    camera = ["--preset", "paper-fig5-both", "--threshold", "100"]
    run(cli, "apply", tmp_path / "in.%04d.exr", "--frames", "1-4",
        "-o", tmp_path / "cli.%04d.exr", *camera)

    done = dask(tmp_path / "in.%04d.exr", tmp_path / "dask.%04d.exr", "--frames", "1-4",
                "--workers", "2", *camera)
    assert done.returncode == 0, done.stderr
    # Both workers took frames.
    workers = {line.split(" on ")[1] for line in done.stdout.splitlines() if " on " in line}
    assert len(workers) == 2, done.stdout
    for n in range(1, 5):
        assert (tmp_path / f"dask.{n:04d}.exr").read_bytes() == (tmp_path / f"cli.{n:04d}.exr").read_bytes()

    # A stopped run resumes: what is written is skipped.
    (tmp_path / "dask.0003.exr").unlink()
    again = dask(tmp_path / "in.%04d.exr", tmp_path / "dask.%04d.exr", "--frames", "1-4",
                 "--workers", "2", *camera)
    assert again.returncode == 0, again.stderr
    assert "3 frame(s) already written, skipped" in again.stdout
    assert "1 written, 0 failed" in again.stdout
    assert (tmp_path / "dask.0003.exr").read_bytes() == (tmp_path / "cli.0003.exr").read_bytes()


def test_a_broken_frame_is_reported_and_the_others_written(tmp_path):
    frames(tmp_path, 3)
    (tmp_path / "in.0002.exr").write_bytes(b"v/1\x01 cut short")
    done = dask(tmp_path / "in.%04d.exr", tmp_path / "out.%04d.exr", "--frames", "1-3",
                "--workers", "2", "--preset", "paper-fig4-bloom")
    assert done.returncode == 1
    assert "frame 2: error:" in done.stderr and "in.0002.exr" in done.stderr
    assert "2 written, 1 failed" in done.stdout
    assert (tmp_path / "out.0001.exr").is_file() and (tmp_path / "out.0003.exr").is_file()
    assert not (tmp_path / "out.0002.exr").exists()
