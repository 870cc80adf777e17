//! The spread function f of an effect as the kernel rasteriser sees it: a
//! density in pixel coordinates, and how finely to sample it over a pixel.

/// The spread function f of an effect, in pixel coordinates.
pub(crate) trait SpreadShape: Sync {
    /// f at (x, y) pixels from the centre, y up, up to a constant factor.
    fn density(&self, x: f64, y: f64) -> f64;

    /// The supersampling grid needed to average f over the pixel centred at
    /// (x, y): finer where f changes fast within the pixel, and in the
    /// direction it changes fastest.
    fn grid(&self, x: f64, y: f64) -> Supersampling;

    /// Whether f puts light in the centre pixel. A PSF singular at the
    /// centre leaves the light that moves by less than half a pixel in the
    /// unspread part.
    fn spreads_centre(&self) -> bool {
        true
    }

    /// Whether f(x, y) = f(|x|, |y|), so that a quarter of the kernel can
    /// be computed and mirrored.
    fn mirror_symmetric(&self) -> bool {
        false
    }

    /// Whether f is exactly 0 (in f64) everywhere in the pixel centred at
    /// (x, y), so that its mean is 0 without sampling. Only a cheap,
    /// conservative test belongs here: false is always correct.
    fn vanishes_over_pixel(&self, _x: f64, _y: f64) -> bool {
        false
    }

    /// On the row of pixels centred at height y: ranges of x (pixel
    /// centres, inclusive) outside which f is exactly 0 over every pixel,
    /// or `None` where any pixel may be lit. Like
    /// [`SpreadShape::vanishes_over_pixel`], a conservative, cheap answer.
    fn lit_spans(&self, _y: f64) -> Option<Vec<(f64, f64)>> {
        None
    }
}

/// A supersampling grid: `x` columns by `y` rows of sample points in a
/// pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Supersampling {
    pub x: u32,
    pub y: u32,
}

impl Supersampling {
    /// The same count along both axes.
    pub fn square(m: u32) -> Supersampling {
        Supersampling { x: m, y: m }
    }

    /// Points per axis so that the midpoint rule's relative error, about
    /// (h²/24)·|f''/f| with h = 1/m, stays near 10⁻³ for a curvature
    /// `relative_curvature` = |f''/f| in px⁻², at most `max`.
    pub fn for_curvature(relative_curvature: f64, max: u32) -> Supersampling {
        let m = (relative_curvature / 0.024).sqrt().ceil();
        Supersampling::square(if m.is_finite() {
            (m as u32).clamp(1, max)
        } else {
            max
        })
    }
}
