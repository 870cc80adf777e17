//! Rasterising a spread function: f averaged over the area of the pixel
//! that receives the light and, for a kernel of an image, of the one that
//! sends it (a tent over 2 × 2 px), by the midpoint rule on grids that each
//! shape chooses (finer where f changes within a pixel), then normalised by
//! its light over the whole plane.

use rayon::prelude::*;

use super::{radial, Extent, Sending};
use crate::control::{for_each, for_each_row, Control};
use crate::error::Result;
use crate::image::{sum_f64, zeros};
use crate::optics::shape::{Sample, SpreadShape, Supersampling, CHUNK_POINTS};
use crate::optics::whole::{Whole, Window};

/// Pixels of a row rasterised together where f has no mirror symmetry.
const PIECE: usize = 256;

/// f averaged as `extent.sending` asks, normalised by its light over the
/// whole plane ([`SpreadShape::whole`]) and scaled by `share`, so that ΣF
/// is `share` times the share of the light the extent holds; `None` when
/// f is not finite there. A mirror-symmetric f is computed, summed and
/// scaled on a quarter, then mirrored: the plane itself is written once.
pub(super) fn shape_plane(
    shape: &dyn SpreadShape,
    extent: &Extent,
    share: f64,
    control: &mut Control,
) -> Result<Option<Vec<f32>>> {
    // A shape singular at the centre keeps the sending pixel a point.
    let mut raster = if extent.sending == Sending::Pixel && shape.spreads_centre() {
        tent_plane(shape, extent, control)?
    } else {
        point_plane(shape, extent, control)?
    };
    let within = raster.sum(extent);
    if !within.is_finite() {
        return Ok(None);
    }
    // None of it falls within the extent (Vos's light in a 1-pixel
    // frame): all of it leaves.
    if within == 0.0 {
        return raster.into_plane(extent).map(Some);
    }
    let window = Window::of(extent.width, extent.height);
    let whole = match shape.whole(&window) {
        Whole::Plane(light) => light,
        Whole::Beyond(light) => within + light,
    };
    // The pixel means and the integral differ by the midpoint rule's
    // 10⁻³ at most: a window that holds nearly all the light keeps it
    // all, and never more.
    let scale = share
        / if whole.is_finite() {
            whole.max(within)
        } else {
            within
        };
    raster
        .values()
        .par_iter_mut()
        .for_each(|v| *v = (f64::from(*v) * scale) as f32);
    raster.into_plane(extent).map(Some)
}

/// A shape rasterised: the whole plane, or the quarter of offsets
/// 0..`span` along x and down the rows of a mirror-symmetric one.
enum Raster {
    Plane(Vec<f32>),
    Quarter { values: Vec<f32>, span: usize },
}

impl Raster {
    /// Σ over the extent's plane in f64, the same bits with any number of
    /// threads: a quarter's values count once for each pixel they mirror
    /// into.
    fn sum(&self, extent: &Extent) -> f64 {
        match self {
            Raster::Plane(plane) => plane_sum(plane, extent.width),
            Raster::Quarter { values, span } => {
                let (cx, cy) = extent.centre();
                // Pixels d from the centre along an axis of n: one or two.
                let count = |d: usize, c: usize, n: usize| {
                    f64::from(u8::from(d <= c) + u8::from(d > 0 && c + d < n))
                };
                let rows: Vec<f64> = values
                    .par_chunks(*span)
                    .enumerate()
                    .map(|(dy, row)| {
                        let (inner, outer) = row.split_at(1);
                        let ends = count(dy, cy, extent.height);
                        // The columns on both sides, then those on one.
                        let both = cx.min(extent.width - 1 - cx).min(outer.len());
                        let one = &outer[both..];
                        ends * (f64::from(inner[0]) + 2.0 * sum_f64(&outer[..both]) + sum_f64(one))
                    })
                    .collect();
                rows.iter().sum()
            }
        }
    }

    /// What is scaled: the plane or the quarter.
    fn values(&mut self) -> &mut [f32] {
        match self {
            Raster::Plane(plane) => plane,
            Raster::Quarter { values, .. } => values,
        }
    }

    /// The extent's plane.
    fn into_plane(self, extent: &Extent) -> Result<Vec<f32>> {
        match self {
            Raster::Plane(plane) => Ok(plane),
            Raster::Quarter { values, span } => {
                let mut plane = zeros(extent.width * extent.height)?;
                mirror(&values, span, &mut plane, extent.width, extent.centre());
                Ok(plane)
            }
        }
    }
}

/// f averaged over every receiving pixel, for light sent by a point.
fn point_plane(shape: &dyn SpreadShape, extent: &Extent, control: &mut Control) -> Result<Raster> {
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = extent.centre();
    if shape.mirror_symmetric() {
        // Offsets 0..=reach along each axis cover both sides of the centre.
        let (reach_x, reach_y) = (cx.max(width - 1 - cx), cy.max(height - 1 - cy));
        let exact =
            |dx: usize, dy: usize| pixel_mean(shape, dx as f64, dy as f64, (dx, dy) == (0, 0));
        let quarter = if shape.radial() {
            let value = |x: f64, y: f64| pixel_mean(shape, x, y, false);
            radial::quarter(shape, (reach_x + 1, reach_y + 1), &exact, &value, control)?
        } else {
            let mut quarter = zeros((reach_x + 1) * (reach_y + 1))?;
            for_each_row(&mut quarter, reach_x + 1, control, |dy, row| {
                let spans = shape.lit_spans(dy as f64);
                // Pixels outside the lit spans stay 0.
                for (dx, value) in row.iter_mut().enumerate() {
                    if lit(spans.as_deref(), dx as f64) {
                        *value = exact(dx, dy) as f32;
                    }
                }
            })?;
            quarter
        };
        return Ok(Raster::Quarter {
            values: quarter,
            span: reach_x + 1,
        });
    }
    let mut plane = zeros(width * height)?;
    // Pieces of rows rather than rows: the few rows through the centre,
    // where every ray is sampled finely, would otherwise hold a batch
    // up on one thread.
    let mut pieces: Vec<(usize, usize, &mut [f32])> = plane
        .chunks_mut(width)
        .enumerate()
        .flat_map(|(j, row)| {
            row.chunks_mut(PIECE)
                .enumerate()
                .map(move |(p, piece)| (j, p * PIECE, piece))
        })
        .collect();
    for_each(&mut pieces, control, |_, (j, first, piece)| {
        let (j, first) = (*j, *first);
        let y = cy as f64 - j as f64;
        let spans = shape.lit_spans(y);
        for (i, value) in piece.iter_mut().enumerate() {
            let i = first + i;
            let x = i as f64 - cx as f64;
            // Pixels outside the lit spans stay 0.
            if lit(spans.as_deref(), x) {
                *value = pixel_mean(shape, x, y, (i, j) == (cx, cy)) as f32;
            }
        }
    })?;
    Ok(Raster::Plane(plane))
}

/// Whether x lies in one of a row's lit spans ([`SpreadShape::lit_spans`];
/// `None`: anywhere may be lit).
fn lit(spans: Option<&[(f64, f64)]>, x: f64) -> bool {
    spans.is_none_or(|s| s.iter().any(|&(a, b)| a <= x && x <= b))
}

/// Σ of a plane in f64: row sums in parallel, added in row order, so the
/// same bits with any number of threads.
pub(super) fn plane_sum(plane: &[f32], width: usize) -> f64 {
    let rows: Vec<f64> = plane.par_chunks(width.max(1)).map(sum_f64).collect();
    rows.iter().sum()
}

/// The mean of f over the pixel centred at (x, y) (`centre`: the kernel's
/// centre pixel).
fn pixel_mean(shape: &dyn SpreadShape, x: f64, y: f64, centre: bool) -> f64 {
    if centre {
        if !shape.spreads_centre() {
            return 0.0;
        }
        // An even count keeps sample points off r = 0, where the direction φ
        // is undefined.
        let m = shape.grid(x, y);
        let even = |n: u32| n.max(16) + n.max(16) % 2;
        let grid = Supersampling {
            x: even(m.x),
            y: even(m.y),
        };
        return pixel_average(shape, x, y, grid);
    }
    match shape.sample(x, y) {
        Sample::Dark => 0.0,
        Sample::One(f) => f,
        Sample::Grid(grid) => pixel_average(shape, x, y, grid),
    }
}

/// A unit square's light under each of its corner pixels' tents: top
/// left, top right, bottom left, bottom right (y up).
type Corners = [f64; 4];
const TOP_LEFT: usize = 0;
const TOP_RIGHT: usize = 1;
const BOTTOM_LEFT: usize = 2;
const BOTTOM_RIGHT: usize = 3;

/// Pixel rows rasterised together: their squares are held at once.
const BAND: usize = 32;

/// f under every pixel's tent, for light sent by a pixel (docs/physics.md
/// §2): the unit squares between four pixel centres are each sampled once
/// ([`corners`]), and a pixel sums its four. A mirror-symmetric f is
/// computed on a quarter and mirrored.
fn tent_plane(shape: &dyn SpreadShape, extent: &Extent, control: &mut Control) -> Result<Raster> {
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = extent.centre();
    if shape.mirror_symmetric() {
        // Squares at (p + ½, q + ½) for p, q ≥ 0; the one at −½ is the
        // mirror of the one at +½. A pixel at offset d ≥ 0 takes the inner
        // corner of the square at d + ½ and the outer of the one at d − ½,
        // or for d = 0 the inner corner of the square at ½ twice.
        let (reach_x, reach_y) = (cx.max(width - 1 - cx), cy.max(height - 1 - cy));
        let sides = |d: usize| [(d, false), (d.saturating_sub(1), d > 0)];
        let combine = |dy: usize, dx: usize, squares: &dyn Fn(usize, usize) -> Corners| {
            let mut sum = 0.0;
            for (q, outer_y) in sides(dy) {
                for (p, outer_x) in sides(dx) {
                    // Inner is toward the centre: left and below.
                    let corner = match (outer_x, outer_y) {
                        (false, false) => BOTTOM_LEFT,
                        (true, false) => BOTTOM_RIGHT,
                        (false, true) => TOP_LEFT,
                        (true, true) => TOP_RIGHT,
                    };
                    sum += squares(q, p)[corner];
                }
            }
            sum
        };
        let quarter = if shape.radial() {
            // The square centred at (x, y), as the bands would sample it.
            let at = |x: f64, y: f64| corners(shape, x, y, shape.sample(x, y));
            let exact =
                |dx: usize, dy: usize| combine(dy, dx, &|q, p| at(p as f64 + 0.5, q as f64 + 0.5));
            let value = |x: f64, y: f64| {
                at(x + 0.5, y + 0.5)[BOTTOM_LEFT]
                    + at(x - 0.5, y + 0.5)[BOTTOM_RIGHT]
                    + at(x + 0.5, y - 0.5)[TOP_LEFT]
                    + at(x - 0.5, y - 0.5)[TOP_RIGHT]
            };
            radial::quarter(shape, (reach_x + 1, reach_y + 1), &exact, &value, control)?
        } else {
            let mut quarter = zeros((reach_x + 1) * (reach_y + 1))?;
            rasterise_bands(
                shape,
                (&mut quarter, reach_x + 1),
                &|q| q as f64 + 0.5,
                0.5,
                &|dy, columns, rows, row| {
                    // Only shapes that are mirror symmetric but not radial
                    // (none in the crate yet) come here: a pixel at a time.
                    for (dx, value) in columns.clone().zip(&mut row[columns]) {
                        *value = combine(dy, dx, &|q, p| rows.get(q)[p]) as f32;
                    }
                },
                control,
            )?;
            quarter
        };
        return Ok(Raster::Quarter {
            values: quarter,
            span: reach_x + 1,
        });
    }
    let mut plane = zeros(width * height)?;
    // Square row k lies between pixel rows k − 1 and k, square i between
    // columns i − 1 and i.
    rasterise_bands(
        shape,
        (&mut plane, width),
        &|k| cy as f64 - k as f64 + 0.5,
        -(cx as f64) - 0.5,
        &|r, columns, rows, row| {
            let ends = columns.start..columns.end + 1;
            let (above, below) = (&rows.get(r)[ends.clone()], &rows.get(r + 1)[ends]);
            let pairs = above.windows(2).zip(below.windows(2));
            for (value, (a, b)) in row[columns].iter_mut().zip(pairs) {
                *value = (a[0][BOTTOM_RIGHT] + a[1][BOTTOM_LEFT] + b[0][TOP_RIGHT] + b[1][TOP_LEFT])
                    as f32;
            }
        },
        control,
    )?;
    Ok(Raster::Plane(plane))
}

/// `plane` (rows of `width`, its centre at `centre`) from the `quarter` of
/// offsets 0..`span` along x and down the rows, mirrored into all four.
fn mirror(quarter: &[f32], span: usize, plane: &mut [f32], width: usize, centre: (usize, usize)) {
    let (cx, cy) = centre;
    plane
        .par_chunks_mut(width)
        .enumerate()
        .for_each(|(j, row)| {
            let dy = j.abs_diff(cy);
            let source = &quarter[dy * span..(dy + 1) * span];
            // Right of the centre a copy, left of it the same reversed.
            let (left, right) = row.split_at_mut(cx);
            right.copy_from_slice(&source[..right.len()]);
            for (value, mirrored) in left.iter_mut().rev().zip(&source[1..]) {
                *value = *mirrored;
            }
        });
}

/// A band's square rows, from square row `first` on.
#[derive(Clone, Copy)]
struct SquareRows<'a> {
    squares: &'a [Corners],
    first: usize,
    per_row: usize,
}

impl<'a> SquareRows<'a> {
    /// The corners of square row k's squares.
    fn get(&self, k: usize) -> &'a [Corners] {
        let at = (k - self.first) * self.per_row;
        &self.squares[at..at + self.per_row]
    }
}

/// Fills `out` (rows of `width` pixels) band by band, pixel row r's
/// `columns` by `combine`(r, columns, rows, row) from the squares about
/// them (a row at a time, so that the squares are read in line, not
/// through a call per pixel): first the square
/// rows the band needs (from the one before its first pixel row to the one
/// after its last), square row k at height `y_of`(k) and square i at
/// `x0` + i for i in 0..=width, evaluated in parallel pieces and left
/// dark outside the shape's lit spans; then every pixel from them. The
/// same sums in the same order on any number of threads.
fn rasterise_bands(
    shape: &dyn SpreadShape,
    (out, width): (&mut [f32], usize),
    y_of: &(dyn Fn(usize) -> f64 + Sync),
    x0: f64,
    combine: &(impl Fn(usize, std::ops::Range<usize>, SquareRows<'_>, &mut [f32]) + Sync),
    control: &mut Control,
) -> Result<()> {
    let bands = (out.len() / width.max(1)).div_ceil(BAND).max(1);
    let per_row = width + 1;
    // A span [a, b] of square centres holds the squares ⌈a − x₀⌉ to
    // ⌊b − x₀⌋.
    let lit_range = |spans: &Option<Vec<(f64, f64)>>| match spans {
        None => 0..per_row,
        Some(spans) => {
            let lo = spans
                .iter()
                .map(|s| (s.0 - x0).ceil().max(0.0))
                .fold(f64::INFINITY, f64::min);
            let hi = spans
                .iter()
                .map(|s| (s.1 - x0).floor() + 1.0)
                .fold(0.0, f64::max);
            let (lo, hi) = (
                lo.min(per_row as f64) as usize,
                hi.clamp(0.0, per_row as f64) as usize,
            );
            lo..hi.max(lo)
        }
    };
    // One band's squares at a time, in one buffer: a band of a 4K kernel
    // holds 8 MB of them, and fresh memory for each band cost more than
    // the squares of a small spread. A row of squares writes every square
    // of its range, dark ones too, and clears what the band before left
    // outside it: outside its range a row holds zeros, and a spread that
    // lights whole rows clears nothing.
    let mut held = vec![[0.0; 4]; (BAND + 2) * per_row];
    let mut written = vec![0..0; BAND + 2];
    for (b, band) in out.chunks_mut(BAND * width.max(1)).enumerate() {
        control.check()?;
        let first = b * BAND;
        let (k0, k1) = (first.saturating_sub(1), first + band.len() / width);
        let squares = &mut held[..(k1 + 1 - k0) * per_row];
        // Per square row, the squares that may hold light; the rest are
        // dark and their pixels stay 0.
        let ranges: Vec<std::ops::Range<usize>> = squares
            .par_chunks_mut(per_row)
            .zip(&mut written)
            .enumerate()
            .map(|(n, (row, written))| {
                let y = y_of(k0 + n);
                let spans = shape.lit_spans(y);
                let range = lit_range(&spans);
                let before = written.start..range.start.min(written.end);
                let after = range.end.max(written.start)..written.end;
                for stale in [before, after] {
                    if !stale.is_empty() {
                        row[stale].fill([0.0; 4]);
                    }
                }
                *written = range.clone();
                row[range.clone()]
                    .par_chunks_mut(PIECE)
                    .enumerate()
                    .for_each(|(p, piece)| {
                        let start = x0 + (range.start + p * PIECE) as f64;
                        let lit = |m: usize| lit(spans.as_deref(), start + m as f64);
                        let mut samples = [Sample::Dark; PIECE];
                        // Runs of lit squares, sampled a run at a time.
                        let mut m = 0;
                        while m < piece.len() {
                            if !lit(m) {
                                piece[m] = [0.0; 4];
                                m += 1;
                                continue;
                            }
                            let run = m;
                            while m < piece.len() && lit(m) {
                                m += 1;
                            }
                            let x = start + run as f64;
                            shape.sample_row(x, y, &mut samples[run..m]);
                            for (i, c) in (run..m).zip(&mut piece[run..m]) {
                                *c = corners(shape, start + i as f64, y, samples[i]);
                            }
                        }
                    });
                range
            })
            .collect();
        let rows = SquareRows {
            squares,
            first: k0,
            per_row,
        };
        band.par_chunks_mut(width).enumerate().for_each(|(n, row)| {
            // A pixel meets the squares of the rows beside its own and
            // the columns beside its own.
            let r = first + n;
            let near = (r.saturating_sub(1).max(k0)..=(r + 1).min(k1))
                .map(|k| &ranges[k - k0])
                .filter(|range| !range.is_empty());
            let (lo, hi) = near.fold((usize::MAX, 0), |(lo, hi), range| {
                (lo.min(range.start), hi.max(range.end))
            });
            if lo >= hi {
                return;
            }
            combine(r, lo.saturating_sub(1)..(hi + 1).min(width), rows, row);
        });
        control.report((b + 1) as f64 / bands as f64);
    }
    Ok(())
}

/// The light of the unit square centred at (x, y) under each corner
/// pixel's tent, bilinear, 1 at the corner and 0 at the far side: the
/// midpoint rule on the shape's grid, at least 16 × 16 where the centre is
/// a corner of the square (its midpoints never fall on r = 0). `sample` is
/// the shape's [`SpreadShape::sample`] there.
/// The answers of one value in line (most squares of a kernel), a grid's
/// sums out of line.
#[inline(always)]
fn corners(shape: &dyn SpreadShape, x: f64, y: f64, sample: Sample) -> Corners {
    let grid = if x.abs() <= 0.5 && y.abs() <= 0.5 {
        let grid = shape.grid(x, y);
        Supersampling {
            x: grid.x.max(16),
            y: grid.y.max(16),
        }
    } else {
        match sample {
            Sample::Dark => return [0.0; 4],
            // The one midpoint is the square's centre: a quarter under
            // each corner's tent.
            Sample::One(f) => return [0.25 * f; 4],
            Sample::Grid(grid) => grid,
        }
    };
    grid_corners(shape, x, y, grid)
}

/// [`corners`] by the midpoint rule on `grid`.
#[inline(never)]
fn grid_corners(shape: &dyn SpreadShape, x: f64, y: f64, grid: Supersampling) -> Corners {
    let (mx, my) = (grid.x.max(1), grid.y.max(1));
    let (step_x, step_y) = (1.0 / f64::from(mx), 1.0 / f64::from(my));
    let mut sums = [0.0; 4];
    let s = |b: u32| -0.5 + (f64::from(b) + 0.5) * step_x;
    let t = |a: u32| -0.5 + (f64::from(a) + 0.5) * step_y;
    let (mut left, mut right) = (0.0, 0.0);
    grid_points(
        shape,
        (mx, my),
        |b| x + s(b),
        |a| y + t(a),
        |a, b, f| {
            left += (0.5 - s(b)) * f;
            right += (0.5 + s(b)) * f;
            if b + 1 == mx {
                let (top, bottom) = (0.5 + t(a), 0.5 - t(a));
                sums[TOP_LEFT] += top * left;
                sums[TOP_RIGHT] += top * right;
                sums[BOTTOM_LEFT] += bottom * left;
                sums[BOTTOM_RIGHT] += bottom * right;
                (left, right) = (0.0, 0.0);
            }
        },
    );
    let n = f64::from(mx * my);
    sums.map(|v| v / n)
}

/// The mean of f over the pixel centred at (x, y), by the midpoint rule on
/// `grid`.
fn pixel_average(shape: &dyn SpreadShape, x: f64, y: f64, grid: Supersampling) -> f64 {
    if grid.x <= 1 && grid.y <= 1 {
        return shape.density(x, y);
    }
    let (mx, my) = (grid.x.max(1), grid.y.max(1));
    let (step_x, step_y) = (1.0 / f64::from(mx), 1.0 / f64::from(my));
    let mut sum = 0.0;
    let sx = |b: u32| x - 0.5 + (f64::from(b) + 0.5) * step_x;
    let sy = |a: u32| y - 0.5 + (f64::from(a) + 0.5) * step_y;
    grid_points(shape, (mx, my), sx, sy, |_, _, f| sum += f);
    sum / f64::from(mx * my)
}

/// `each(a, b, f)` for the `mx` × `my` midpoints of a pixel's grid, row
/// a by row in order, f the shape's density at (`x(b)`, `y(a)`), asked
/// for a chunk at a time ([`SpreadShape::density_at`]): a thin ray's grid
/// is a few points along it by dozens across, and chunks that run on from
/// row to row keep the passes long whichever way it lies. Small grids go
/// through the chunks too: the corona's passes in vectors beat one point
/// at a time from two points on (`paper-fig6c` at 4K built 1.36 → 1.21 s).
fn grid_points(
    shape: &dyn SpreadShape,
    (mx, my): (u32, u32),
    x: impl Fn(u32) -> f64,
    y: impl Fn(u32) -> f64,
    mut each: impl FnMut(u32, u32, f64),
) {
    let total = mx as usize * my as usize;
    let (mut xs, mut ys, mut f) = (
        [0.0; CHUNK_POINTS],
        [0.0; CHUNK_POINTS],
        [0.0; CHUNK_POINTS],
    );
    let at = |i: usize| ((i / mx as usize) as u32, (i % mx as usize) as u32);
    for first in (0..total).step_by(CHUNK_POINTS) {
        let n = (total - first).min(CHUNK_POINTS);
        for (i, (x_i, y_i)) in (first..).zip(xs[..n].iter_mut().zip(&mut ys[..n])) {
            let (a, b) = at(i);
            (*x_i, *y_i) = (x(b), y(a));
        }
        shape.density_at(&xs[..n], &ys[..n], &mut f[..n]);
        for (i, &f) in (first..).zip(&f[..n]) {
            let (a, b) = at(i);
            each(a, b, f);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::CameraGeometry;
    use crate::config::ConfigFile;
    use crate::control::Cancel;
    use crate::optics::{Context, Source};

    /// A shape as it is, but not said to be radial (its kernel computed
    /// pixel by pixel), and with `mirrored` false not said to be mirror
    /// symmetric either (its whole plane computed).
    struct Plain<'a> {
        shape: &'a dyn SpreadShape,
        mirrored: bool,
    }

    impl SpreadShape for Plain<'_> {
        fn density(&self, x: f64, y: f64) -> f64 {
            self.shape.density(x, y)
        }
        fn whole(&self, window: &Window) -> Whole {
            self.shape.whole(window)
        }
        fn grid(&self, x: f64, y: f64) -> Supersampling {
            self.shape.grid(x, y)
        }
        fn spreads_centre(&self) -> bool {
            self.shape.spreads_centre()
        }
        fn mirror_symmetric(&self) -> bool {
            self.mirrored && self.shape.mirror_symmetric()
        }
        fn sample(&self, x: f64, y: f64) -> Sample {
            self.shape.sample(x, y)
        }
        fn one_point_squared(&self) -> f64 {
            self.shape.one_point_squared()
        }
        fn sample_row(&self, x0: f64, y: f64, out: &mut [Sample]) {
            self.shape.sample_row(x0, y, out)
        }
        fn density_at(&self, xs: &[f64], ys: &[f64], out: &mut [f64]) {
            self.shape.density_at(xs, ys, out)
        }
        fn lit_spans(&self, y: f64) -> Option<Vec<(f64, f64)>> {
            self.shape.lit_spans(y)
        }
    }

    /// `shape`'s plane over `extent` as the rasteriser computes it, and
    /// as it computes the [`Plain`] shape (`mirrored` as given).
    fn against_plain(
        shape: &dyn SpreadShape,
        extent: &Extent,
        mirrored: bool,
        control: &mut Control,
    ) -> (Vec<f32>, Vec<f32>) {
        let plain = Plain { shape, mirrored };
        let as_is = shape_plane(shape, extent, 1.0, control).unwrap().unwrap();
        let plain = shape_plane(&plain, extent, 1.0, control).unwrap().unwrap();
        (as_is, plain)
    }

    #[test]
    fn a_corona_of_identical_rays_on_the_axes_is_computed_on_a_quarter() {
        // Rays on the axes (turned by 0° or half a period), an even count,
        // no jitter: mirrored. Any of those otherwise: not. The quarter is
        // the whole plane's, diagonal rays (8 and 12 here) included: each
        // is sampled along the same axis as its mirror images.
        let corona = |extra: &str| {
            let toml = format!(
                "[[effect]]\ntype = \"corona\"\nepsilon = 0.1\nlength = \"30px\"\nwidth = \"2px\"\n{extra}"
            );
            let file = ConfigFile::parse(&toml, "test").unwrap();
            let extent = Extent::new(121, 81).unwrap();
            let context = Context {
                camera: &CameraGeometry::default(),
                pitch_mm: None,
                seed: 1,
                index_of_kind: 0,
                kernel_size: (extent.width, extent.height),
                sending: Sending::Pixel,
            };
            match file.effects[0].source(&context).unwrap() {
                Source::Shape(_, shape) => shape,
                _ => unreachable!("a corona is one shape"),
            }
        };
        let still = "length_jitter = 0.0\n";
        for (extra, mirrored) in [
            (format!("{still}rays = 8\nspread = 0.5"), true),
            (
                format!("{still}rays = 12\nrotation_deg = 15.0\nspread = 1.0"),
                true,
            ),
            (format!("{still}rays = 6\nspread = -1.0"), true),
            (format!("{still}rays = 7"), false),
            (format!("{still}rays = 8\nrotation_deg = 5.0"), false),
            ("rays = 8\nlength_jitter = 0.25".to_string(), false),
            (format!("{still}rays = 8\nwidth_jitter = 0.1"), false),
        ] {
            let shape = corona(&extra);
            assert_eq!(shape.mirror_symmetric(), mirrored, "{extra}");
            if !mirrored {
                continue;
            }
            let cancel = Cancel::new();
            let mut quiet = Control::quiet(&cancel);
            for (w, h, sending) in [(121, 81, Sending::Pixel), (120, 81, Sending::Point)] {
                let extent = Extent::new(w, h).unwrap().sent_by(sending);
                let (quarter, whole) = against_plain(shape.as_ref(), &extent, false, &mut quiet);
                let peak = whole.iter().fold(0.0f32, |m, v| m.max(*v));
                for (k, (a, b)) in quarter.iter().zip(&whole).enumerate() {
                    assert!(
                        (a - b).abs() <= 1e-6 * b.abs() + 1e-12 * peak,
                        "{extra}, {w}x{h}: pixel {} {}: {a} vs {b}",
                        k % w,
                        k / w
                    );
                }
            }
        }
    }

    /// The tables of distance (kernel::radial) give every radial shape's
    /// kernel within a few f32 roundings of the one computed pixel by
    /// pixel, for light sent by a pixel and by a point, and hold most of
    /// its pixels (else this would compare the same computation twice).
    #[test]
    fn a_quarter_sums_to_the_plane_it_mirrors_into() {
        // Odd and even sides: an even side has one pixel less right of
        // (or below) the centre than left of (above) it.
        for (w, h) in [(1, 1), (2, 1), (5, 4), (8, 7), (12, 9), (3, 16), (601, 401)] {
            let extent = Extent::new(w, h).unwrap();
            let (cx, cy) = extent.centre();
            let span = cx.max(w - 1 - cx) + 1;
            let rows = cy.max(h - 1 - cy) + 1;
            let values: Vec<f32> = (0..span * rows)
                .map(|i| ((i * 37 % 101) as f32 + 0.5) * 1e-3)
                .collect();
            let quarter = Raster::Quarter { values, span };
            let sum = quarter.sum(&extent);
            let plane = quarter.into_plane(&extent).unwrap();
            let direct = plane_sum(&plane, w);
            assert!(
                (sum - direct).abs() <= 1e-12 * direct,
                "{w}x{h}: {sum} against {direct}"
            );
        }
    }

    #[test]
    fn a_radial_kernel_from_tables_is_the_kernel_pixel_by_pixel() {
        let effects = r#"
            [camera]
            sensor_width_mm = 36.0
            focal_length_mm = 50.0
            [[effect]]
            type = "bloom"
            epsilon = 0.1
            beta = 2.0
            radius = "10.4px"
            [[effect]]
            type = "bloom"
            epsilon = 0.1
            beta = 1.2
            radius = "0.7px"
            [[effect]]
            type = "bloom"
            epsilon = 0.1
            beta = 6.0
            radius = "60px"
            [[effect]]
            type = "vos"
            epsilon = 0.1
            exponent = 1.5
            [[effect]]
            type = "vos"
            epsilon = 0.1
            exponent = 3.0
            [[effect]]
            type = "halation"
            [[effect]]
            type = "halation"
            base_thickness = "20um"
            red_transmission = 0.01
            [[effect]]
            type = "halation"
            remjet = true
        "#;
        let file = ConfigFile::parse(effects, "test").unwrap();
        let camera: CameraGeometry = file.camera.unwrap();
        let cancel = Cancel::new();
        let mut quiet = Control::quiet(&cancel);
        // Shapes whose tables hold more than 90 % of a quarter's pixels.
        let mut held_most = 0;
        for (sending, image_width) in [(Sending::Pixel, 600), (Sending::Point, 1200)] {
            let extent = Extent::new(601, 401).unwrap().with_image_width(image_width);
            let extent = extent.sent_by(sending);
            for effect in &file.effects {
                let context = Context {
                    camera: &camera,
                    pitch_mm: Some(36.0 / image_width as f64),
                    seed: 1,
                    index_of_kind: 0,
                    kernel_size: (extent.width, extent.height),
                    sending,
                };
                let shapes = match effect.source(&context).unwrap() {
                    Source::Shape(_, shape) => vec![shape],
                    Source::Shapes(planes) => planes.into_iter().map(|(_, s)| s).collect(),
                    _ => unreachable!("a radial effect"),
                };
                for shape in &shapes {
                    assert!(shape.radial());
                    let (tables, exact) = against_plain(shape.as_ref(), &extent, true, &mut quiet);
                    let (mut differ, mut worst) = (0, 0.0f64);
                    for (t, e) in tables.iter().zip(&exact) {
                        if t != e {
                            differ += 1;
                            // Denormals keep fewer bits: from them on, an
                            // absolute bound.
                            let error = f64::from((t - e).abs());
                            let of = f64::from(e.abs()).max(f64::from(f32::MIN_POSITIVE));
                            worst = worst.max(error / of);
                        }
                    }
                    assert!(
                        worst < 5e-7 && differ * 50 < tables.len(),
                        "{effect:?} sent by {sending:?}: {differ} pixels differ, by up to {worst:e}"
                    );
                    if sending == Sending::Point {
                        let value = |x: f64, y: f64| pixel_mean(shape.as_ref(), x, y, false);
                        let held = radial::held(shape.as_ref(), (301, 201), &value);
                        held_most += usize::from(held * 10 > 301 * 201 * 9);
                    }
                }
            }
        }
        // Every shape but the three layers' halos of a 20 µm base at 30 µm
        // pixels, which fall by e⁻¹ or more from one pixel to the next.
        assert_eq!(held_most, 11, "shapes whose tables held 90 % of the pixels");
    }
}
