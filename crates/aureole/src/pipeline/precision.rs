//! Whether f32 is precise enough for a scene (docs/physics.md §8): FFT
//! round-off is about the unit round-off times the bright part, enough to
//! drown a 10⁻² cd/m² night sky next to a 10⁹ cd/m² sun. When it would
//! reach the dark pixels, the f64 engine runs instead.

use crate::image::PixelLuminance;

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
    4.0 * f64::from(f32::EPSILON) / 2.0 * n.log2().sqrt() * bright_l2 * moved / n.sqrt()
}

/// Whether f32 FFT round-off would show in the dark pixels of an image of
/// `pixels` pixels: its expected size ([`f32_round_off`]) must stay below
/// [`DARK_TOLERANCE`] of the dark level, the 1st percentile of the positive
/// luminances (sampled). `squares` is ‖B‖₂², `centres` the kernel's centre
/// weights and `padded` the f32 engine's grid.
pub(super) fn beyond_f32(
    luminance: &PixelLuminance,
    pixels: usize,
    squares: f64,
    centres: &[f32],
    padded: (usize, usize),
) -> bool {
    let stride = (pixels / 65536).max(1);
    let mut sample: Vec<f32> = (0..pixels)
        .step_by(stride)
        .map(|i| luminance.at(i))
        .filter(|&y| y > 0.0)
        .collect();
    if sample.is_empty() {
        return false;
    }
    let at = sample.len() / 100;
    let (_, dark, _) = sample.select_nth_unstable_by(at, f32::total_cmp);
    let moved = 1.0 - centres.iter().copied().fold(1.0f32, f32::min);
    let noise = f32_round_off(squares.sqrt(), f64::from(moved), padded);
    noise > DARK_TOLERANCE * f64::from(*dark)
}
