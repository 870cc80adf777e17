//! Splatting (docs/physics.md §8): the kernel added, weighted, at every
//! bright pixel, O = I − B + Σ over bright pixels of B·K. Exact in f32, and
//! cheaper than the FFT for a few bright pixels or a small kernel. Its cost
//! is the area the bright pixels' kernels cover in the frame: each output
//! row visits only the source rows within the kernel's height.

use rayon::prelude::*;

use super::threshold::Threshold;
use crate::control::{for_each_row, Control};
use crate::convolve::Term;
use crate::error::Result;
use crate::image::{Image, PixelLuminance};
use crate::kernel::Kernel;

/// The image through `kernel`, splatted row by row: each output row adds
/// the bright pixels in a fixed order, so the bits are the same with any
/// number of threads. `terms` are each output plane's kernel planes and
/// weights; the results go into the planes of `recycled`.
pub(super) fn splat(
    image: &Image,
    luminance: &PixelLuminance,
    threshold: Threshold,
    kernel: &Kernel,
    terms: &[Vec<Term>],
    recycled: Vec<Vec<f32>>,
    control: &mut Control,
) -> Result<Vec<Vec<f32>>> {
    let (w, h) = (image.width, image.height);
    let (kw, kh) = (kernel.width(), kernel.height());
    let (cx, cy) = kernel.centre();
    let planes = kernel.planes();
    // The bright pixels of each row: column and spread fraction.
    let rows: Vec<Vec<(usize, f32)>> = (0..h)
        .into_par_iter()
        .map(|y| {
            (0..w)
                .filter_map(|x| {
                    let f = threshold.fraction(luminance, y * w + x);
                    (f > 0.0).then_some((x, f))
                })
                .collect()
        })
        .collect();
    let mut outputs = copies(&image.planes, recycled);
    let cancel = control.cancel();
    let share = 1.0 / outputs.len().max(1) as f64;
    for (c, ((out, plane), terms)) in outputs.iter_mut().zip(&image.planes).zip(terms).enumerate() {
        let mut part = control.part(c as f64 * share, (c + 1) as f64 * share);
        for_each_row(out, w, &mut part, |y, row| {
            // The light that leaves: the bright part of this row.
            for &(x, f) in &rows[y] {
                row[x] -= plane[y * w + x] * f;
            }
            // Kernel row j lands on output row by + j − cy: only the source
            // rows by from y + cy − (kh − 1) to y + cy reach this one. They
            // are visited top to bottom, so every output row adds its
            // bright pixels in row-major order.
            let reach = (y + cy + 1).saturating_sub(kh)..(y + cy + 1).min(h);
            for by in reach {
                if cancel.is_cancelled() {
                    return;
                }
                let j = y + cy - by;
                for &(x, f) in &rows[by] {
                    let value = plane[by * w + x] * f;
                    let first = x.saturating_sub(cx);
                    let last = (x + kw - cx).min(w);
                    if first >= last {
                        continue;
                    }
                    let start = first + cx - x;
                    for term in terms {
                        let weights = &planes[term.kernel_plane]
                            [j * kw + start..j * kw + start + (last - first)];
                        let v = value * term.weight;
                        for (o, &kv) in row[first..last].iter_mut().zip(weights) {
                            *o += v * kv;
                        }
                    }
                }
            }
        })?;
    }
    Ok(outputs)
}

/// `planes` copied into the planes of `recycled` (resized to match).
pub(super) fn copies(planes: &[Vec<f32>], mut recycled: Vec<Vec<f32>>) -> Vec<Vec<f32>> {
    recycled.truncate(planes.len());
    recycled.resize_with(planes.len(), Vec::new);
    for (out, plane) in recycled.iter_mut().zip(planes) {
        out.clear();
        out.extend_from_slice(plane);
    }
    recycled
}
