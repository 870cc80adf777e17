//! Which way of spreading is faster for an image: the FFT's cost does not
//! depend on how many pixels are bright, splatting's grows with them.
//! Fitted to runs at 4K with full-frame and 401×401 kernels on two cores
//! (`cargo run --release -p aureole-tools --bin crossover`).

use super::options::Method;
use super::threshold::Survey;
use crate::image::Layout;

/// What each way of spreading an image would take, nanoseconds.
#[derive(Debug, Clone, Copy)]
pub(super) struct Estimate {
    /// Adding the kernel at each bright pixel.
    pub splat: f64,
    /// Convolving by FFT.
    pub fft: f64,
    /// The convolutions either way: one per image plane, or per kernel
    /// plane for a luminance image.
    pub convolutions: usize,
}

impl Estimate {
    /// The estimate for an image of `size` and `layout` whose bright
    /// pixels `survey` found, through a kernel of `kernel` pixels (width,
    /// height) and `kernel_planes` planes on a `padded` FFT grid.
    pub fn of(
        survey: &Survey,
        (size, layout): ((usize, usize), Layout),
        (kernel, kernel_planes): ((usize, usize), usize),
        padded: (usize, usize),
    ) -> Estimate {
        // An RGB image takes a convolution per plane; a luminance image one
        // per kernel plane (a coloured kernel weighs its planes into Y).
        let convolutions = match layout {
            Layout::Rgb => 3,
            Layout::Luminance => kernel_planes,
        };
        Estimate {
            splat: splat(
                kernel.0 * kernel.1,
                survey.splat_area,
                survey.splat_rows,
                size,
                convolutions,
            ),
            fft: fft(padded, size, convolutions),
            convolutions,
        }
    }

    /// The method `asked` for: `Auto` takes the cheaper.
    pub fn choose(&self, asked: Method) -> Method {
        match asked {
            Method::Auto if self.splat < self.fft => Method::Splat,
            Method::Auto => Method::Fft,
            chosen => chosen,
        }
    }
}

/// Nanoseconds the FFT route takes for `convolutions` planes of
/// `width`×`height` pixels on a `padded` grid: the transforms' n·log₂n
/// count plus the passes over the planes around them.
pub(super) fn fft(
    padded: (usize, usize),
    (width, height): (usize, usize),
    convolutions: usize,
) -> f64 {
    let (px, py) = padded;
    let n_log = |n: usize| n as f64 * libm::log2(n as f64);
    let h = height as f64;
    let columns = (px / 2 + 1) as f64;
    let per_plane = 2.0 * h * n_log(px) + 2.0 * columns * n_log(py);
    let pixels = (width * height) as f64;
    (0.04 * per_plane + 5.0 * pixels) * convolutions as f64
}

/// Nanoseconds splatting takes: every bright pixel adds the part of a
/// `kernel_pixels` kernel that falls inside the frame (`area` output pixels
/// in all, over `rows` visits of an output row to a bright pixel, ~5 ns
/// each: small kernels at many bright pixels are bound by them) to every
/// output plane, after a pass over the planes.
pub(super) fn splat(
    kernel_pixels: usize,
    area: usize,
    rows: usize,
    (width, height): (usize, usize),
    convolutions: usize,
) -> f64 {
    let pixels = (width * height) as f64;
    // Kernel rows that stay in cache between bright pixels add faster.
    let per_add = if kernel_pixels <= 1 << 20 {
        0.055
    } else {
        0.19
    };
    (per_add * area as f64 + 5.0 * rows as f64 + 2.0 * pixels) * convolutions as f64
}

/// How many lamps (pixels whose near light is added directly, a window of
/// (2·`radius` + 1)² pixels each, into `convolutions` planes) fit in
/// `budget` nanoseconds.
pub(super) fn lamps_within(budget: f64, radius: usize, convolutions: usize) -> usize {
    let side = (2 * radius + 1) as f64;
    (budget / (0.1 * side * side * convolutions.max(1) as f64)) as usize
}
