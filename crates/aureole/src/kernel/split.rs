//! A kernel while it is built: per plane, the unspread weight at the centre
//! and the spread plane, kept apart so that composing never mixes the
//! large centre weight into the round-off of the small spread values. The
//! effects of a chain compose by convolution.

use rayon::prelude::*;

use super::coarse::Coarse;
use super::raster::shape_plane;
use super::{Extent, Kernel};
use crate::control::Control;
use crate::convolve::{self, Composing};
use crate::error::Result;
use crate::image::zeros;
use crate::optics::shape::SpreadShape;

/// A PSF on the kernel grid, split into centre weight and spread plane.
pub(super) struct SplitKernel {
    extent: Extent,
    planes: Vec<Layer>,
}

struct Layer {
    centre: f64,
    /// f32 like the kernel it becomes: half the memory of f64 while a 4K
    /// chain is built, and sums over it run in f64.
    spread: Vec<f32>,
    /// Whether the spread is a shape of the distance from the centre alone
    /// (a composition of such shapes too): one such may compose coarsely
    /// far from the centre ([`Coarse`]).
    radial: bool,
}

impl SplitKernel {
    /// K = (1 − ε)·[centre] + ε·F/ΣF of a shape f.
    pub fn from_shape(
        epsilon: f64,
        shape: &dyn SpreadShape,
        extent: &Extent,
        control: &mut Control,
    ) -> Result<SplitKernel> {
        let spread = if epsilon > 0.0 {
            shape_plane(shape, extent, epsilon, control)?
        } else {
            None
        };
        let layer = match spread {
            Some(spread) => Layer {
                centre: 1.0 - epsilon,
                spread,
                radial: shape.radial(),
            },
            // Nothing spread: all light stays.
            None => Layer {
                centre: 1.0,
                spread: zeros(extent.width * extent.height)?,
                radial: true,
            },
        };
        Ok(SplitKernel {
            extent: *extent,
            planes: vec![layer],
        })
    }

    /// One plane per shape, each K = (1 − ε)·[centre] + ε·F/ΣF: a PSF
    /// whose colours spread differently.
    pub fn from_shapes(
        planes: &[(f64, Box<dyn SpreadShape>)],
        extent: &Extent,
        control: &mut Control,
    ) -> Result<SplitKernel> {
        let share = 1.0 / planes.len().max(1) as f64;
        let mut layers = Vec::with_capacity(planes.len());
        for (c, (epsilon, shape)) in planes.iter().enumerate() {
            let mut part = control.part(c as f64 * share, (c + 1) as f64 * share);
            let one = SplitKernel::from_shape(*epsilon, shape.as_ref(), extent, &mut part)?;
            layers.extend(one.planes);
        }
        Ok(SplitKernel {
            extent: *extent,
            planes: layers,
        })
    }

    /// A PSF that is all pattern (no unspread part): planes summing to 1.
    pub fn from_pattern(planes: Vec<Vec<f64>>, extent: &Extent) -> SplitKernel {
        SplitKernel {
            extent: *extent,
            planes: planes
                .into_iter()
                .map(|plane| Layer {
                    centre: 0.0,
                    spread: plane.par_iter().map(|&v| v as f32).collect(),
                    radial: false,
                })
                .collect(),
        }
    }

    /// This PSF followed by `next` in the optical chain: their convolution.
    /// (a δ + S) ⊛ (b δ + T) = ab δ + a T + b S + S ⊛ T over the extent,
    /// whose light beyond it leaves, like any spread light. A plane of a
    /// one-plane PSF pairs with every plane of the other. This PSF's
    /// spread planes become the result's where they can.
    pub fn then(
        self,
        next: &SplitKernel,
        composing: &mut Composing,
        control: &mut Control,
    ) -> Result<SplitKernel> {
        let count = self.planes.len().max(next.planes.len());
        let extent = self.extent;
        let mut own = self.planes;
        // A one-plane PSF's plane pairs with every plane of `next`: copies
        // for all but the last.
        while let Some(last) = own.last().filter(|_| own.len() < count) {
            let copy = Layer {
                spread: last.spread.clone(),
                ..*last
            };
            own.push(copy);
        }
        let share = 1.0 / count as f64;
        let planes = own
            .into_iter()
            .enumerate()
            .map(|(c, a)| {
                let b = &next.planes[c.min(next.planes.len() - 1)];
                let mut part = control.part(c as f64 * share, (c + 1) as f64 * share);
                compose_layers(a, b, &extent, composing, &mut part)
            })
            .collect::<Result<_>>()?;
        Ok(SplitKernel { extent, planes })
    }

    /// The kernel: each plane's spread part with its centre weight added.
    pub fn into_kernel(self) -> Kernel {
        let extent = self.extent;
        let (cx, cy) = extent.centre();
        let centre = cy * extent.width + cx;
        let planes = self
            .planes
            .into_iter()
            .map(|layer| {
                let mut plane = layer.spread;
                plane[centre] = (f64::from(plane[centre]) + layer.centre) as f32;
                plane
            })
            .collect();
        Kernel {
            width: extent.width,
            height: extent.height,
            planes,
        }
    }
}

/// One layer followed by another: (a δ + P) ⊛ (b δ + Q), P ⊛ Q computed
/// coarsely far from the centre where one of them is radial and smooth
/// enough there ([`Coarse`]), else exactly; the result in P's memory.
fn compose_layers(
    mut a: Layer,
    b: &Layer,
    extent: &Extent,
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Layer> {
    let lit = |plane: &[f32]| plane.par_iter().any(|&v| v > 0.0);
    let weights = (b.centre, a.centre);
    let layer = |spread| Layer {
        centre: a.centre * b.centre,
        radial: a.radial && b.radial,
        spread,
    };
    if !(lit(&a.spread) && lit(&b.spread)) {
        a.spread
            .par_iter_mut()
            .zip(&b.spread)
            .for_each(|(p, &q)| *p = combined(weights, *p, q, 0.0));
        return Ok(layer(a.spread));
    }
    if a.radial || b.radial {
        let (s, t) = if a.radial {
            (&a.spread, &b.spread)
        } else {
            (&b.spread, &a.spread)
        };
        if let Some((coarse, t_reach)) = Coarse::plan(s, t, extent) {
            coarse.compose_into(
                (&mut a.spread, &b.spread, a.radial),
                t_reach,
                weights,
                extent,
                composing,
                control,
            )?;
            return Ok(layer(a.spread));
        }
    }
    let mut twice = compose(&a.spread, &b.spread, extent, composing, control)?;
    twice
        .par_iter_mut()
        .zip(&a.spread)
        .zip(&b.spread)
        .for_each(|((v, &p), &q)| *v = combined(weights, p, q, f64::from(*v)));
    Ok(layer(twice))
}

/// A composed spread's value from P, Q and P ⊛ Q there: `weights` are
/// those of P and Q (each the other's centre weight). FFT round-off
/// leaves tiny negatives in P ⊛ Q where the true value is ~0; light is
/// never negative.
pub(super) fn combined((wp, wq): (f64, f64), p: f32, q: f32, twice: f64) -> f32 {
    (wp * f64::from(p) + wq * f64::from(q) + twice.max(0.0)) as f32
}

/// S ⊛ T over the extent, both centred: the linear convolution in f32, zero
/// padded so that nothing wraps. Its round-off, ~10⁻⁷ of the largest value,
/// stays far below what the f32 convolution of an image with the kernel
/// adds anyway. The plane whose light reaches less far from the centre is
/// the kernel, cut to its reach: the transforms then pad the extent by
/// that reach rather than by the whole extent (a corona's rays of a few
/// hundred pixels over a full-frame bloom: a third of the samples).
fn compose(
    s: &[f32],
    t: &[f32],
    extent: &Extent,
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Vec<f32>> {
    let (rs, rt) = (reach(s, extent), reach(t, extent));
    let area = |(x, y): (usize, usize)| (2 * x + 1) * (2 * y + 1);
    let (image, kernel, (rx, ry)) = if area(rt) <= area(rs) {
        (s, t, rt)
    } else {
        (t, s, rs)
    };
    let (cx, cy) = extent.centre();
    let (kw, kh) = (2 * rx + 1, 2 * ry + 1);
    // The reach is the farther side's: the nearer side is padded with 0.
    let (w, h) = (extent.width, extent.height);
    let cut = if (kw, kh) == (w, h) {
        None
    } else {
        let mut cut = vec![0.0; kw * kh];
        for (row, j) in cut.chunks_mut(kw).zip(cy as i64 - ry as i64..) {
            if j < 0 || j >= h as i64 {
                continue;
            }
            let first = cx.saturating_sub(rx);
            let last = (cx + rx).min(w - 1);
            let at = j as usize * w;
            row[first + rx - cx..=last + rx - cx].copy_from_slice(&kernel[at + first..=at + last]);
        }
        Some(cut)
    };
    let kernel = cut.as_deref().unwrap_or(kernel);
    convolve::compose(kernel, (kw, kh), image, (w, h), composing, control)
}

/// How far from the centre a plane of the extent holds light, columns and
/// rows (0, 0 for none or the centre alone).
pub(super) fn reach(plane: &[f32], extent: &Extent) -> (usize, usize) {
    let (cx, cy) = extent.centre();
    plane
        .par_chunks(extent.width)
        .enumerate()
        .filter_map(|(j, row)| {
            let first = row.iter().position(|&v| v != 0.0)?;
            let last = row.iter().rposition(|&v| v != 0.0)?;
            Some((first.abs_diff(cx).max(last.abs_diff(cx)), j.abs_diff(cy)))
        })
        .reduce(|| (0, 0), |a, b| (a.0.max(b.0), a.1.max(b.1)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::Cancel;

    #[test]
    fn composing_is_the_linear_convolution_over_the_extent() {
        let at = |p: &[f32], w: usize, h: usize, x: i64, y: i64| {
            let (i, j) = (x + (w / 2) as i64, y + (h / 2) as i64);
            if i < 0 || j < 0 || i >= w as i64 || j >= h as i64 {
                0.0
            } else {
                f64::from(p[j as usize * w + i as usize])
            }
        };
        let cancel = Cancel::new();
        let mut quiet = Control::quiet(&cancel);
        // Full planes, and planes whose light reaches a pixel or two from
        // the centre (the transform is then cut to the shorter reach).
        let cases = [(1, 1), (5, 4), (8, 7), (12, 9), (3, 16), (15, 11), (9, 13)];
        for (n, (w, h)) in cases.into_iter().enumerate() {
            let near =
                |i: usize, r: usize| (i % w).abs_diff(w / 2) <= r && (i / w).abs_diff(h / 2) <= r;
            let s: Vec<f32> = (0..w * h)
                .map(|i| {
                    if n == 6 && !near(i, 2) {
                        0.0
                    } else {
                        (i * 37 % 11) as f32 + 0.25
                    }
                })
                .collect();
            let t: Vec<f32> = (0..w * h)
                .map(|i| {
                    if n == 5 && !near(i, 1) {
                        0.0
                    } else {
                        (i * 13 % 7) as f32 + 0.5
                    }
                })
                .collect();
            let extent = Extent::new(w, h).unwrap();
            let fast = compose(&s, &t, &extent, &mut Composing::cpu(), &mut quiet).unwrap();
            let (cx, cy) = ((w / 2) as i64, (h / 2) as i64);
            for oy in -cy..h as i64 - cy {
                for ox in -cx..w as i64 - cx {
                    let mut sum = 0.0;
                    for py in -cy..h as i64 - cy {
                        for px in -cx..w as i64 - cx {
                            sum += at(&s, w, h, px, py) * at(&t, w, h, ox - px, oy - py);
                        }
                    }
                    let f = f64::from(fast[(oy + cy) as usize * w + (ox + cx) as usize]);
                    assert!(
                        (f - sum).abs() < 1e-5 * sum.max(1.0),
                        "{w}x{h}: {f} vs {sum}"
                    );
                }
            }
        }
    }
}
