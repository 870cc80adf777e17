//! The near field of the brightest pixels, added exactly (docs/physics.md
//! §8): an f32 FFT leaves round-off of about u·‖B‖₂ times the light the
//! kernel moves in every pixel, so a few lamps of 10⁵ cd/m² drown a night
//! sky of 10⁻³. Their light within a small window goes out by direct sums,
//! exact in f32; only the kernel beyond the window, which carries a few
//! thousandths of the light, sees their values in a transform. Everything
//! else goes through the transform with the whole kernel as before.

use rayon::prelude::*;

use crate::control::Cancel;

/// The kernel split at a radius: a window around its centre, added at the
/// lamps directly, and the rest, which the engine transforms.
pub(crate) struct Near {
    /// Half the window's side, pixels.
    pub radius: usize,
    /// Per kernel plane, the (2r + 1)² window around the centre, rows
    /// downwards as in an image, with the centre weight zero (the engine
    /// applies it to every pixel).
    windows: Vec<Vec<f32>>,
}

impl Near {
    /// The windows of `planes` (row-major, `size`, centre at the middle) at
    /// `radius`; `None` where the window does not fit inside the kernel or
    /// the planes are not `count` planes of that size (an engine's kernel).
    pub fn fitting(
        planes: &[&[f32]],
        size: (usize, usize),
        radius: usize,
        count: usize,
    ) -> Option<Near> {
        let (cx, cy) = (size.0 / 2, size.1 / 2);
        let fits = radius <= cx.min(cy).min(size.0 - 1 - cx).min(size.1 - 1 - cy);
        let shaped = planes.len() == count && planes.iter().all(|p| p.len() == size.0 * size.1);
        (fits && shaped).then(|| Near::new(planes, size, radius))
    }

    /// The windows of `planes` (row-major, `size`, centre at the middle) at
    /// `radius`, which must fit inside the kernel.
    fn new(planes: &[&[f32]], (kw, kh): (usize, usize), radius: usize) -> Near {
        let (cx, cy) = (kw / 2, kh / 2);
        let side = 2 * radius + 1;
        let windows = planes
            .iter()
            .map(|plane| {
                let mut window = Vec::with_capacity(side * side);
                for j in cy - radius..=cy + radius {
                    window.extend_from_slice(&plane[j * kw + cx - radius..=j * kw + cx + radius]);
                }
                window[radius * side + radius] = 0.0;
                window
            })
            .collect();
        Near { radius, windows }
    }

    /// Kernel plane `plane`'s window: (2r + 1)² weights, rows downwards,
    /// the centre's 0.
    pub fn window(&self, plane: usize) -> &[f32] {
        &self.windows[plane]
    }

    /// Kernel plane `plane` less its window (and centre): what the
    /// transform carries for the lamps. The CPU's engine leaves the
    /// window out as it places the rows (`Placement::hole`) instead.
    #[cfg(feature = "gpu")]
    pub fn far_plane(&self, plane: &[f32], (kw, kh): (usize, usize)) -> Vec<f32> {
        let (cx, cy, r) = (kw / 2, kh / 2, self.radius);
        let mut far = plane.to_vec();
        for j in cy - r..=cy + r {
            far[j * kw + cx - r..=j * kw + cx + r]
                .iter_mut()
                .for_each(|v| *v = 0.0);
        }
        far
    }

    /// Adds to `out` (row-major, `width` wide) the window of kernel plane
    /// `plane` at every lamp (row-major indices, ascending), weighted by
    /// its bright part `bright(i)`. Each output row adds its lamps in index
    /// order: the same bytes with any number of threads.
    #[allow(clippy::too_many_arguments)]
    pub fn add(
        &self,
        plane: usize,
        lamps: &[usize],
        bright: &(dyn Fn(usize) -> f32 + Sync),
        out: &mut [f32],
        width: usize,
        cancel: &Cancel,
    ) {
        let r = self.radius;
        let side = 2 * r + 1;
        let window = &self.windows[plane];
        out.par_chunks_mut(width).enumerate().for_each(|(y, row)| {
            if cancel.is_cancelled() {
                return;
            }
            let first = lamps.partition_point(|&i| i / width + r < y);
            let last = lamps.partition_point(|&i| i / width <= y + r);
            for &i in &lamps[first..last] {
                let (lx, ly) = (i % width, i / width);
                let weights = &window[(y + r - ly) * side..(y + r - ly + 1) * side];
                let b = bright(i);
                // Columns lx − r ..= lx + r, clipped to the frame.
                let skip = r.saturating_sub(lx);
                let start = lx + skip - r;
                let end = (lx + r + 1).min(width);
                for (o, w) in row[start..end].iter_mut().zip(&weights[skip..]) {
                    *o += b * w;
                }
            }
        });
    }
}
