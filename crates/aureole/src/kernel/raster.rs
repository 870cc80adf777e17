//! Rasterising a spread function: f averaged over the area of the pixel
//! that receives the light and, for a kernel of an image, of the one that
//! sends it (a tent over 2 × 2 px), by the midpoint rule on grids that each
//! shape chooses (finer where f changes within a pixel), then normalised to
//! ΣF = 1.

use rayon::prelude::*;

use super::{Extent, Sending};
use crate::control::{for_each, for_each_row, Control};
use crate::error::Result;
use crate::image::sum_f64;
use crate::optics::shape::{SpreadShape, Supersampling};

/// Pixels of a row rasterised together where f has no mirror symmetry.
const PIECE: usize = 256;

/// f averaged as `extent.sending` asks and normalised to ΣF = 1; `None` when
/// f puts nothing inside the extent. A mirror-symmetric f is computed on a
/// quarter and mirrored.
pub(super) fn shape_plane(
    shape: &dyn SpreadShape,
    extent: &Extent,
    control: &mut Control,
) -> Result<Option<Vec<f32>>> {
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = extent.centre();
    // A shape singular at the centre keeps the sending pixel a point.
    let tent = extent.sending == Sending::Pixel && shape.spreads_centre();
    let mut plane = vec![0f32; width * height];
    if shape.mirror_symmetric() {
        // Offsets 0..=reach along each axis cover both sides of the centre.
        let (reach_x, reach_y) = (cx.max(width - 1 - cx), cy.max(height - 1 - cy));
        let mut quarter = vec![0.0; (reach_x + 1) * (reach_y + 1)];
        for_each_row(&mut quarter, reach_x + 1, control, |dy, row| {
            for (dx, value) in row.iter_mut().enumerate() {
                *value = pixel_mean(shape, dx as f64, dy as f64, (dx, dy) == (0, 0), tent) as f32;
            }
        })?;
        plane
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(j, row)| {
                let dy = j.abs_diff(cy);
                let source = &quarter[dy * (reach_x + 1)..(dy + 1) * (reach_x + 1)];
                for (i, value) in row.iter_mut().enumerate() {
                    *value = source[i.abs_diff(cx)];
                }
            });
    } else {
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
            let spans = lit_spans(shape, y, tent);
            for (i, value) in piece.iter_mut().enumerate() {
                let i = first + i;
                let x = i as f64 - cx as f64;
                // Pixels outside the lit spans stay 0.
                if let Some(spans) = &spans {
                    if !spans.iter().any(|&(a, b)| a <= x && x <= b) {
                        continue;
                    }
                }
                *value = pixel_mean(shape, x, y, (i, j) == (cx, cy), tent) as f32;
            }
        })?;
    }
    let total = plane_sum(&plane, width);
    if !(total > 0.0 && total.is_finite()) {
        return Ok(None);
    }
    let scale = 1.0 / total;
    plane
        .par_iter_mut()
        .for_each(|v| *v = (f64::from(*v) * scale) as f32);
    Ok(Some(plane))
}

/// The ranges of pixel centres on the row at height y that may hold light:
/// with the `tent`, those of the unit squares on the half rows above and
/// below, widened by half a pixel.
fn lit_spans(shape: &dyn SpreadShape, y: f64, tent: bool) -> Option<Vec<(f64, f64)>> {
    if !tent {
        return shape.lit_spans(y);
    }
    let mut spans = shape.lit_spans(y - 0.5)?;
    spans.extend(shape.lit_spans(y + 0.5)?);
    Some(spans.into_iter().map(|(a, b)| (a - 0.5, b + 0.5)).collect())
}

/// Σ of a plane in f64: row sums in parallel, added in row order, so the
/// same bits with any number of threads.
pub(super) fn plane_sum(plane: &[f32], width: usize) -> f64 {
    let rows: Vec<f64> = plane.par_chunks(width.max(1)).map(sum_f64).collect();
    rows.iter().sum()
}

/// The light that the pixel centred at (x, y) receives from the centre
/// (`centre`: it is the centre pixel). With the `tent`, from a pixel of
/// uniform radiance there: f averaged over both pixels' areas, its mean
/// under (1 − |s|)(1 − |t|) over the 2 × 2 px about (x, y)
/// (docs/physics.md §2). Without, from a point at its centre: f averaged
/// over the receiving pixel.
fn pixel_mean(shape: &dyn SpreadShape, x: f64, y: f64, centre: bool, tent: bool) -> f64 {
    if !tent {
        if centre {
            if !shape.spreads_centre() {
                return 0.0;
            }
            // An even count keeps sample points off r = 0, where the
            // direction φ is undefined.
            let m = shape.grid(x, y);
            let even = |n: u32| n.max(16) + n.max(16) % 2;
            let grid = Supersampling {
                x: even(m.x),
                y: even(m.y),
            };
            return pixel_average(shape, x, y, grid);
        }
        if shape.vanishes_over_pixel(x, y) {
            return 0.0;
        }
        return pixel_average(shape, x, y, shape.grid(x, y));
    }
    let quarters = QUARTERS.map(|(sx, sy)| (x + 0.5 * sx, y + 0.5 * sy));
    if quarters
        .iter()
        .all(|&(qx, qy)| shape.vanishes_over_pixel(qx, qy))
    {
        return 0.0;
    }
    let grids = quarters.map(|(qx, qy)| {
        let m = shape.grid(qx, qy);
        // A quarter with the centre at a corner holds the steepest part
        // of f; its midpoints never fall on r = 0.
        if qx.abs() <= 0.5 && qy.abs() <= 0.5 {
            Supersampling {
                x: m.x.max(16),
                y: m.y.max(16),
            }
        } else {
            m
        }
    });
    if grids.iter().all(|g| g.x <= 1 && g.y <= 1) {
        // f is smooth over the 2 × 2 px: the midpoint rule's error, f''/12
        // of the tent's variance, is the box's own order.
        return shape.density(x, y);
    }
    let sum: f64 = QUARTERS
        .iter()
        .zip(grids)
        .map(|(&(sx, sy), grid)| quarter_mean(shape, x, y, (sx, sy), grid))
        .sum();
    0.25 * sum
}

/// The directions from a pixel's centre to the centres of the four unit
/// squares that its tent covers, in half pixels.
const QUARTERS: [(f64, f64); 4] = [(-1.0, -1.0), (1.0, -1.0), (-1.0, 1.0), (1.0, 1.0)];

/// The mean of f weighted by 2(1 − |s|)·2(1 − |t|) (mean 1) over the unit
/// square between (x, y) and (x + sx, y + sy), by the midpoint rule on
/// `grid`, which sums the linear weight exactly.
fn quarter_mean(
    shape: &dyn SpreadShape,
    x: f64,
    y: f64,
    (sx, sy): (f64, f64),
    grid: Supersampling,
) -> f64 {
    let (mx, my) = (grid.x.max(1), grid.y.max(1));
    let (step_x, step_y) = (1.0 / f64::from(mx), 1.0 / f64::from(my));
    let mut sum = 0.0;
    for a in 0..my {
        let t = (f64::from(a) + 0.5) * step_y;
        let mut row = 0.0;
        for b in 0..mx {
            let s = (f64::from(b) + 0.5) * step_x;
            row += 2.0 * (1.0 - s) * shape.density(x + sx * s, y + sy * t);
        }
        sum += 2.0 * (1.0 - t) * row;
    }
    sum / f64::from(mx * my)
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
    for a in 0..my {
        let sy = y - 0.5 + (f64::from(a) + 0.5) * step_y;
        for b in 0..mx {
            let sx = x - 0.5 + (f64::from(b) + 0.5) * step_x;
            sum += shape.density(sx, sy);
        }
    }
    sum / f64::from(mx * my)
}
