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

    /// What the rasteriser needs of the pixel (or unit square) centred at
    /// (x, y), in one call: whether f vanishes over it, else its grid, and
    /// where that grid is a single point f there. A shape whose test, grid
    /// and density share work (a direction, the nearest ray) computes it
    /// once here; the answer must be the one the three calls would give.
    fn sample(&self, x: f64, y: f64) -> Sample {
        if x * x + y * y > self.one_point_squared() {
            return Sample::One(self.density(x, y));
        }
        if self.vanishes_over_pixel(x, y) {
            return Sample::Dark;
        }
        let grid = self.grid(x, y);
        if grid.x <= 1 && grid.y <= 1 {
            Sample::One(self.density(x, y))
        } else {
            Sample::Grid(grid)
        }
    }

    /// The squared distance from the centre beyond which every pixel's
    /// grid is one point and f never vanishes, so that
    /// [`SpreadShape::sample`] asks for neither: most of a full-frame
    /// kernel of a smooth shape. Infinite (the default): nowhere.
    fn one_point_squared(&self) -> f64 {
        f64::INFINITY
    }

    /// [`SpreadShape::sample`] at the points (x₀ + i, y) for each i of
    /// `out`: a shape whose answer takes long chains of dependent
    /// operations computes them stage by stage over the row, so that the
    /// processor overlaps the points' chains.
    fn sample_row(&self, x0: f64, y: f64, out: &mut [Sample]) {
        for (i, sample) in out.iter_mut().enumerate() {
            *sample = self.sample(x0 + i as f64, y);
        }
    }

    /// On the row of pixels centred at height y: ranges of x (pixel
    /// centres, inclusive) outside which f is exactly 0 over every pixel,
    /// or `None` where any pixel may be lit. Like
    /// [`SpreadShape::vanishes_over_pixel`], a conservative, cheap answer.
    fn lit_spans(&self, _y: f64) -> Option<Vec<(f64, f64)>> {
        None
    }
}

/// [`SpreadShape::sample`]'s answer for one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Sample {
    /// f is exactly 0 over the pixel.
    Dark,
    /// One point is enough: f at the pixel's centre.
    One(f64),
    /// f is averaged over this grid.
    Grid(Supersampling),
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

/// For a shape that lights every pixel: each of `points`' samples is the
/// grid the shape asks for there, and where that is one point, f there to
/// the bit. How many were one point.
#[cfg(test)]
pub(crate) fn assert_samples_agree(
    shape: &dyn SpreadShape,
    points: impl Iterator<Item = (f64, f64)>,
) -> usize {
    let mut ones = 0;
    for (x, y) in points {
        let grid = shape.grid(x, y);
        match shape.sample(x, y) {
            Sample::One(f) => {
                ones += 1;
                assert_eq!(grid, Supersampling::square(1), "({x}, {y})");
                assert_eq!(f, shape.density(x, y), "({x}, {y})");
            }
            Sample::Grid(g) => assert_eq!(g, grid, "({x}, {y})"),
            Sample::Dark => panic!("({x}, {y}) is dark where every pixel is lit"),
        }
    }
    ones
}
