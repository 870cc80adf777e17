"""The Blender add-on in real Blenders, headless: Debian's Blender 3.4 with
the legacy add-on (`blender -b`), and Blender 4.5 as a Python module (PyPI's
bpy, which scripts/test installs into target/bpyvenv) with the 4.2+
extension, its wheel installed by Blender. blender_scene.py renders a lamp
through a 7-blade f/8 camera with Cycles and the add-on applies aureole
after the render; these tests read what it wrote."""

import os
import pathlib
import shutil
import subprocess
import sys

import numpy as np
import pytest

import aureole

# Its module fixtures run once: on one worker under pytest-xdist.
pytestmark = pytest.mark.xdist_group("blender")

HERE = pathlib.Path(__file__).resolve().parent
ROOT = HERE.parents[2]
REC709 = np.array([0.2126, 0.7152, 0.0722])
# The lamp's emission strength in the scene, and the add-on's default
# luminance of one unit of Blender's radiance.
LAMP = 100.0
UNIT_CD_M2 = 683.0


@pytest.fixture(scope="module")
def cli():
    """The `aureole` binary whose bytes the add-on's are compared with:
    AUREOLE_BIN (as scripts/test sets it), else the workspace's release
    build."""
    binary = pathlib.Path(os.environ.get("AUREOLE_BIN")
                          or ROOT / "target" / "release" / "aureole")
    if not binary.is_file():
        pytest.fail("no aureole binary: cargo build --release -p aureole-cli, or set AUREOLE_BIN")
    return str(binary)


def wheel():
    """The aureole wheel scripts/test builds (AUREOLE_WHEEL, else
    target/wheels)."""
    if os.environ.get("AUREOLE_WHEEL"):
        return pathlib.Path(os.environ["AUREOLE_WHEEL"])
    found = sorted((ROOT / "target" / "wheels").glob("aureole-*.whl"))
    return found[-1] if found else None


def blender(kind):
    """How to run a script in a Blender, and which zip it installs."""
    if kind == "legacy":
        found = shutil.which("blender")
        if found is None:
            pytest.skip("Blender is not installed (Debian: apt-get install blender python3-numpy)")
        return [found, "-b", "--factory-startup", "--python-exit-code", "1", "-P"]
    python = pathlib.Path(os.environ.get("AUREOLE_BPY_PYTHON")
                          or ROOT / "target" / "bpyvenv" / "bin" / "python")
    if not python.is_file():
        pytest.skip("no Blender 4.2+ module: python3 -m venv target/bpyvenv && "
                    "target/bpyvenv/bin/pip install 'bpy>=4.5,<4.6'")
    return [str(python)]


@pytest.fixture(scope="module", params=["legacy", "extension"])
def addon(request, tmp_path_factory):
    """A Blender, and the add-on zip it installs, packed with the wheel."""
    command = blender(request.param)
    built = wheel()
    if built is None:
        pytest.skip("no aureole wheel: pip wheel --no-deps -w target/wheels ./crates/aureole-py")
    folder = tmp_path_factory.mktemp("addon")
    subprocess.run([sys.executable, HERE.parent / "package.py", "--wheel", built,
                    "--out", folder], check=True, capture_output=True)
    return command, next(folder.glob(f"*-{request.param}.zip"))


def in_blender(addon, folder, script, *args):
    """Runs `script` in a headless Blender with the add-on installed in
    folders of the test's own."""
    command, zip_path = addon
    env = dict(os.environ, BLENDER_USER_SCRIPTS=str(folder / "scripts"),
               BLENDER_USER_RESOURCES=str(folder / "resources"))
    done = subprocess.run([*command, HERE / script, "--", zip_path, *args],
                          capture_output=True, text=True, env=env, timeout=600)
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    return done.stdout


@pytest.fixture(scope="module")
def rendered(addon, tmp_path_factory):
    folder = tmp_path_factory.mktemp("blender")
    return folder / "out", in_blender(addon, folder, "blender_scene.py", folder / "out")


def test_the_camera_is_read_as_blender_frames_it(addon, tmp_path):
    said = in_blender(addon, tmp_path, "blender_lens.py")
    assert "18 sensor fits agree with Blender's frame" in said


def luminance(image):
    return image[..., :3] @ REC709


def centre(source):
    y = luminance(source)
    rows, columns = np.nonzero(y > 0)
    weights = y[rows, columns]
    return (rows * weights).sum() / weights.sum(), (columns * weights).sum() / weights.sum()


def rays(glare, at, radius, samples=2880):
    """The directions (degrees, counter-clockwise from +x, y up) of the
    maxima of the glare's luminance on a circle, where it is over twice
    its median there: the rays crossing that circle."""
    angles = np.linspace(0.0, 2.0 * np.pi, samples, endpoint=False)
    y = at[0] - radius * np.sin(angles)
    x = at[1] + radius * np.cos(angles)
    y0, x0 = np.floor(y).astype(int), np.floor(x).astype(int)
    fy, fx = y - y0, x - x0
    ring = (glare[y0, x0] * (1 - fy) * (1 - fx) + glare[y0 + 1, x0] * fy * (1 - fx)
            + glare[y0, x0 + 1] * (1 - fy) * fx + glare[y0 + 1, x0 + 1] * fy * fx)
    floor = 2.0 * np.median(ring)
    peaks = (ring > np.roll(ring, 1)) & (ring >= np.roll(ring, -1)) & (ring > floor)
    return np.degrees(angles[peaks])


def test_the_lamp_renders_at_its_luminance(rendered):
    out, _ = rendered
    source, meta = aureole.read(out / "render.0001.exr")
    # Blender's multilayer EXR: the add-on spread its Combined pass.
    assert source.shape == (96, 128, 4)
    assert luminance(source).max() == pytest.approx(LAMP, rel=1e-6)


@pytest.mark.parametrize("folder, blades, count", [("aureole", 7, 14), ("six", 6, 6)])
def test_the_blades_give_the_rays(rendered, folder, blades, count):
    out, _ = rendered
    source, _ = aureole.read(out / "render.0001.exr")
    result, _ = aureole.read(out / folder / "render.0001.exr")
    glare = luminance(result) - luminance(source)
    at = centre(source)
    for radius in (16, 24, 32, 40):
        found = rays(glare, at, radius)
        assert len(found) == count, (radius, found)
        # At Blender's rotation 0 a side of Cycles' polygon faces +x, so a
        # ray runs along it; the rest are 360°/count apart.
        steps = found / (360.0 / count)
        assert np.abs(steps - np.round(steps)).max() < 0.06, found


def test_energy_is_kept_but_what_leaves_the_frame(rendered, tmp_path):
    """Nothing is created: the light out is the light in less what the
    kernel sends beyond the frame, pixel by pixel."""
    out, _ = rendered
    source, _ = aureole.read(out / "render.0001.exr")
    result, _ = aureole.read(out / "aureole" / "render.0001.exr")
    height, width = source.shape[:2]
    camera = aureole.Camera.from_toml(equivalent_toml(7))
    kernel = camera.kernel(2 * width - 1, 2 * height - 1, image_width=width).astype(np.float64)
    # Summed-area table: the weight a pixel at (y, x) keeps in the frame is
    # the kernel's sum over the frame shifted by it.
    table = np.pad(kernel.cumsum(0).cumsum(1), ((1, 0), (1, 0), (0, 0)))
    kept = np.zeros((height, width, 3))
    for y in range(height):
        for x in range(width):
            top, left = height - 1 - y, width - 1 - x
            kept[y, x] = (table[top + height, left + width] - table[top, left + width]
                          - table[top + height, left] + table[top, left])
    light_in = source[..., :3].astype(np.float64)
    expected = (light_in * kept).sum((0, 1))
    got = result[..., :3].astype(np.float64).sum((0, 1))
    assert np.all(got <= light_in.sum((0, 1)))
    np.testing.assert_allclose(got, expected, rtol=1e-5)
    assert 1.0 - got.sum() / light_in.sum() > 1e-5  # some light did leave


def equivalent_toml(blades):
    """The scene camera written by hand: the 6 mm sensor spans the 128 px,
    the 50 mm lens at f/8; aureole's stop turned half a blade from Cycles'
    (a side of Cycles' polygon faces +x at rotation 0, a tip of aureole's)."""
    return (f"[camera]\nsensor_width_mm = 6.0\nfocal_length_mm = 50.0\nf_number = 8.0\n"
            f"[[effect]]\ntype = \"aperture\"\nblades = {blades}\n"
            f"rotation_deg = {180.0 / blades!r}\n")


@pytest.mark.parametrize("folder, blades", [("aureole", 7), ("six", 6)])
def test_the_add_on_gives_the_bytes_of_the_cli(rendered, tmp_path, cli, folder, blades):
    out, _ = rendered
    config = tmp_path / "camera.toml"
    config.write_text(equivalent_toml(blades))
    expected = tmp_path / "cli.exr"
    subprocess.run([cli, "-q", "apply", out / "render.0001.exr", "-o", expected,
                    "--config", config, "--threshold", "0", "--input-scale", str(UNIT_CD_M2),
                    "--device", "cpu"], check=True)
    assert (out / folder / "render.0001.exr").read_bytes() == expected.read_bytes()


def test_the_lens_ghosts_chosen_in_the_panel_give_the_bytes_of_the_cli(rendered, tmp_path, cli):
    out, _ = rendered
    config = tmp_path / "camera.toml"
    config.write_text(equivalent_toml(6)
                      + '[[effect]]\ntype = "ghosts"\nlens = "double-gauss-50mm-f1.4"\n')
    expected = tmp_path / "cli.exr"
    subprocess.run([cli, "-q", "apply", out / "render.0001.exr", "-o", expected,
                    "--config", config, "--threshold", "0", "--input-scale", str(UNIT_CD_M2),
                    "--device", "cpu", "--layers"], check=True)
    assert (out / "ghosts" / "render.0001.exr").read_bytes() == expected.read_bytes()
    ghosts, _ = aureole.read(expected, layer="ViewLayer.glare.ghosts")
    assert ghosts.max() > 0


def test_the_other_passes_are_kept(rendered):
    out, _ = rendered
    openexr = pytest.importorskip("OpenEXR")
    before = openexr.File(str(out / "render.0001.exr")).channels()
    after = openexr.File(str(out / "aureole" / "render.0001.exr")).channels()
    assert sorted(after) == sorted(before)
    assert "ViewLayer.Depth.Z" in after
    np.testing.assert_array_equal(after["ViewLayer.Depth.Z"].pixels,
                                  before["ViewLayer.Depth.Z"].pixels)
    assert not np.array_equal(after["ViewLayer.Combined"].pixels,
                              before["ViewLayer.Combined"].pixels)


def test_each_render_is_applied_once(rendered):
    """The animation's frame, the still after its render, the still from the
    Render Result, the written frame again: four results, no more."""
    _, said = rendered
    written = [line.split()[2] for line in said.splitlines() if line.startswith("aureole: wrote")]
    assert [pathlib.Path(p.rstrip(":")).parent.name for p in written] == [
        "aureole", "after-still", "still", "six", "ghosts"], said[-3000:]


@pytest.mark.parametrize("folder", ["after-still", "still"])
def test_a_still_is_applied_from_the_render_result(rendered, folder):
    """F12 with Apply after rendering, or then Apply to Render Result: the
    still's result is the written frame's (Cycles renders the same pixels
    with the same seed)."""
    out, _ = rendered
    still, _ = aureole.read(out / folder / "render.0001.exr")
    frame, _ = aureole.read(out / "aureole" / "render.0001.exr")
    np.testing.assert_array_equal(still, frame)
