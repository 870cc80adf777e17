"""Type stubs of the aureole package (its functions live in the compiled
`aureole._aureole` module)."""

from collections.abc import Callable
from os import PathLike
from typing import Any, Literal, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str

ImageLike = npt.ArrayLike
Progress = Callable[[str, float], Any]
Exposure = Union[float, Literal["auto"]]
ToneCurve = Literal["filmic", "reinhard", "clip"]
Path = Union[str, PathLike[str]]

def presets() -> list[tuple[str, str]]:
    """The built-in presets: (name, one-line description) pairs."""

def lenses() -> list[tuple[str, str]]:
    """The shipped lenses a config's ghosts name (`lens = "..."`): (name,
    what the lens is) pairs."""

class Camera:
    """A camera: the optical chain of presets and config files composed in
    order (later settings replace earlier ones, effects are appended)."""

    @staticmethod
    def preset(name: str) -> Camera:
        """A built-in preset by name (`presets()` lists them)."""
    @staticmethod
    def from_toml(text: str, name: str = "<string>") -> Camera:
        """A camera from TOML text, as in a config file; `name` starts its
        error messages."""
    @staticmethod
    def from_file(path: Path) -> Camera:
        """A camera from a TOML config file."""
    @staticmethod
    def compose(*cameras: Camera) -> Camera:
        """The cameras composed in order."""
    def toml(self) -> str:
        """The camera as TOML: `aureole apply --config` with it gives the
        same picture."""
    @property
    def threshold(self) -> float:
        """The camera's threshold in cd/m²: pixels at or below it stay."""
    @property
    def seed(self) -> int:
        """The seed of the random ray lengths."""
    def kernel(
        self,
        width: int,
        height: int,
        image_width: Optional[int] = None,
        progress: Optional[Progress] = None,
        sent_by: Literal["pixel", "point"] = "pixel",
        device: Literal["auto", "cpu", "gpu"] = "auto",
    ) -> npt.NDArray[np.float32]:
        """The kernel (PSF) of the chain, float32 (H, W) or (H, W, 3),
        each channel holding the share of its PSF's light within it (at
        most 1), its centre at (height // 2, width // 2).
        `image_width` sets the pixel pitch (sensor width / image width).
        `sent_by`: "pixel", the kernel an image is convolved with (each
        pixel's light leaves its whole square), or "point", the PSF of a
        point of light as an optics program gives it. `device`: where the
        effects convolve one another, as for `apply`."""
    def pupil(
        self, x: npt.NDArray[np.float64], y: npt.NDArray[np.float64]
    ) -> npt.NDArray[np.complex128]:
        """What the first aperture's pupil transmits at (x, y), mm from its
        centre: 1 on clear glass, 0 on the stop, dust and scratches, the
        smudge's amplitude under grease; the dirt drawn from the seed."""
    def apply(
        self,
        image: ImageLike,
        threshold: Optional[float] = None,
        knee: float = 0.0,
        input_scale: float = 1.0,
        glare_only: bool = False,
        method: Literal["auto", "fft", "splat"] = "auto",
        progress: Optional[Progress] = None,
        layers: bool = False,
        device: Literal["auto", "cpu", "gpu"] = "auto",
    ) -> Any:
        """The image the camera records: a new float32 array of the same
        shape, alpha carried through. Frames of one size reuse the kernel.
        With `layers=True`, (result, layers): a dict of the light each
        effect adds ("glare.bloom", …) and the total ("glare"), which they
        sum to, each of the image's shape without alpha. `device`: "auto"
        convolves on a hardware GPU when there is one, "gpu" insists (a
        software adapter too; ValueError without one), "cpu" never looks."""

    def apply_file(
        self,
        input: Path,
        output: Path,
        threshold: Optional[float] = None,
        knee: float = 0.0,
        input_scale: Optional[float] = None,
        glare_only: bool = False,
        method: Literal["auto", "fft", "splat"] = "auto",
        half: Optional[bool] = None,
        compression: Optional[str] = None,
        layer: Optional[str] = None,
        part: Optional[str] = None,
        progress: Optional[Progress] = None,
        layers: bool = False,
        device: Literal["auto", "cpu", "gpu"] = "auto",
    ) -> dict[str, Any]:
        """`aureole apply INPUT -o OUTPUT` with this camera, the same bytes:
        an EXR result keeps the input's layers, parts and attributes, and
        with `layers=True` holds the glare of each effect beside it
        (`aureole apply --layers`). Returns energy_in, energy_out,
        spread_pixels, threshold, scale, notes and ghosts (None, or the
        lens ghosts' found and traced sources, paths, f_number and light:
        their share of the traced sources' light)."""

def read(
    path: Path, layer: Optional[str] = None, part: Optional[str] = None
) -> tuple[npt.NDArray[np.float32], dict[str, Any]]:
    """An HDR image file as a float32 array in the file's units, and its
    metadata: scale, whiteLuminance, chromaticities, layout, format,
    display_referred, notes."""

def write(
    path: Path,
    image: ImageLike,
    half: bool = False,
    compression: Optional[str] = None,
    metadata: Optional[dict[str, Any]] = None,
    exposure: Optional[Exposure] = None,
    tonemap: ToneCurve = "filmic",
) -> list[str]:
    """Writes `image` atomically in the format the extension names; returns
    what the format could not keep."""

def render(
    image: ImageLike,
    exposure: Optional[Exposure] = None,
    tonemap: ToneCurve = "filmic",
    scale: float = 1.0,
) -> npt.NDArray[np.uint8]:
    """`image` as uint8 sRGB (H, W, 3) for a display."""

def glare(
    source: Union[ImageLike, Path],
    *,
    view: Optional[str] = None,
    projection: Optional[str] = None,
    fov: Optional[float] = None,
    fov_vertical: Optional[float] = None,
    input_scale: Optional[float] = None,
    threshold: Optional[float] = None,
    multiple: Optional[float] = None,
    task: Optional[tuple[float, float, float]] = None,
    search: float = 0.2,
    peak: Optional[float] = 50000.0,
    layer: Optional[str] = None,
    part: Optional[str] = None,
) -> dict[str, Any]:
    """The glare figures of a view as `evalglare` defines them (E_v,
    DGP, DGI, UGR, VCP, CGI, background luminance and the glare sources),
    the dict `aureole glare --json` prints. `source` is a picture file
    (a Radiance picture's VIEW header gives its view) or a luminance array
    with `view` (Radiance's options) or `projection` and `fov`."""
