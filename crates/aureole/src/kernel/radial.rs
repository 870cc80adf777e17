//! A radial spread function's kernel read from tables of distance.
//!
//! Where f, its grid and its dark test depend on the distance r from the
//! centre alone (bloom, halation, the eye), a pixel's value V(x, y) (f
//! averaged over the receiving pixel, and the sending one's tent) is a
//! smooth function of r and of the direction θ. The square pixel makes it
//! symmetric under quarter turns and mirrors, so V(r, θ) = A₀(r) +
//! A₄(r) cos 4θ + A₈(r) cos 8θ + …, where A₄ comes from the 4th moments of
//! the pixel's averaging (about 10⁻²·|∂⁴f| of f) and A₈ from its 8th.
//! Three tables of r (along the axis, the diagonal and halfway between,
//! θ = 0, π/4 and π/8) give A₀, A₄ and A₈ exactly at their nodes; a pixel
//! interpolates each in r and adds the three terms. What is left are the
//! 12th harmonic and the interpolation, both below 10⁻⁹ of V for the
//! shapes here (`tests`). A full-frame 4K kernel then costs a few table
//! lookups per pixel instead of the shape's functions at every point of
//! every pixel's grid (docs/physics.md §2).
//!
//! Where V is not smooth in r (the centre, within [`NEAR`] px; where the
//! shape changes its grid or test, such as a halo's total-reflection ring
//! or the radius beyond which one point per pixel is enough) pixels are
//! computed as they would be without the tables, to the bit.

use std::f64::consts::{FRAC_1_SQRT_2, PI};

use rayon::prelude::*;

use crate::control::{for_each_row, Control};
use crate::error::Result;
use crate::image::zeros;
use crate::optics::shape::{Sample, SpreadShape};

/// Pixels nearer the centre than this (px) are always computed.
const NEAR: f64 = 16.0;

/// The largest error relative to V that a node's model may show where it
/// is checked (`Tables::new`): a sixth of f32's resolution.
const HOLDS: f64 = 1e-8;

/// Table nodes per pixel of distance.
const NODES_PER_PX: f64 = 4.0;

/// How far (px) from a pixel's distance the shape's grid and test must
/// stay the same for the tables to hold its value: its tent's squares lie
/// within √2/2 of it, the nodes it interpolates within 3/4, and those
/// nodes' squares within √2/2 of theirs.
const SAME_GRID: f64 = 1.75;

/// What a shape says of a point, its value left out: dark, one point, or
/// a grid of so many points.
fn class(sample: Sample) -> (u8, u32, u32) {
    match sample {
        Sample::Dark => (0, 0, 0),
        Sample::One(_) => (1, 0, 0),
        Sample::Grid(grid) => (2, grid.x, grid.y),
    }
}

/// The quarter of a radial shape's kernel, offsets 0..`span_x` along x and
/// 0..`span_y` down the rows: `exact(dx, dy)` for the pixels the tables do
/// not hold, and the tables of `value(x, y)` (the same pixel value at any
/// point) for the rest.
pub(super) fn quarter(
    shape: &dyn SpreadShape,
    (span_x, span_y): (usize, usize),
    exact: &(dyn Fn(usize, usize) -> f64 + Sync),
    value: &(dyn Fn(f64, f64) -> f64 + Sync),
    control: &mut Control,
) -> Result<Vec<f32>> {
    let tables = Tables::new(shape, (span_x, span_y), value);
    let mut quarter = zeros(span_x * span_y)?;
    for_each_row(&mut quarter, span_x, control, |dy, row| {
        for (c, chunk) in row.chunks_mut(CHUNK).enumerate() {
            tables.fill(c * CHUNK, dy, chunk, exact);
        }
    })?;
    Ok(quarter)
}

/// How many pixels of a quarter of `span` the tables of `value` hold.
#[cfg(test)]
pub(super) fn held(
    shape: &dyn SpreadShape,
    (span_x, span_y): (usize, usize),
    value: &(dyn Fn(f64, f64) -> f64 + Sync),
) -> usize {
    let tables = Tables::new(shape, (span_x, span_y), value);
    (0..span_y)
        .flat_map(|y| (0..span_x).map(move |x| (x, y)))
        .filter(|&(x, y)| tables.hold(((x * x + y * y) as f64).sqrt() * NODES_PER_PX))
        .count()
}

/// Pixels of a row read from the tables in one pass each: the distances
/// and weights in loops the processor runs four or eight wide, the table
/// reads after them.
const CHUNK: usize = 64;

/// A₀, A₄ and A₈ at every 1/[`NODES_PER_PX`] px of distance, and where a
/// pixel may be read from them.
struct Tables {
    terms: Vec<[f64; 3]>,
    /// Per node: whether a pixel at its distance is smooth enough in r.
    smooth: Vec<bool>,
}

impl Tables {
    /// The tables for a quarter of `span` pixels.
    fn new(
        shape: &dyn SpreadShape,
        (span_x, span_y): (usize, usize),
        value: &(dyn Fn(f64, f64) -> f64 + Sync),
    ) -> Tables {
        let far = (((span_x * span_x + span_y * span_y) as f64).sqrt() + SAME_GRID + 1.0) as usize;
        let nodes = far * NODES_PER_PX as usize + 8;
        let (cos8, sin8) = (libm::cos(PI / 8.0), libm::sin(PI / 8.0));
        // V along θ = 0 (a), π/4 (d) and π/8 (b): a = A₀ + A₄ + A₈,
        // d = A₀ − A₄ + A₈, b = A₀ − A₈ (the 12th harmonic left out).
        let terms: Vec<[f64; 3]> = (0..nodes)
            .into_par_iter()
            .map(|k| {
                let r = k as f64 / NODES_PER_PX;
                let a = value(r, 0.0);
                let d = value(r * FRAC_1_SQRT_2, r * FRAC_1_SQRT_2);
                let b = value(r * cos8, r * sin8);
                let half = 0.5 * (a + d);
                [0.5 * (half + b), 0.5 * (a - d), 0.5 * (half - b)]
            })
            .collect();
        // The shape's grid and test at every 1/8 px of distance, and for
        // each the first of the run it belongs to.
        let fine = 8.0;
        let classes: Vec<(u8, u32, u32)> = (0..(nodes as f64 / NODES_PER_PX * fine) as usize)
            .into_par_iter()
            .map(|j| class(shape.sample(j as f64 / fine, 0.0)))
            .collect();
        let mut first = vec![0; classes.len()];
        for j in 1..classes.len() {
            first[j] = if classes[j] == classes[j - 1] {
                first[j - 1]
            } else {
                j
            };
        }
        let same_grid = |k: usize| {
            let r = k as f64 / NODES_PER_PX;
            let (low, high) = (r - SAME_GRID, r + SAME_GRID + 1.0 / NODES_PER_PX);
            let (lo, hi) = ((low * fine).floor() as usize, (high * fine).ceil() as usize);
            low > NEAR && hi < classes.len() && first[hi] <= lo
        };
        let mut tables = Tables {
            terms,
            smooth: vec![false; nodes],
        };
        // Each node's model against V itself where it is weakest: at
        // θ = π/16, where the 12th harmonic left out is largest, and
        // halfway to the next node along the axis, where the quintic
        // strays most.
        let (cos16, sin16) = (libm::cos(PI / 16.0), libm::sin(PI / 16.0));
        let holds: Vec<bool> = (0..nodes)
            .into_par_iter()
            .map(|k| {
                if k < 2 || k + 4 > nodes || !same_grid(k) {
                    return false;
                }
                let r = k as f64 / NODES_PER_PX;
                let t = k as f64;
                let close = |model: f64, v: f64| (model - v).abs() <= HOLDS * v.abs();
                let slanted = value(r * cos16, r * sin16);
                let between = value(r + 0.5 / NODES_PER_PX, 0.0);
                close(tables.model(t, FRAC_1_SQRT_2), slanted)
                    && close(tables.model(t + 0.5, 1.0), between)
            })
            .collect();
        // A pixel reads six nodes about its own: each must hold.
        for k in 3..nodes.saturating_sub(3) {
            tables.smooth[k] = holds[k - 3..=k + 3].iter().all(|&h| h);
        }
        tables
    }

    /// Whether the tables hold a pixel t nodes from the centre.
    fn hold(&self, t: f64) -> bool {
        self.smooth.get(t as usize).copied().unwrap_or(false)
    }

    /// A₀ + A₄ cos 4θ + A₈ cos 8θ at t nodes of distance (t ≥ 2, within
    /// the tables), given cos 4θ.
    fn model(&self, t: f64, c4: f64) -> f64 {
        self.combine(t as usize, &lagrange(t - t.floor()), c4)
    }

    /// The model past node k with the nodes' weights `w`, given cos 4θ.
    fn combine(&self, k: usize, w: &[f64; 6], c4: f64) -> f64 {
        let mut sum = [0.0; 3];
        for (node, w) in self.terms[k - 2..k + 4].iter().zip(w) {
            for (s, term) in sum.iter_mut().zip(node) {
                *s += w * term;
            }
        }
        let c8 = 2.0 * c4 * c4 - 1.0;
        (sum[0] + sum[1] * c4 + sum[2] * c8).max(0.0)
    }

    /// The pixels (x₀ + i, y) of `out`, from the tables where they hold
    /// them and from `exact` elsewhere.
    fn fill(
        &self,
        x0: usize,
        y: usize,
        out: &mut [f32],
        exact: &(dyn Fn(usize, usize) -> f64 + Sync),
    ) {
        let n = out.len();
        let yf = y as f64;
        let mut t = [0.0; CHUNK];
        let mut c4 = [0.0; CHUNK];
        for (i, (t, c4)) in t.iter_mut().zip(&mut c4).enumerate().take(n) {
            let x = (x0 + i) as f64;
            let (xx, yy) = (x * x, yf * yf);
            let r2 = xx + yy;
            *t = r2.sqrt() * NODES_PER_PX;
            // cos 4θ = 1 − 8x²y²/r⁴.
            *c4 = 1.0 - 8.0 * xx * yy / (r2 * r2);
        }
        let mut w = [[0.0; 6]; CHUNK];
        for (w, &t) in w.iter_mut().zip(&t).take(n) {
            *w = lagrange(t - t.floor());
        }
        for (i, v) in out.iter_mut().enumerate() {
            *v = if self.hold(t[i]) {
                self.combine(t[i] as usize, &w[i], c4[i])
            } else {
                exact(x0 + i, y)
            } as f32;
        }
    }
}

/// The weights of the six nodes k − 2 … k + 3 for a point u ∈ [0, 1) past
/// node k: Lagrange's quintic through them.
fn lagrange(u: f64) -> [f64; 6] {
    let p = [u + 2.0, u + 1.0, u, u - 1.0, u - 2.0, u - 3.0];
    // 1 / ∏_{m ≠ j} (j − m) for nodes −2 … 3.
    const SCALE: [f64; 6] = [
        -1.0 / 120.0,
        1.0 / 24.0,
        -1.0 / 12.0,
        1.0 / 12.0,
        -1.0 / 24.0,
        1.0 / 120.0,
    ];
    let p01 = p[0] * p[1];
    let p45 = p[4] * p[5];
    let p23 = p[2] * p[3];
    let p0123 = p01 * p23;
    let p2345 = p23 * p45;
    let p0145 = p01 * p45;
    [
        p[1] * p2345 * SCALE[0],
        p[0] * p2345 * SCALE[1],
        p0145 * p[3] * SCALE[2],
        p0145 * p[2] * SCALE[3],
        p0123 * p[5] * SCALE[4],
        p0123 * p[4] * SCALE[5],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_weights_reproduce_a_quintic_and_sum_to_one() {
        let f = |x: f64| 0.3 - 1.2 * x + 0.7 * x * x - 0.05 * x.powi(3) + 0.01 * x.powi(5);
        for u in [0.0, 0.1, 0.5, 0.93] {
            let w = lagrange(u);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-14);
            let at: f64 = (-2..4).zip(&w).map(|(m, w)| f(f64::from(m)) * w).sum();
            assert!((at - f(u)).abs() < 1e-12, "{u}: {at} vs {}", f(u));
        }
    }
}
