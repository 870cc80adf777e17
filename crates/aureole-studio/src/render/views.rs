//! What a render shows besides the picture through the camera: the kernel
//! with its profiles, the pixels the threshold spreads, the linear samples,
//! and the PNG the page receives.

use aureole::kernel::profile;
use aureole::Image;
use aureole_io::display::Picture;
use rayon::prelude::*;

use crate::error::StudioError;

/// The kernel's profiles as `aureole psf --profile` draws them
/// ([`aureole::kernel::profile`]), over its planes' mean: the radial one
/// out to `reach` px (at most 64 samples), the angular one in 2° steps on
/// the circle of reach/4, relative to its median.
pub(super) fn kernel_profiles(kernel: &aureole::Kernel, reach: usize) -> (Vec<f64>, Vec<f64>) {
    let planes = kernel.planes().len();
    let mean = |each: &dyn Fn(usize) -> Vec<f64>| {
        let mut sum = each(0);
        for plane in 1..planes {
            sum.iter_mut().zip(each(plane)).for_each(|(s, v)| *s += v);
        }
        sum.iter_mut().for_each(|s| *s /= planes as f64);
        sum
    };
    let rings = mean(&|plane| profile::radial_profile(kernel, plane));
    let reach = reach.clamp(2, rings.len().saturating_sub(1).max(2));
    let step = (reach as f64 / 64.0).max(1.0);
    let radial = (1..=reach.min(64))
        .filter_map(|k| rings.get((k as f64 * step).round() as usize).copied())
        .collect();
    const BINS: usize = 180;
    let radius = (reach as f64 / 4.0).max(2.0);
    let mut angular = mean(&|plane| {
        let samples = profile::angular_profile(kernel, plane, radius, BINS);
        samples.into_iter().map(|(_, value)| value).collect()
    });
    let mut sorted = angular.clone();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[BINS / 2].max(1e-300);
    angular.iter_mut().for_each(|v| *v /= median);
    (radial, angular)
}

/// `image` dimmed to a quarter, with the pixels the camera spreads (above
/// `threshold` cd/m², through the soft `knee` as the core spreads them) in
/// magenta at their own luminance, by the fraction of their light spread.
pub(super) fn spread_overlay(image: &Image, scale: f64, threshold: f64, knee: f64) -> Image {
    let luminance = image.luminance();
    let mut shown = Image::filled(image.width, image.height, aureole::Layout::Rgb, 0.0);
    shown.white_luminance = image.white_luminance;
    for (i, &y) in luminance.iter().enumerate() {
        let spread = aureole::pipeline::spread_fraction(f64::from(y) * scale, threshold, knee);
        for c in 0..3 {
            let own = 0.25 * image.planes[c.min(image.planes.len() - 1)][i];
            let magenta = if c == 1 { 0.2 * y } else { y };
            shown.planes[c][i] = spread * magenta + (1.0 - spread) * own;
        }
    }
    shown
}

/// The image in cd/m² as little-endian f32 R, G, B per pixel (a
/// luminance image in all three).
pub(super) fn linear_bytes(image: &Image, scale: f64) -> Vec<u8> {
    let width = image.width.max(1);
    let plane = |c: usize| &image.planes[c.min(image.planes.len() - 1)];
    let mut bytes = vec![0u8; image.width * image.height * 12];
    bytes
        .par_chunks_mut(12 * width)
        .enumerate()
        .for_each(|(y, row)| {
            for (x, pixel) in row.chunks_exact_mut(12).enumerate() {
                for (c, sample) in pixel.chunks_exact_mut(4).enumerate() {
                    let value = (f64::from(plane(c)[y * width + x]) * scale) as f32;
                    sample.copy_from_slice(&value.to_le_bytes());
                }
            }
        });
    bytes
}

/// A picture as the PNG a page shows.
pub(super) fn png(picture: &Picture) -> Result<Vec<u8>, StudioError> {
    aureole_io::write::preview_png(picture).map_err(StudioError::Internal)
}

#[cfg(test)]
mod tests {
    use super::*;
    use aureole::image::Layout;

    #[test]
    fn linear_samples_are_each_pixels_rgb_in_cd_per_m2() {
        let (w, h) = (5, 3);
        let mut rgb = Image::filled(w, h, Layout::Rgb, 0.0);
        for (c, plane) in rgb.planes.iter_mut().enumerate() {
            for (i, v) in plane.iter_mut().enumerate() {
                *v = (100 * c + i) as f32 + 0.25;
            }
        }
        let mut grey = Image::filled(w, h, Layout::Luminance, 0.0);
        for (i, v) in grey.planes[0].iter_mut().enumerate() {
            *v = i as f32 * 0.5;
        }
        let floats = |bytes: Vec<u8>| -> Vec<f32> {
            bytes
                .chunks_exact(4)
                .map(|b| f32::from_le_bytes([b[0], b[1], b[2], b[3]]))
                .collect()
        };
        let samples = floats(linear_bytes(&rgb, 2.0));
        assert_eq!(samples.len(), 3 * w * h);
        for i in 0..w * h {
            for c in 0..3 {
                assert_eq!(samples[3 * i + c], 2.0 * ((100 * c + i) as f32 + 0.25));
            }
        }
        let samples = floats(linear_bytes(&grey, 4.0));
        for i in 0..w * h {
            assert_eq!(samples[3 * i..3 * i + 3], [2.0 * i as f32; 3]);
        }
    }
}
