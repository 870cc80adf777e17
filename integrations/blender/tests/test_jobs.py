"""The add-on's jobs outside Blender (jobs.py touches no bpy): a frame
applied on the add-on's thread, and Cancel stopping a long one before
its end, leaving no output."""

import importlib.util
import pathlib
import time

import numpy as np
import pytest

import aureole

JOBS = pathlib.Path(__file__).resolve().parents[1] / "aureole_blender" / "jobs.py"
spec = importlib.util.spec_from_file_location("aureole_blender_jobs", JOBS)
jobs = importlib.util.module_from_spec(spec)
spec.loader.exec_module(jobs)


def frame(path, width, height):
    image = np.full((height, width, 3), 0.01, np.float32)
    image[height // 3, width // 4] = 5e4
    image[height // 2, width // 2] = 2e4
    aureole.write(path, image)
    return path


def wait(runner, seconds):
    end = time.monotonic() + seconds
    while runner.busy() and time.monotonic() < end:
        time.sleep(0.01)


def test_a_frame_is_applied_off_the_calling_thread(tmp_path):
    source = frame(tmp_path / "render.0001.exr", 96, 64)
    runner = jobs.Runner()
    job = jobs.Job(source=source, output=tmp_path / "aureole" / source.name,
                   camera=aureole.Camera.preset("camera-f8-7blade"),
                   options={"threshold": 0.0, "input_scale": 683.0, "device": "cpu"})
    runner.submit(job)
    wait(runner, 60)
    assert job.state == "done", job.message
    assert job.result["energy_out"] <= job.result["energy_in"]
    expected = tmp_path / "direct.exr"
    aureole.Camera.preset("camera-f8-7blade").apply_file(
        source, expected, threshold=0.0, input_scale=683.0, device="cpu")
    assert job.output.read_bytes() == expected.read_bytes()


@pytest.mark.latency
def test_cancel_stops_a_long_frame_before_its_end(tmp_path):
    source = frame(tmp_path / "render.0001.exr", 1600, 1200)
    runner = jobs.Runner()
    camera = aureole.Camera.preset("camera-f8-7blade")
    long = jobs.Job(source=source, output=tmp_path / "out" / "long.exr", camera=camera,
                    options={"threshold": 0.0, "device": "cpu"})
    waiting = jobs.Job(source=source, output=tmp_path / "out" / "next.exr", camera=camera,
                       options={"threshold": 0.0, "device": "cpu"})
    runner.submit(long)
    runner.submit(waiting)
    start = time.monotonic()
    while long.state != "running" or long.stage == "":
        assert time.monotonic() - start < 60
        time.sleep(0.01)
    # Cancelled once its work has begun, not after a sleep that would race
    # the frame's end; the outcome is what is asserted, with no clock: both
    # jobs cancelled, the long one's apply_file never returned (a Cancel
    # honoured only at the frame's end would have a result), neither
    # output written.
    assert long.state == "running", "the frame ended before it could be cancelled"
    runner.cancel_all()
    wait(runner, 60)
    assert (long.state, waiting.state) == ("cancelled", "cancelled")
    assert long.result is None
    assert not (tmp_path / "out" / "long.exr").exists()
    assert not (tmp_path / "out" / "next.exr").exists()


def test_a_failure_is_one_line(tmp_path):
    bad = tmp_path / "render.0001.exr"
    bad.write_bytes(b"v/1\x01not an exr")
    job = jobs.Job(source=bad, output=tmp_path / "out.exr",
                   camera=aureole.Camera.preset("camera-f8-7blade"), options={})
    job.run()
    assert job.state == "failed"
    assert "render.0001.exr" in job.message and "\n" not in job.message


def test_a_long_session_keeps_only_the_last_jobs(tmp_path):
    runner = jobs.Runner()
    for n in range(12):
        job = jobs.Job(source=tmp_path / f"{n}.exr", output=tmp_path / "out" / f"{n}.exr",
                       camera=None, options={}, state="done", reported=n < 10)
        runner.jobs.append(job)
    runner.trim(keep=8)
    # The two not yet reported stay, with the last eight reported.
    assert [job.source.stem for job in runner.jobs] == [str(n) for n in range(2, 12)]
