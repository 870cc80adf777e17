//! The spread function f of an effect as the kernel rasteriser sees it: a
//! density in pixel coordinates, and how finely to sample it over a pixel.

use super::whole::{Whole, Window};

/// The spread function f of an effect, in pixel coordinates.
pub(crate) trait SpreadShape: Sync {
    /// f at (x, y) pixels from the centre, y up, up to a constant factor.
    fn density(&self, x: f64, y: f64) -> f64;

    /// The light of f that a kernel's `window` does not hold, with the
    /// constant factor of [`SpreadShape::density`]: its integral over the
    /// whole plane or, for a shape that leaves its centre pixel out
    /// ([`SpreadShape::spreads_centre`]), over the plane outside the
    /// window. The kernel is normalised by it (docs/physics.md §2).
    fn whole(&self, window: &Window) -> Whole;

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
    /// be computed and mirrored: every radial shape is.
    fn mirror_symmetric(&self) -> bool {
        self.radial()
    }

    /// Whether f, its grid and its dark test depend on the distance from
    /// the centre alone, so that the pixels of a kernel away from the
    /// centre are read from tables of that distance (`kernel::radial`).
    fn radial(&self) -> bool {
        false
    }

    /// What the rasteriser needs of the pixel (or unit square) centred at
    /// (x, y), in one call: whether the kernel holds 0 there, f being 0 or
    /// below the shape's own bound of what it drops (the corona's 10⁻¹² of
    /// its brightest ray) over all of it (only a cheap, conservative test:
    /// `Dark` must be true), else its
    /// grid, and where that grid is a single point f there. A shape whose
    /// test, grid and density share work (a direction, the nearest ray)
    /// computes it once here; the grid and f must be those of `grid` and
    /// `density`.
    fn sample(&self, x: f64, y: f64) -> Sample {
        if x * x + y * y > self.one_point_squared() {
            return Sample::One(self.density(x, y));
        }
        let grid = self.grid(x, y);
        if grid.x <= 1 && grid.y <= 1 {
            Sample::One(self.density(x, y))
        } else {
            Sample::Grid(grid)
        }
    }

    /// The squared distance from the centre beyond which every pixel's
    /// grid is one point, so that [`SpreadShape::sample`] does not ask for
    /// it: most of a full-frame kernel of a smooth shape. Infinite (the
    /// default): nowhere.
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

    /// f at the points (`xs[i]`, `ys[i]`), into `out`:
    /// [`SpreadShape::density`]'s values to the bit, computed stage by
    /// stage over the points by a shape whose f is a long chain (a pixel's
    /// grid of midpoints, a chunk at a time).
    fn density_at(&self, xs: &[f64], ys: &[f64], out: &mut [f64]) {
        for ((f, &x), &y) in out.iter_mut().zip(xs).zip(ys) {
            *f = self.density(x, y);
        }
    }

    /// On the row of pixels centred at height y: ranges of x (pixel
    /// centres, inclusive) outside which every pixel is `Dark`,
    /// or `None` where any pixel may be lit. Like [`SpreadShape::sample`]'s
    /// `Dark`, a conservative, cheap answer.
    fn lit_spans(&self, _y: f64) -> Option<Vec<(f64, f64)>> {
        None
    }
}

/// Points a shape's [`SpreadShape::density_at`] takes in one pass.
pub(crate) const CHUNK_POINTS: usize = 64;

/// `pass(xs, ys, out)` over the points a chunk of at most
/// [`CHUNK_POINTS`] at a time: what a shape's `density_at` computes its
/// stages over.
pub(crate) fn in_chunks(
    xs: &[f64],
    ys: &[f64],
    out: &mut [f64],
    mut pass: impl FnMut(&[f64], &[f64], &mut [f64]),
) {
    for ((xs, ys), out) in xs
        .chunks(CHUNK_POINTS)
        .zip(ys.chunks(CHUNK_POINTS))
        .zip(out.chunks_mut(CHUNK_POINTS))
    {
        pass(xs, ys, out);
    }
}

/// [`SpreadShape::sample`]'s answer for one pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Sample {
    /// The kernel holds 0: f is 0, or below the shape's bound of what it
    /// drops, over the pixel.
    Dark,
    /// One point is enough: f at the pixel's centre.
    One(f64),
    /// f is averaged over this grid.
    Grid(Supersampling),
}

/// The largest |f''/f| in px⁻² that one point per pixel keeps near 10⁻³.
const ONE_POINT_CURVATURE: f64 = 0.024;

/// For a radial f whose curvature at distance r is at most c/(a + r²),
/// taken at a pixel's nearest point (√2/2 px nearer the centre): the
/// squared distance beyond which [`Supersampling::for_curvature`] gives
/// one point, with a pixel to spare.
pub(crate) fn one_point_beyond(c: f64, a: f64) -> f64 {
    let flat = (c / ONE_POINT_CURVATURE - a).max(0.0).sqrt();
    let r = flat + std::f64::consts::FRAC_1_SQRT_2 + 1.0;
    r * r
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
        let m = (relative_curvature / ONE_POINT_CURVATURE).sqrt().ceil();
        Supersampling::square(if m.is_finite() {
            (m as u32).clamp(1, max)
        } else {
            max
        })
    }
}

/// Each row of `rows` (x₀, y, n: the points (x₀ + i, y), i < n) through
/// [`SpreadShape::sample_row`]: every point is what [`SpreadShape::sample`]
/// says of it alone, its grid is [`SpreadShape::grid`]'s, and where that is
/// one point, f is [`SpreadShape::density`]'s to the bit; `dark` checks
/// each point called dark; and [`SpreadShape::density_at`] over the row
/// and over points a fraction of a pixel apart, on it and beside it, gives
/// `density`'s values to the bit. How many were one point, a grid, dark.
#[cfg(test)]
pub(crate) fn assert_rows_agree(
    shape: &dyn SpreadShape,
    rows: impl Iterator<Item = (f64, f64, usize)>,
    mut dark: impl FnMut(f64, f64),
) -> [usize; 3] {
    let mut counts = [0; 3];
    for (x0, y, n) in rows {
        // The row's pixel centres, then points 1/7 px apart over as many
        // pixels as a grid row covers (more than one chunk of them).
        for step in [1.0, 1.0 / 7.0] {
            let xs: Vec<f64> = (0..n.max(70)).map(|i| x0 + i as f64 * step).collect();
            let ys: Vec<f64> = (0..xs.len()).map(|i| y + (i % 3) as f64 * step).collect();
            let mut f = vec![f64::NAN; xs.len()];
            shape.density_at(&xs, &ys, &mut f);
            for ((&x, &y), &f) in xs.iter().zip(&ys).zip(&f) {
                assert_eq!(f.to_bits(), shape.density(x, y).to_bits(), "({x}, {y})");
            }
        }
        let mut row = vec![Sample::Dark; n];
        shape.sample_row(x0, y, &mut row);
        for (i, sample) in row.into_iter().enumerate() {
            let x = x0 + i as f64;
            assert_eq!(sample, shape.sample(x, y), "({x}, {y})");
            match sample {
                Sample::One(f) => {
                    counts[0] += 1;
                    assert_eq!(shape.grid(x, y), Supersampling::square(1), "({x}, {y})");
                    assert_eq!(f, shape.density(x, y), "({x}, {y})");
                }
                Sample::Grid(g) => {
                    counts[1] += 1;
                    assert_eq!(g, shape.grid(x, y), "({x}, {y})");
                }
                Sample::Dark => {
                    counts[2] += 1;
                    dark(x, y);
                }
            }
        }
    }
    counts
}
