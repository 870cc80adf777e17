//! Whether f32 is precise enough for a scene (docs/physics.md §8): FFT
//! round-off is about the unit round-off times the bright part, enough to
//! drown a 10⁻² cd/m² night sky next to a 10⁹ cd/m² sun. When it would
//! reach the dark pixels, the brightest pixels' near light is added exactly
//! (see [`crate::convolve`]'s near field), or, beyond that, the f64 engine
//! runs.

use rayon::prelude::*;

use super::threshold::Threshold;
use crate::image::PixelLuminance;
use crate::kernel::Kernel;

/// The share of the dark level the round-off may reach before f64 is used:
/// a tenth of the 1 % that a user could see.
const DARK_TOLERANCE: f64 = 1e-3;

/// The round-off an f32 FFT convolution leaves in a pixel, as an upper
/// estimate: per pixel about u·√(log₂ N)·‖B‖₂·m/√N for N padded samples,
/// bright part B (‖·‖₂ over the image) and moved mass m (the kernel less its
/// centre sums to m), u = 2⁻²⁴; times 4 to cover the largest pixel rather
/// than the typical one (checked against direct sums in tests/apply.rs).
pub fn f32_round_off(bright_l2: f64, moved: f64, padded: (usize, usize)) -> f64 {
    let n = (padded.0 * padded.1) as f64;
    4.0 * f64::from(f32::EPSILON) / 2.0 * libm::log2(n).sqrt() * bright_l2 * moved / n.sqrt()
}

/// How an FFT application computes, from the scene's range.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Route {
    /// f32 throughout: its round-off stays below the dark pixels.
    Single,
    /// f32, with the light of `lamps` (row-major indices, ascending)
    /// within `radius` of them added exactly, the rest transformed.
    Lamps { radius: usize, lamps: Vec<usize> },
    /// f64: even with the lamps apart, f32 would show.
    Double,
}

/// What the range check reads: the luminance, the threshold that makes the
/// bright part B, ‖B‖₂², the light the kernel moves (1 less its smallest
/// centre weight) and the f32 engine's grid.
pub(super) struct Scene<'a> {
    pub luminance: &'a PixelLuminance<'a>,
    pub threshold: &'a Threshold,
    pub pixels: usize,
    pub squares: f64,
    pub moved: f64,
    pub padded: (usize, usize),
}

/// Bins of the bright part's luminance: its f32 exponent and two bits of
/// mantissa, a quarter of an octave each.
const BINS: usize = 1 << 10;

fn bin(b: f32) -> usize {
    (b.to_bits() >> 21) as usize & (BINS - 1)
}

/// The route for `scene`, where f32 round-off (its expected size,
/// [`f32_round_off`]) must stay below [`DARK_TOLERANCE`] of the dark level,
/// the 1st percentile of the positive luminances (sampled). When the whole
/// bright part would exceed it, the brightest pixels are set apart as
/// lamps: the rest B_lo goes through the whole kernel, the lamps only
/// through the kernel beyond a window, and each band gets half the
/// tolerance. `near` gives the windows to choose from, smallest first:
/// (radius, the light the kernel moves beyond it). Only as many lamps as
/// `max_lamps(radius)` allows; else f64.
pub(super) fn route(
    scene: &Scene,
    near: impl FnOnce() -> Vec<(usize, f64)>,
    max_lamps: impl Fn(usize) -> usize,
) -> Route {
    let Some(dark) = dark_level(scene.luminance, scene.pixels) else {
        return Route::Single;
    };
    let tolerance = DARK_TOLERANCE * dark;
    let per_unit = f32_round_off(1.0, 1.0, scene.padded);
    let norm = scene.squares.sqrt();
    if per_unit * norm * scene.moved <= tolerance {
        return Route::Single;
    }
    // The lamps are at most all the bright light.
    let options = near();
    let Some(radius) = options
        .into_iter()
        .find(|(_, far)| per_unit * norm * far <= tolerance / 2.0)
        .map(|(radius, _)| radius)
    else {
        return Route::Double;
    };
    let allowed = (tolerance / 2.0 / (per_unit * scene.moved)).powi(2);
    let histogram = histogram(scene);
    let mut below = 0.0;
    let mut first = BINS;
    for (k, (_, squares)) in histogram.iter().enumerate() {
        if below + squares > allowed {
            first = k;
            break;
        }
        below += squares;
    }
    let count: usize = histogram[first..].iter().map(|(n, _)| n).sum();
    if count > max_lamps(radius) {
        return Route::Double;
    }
    let lamps = (0..scene.pixels)
        .into_par_iter()
        .filter(|&i| {
            let b = bright(scene, i);
            b > 0.0 && bin(b) >= first
        })
        .collect();
    Route::Lamps { radius, lamps }
}

/// The bright part of pixel `i`'s luminance.
fn bright(scene: &Scene, i: usize) -> f32 {
    scene.luminance.at(i) * scene.threshold.fraction(scene.luminance, i)
}

/// Per bin, the pixels and Σ of their squared bright luminance; summed in
/// fixed chunks in order, the same on any number of threads.
fn histogram(scene: &Scene) -> Vec<(usize, f64)> {
    let chunk = 1 << 16;
    let parts: Vec<Vec<(usize, f64)>> = (0..scene.pixels.div_ceil(chunk))
        .into_par_iter()
        .map(|c| {
            let mut part = vec![(0usize, 0.0f64); BINS];
            for i in c * chunk..((c + 1) * chunk).min(scene.pixels) {
                let b = bright(scene, i);
                if b > 0.0 {
                    let slot = &mut part[bin(b)];
                    slot.0 += 1;
                    slot.1 += f64::from(b) * f64::from(b);
                }
            }
            part
        })
        .collect();
    let mut total = vec![(0usize, 0.0f64); BINS];
    for part in parts {
        for (t, p) in total.iter_mut().zip(part) {
            t.0 += p.0;
            t.1 += p.1;
        }
    }
    total
}

/// The 1st percentile of the positive luminances, sampled; `None` when
/// there are none.
fn dark_level(luminance: &PixelLuminance, pixels: usize) -> Option<f64> {
    let stride = (pixels / 65536).max(1);
    let mut sample: Vec<f32> = (0..pixels)
        .step_by(stride)
        .map(|i| luminance.at(i))
        .filter(|&y| y > 0.0)
        .collect();
    if sample.is_empty() {
        return None;
    }
    let at = sample.len() / 100;
    let (_, dark, _) = sample.select_nth_unstable_by(at, f32::total_cmp);
    Some(f64::from(*dark))
}

/// The near windows `kernel` can be split at, smallest first: radii of 4,
/// 8, … 128 pixels that fit inside it, each with the light the kernel moves
/// beyond it.
pub(super) fn split_radii(kernel: &Kernel) -> Vec<(usize, f64)> {
    let radii = [4usize, 8, 16, 32, 64, 128];
    radii
        .into_iter()
        .zip(kernel.beyond_each(&radii))
        .map_while(|(r, beyond)| Some((r, beyond?)))
        .collect()
}
