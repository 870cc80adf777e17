//! What the f32 engine holds, for the memory estimate, known before it is
//! built.

use crate::convolve::grid::Grid;
use crate::convolve::{Footprint, Load};

/// Bytes of a complex f32.
const COMPLEX: u64 = 8;

/// Rows of a near window held as row spectra, at most (a radius of 128).
const WINDOW_ROWS: u64 = 257;

/// What the engine holds: transforming, the kernel's
/// spectrum and its rows' spectra; spreading, the spectrum (split for
/// lamps: the far spectrum and the window's row spectra) and every plane's
/// row spectra.
pub(in crate::convolve) fn footprint(load: &Load) -> Footprint {
    let grid = Grid::new(load.kernel, load.image, true);
    let (half, py) = (grid.spectrum_width() as u64, grid.padded().1 as u64);
    let kernel_planes = load.kernel_planes as u64;
    let spectrum = half * py * COMPLEX * kernel_planes;
    let window = if load.split {
        WINDOW_ROWS.min(py) * half * COMPLEX * kernel_planes
    } else {
        0
    };
    let rows = half * load.image.1 as u64 * COMPLEX * load.planes as u64;
    Footprint {
        preparing: spectrum + half * load.kernel.1 as u64 * COMPLEX,
        spreading: spectrum + window + rows,
    }
}

/// What [`super::compose`] holds beside its plane and result: the
/// spectrum of the kernel (`size`) at the plane's size, and the plane's
/// row spectra.
pub(in crate::convolve) fn compose_bytes(size: (usize, usize), plane: (usize, usize)) -> u64 {
    let grid = Grid::new(size, plane, true);
    let (half, py) = (grid.spectrum_width() as u64, grid.padded().1 as u64);
    half * (py + 2 * size.1 as u64) * COMPLEX
}
