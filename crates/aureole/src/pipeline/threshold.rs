//! The threshold (docs/physics.md §7): the light of pixels brighter than T
//! is spread, the rest stays, O = I·[Y ≤ T] + K ⊛ (I·[Y > T]); with a soft
//! knee the spread fraction rises smoothly above T.

use rayon::prelude::*;

use crate::image::PixelLuminance;

/// The fraction of a pixel's light that is spread, from its luminance `y`
/// (file units): 0 at or below the threshold, 1 above it, or a smoothstep
/// from T to T·(1 + knee).
pub fn spread_fraction(y: f64, threshold: f64, knee: f64) -> f32 {
    if y <= threshold {
        return 0.0;
    }
    let width = knee * threshold;
    if width <= 0.0 || y >= threshold + width {
        return 1.0;
    }
    let t = (y - threshold) / width;
    (t * t * (3.0 - 2.0 * t)) as f32
}

/// What one pass over the luminance finds.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Survey {
    /// Pixels with some light spread.
    pub spread: usize,
    /// Pixels with all their light spread.
    pub full: usize,
    /// Σ of the squared spread luminance: ‖B‖₂², for the round-off estimate.
    pub squares: f64,
    /// Σ over spread pixels of the output pixels their kernel reaches (the
    /// kernel's reach is a rectangle: row sums of its widths times its
    /// height on that row), for the cost of splatting.
    pub splat_area: usize,
    /// Σ over spread pixels of the output rows their kernel reaches: the
    /// visits splatting by rows makes.
    pub splat_rows: usize,
}

impl Survey {
    fn add(self, other: Survey) -> Survey {
        Survey {
            spread: self.spread + other.spread,
            full: self.full + other.full,
            squares: self.squares + other.squares,
            splat_area: self.splat_area + other.splat_area,
            splat_rows: self.splat_rows + other.splat_rows,
        }
    }
}

/// The threshold of one application: T and the knee, in file units.
#[derive(Debug, Clone, Copy)]
pub(super) struct Threshold {
    pub level: f64,
    pub knee: f64,
}

impl Threshold {
    /// The spread fraction of pixel `i`.
    #[inline]
    pub fn fraction(&self, luminance: &PixelLuminance, i: usize) -> f32 {
        spread_fraction(f64::from(luminance.at(i)), self.level, self.knee)
    }

    /// Counts row by row, without a plane of fractions (with every pixel
    /// fully spread, threshold 0, none is needed), what spreading costs:
    /// `kernel` is the kernel's size and `centre` its centre.
    pub fn survey(
        &self,
        luminance: &PixelLuminance,
        (w, h): (usize, usize),
        (kw, kh): (usize, usize),
        (cx, cy): (usize, usize),
    ) -> Survey {
        (0..h)
            .into_par_iter()
            .map(|y| {
                let mut row = Survey::default();
                for x in 0..w {
                    let y_lum = f64::from(luminance.at(y * w + x));
                    let f = spread_fraction(y_lum, self.level, self.knee);
                    if f > 0.0 {
                        let b = y_lum * f64::from(f);
                        row.squares += b * b;
                        row.spread += 1;
                        row.full += usize::from(f == 1.0);
                        row.splat_area += covered(x, kw, cx, w);
                    }
                }
                let rows = covered(y, kh, cy, h);
                row.splat_area *= rows;
                row.splat_rows = row.spread * rows;
                row
            })
            .collect::<Vec<Survey>>()
            .into_iter()
            // In row order: the same sums with any number of threads.
            .fold(Survey::default(), Survey::add)
    }

    /// The spread fraction of every pixel.
    pub fn fractions(&self, luminance: &PixelLuminance, pixels: usize) -> Vec<f32> {
        (0..pixels)
            .into_par_iter()
            .map(|i| self.fraction(luminance, i))
            .collect()
    }
}

/// How many of the `n` output positions p + i − c, for kernel indices i in
/// [0, k), fall inside [0, n): a kernel's reach from p along one axis.
fn covered(p: usize, k: usize, c: usize, n: usize) -> usize {
    (p + k - c).min(n).saturating_sub(p.saturating_sub(c))
}
