"""The Open Job Description template (farm/aureole-sequence/template.yaml) run by
the reference runner, `openjd run`, against one `aureole apply` batch."""

import os
import pathlib
import re
import shutil
import subprocess
import sys

import numpy as np
import pytest

import aureole

# Its module fixtures run once: on one worker under pytest-xdist.
pytestmark = pytest.mark.xdist_group("openjd")

TEMPLATE = pathlib.Path(__file__).resolve().parents[1] / "aureole-sequence" / "template.yaml"
FRAMES = 7


@pytest.fixture(scope="module")
def cli():
    """The `aureole` binary the farm runs: AUREOLE_BIN (as scripts/test
    sets it), else the workspace's release build."""
    binary = pathlib.Path(os.environ.get("AUREOLE_BIN")
                          or TEMPLATE.parents[2] / "target" / "release" / "aureole")
    if not binary.is_file():
        pytest.fail("no aureole binary: cargo build --release -p aureole-cli, or set AUREOLE_BIN")
    return str(binary)


@pytest.fixture(scope="module")
def openjd():
    # scripts/test installs openjd-cli beside the Python that runs pytest.
    beside = pathlib.Path(sys.executable).parent / "openjd"
    found = str(beside) if beside.is_file() else shutil.which("openjd")
    if found is None:
        pytest.skip("openjd-cli is not installed (pip install openjd-cli)")
    return found


@pytest.fixture(scope="module")
def sequence(tmp_path_factory):
    """Seven 96×54 frames of lamps over a dim street, in cd/m²."""
    folder = tmp_path_factory.mktemp("frames")
    rng = np.random.default_rng(7)
    for frame in range(1, FRAMES + 1):
        image = np.full((54, 96, 3), 0.05, np.float32)
        for _ in range(4):
            y, x = rng.integers(4, 50), rng.integers(4, 92)
            image[y, x] = rng.uniform(2e3, 1e5, 3)
        aureole.write(folder / f"shot.{frame:04d}.exr", image, half=True)
    return folder / "shot.%04d.exr"


def run_job(openjd, cli, sequence, out, camera, chunk, threshold="", resume="no"):
    kernel = out.parent / f"{out.name}-kernel.exr"
    done = subprocess.run(
        [openjd, "run", str(TEMPLATE),
         "-p", f"Input={sequence}", "-p", f"Output={out}",
         "-p", f"Frames=1-{FRAMES}", "-p", f"ChunkSize={chunk}",
         "-p", f"Camera={camera}", "-p", f"Threshold={threshold}",
         "-p", f"Kernel={kernel}", "-p", f"Aureole={cli}", "-p", f"Resume={resume}"],
        capture_output=True, text=True, timeout=600)
    return done, kernel


def batch(cli, sequence, out, camera, threshold=None):
    out.mkdir()
    flag = "--config" if camera.endswith(".toml") else "--preset"
    args = [cli, "-q", "apply", str(sequence), "--frames", f"1-{FRAMES}", "-o", str(out),
            flag, camera]
    if threshold is not None:
        args += ["--threshold", str(threshold)]
    subprocess.run(args, check=True)


def test_the_template_is_valid(openjd):
    done = subprocess.run([openjd, "check", str(TEMPLATE)], capture_output=True, text=True)
    assert done.returncode == 0, done.stdout + done.stderr


@pytest.mark.parametrize("camera", ["camera-f8-7blade", "toml"])
def test_chunks_give_the_bytes_of_one_batch(openjd, cli, sequence, tmp_path, camera):
    if camera == "toml":
        # A camera of its own with its own threshold, which the kernel
        # carries to every chunk.
        camera = str(tmp_path / "lens.toml")
        pathlib.Path(camera).write_text(
            'threshold = 3000.0\n[camera]\nsensor_width_mm = 36.0\nfocal_length_mm = 35.0\n'
            'f_number = 11.0\n[[effect]]\ntype = "aperture"\nblades = 6\n'
            '[[effect]]\ntype = "bloom"\nepsilon = 0.01\nbeta = 3.0\nradius = "4px"\n')
    out = tmp_path / "farm"
    out.mkdir()
    done, kernel = run_job(openjd, cli, sequence, out, camera, chunk=3)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr
    # One kernel task, then chunks of at most 3 frames covering the range
    # once (the runner balances them: 1-3, 4-5, 6-7).
    assert done.stdout.count("wrote " + str(kernel)) == 1
    chunks = re.findall(r"Frame\(CHUNK\[INT\]\) = (\d+)-(\d+)", done.stdout)
    covered = [f for a, b in chunks for f in range(int(a), int(b) + 1)]
    assert covered == list(range(1, FRAMES + 1)), chunks
    assert len(chunks) >= 3 and all(int(b) - int(a) < 3 for a, b in chunks), chunks
    assert f"Chunks run: {len(chunks) + 1}" in done.stdout
    expected = tmp_path / "batch"
    batch(cli, sequence, expected, camera)
    names = sorted(p.name for p in expected.iterdir())
    assert names == [f"shot.{f:04d}.exr" for f in range(1, FRAMES + 1)]
    assert sorted(p.name for p in out.iterdir()) == names
    for name in names:
        assert (out / name).read_bytes() == (expected / name).read_bytes(), name


def test_a_threshold_and_a_failing_chunk(openjd, cli, sequence, tmp_path):
    frames = tmp_path / "frames"
    shutil.copytree(sequence.parent, frames)
    damaged = frames / "shot.0005.exr"
    damaged.write_bytes(damaged.read_bytes()[:300])
    out = tmp_path / "farm"
    out.mkdir()
    done, _ = run_job(openjd, cli, frames / sequence.name, out, "camera-f8-7blade", chunk=4,
                      threshold="1000")
    # The chunk holding the damaged frame fails the job, and says why.
    assert done.returncode != 0
    assert "shot.0005.exr" in done.stdout
    # The good frames of the run are the batch's; a rerun with Resume once
    # the frame is mended writes only what is missing, one without writes
    # everything again.
    shutil.copy(sequence.parent / "shot.0005.exr", damaged)
    written = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert written and len(written) < FRAMES
    done, _ = run_job(openjd, cli, frames / sequence.name, out, "camera-f8-7blade", chunk=4,
                      threshold="1000", resume="yes")
    assert done.returncode == 0, done.stdout[-3000:]
    for name, mtime in written.items():
        assert (out / name).stat().st_mtime_ns == mtime, f"{name} was written again"
    assert len(list(out.iterdir())) == FRAMES
    resumed = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    done, _ = run_job(openjd, cli, frames / sequence.name, out, "camera-f8-7blade", chunk=4,
                      threshold="1000")
    assert done.returncode == 0, done.stdout[-3000:]
    assert all((out / name).stat().st_mtime_ns != mtime for name, mtime in resumed.items())
    expected = tmp_path / "batch"
    batch(cli, frames / sequence.name, expected, "camera-f8-7blade", threshold=1000)
    for path in expected.iterdir():
        assert (out / path.name).read_bytes() == path.read_bytes(), path.name


def test_parameters_are_arguments_never_commands(openjd, cli, sequence, tmp_path):
    """Paths with quotes, `$(...)`, backquotes, backslashes and spaces reach
    aureole as they are: no parameter is pasted into a shell's text."""
    odd = tmp_path / "it's \"a\" $(touch PWNED) `touch PWNED2` back\\slash"
    frames = odd / "frames"
    shutil.copytree(sequence.parent, frames)
    out = odd / "out $HOME"
    out.mkdir()
    done, kernel = run_job(openjd, cli, frames / sequence.name, out, "camera-f8-7blade", chunk=4,
                           threshold="1000")
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr
    assert kernel.is_file()
    expected = tmp_path / "batch"
    batch(cli, frames / sequence.name, expected, "camera-f8-7blade", threshold=1000)
    for path in expected.iterdir():
        assert (out / path.name).read_bytes() == path.read_bytes(), path.name
    for root in (tmp_path, pathlib.Path.cwd()):
        assert not list(root.rglob("PWNED*")), "a parameter ran as a command"
