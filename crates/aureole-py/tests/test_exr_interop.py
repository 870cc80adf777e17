"""EXR both ways against a reader and a writer we did not write: the
OpenEXR package (the reference library's own Python binding) reads the
files aureole writes and must find the values aureole was given, and
aureole reads the files OpenEXR writes and must find the values OpenEXR
was given, bit for bit, in every lossless compression, in half and in
float."""

import numpy as np
import pytest

import aureole

OpenEXR = pytest.importorskip("OpenEXR")

# Lossless for both sample types; PXR24 only for half (it rounds float
# to 24 bits).
LOSSLESS = {
    "none": OpenEXR.NO_COMPRESSION,
    "rle": OpenEXR.RLE_COMPRESSION,
    "zips": OpenEXR.ZIPS_COMPRESSION,
    "zip": OpenEXR.ZIP_COMPRESSION,
    "piz": OpenEXR.PIZ_COMPRESSION,
}
CASES = [(name, half) for name in LOSSLESS for half in (False, True)] + [("pxr24", True)]


def scene(half):
    """333x77 RGB over nine decades, negatives, zeros and flat runs (which
    RLE and PIZ treat apart), within the half range when half."""
    rng = np.random.default_rng(5)
    image = (10.0 ** rng.uniform(-5, 4, (77, 333, 3))).astype(np.float32)
    image[rng.random((77, 333, 3)) < 0.09] *= -1
    image[10:20, :, :] = 0.25
    image[30, 40:90, 1] = 0.0
    if half:
        image = np.clip(image, -65504, 65504).astype(np.float16).astype(np.float32)
    return image


@pytest.mark.parametrize("compression,half", CASES)
def test_openexr_reads_what_aureole_wrote(tmp_path, compression, half):
    image = scene(half)
    path = tmp_path / "ours.exr"
    aureole.write(str(path), image, half=half, compression=compression)
    with OpenEXR.File(str(path), separate_channels=True) as f:
        assert f.header()["compression"] == (
            OpenEXR.PXR24_COMPRESSION if compression == "pxr24" else LOSSLESS[compression])
        channels = f.channels()
        theirs = np.stack([channels[c].pixels for c in "RGB"], axis=-1)
    assert theirs.dtype == (np.float16 if half else np.float32)
    found = theirs.astype(np.float32)
    assert np.array_equal(found.view(np.uint32), image.view(np.uint32)), (
        f"{compression}: {np.count_nonzero(found != image)} samples differ")


@pytest.mark.parametrize("compression,half", CASES)
def test_aureole_reads_what_openexr_wrote(tmp_path, compression, half):
    image = scene(half)
    kind = np.float16 if half else np.float32
    code = OpenEXR.PXR24_COMPRESSION if compression == "pxr24" else LOSSLESS[compression]
    path = tmp_path / "theirs.exr"
    header = {"compression": code, "type": OpenEXR.scanlineimage}
    channels = {c: np.ascontiguousarray(image[..., i].astype(kind)) for i, c in enumerate("RGB")}
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))
    ours, meta = aureole.read(str(path))
    assert ours.shape == image.shape
    assert np.array_equal(ours.astype(np.float32).view(np.uint32), image.view(np.uint32)), (
        f"{compression}: {np.count_nonzero(ours != image)} samples differ")
