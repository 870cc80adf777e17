"""Physically based camera bloom, corona and glare for HDR images.

Images are numpy arrays of luminance (cd/m² × 1/input_scale): (H, W) or
(H, W, 1) for luminance, (H, W, 3) for RGB, (H, W, 4) for RGB with alpha
(carried through), of float16, float32 or float64. A C-contiguous float32
array is read without a conversion copy. Results are float32.

    camera = aureole.Camera.preset("camera-f8-7blade")
    out = camera.apply(image, threshold=500.0)

Everything computes with the GIL released; Ctrl-C (KeyboardInterrupt)
stops a long call within a second. Bad parameters raise ValueError with the
library's one-line message, unreadable files OSError.
"""

from ._aureole import Camera, __version__, glare, lenses, presets, read, render, write

__all__ = ["Camera", "glare", "lenses", "presets", "read", "write", "render", "__version__"]
