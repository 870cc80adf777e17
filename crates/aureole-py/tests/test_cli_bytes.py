"""camera.apply on an array gives the command line's bytes, for a bloom, a
corona and a spectral aperture, with and without a threshold."""

import subprocess

import numpy as np
import pytest

import aureole

from conftest import ROOT, run

CAMERAS = ["paper-fig4-bloom", "paper-fig5-corona", "camera-f8-7blade"]


@pytest.mark.parametrize("preset", CAMERAS)
@pytest.mark.parametrize("threshold", [None, 300.0])
def test_apply_on_an_array_equals_aureole_apply_on_the_file(cli, street, tmp_path, preset, threshold):
    _, pfm = street
    out = tmp_path / "out.pfm"
    args = ["apply", pfm, "-o", out, "--preset", preset]
    if threshold is not None:
        args += ["--threshold", threshold]
    run(cli, *args)
    expected, _ = aureole.read(out)

    image, meta = aureole.read(pfm)
    got = aureole.Camera.preset(preset).apply(image, threshold=threshold, input_scale=meta["scale"])
    assert got.dtype == expected.dtype and got.shape == expected.shape
    assert got.tobytes() == expected.tobytes()


@pytest.mark.parametrize("preset", CAMERAS)
def test_apply_file_writes_the_command_lines_exr_byte_for_byte(cli, street, tmp_path, preset):
    exr, _ = street
    run(cli, "apply", exr, "-o", tmp_path / "cli.exr", "--preset", preset, "--threshold", "300")
    report = aureole.Camera.preset(preset).apply_file(exr, tmp_path / "py.exr", threshold=300.0)
    assert (tmp_path / "py.exr").read_bytes() == (tmp_path / "cli.exr").read_bytes()
    assert report["energy_out"] <= report["energy_in"] * (1 + 1e-6)
    assert report["threshold"] == 300.0


STEREO = ROOT.parent / "shared/data/openexr-images/Beachball/multipart.0001.exr"


@pytest.mark.skipif(not STEREO.is_file(), reason="OpenEXR's sample set is absent")
def test_apply_file_puts_both_eyes_of_a_stereo_plate_through_the_camera(cli, tmp_path):
    run(cli, "apply", STEREO, "-o", tmp_path / "cli.exr", "--preset", "paper-fig4-bloom",
        "--threshold", "0.3")
    report = aureole.Camera.preset("paper-fig4-bloom").apply_file(
        STEREO, tmp_path / "py.exr", threshold=0.3)
    assert any("every view goes through the camera" in n for n in report["notes"])
    assert (tmp_path / "py.exr").read_bytes() == (tmp_path / "cli.exr").read_bytes()


def test_apply_file_refuses_to_overwrite_its_input(street, tmp_path):
    exr, _ = street
    copy = tmp_path / "in.exr"
    copy.write_bytes(exr.read_bytes())
    with pytest.raises(ValueError, match="overwrite the input"):
        aureole.Camera.preset("paper-fig4-bloom").apply_file(copy, copy)
    assert copy.read_bytes() == exr.read_bytes()


def test_the_camera_toml_drives_the_cli_to_the_same_bytes(cli, street, tmp_path):
    _, pfm = street
    camera = aureole.Camera.compose(aureole.Camera.preset("paper-fig4-bloom"),
                                    aureole.Camera.preset("star-filter-6pt"))
    config = tmp_path / "camera.toml"
    config.write_text(camera.toml())
    run(cli, "apply", pfm, "-o", tmp_path / "out.pfm", "--config", config)
    image, _ = aureole.read(pfm)
    assert camera.apply(image).tobytes() == aureole.read(tmp_path / "out.pfm")[0].tobytes()


def test_glare_layers_sum_to_the_glare_and_match_the_command_line(cli, street, tmp_path):
    exr, pfm = street
    camera = aureole.Camera.preset("paper-fig5-both")
    image, meta = aureole.read(pfm)
    result, layers = camera.apply(image, input_scale=meta["scale"], layers=True)
    assert list(layers) == ["glare.bloom", "glare.corona", "glare"]
    assert result.tobytes() == camera.apply(image, input_scale=meta["scale"]).tobytes()
    peak = float(image.max())
    np.testing.assert_allclose(layers["glare"], result - image, rtol=0, atol=1e-6 * peak)
    np.testing.assert_allclose(
        layers["glare.bloom"] + layers["glare.corona"], layers["glare"], rtol=0, atol=1e-6 * peak
    )
    # The file: the same bytes as aureole apply --layers.
    run(cli, "apply", exr, "-o", tmp_path / "cli.exr", "--preset", "paper-fig5-both", "--layers")
    camera.apply_file(exr, tmp_path / "py.exr", layers=True)
    assert (tmp_path / "py.exr").read_bytes() == (tmp_path / "cli.exr").read_bytes()
    with pytest.raises(ValueError, match="glare layers are written only into OpenEXR"):
        camera.apply_file(exr, tmp_path / "py.png", layers=True)
    assert not (tmp_path / "py.png").exists()
    with pytest.raises(ValueError, match="ask for the layers or for the glare alone"):
        camera.apply(image, layers=True, glare_only=True)


FISHEYE_EYE = """
[camera]
projection = "equidistant"
field_of_view_deg = 180

[[effect]]
type = "eye"
age = 70
pigmentation = 1.0
"""


def test_the_eye_over_a_fisheye_is_the_command_lines(cli, street, tmp_path):
    """A wide view's eye, spread over the sphere, gives the same bytes
    from Python as from the command line."""
    _, pfm = street
    config = tmp_path / "fisheye.toml"
    config.write_text(FISHEYE_EYE)
    out = tmp_path / "out.pfm"
    run(cli, "apply", pfm, "-o", out, "--config", config, "--threshold", "300")
    expected, _ = aureole.read(out)
    image, meta = aureole.read(pfm)
    got = aureole.Camera.from_toml(FISHEYE_EYE).apply(image, threshold=300.0, input_scale=meta["scale"])
    assert got.tobytes() == expected.tobytes()
