"""OpenEXR's luminance/chroma samples (Y at full resolution, RY and BY at
2x2), read by aureole as RGB, against the same files decoded by the
OpenEXR Python package: the luminance of aureole's RGB is the file's Y,
and its chroma at every chroma sample is the file's RY and BY. (The RGB
itself is checked sample for sample against OpenEXR's C++ RGBA reader in
crates/aureole-io/tests/luminance_chroma.rs.)"""

import pathlib

import numpy as np
import pytest

import aureole

OpenEXR = pytest.importorskip("OpenEXR")

IMAGES = pathlib.Path(__file__).resolve().parents[3].parent / "shared/data/openexr-images"
FILES = [
    "LuminanceChroma/CrissyField.exr",
    "LuminanceChroma/Flowers.exr",
    "LuminanceChroma/MtTamNorth.exr",
    "LuminanceChroma/StarField.exr",
    "Chromaticities/Rec709_YC.exr",
    "Chromaticities/XYZ_YC.exr",
]


def luminance_weights(header):
    """OpenEXR's computeYw: the Y row of RGB to XYZ for the file's
    chromaticities (Rec.709 without them), over its sum."""
    c = header.get("chromaticities")
    r, g, b, w = (np.array(c[i:i + 2], float) for i in range(0, 8, 2)) if c is not None else (
        np.array(p) for p in ((0.64, 0.33), (0.30, 0.60), (0.15, 0.06), (0.3127, 0.3290)))
    xyz = lambda p: np.array([p[0], p[1], 1 - p[0] - p[1]])
    primaries = np.stack([xyz(r), xyz(g), xyz(b)], axis=1)
    white = xyz(w) / w[1]
    scale = np.linalg.lstsq(primaries, white, rcond=None)[0]
    row = primaries[1] * scale
    return row / row.sum()


@pytest.mark.parametrize("name", FILES)
def test_luminance_chroma_files_match_openexrs_decoding(name):
    path = IMAGES / name
    if not path.is_file():
        pytest.skip(f"{path} is absent")
    with OpenEXR.File(str(path), separate_channels=True) as f:
        channels = f.channels()
        y = channels["Y"].pixels.astype(np.float64)
        ry = channels["RY"].pixels.astype(np.float64)
        by = channels["BY"].pixels.astype(np.float64)
        weights = luminance_weights(f.header())
    image, meta = aureole.read(str(path))
    assert image.shape == (*y.shape, 3)
    assert any("luminance/chroma" in n for n in meta["notes"])
    rgb = image.astype(np.float64)
    ours = rgb @ weights
    lit = y > 1e-3
    # Half floats and OpenEXR's desaturation of the most saturated
    # pixels keep luminance to a few parts in a thousand.
    relative = np.abs(ours[lit] - y[lit]) / y[lit]
    assert np.percentile(relative, 99.9) < 5e-3, np.percentile(relative, 99.9)
    # The chroma samples sit on the even pixels of the even lines.
    sites = (slice(0, None, 2), slice(0, None, 2))
    ys = y[sites]
    keep = ys > 1e-3
    for ours_c, theirs in ((rgb[sites][..., 0], ry), (rgb[sites][..., 2], by)):
        chroma = (ours_c[keep] - ys[keep]) / ys[keep]
        close = np.abs(chroma - theirs[keep]) <= 5e-3 * (1 + np.abs(theirs[keep]))
        assert close.mean() > 0.99, close.mean()
