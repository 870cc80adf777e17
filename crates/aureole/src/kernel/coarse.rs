//! A composition S ⊛ T where S's light varies slowly away from the centre
//! (a bloom's tail, Vos's, a halo's): S is split by a smooth taper into
//! its near part, composed exactly over a box about the centre, and its
//! far part, composed on a grid of nodes `step` px apart and interpolated
//! (docs/physics.md §2, *The far part composed on a grid*). The exact
//! composition of two full-frame planes transforms 1.5× the kernel's width
//! by 1.5× its height; this transforms the near box and 1/step² of that.

use std::f64::consts::FRAC_PI_2;

use rayon::prelude::*;

use super::split::{combined, reach};
use super::Extent;
use crate::control::{for_each_row, Control};
use crate::convolve::pool::Scratch;
use crate::convolve::{self, Composing};
use crate::error::Result;
use crate::image::zeros;

/// Kernels with fewer pixels are composed exactly: the exact transforms
/// are short there, and a 720p preview's kernel is near this.
const LEAST_PIXELS: usize = 1 << 22;

/// The largest error of the far part's bilinear interpolation between its
/// nodes, relative to S at the pixel. The composition's error is at most
/// about twice it, relative to S ⊛ T (the spreading of T onto the nodes
/// errs as much as the interpolation does), and S ⊛ T is itself the
/// smallest of a composition's terms.
const TOLERANCE: f64 = 2e-4;

/// The node spacings tried, the coarsest first.
const STEPS: [usize; 5] = [8, 6, 4, 3, 2];

/// How S is split, and the spacing of the far part's nodes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(super) struct Coarse {
    /// Where the taper starts: S is all near part within it, all far part
    /// beyond twice it.
    near: usize,
    step: usize,
}

impl Coarse {
    /// How to compose the radial plane `s` coarsely with `t`, and how far
    /// from the centre t's light reaches (columns, rows); `None` where the
    /// kernel is small or S's far part is too curved for every step: a
    /// ring, a core wider than the taper.
    pub fn plan(s: &[f32], t: &[f32], extent: &Extent) -> Option<(Coarse, (usize, usize))> {
        if extent.width * extent.height < LEAST_PIXELS {
            return None;
        }
        let t_reach = reach(t, extent);
        Coarse::fitting(s, t_reach, extent).map(|coarse| (coarse, t_reach))
    }

    /// [`Coarse::plan`] at any size: of the tapers at 1/16, 1/8 and 1/4 of
    /// the shortest side's reach, each with the coarsest step that holds,
    /// the one whose transforms are smallest.
    fn fitting(s: &[f32], t_reach: (usize, usize), extent: &Extent) -> Option<Coarse> {
        let (w, h) = (extent.width, extent.height);
        let (cx, cy) = extent.centre();
        let half = cx.min(cy).min(w - 1 - cx).min(h - 1 - cy);
        [16, 8, 4]
            .into_iter()
            .map(|part| half / part)
            .filter(|&near| near >= 16)
            .filter_map(|near| {
                STEPS
                    .into_iter()
                    .map(|step| Coarse { near, step })
                    .find(|coarse| coarse.holds(s, extent))
            })
            .min_by_key(|coarse| coarse.transformed(t_reach, extent))
    }

    /// The padded pixels of the two transforms, roughly: the near box
    /// grown by the near part's reach, and the grid of nodes grown by T's
    /// reach in nodes.
    fn transformed(&self, (tx, ty): (usize, usize), extent: &Extent) -> usize {
        let k = 2 * self.near;
        let grown = |reach: usize, side: usize| (2 * (k + reach) + 1).min(side) + k;
        let near = grown(tx, extent.width) * grown(ty, extent.height);
        let nodes = |reach: usize, side: usize| {
            side.div_ceil(self.step) + 1 + (reach.div_ceil(self.step) + 1).min(side / self.step)
        };
        near + nodes(tx, extent.width) * nodes(ty, extent.height)
    }

    /// The far part's share of S at distance r from the centre: 0 within
    /// `near`, 1 beyond twice it, sin² between, whose curvature stays
    /// within (π/near)²/2.
    fn far_share(&self, r: f64) -> f64 {
        let near = self.near as f64;
        if r <= near {
            0.0
        } else if r >= 2.0 * near {
            1.0
        } else {
            let s = libm::sin(FRAC_PI_2 * (r - near) / near);
            s * s
        }
    }

    /// The node at or before offset `d` (px) from the centre, counted in
    /// steps, and the share of the node after it: where `d` lies between.
    fn cell(&self, d: i64) -> (i64, f64) {
        let step = self.step as i64;
        let node = d.div_euclid(step);
        (node, (d - node * step) as f64 / step as f64)
    }

    /// Whether the far part of `s` interpolates bilinearly from its nodes
    /// within [`TOLERANCE`] of S, checked on the rows through the centre
    /// and half a step from it, the column through it and the diagonal:
    /// for a radial S, every direction a pixel's neighbours lie in. Pixels
    /// beyond the last node inside the extent are left out (the edge band
    /// of docs/physics.md).
    fn holds(&self, s: &[f32], extent: &Extent) -> bool {
        let (w, h) = (extent.width, extent.height);
        let (cx, cy) = (extent.centre().0 as i64, extent.centre().1 as i64);
        let step = self.step as i64;
        let value = |dx: i64, dy: i64| f64::from(s[((cy + dy) * w as i64 + cx + dx) as usize]);
        let far =
            |dx: i64, dy: i64| value(dx, dy) * self.far_share(((dx * dx + dy * dy) as f64).sqrt());
        // The last node on each side within the extent, in px.
        let right = (w as i64 - 1 - cx) / step * step;
        let below = (h as i64 - 1 - cy) / step * step;
        let fits = |dx: i64, dy: i64| {
            let ((x0, fx), (y0, fy)) = (self.cell(dx), self.cell(dy));
            let (x0, y0) = (x0 * step, y0 * step);
            if x0 + step > right || y0 + step > below {
                return true;
            }
            let between = (1.0 - fy) * ((1.0 - fx) * far(x0, y0) + fx * far(x0 + step, y0))
                + fy * ((1.0 - fx) * far(x0, y0 + step) + fx * far(x0 + step, y0 + step));
            (far(dx, dy) - between).abs() <= TOLERANCE * value(dx, dy)
        };
        let first = self.near as i64 - step;
        let across = (first..=right).all(|d| fits(d, 0) && fits(d, step / 2));
        let down = (first..=below).all(|d| fits(0, d));
        let diagonal = (first..=right.min(below)).all(|d| fits(d, d));
        across && down && diagonal
    }

    /// (a δ + P) ⊛ (b δ + Q)'s spread into P: P's and Q's values by
    /// `weights` ([`combined`]) and S ⊛ T, S the radial one of them (P
    /// where `s_is_p`) and T the other, whose light lies within `t_reach`
    /// of the centre: the near part's composition with T, exact, and the
    /// far part's on the nodes, interpolated to every pixel.
    pub fn compose_into(
        &self,
        (p, q, s_is_p): (&mut [f32], &[f32], bool),
        t_reach: (usize, usize),
        weights: (f64, f64),
        extent: &Extent,
        composing: &mut Composing,
        control: &mut Control,
    ) -> Result<()> {
        let w = extent.width;
        let (cx, cy) = extent.centre();
        let (s, t) = if s_is_p { (&*p, q) } else { (q, &*p) };
        let pair = Pair {
            s,
            t,
            t_reach,
            extent,
        };
        let nodes = self.far_composed(&pair, composing, &mut control.part(0.0, 0.3))?;
        let near = self.near_composed(&pair, composing, &mut control.part(0.3, 0.9))?;
        control.check()?;
        let (mx, my) = (nodes.x_reach as i64, nodes.y_reach as i64);
        let span = nodes.x_reach * 2 + 1;
        // Per column: the node left of it (an index into a row of nodes)
        // and the share of the node right of it.
        let columns: Vec<(usize, f64)> = (0..w as i64)
            .map(|x| {
                let (node, share) = self.cell(x - cx as i64);
                ((node + mx) as usize, share)
            })
            .collect();
        let rows = Scratch::<(Vec<f64>, Vec<f64>)>::default();
        for_each_row(p, w, &mut control.part(0.9, 1.0), |y, row| {
            let (node, fy) = self.cell(y as i64 - cy as i64);
            let upper = &nodes.values[(node + my) as usize * span..][..span];
            let mut lent = rows.lend(Default::default);
            let (mixed, twice) = &mut *lent;
            // The row of nodes interpolated to this row first: a pixel on a
            // row of nodes takes nothing from the next row, which past the
            // last row does not exist.
            mixed.clear();
            if fy > 0.0 {
                let lower = &nodes.values[(node + my + 1) as usize * span..][..span];
                mixed.extend(
                    upper
                        .iter()
                        .zip(lower)
                        .map(|(&u, &l)| (1.0 - fy) * f64::from(u) + fy * f64::from(l)),
                );
            } else {
                mixed.extend(upper.iter().map(|&u| f64::from(u)));
            }
            // A last node right of the last column, so that every pixel
            // reads two.
            mixed.push(0.0);
            twice.clear();
            twice.extend(
                columns
                    .iter()
                    .map(|&(i, fx)| (1.0 - fx) * mixed[i] + fx * mixed[i + 1]),
            );
            if let Some(line) = near.row(y) {
                for (value, &n) in twice[near.left..].iter_mut().zip(line) {
                    *value += f64::from(n);
                }
            }
            let q = &q[y * w..(y + 1) * w];
            for ((value, &q), &twice) in row.iter_mut().zip(q).zip(twice.iter()) {
                *value = combined(weights, *value, q, twice);
            }
        })?;
        Ok(())
    }

    /// The near part of S composed with T over the box that holds their
    /// sum of reaches: exact, as [`super::split`]'s composition is.
    fn near_composed(
        &self,
        pair: &Pair,
        composing: &mut Composing,
        control: &mut Control,
    ) -> Result<Boxed> {
        let Pair {
            s,
            t,
            t_reach: (tx, ty),
            extent,
        } = *pair;
        let (w, h) = (extent.width, extent.height);
        let (cx, cy) = extent.centre();
        // Within the extent on every side: `near` is at most a quarter of
        // the shortest side's reach.
        let k = 2 * self.near;
        let side = 2 * k + 1;
        let mut part = vec![0.0f32; side * side];
        for (j, line) in part.chunks_mut(side).enumerate() {
            let dy = j as f64 - k as f64;
            let from = (cy + j - k) * w + cx - k;
            for (i, (value, &v)) in line.iter_mut().zip(&s[from..from + side]).enumerate() {
                let dx = i as f64 - k as f64;
                *value = (f64::from(v) * (1.0 - self.far_share((dx * dx + dy * dy).sqrt()))) as f32;
            }
        }
        let (left, right) = ((k + tx).min(cx), (k + tx).min(w - 1 - cx));
        let (top, bottom) = ((k + ty).min(cy), (k + ty).min(h - 1 - cy));
        let (bw, bh) = (left + right + 1, top + bottom + 1);
        let (x0, y0) = (cx - left, cy - top);
        let cut;
        let image = if (bw, bh) == (w, h) {
            t
        } else {
            cut = (y0..y0 + bh)
                .flat_map(|y| &t[y * w + x0..y * w + x0 + bw])
                .copied()
                .collect::<Vec<f32>>();
            &cut
        };
        let values = convolve::compose(&part, (side, side), image, (bw, bh), composing, control)?;
        Ok(Boxed {
            values,
            left: x0,
            top: y0,
            width: bw,
        })
    }

    /// The far part of S at its nodes composed with T spread onto them
    /// bilinearly (mass and first moments kept): S ⊛ T at every node of
    /// a grid that covers the extent.
    fn far_composed(
        &self,
        pair: &Pair,
        composing: &mut Composing,
        control: &mut Control,
    ) -> Result<Nodes> {
        let step = self.step;
        let (s, t, extent) = (pair.s, pair.t, pair.extent);
        let ((w, h), (cx, cy)) = ((extent.width, extent.height), extent.centre());
        let (tx, ty) = pair.t_reach;
        // The nodes cover a pixel beyond the extent's farthest side, so
        // that every pixel lies between nodes; S's are 0 beyond the extent.
        let (mx, my) = (
            cx.max(w - 1 - cx).div_ceil(step),
            cy.max(h - 1 - cy).div_ceil(step),
        );
        let (span, rows) = (2 * mx + 1, 2 * my + 1);
        let far_nodes: Vec<f32> = (0..span * rows)
            .into_par_iter()
            .map(|n| {
                let (dx, dy) = (
                    ((n % span) as i64 - mx as i64) * step as i64,
                    ((n / span) as i64 - my as i64) * step as i64,
                );
                let (x, y) = (cx as i64 + dx, cy as i64 + dy);
                if x < 0 || y < 0 || x >= w as i64 || y >= h as i64 {
                    return 0.0;
                }
                let r = ((dx * dx + dy * dy) as f64).sqrt();
                (f64::from(s[y as usize * w + x as usize]) * self.far_share(r)) as f32
            })
            .collect();
        // T spread onto the nodes within its reach: the transforms' kernel,
        // so that they pad the grid by T's reach rather than by S's.
        let (ux, uy) = (
            (tx.div_ceil(step) + 1).min(mx),
            (ty.div_ceil(step) + 1).min(my),
        );
        let (tw, th) = (2 * ux + 1, 2 * uy + 1);
        let (left, right) = (cx - tx.min(cx), cx + tx.min(w - 1 - cx));
        let (top, bottom) = (cy - ty.min(cy), cy + ty.min(h - 1 - cy));
        // Per column: the node left of it and the share of the node right
        // of it.
        let columns: Vec<(usize, f64)> = (left..=right)
            .map(|x| {
                let (node, share) = self.cell(x as i64 - cx as i64);
                ((node + ux as i64) as usize, share)
            })
            .collect();
        let mut spread = zeros(tw * th)?;
        for_each_row(&mut spread, tw, &mut control.part(0.0, 0.5), |j, row| {
            // The pixel rows within a step of this row of nodes, summed by
            // their shares of it, then each column shared by its nodes.
            let centre = cy as i64 + (j as i64 - uy as i64) * step as i64;
            let mut line = vec![0.0f64; columns.len()];
            let first = (centre - step as i64 + 1).max(top as i64);
            let last = (centre + step as i64 - 1).min(bottom as i64);
            for y in first..=last {
                let wy = 1.0 - (y - centre).unsigned_abs() as f64 / step as f64;
                let pixels = &t[y as usize * w + left..=y as usize * w + right];
                for (sum, &v) in line.iter_mut().zip(pixels) {
                    *sum += wy * f64::from(v);
                }
            }
            // A node past the last, which only a share of 0 reaches.
            let mut sums = vec![0.0f64; tw + 1];
            for (&v, &(i, fx)) in line.iter().zip(&columns) {
                sums[i] += v * (1.0 - fx);
                sums[i + 1] += v * fx;
            }
            for (value, sum) in row.iter_mut().zip(sums) {
                *value = sum as f32;
            }
        })?;
        let values = convolve::compose(
            &spread,
            (tw, th),
            &far_nodes,
            (span, rows),
            composing,
            &mut control.part(0.5, 1.0),
        )?;
        Ok(Nodes {
            values,
            x_reach: mx,
            y_reach: my,
        })
    }
}

/// The planes composed: S, the radial one, and T, whose light lies
/// within `t_reach` (columns, rows) of the centre of `extent`.
#[derive(Clone, Copy)]
struct Pair<'a> {
    s: &'a [f32],
    t: &'a [f32],
    t_reach: (usize, usize),
    extent: &'a Extent,
}

/// S ⊛ T at the nodes, `x_reach` and `y_reach` nodes either side of the
/// centre's.
struct Nodes {
    values: Vec<f32>,
    x_reach: usize,
    y_reach: usize,
}

/// A box of the extent, `width` wide, from (`left`, `top`).
struct Boxed {
    values: Vec<f32>,
    left: usize,
    top: usize,
    width: usize,
}

impl Boxed {
    /// The box's part of the extent's row `y`, from column `left`.
    fn row(&self, y: usize) -> Option<&[f32]> {
        let j = y.checked_sub(self.top)?;
        self.values.get(j * self.width..(j + 1) * self.width)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::Cancel;

    /// A plane of `extent` from f at each pixel's offset from the centre.
    fn plane(extent: &Extent, f: impl Fn(f64, f64) -> f64) -> Vec<f32> {
        let (cx, cy) = extent.centre();
        (0..extent.width * extent.height)
            .map(|i| {
                let (x, y) = (i % extent.width, i / extent.width);
                f(x as f64 - cx as f64, y as f64 - cy as f64) as f32
            })
            .collect()
    }

    /// A bloom's shape: Moffat's, R = 6 px, β = 2.
    fn moffat(x: f64, y: f64) -> f64 {
        1e-3 / (1.0 + (x * x + y * y) / 36.0).powi(2)
    }

    /// S ⊛ T at pixel (x, y) of the extent, in f64, summed directly.
    fn direct(s: &[f32], t: &[f32], extent: &Extent, (x, y): (usize, usize)) -> f64 {
        let (w, h) = (extent.width as i64, extent.height as i64);
        let (cx, cy) = (w / 2, h / 2);
        let mut sum = 0.0;
        for (j, row) in t.chunks(w as usize).enumerate() {
            let sy = y as i64 - (j as i64 - cy);
            if sy < 0 || sy >= h {
                continue;
            }
            for (i, &v) in row.iter().enumerate().filter(|(_, v)| **v != 0.0) {
                let sx = x as i64 - (i as i64 - cx);
                if sx >= 0 && sx < w {
                    sum += f64::from(v) * f64::from(s[(sy * w + sx) as usize]);
                }
            }
        }
        sum
    }

    #[test]
    fn the_coarse_composition_is_the_direct_sum() {
        let extent = Extent::new(1401, 1001).unwrap();
        let s = moffat;
        // A corona's 14 lobes fading over 8 px, lit within 150 px; and
        // fading over 200 px, lit over the whole extent.
        let lobes = |x: f64, y: f64| 0.2 + libm::cos(7.0 * libm::atan2(y, x)).powi(2);
        let short = |x: f64, y: f64| {
            let r = (x * x + y * y).sqrt();
            if r > 150.0 {
                0.0
            } else {
                libm::exp(-r / 8.0) * lobes(x, y) * 1e-3
            }
        };
        let long = |x: f64, y: f64| libm::exp(-(x * x + y * y).sqrt() / 200.0) * lobes(x, y) * 1e-6;
        let s = plane(&extent, s);
        let cancel = Cancel::new();
        for t in [plane(&extent, short), plane(&extent, long)] {
            let t_reach = reach(&t, &extent);
            let coarse = Coarse::fitting(&s, t_reach, &extent).unwrap();
            assert!(coarse.step > 1, "{coarse:?}");
            let mut p = s.clone();
            coarse
                .compose_into(
                    (&mut p, &t, true),
                    t_reach,
                    (0.0, 0.0),
                    &extent,
                    &mut Composing::cpu(),
                    &mut Control::quiet(&cancel),
                )
                .unwrap();
            // Within the bound of docs/physics.md, and within the box of the
            // near part's transforms their f32 round-off, a few 10⁻⁸ of the
            // largest value, which the exact composition has everywhere;
            // beyond the edge band, where T's light would cross the edge
            // within a cell of the nodes: 7 % at the edge itself for the
            // short T, 10⁻⁴ at 49 px.
            let (cx, cy) = extent.centre();
            let largest = direct(&s, &t, &extent, (cx, cy));
            let points = (0..40)
                .map(|k| (cx + k * 15, cy))
                .chain((0..40).map(|k| (cx, cy + k * 10)))
                .chain((0..60).map(|k| ((k * 397) % 1401, (k * 211) % 1001)));
            let band = 64;
            let inside = |&(x, y): &(usize, usize)| {
                x.min(y)
                    .min(extent.width - 1 - x)
                    .min(extent.height - 1 - y)
                    >= band
            };
            for (x, y) in points.filter(inside) {
                let exact = direct(&s, &t, &extent, (x, y));
                let error = (f64::from(p[y * extent.width + x]) - exact).abs();
                let boxed = x.abs_diff(cx) <= 2 * coarse.near + t_reach.0
                    && y.abs_diff(cy) <= 2 * coarse.near + t_reach.1;
                let round_off = if boxed { 5e-8 * largest } else { 1e-6 * exact };
                assert!(
                    error <= 2.0 * TOLERANCE * exact + round_off,
                    "{coarse:?} at ({x}, {y}): {} against {exact}",
                    p[y * extent.width + x]
                );
            }
        }
    }

    #[test]
    fn a_ring_far_from_the_centre_is_composed_exactly() {
        let extent = Extent::new(1401, 1001).unwrap();
        let ring = |x: f64, y: f64| {
            let r = (x * x + y * y).sqrt();
            moffat(x, y) + 1e-5 * libm::exp(-((r - 300.0) / 2.0).powi(2))
        };
        assert!(Coarse::fitting(&plane(&extent, moffat), (10, 10), &extent).is_some());
        assert_eq!(
            Coarse::fitting(&plane(&extent, ring), (10, 10), &extent),
            None
        );
        // A small kernel is composed exactly whatever its shape.
        let bloom = plane(&extent, moffat);
        assert_eq!(Coarse::plan(&bloom, &bloom, &extent), None);
    }
}
