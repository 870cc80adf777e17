//! How much memory a run will take, known before anything large is
//! allocated. How much a front end may use is the front end's to say.

pub use crate::bytes::format_bytes;

use crate::config::Config;
use crate::convolve::padded_size;
use crate::error::{Fit, Result};
use crate::kernel::Extent;
use crate::optics::Effect;

/// The peak memory of applying a camera to one image, in bytes, and the
/// stage where it peaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Estimate {
    /// Bytes at the peak.
    pub bytes: u64,
    /// The stage that peaks, in words ("building the kernel", …).
    pub stage: &'static str,
}

/// What a run works on: the image and the kernel it will build (or load).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Workload {
    /// Image width in pixels.
    pub width: usize,
    /// Image height in pixels.
    pub height: usize,
    /// Colour planes of the image (1 or 3), alpha not counted.
    pub planes: usize,
    /// Whether the image has an alpha plane.
    pub alpha: bool,
    /// Kernel extent in pixels.
    pub kernel: (usize, usize),
    /// Kernel planes (1, or 3 for a coloured kernel).
    pub kernel_planes: usize,
}

impl Workload {
    /// The workload of `config` on a `width`×`height` image of `planes`
    /// colour planes, with the kernel extent [`crate::Plan::for_image`]
    /// would choose.
    pub fn of_config(
        config: &Config,
        width: usize,
        height: usize,
        planes: usize,
        alpha: bool,
        max_extent: Option<(usize, usize)>,
    ) -> Result<Workload> {
        let extent = Extent::for_image_within(width, height, max_extent)?;
        Ok(Workload {
            width,
            height,
            planes,
            alpha,
            kernel: (extent.width, extent.height),
            kernel_planes: config.effects.iter().map(Effect::planes).max().unwrap_or(1),
        })
    }

    /// The peak memory of building the kernel of `effects` (empty when the
    /// kernel is loaded from a file) and applying it to the image. The
    /// model counts the large buffers of each stage; measured peaks of
    /// whole runs (1080p and 4K, bloom, corona, diffraction, capped
    /// kernels) lie 0–25 % above it, so a quarter and the program's own
    /// baseline are added to stay on the safe side.
    pub fn estimate(&self, effects: &[Effect]) -> Estimate {
        const COMPLEX: u64 = 8;
        const BASELINE: u64 = 16 << 20;
        let pixels = self.width as u64 * self.height as u64;
        let planes = self.planes as u64 + u64::from(self.alpha);
        let image = pixels * planes * 4;
        let (kw, kh) = (self.kernel.0 as u64, self.kernel.1 as u64);
        let layer = kw * kh * 4;
        let kernel = layer * self.kernel_planes as u64;

        // Building: the chain so far and the next effect's layers; to
        // compose them, the zero-padded transform of one, the row spectra
        // of the other and the result; a diffraction pattern is held in f64
        // before it becomes f32.
        let (cx, cy) = padded_size(self.kernel.0, self.kernel.1, self.kernel.0, self.kernel.1);
        let compose = (cx as u64 / 2 + 1) * (cy as u64 + 2 * kh) * COMPLEX;
        let mut building = 0u64;
        let mut chain = 0u64;
        for (index, effect) in effects.iter().enumerate() {
            let layers = effect.planes() as u64;
            let pattern = effect.building_bytes(layer);
            let composing = if index > 0 {
                compose + layer * chain.max(layers)
            } else {
                0
            };
            building = building.max(layer * chain + pattern + composing);
            chain = chain.max(layers);
        }

        // Then the plan (the kernel and its spectrum at the apply size, and
        // the row spectra it keeps for every plane) and the output planes
        // stay until the result is written; a night scene's lamps add the
        // spectrum of the kernel beyond their windows.
        let (px, py) = padded_size(self.kernel.0, self.kernel.1, self.width, self.height);
        let half = px as u64 / 2 + 1;
        let spectrum = half * py as u64 * COMPLEX * self.kernel_planes as u64;
        let rows = half * self.height as u64 * COMPLEX * self.planes as u64;
        let plan = kernel + 2 * spectrum + rows + image;
        let stages = [
            ("reading", 2 * image),
            ("building the kernel", building),
            (
                "transforming the kernel",
                kernel + spectrum + half * kh * COMPLEX,
            ),
            ("convolving", plan + image / 3),
            ("writing", plan + image + image / 2),
        ];
        let (stage, peak) = stages
            .into_iter()
            .max_by_key(|(_, bytes)| *bytes)
            .unwrap_or(("convolving", 0));
        // The input image stays in memory throughout.
        let bytes = image + peak;
        Estimate {
            bytes: bytes + bytes / 4 + BASELINE,
            stage,
        }
    }

    /// What the f64 engine adds to [`Workload::estimate`] when a scene's
    /// range needs it: the spectra in f64, and per plane its f64 planes and
    /// the column spectra, with the same margin.
    pub fn double_extra(&self) -> u64 {
        const COMPLEX: u64 = 16;
        let (px, py) = padded_size(self.kernel.0, self.kernel.1, self.width, self.height);
        let half = px as u64 / 2 + 1;
        let pixels = self.width as u64 * self.height as u64;
        let spectra = half * py as u64 * COMPLEX * self.kernel_planes as u64;
        let plane =
            3 * pixels * 8 + half * py as u64 * COMPLEX + self.height as u64 * px as u64 * 24;
        let bytes = spectra + plane;
        bytes + bytes / 4
    }

    /// The largest kernel, halving the extent from `start` (width, height),
    /// with which the run would fit in `limit` bytes; `None` when even a
    /// small one would not.
    pub fn largest_fitting(
        &self,
        effects: &[Effect],
        start: (usize, usize),
        limit: u64,
    ) -> Option<Fit> {
        let (mut w, mut h) = start;
        while w > 16 && h > 16 {
            w /= 2;
            h /= 2;
            let smaller = Workload {
                kernel: (w.min(self.kernel.0), h.min(self.kernel.1)),
                ..*self
            };
            let bytes = smaller.estimate(effects).bytes;
            if bytes <= limit {
                return Some(Fit {
                    kernel: (w, h),
                    bytes,
                });
            }
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_smaller_kernel_fits_a_smaller_limit() {
        let workload = Workload {
            width: 1000,
            height: 600,
            planes: 3,
            alpha: false,
            kernel: (1999, 1199),
            kernel_planes: 1,
        };
        let half = Workload {
            kernel: (999, 599),
            ..workload
        };
        let limit = half.estimate(&[]).bytes;
        assert!(workload.estimate(&[]).bytes > limit);
        let fit = workload
            .largest_fitting(&[], workload.kernel, limit)
            .unwrap();
        assert_eq!((fit.kernel, fit.bytes), ((999, 599), limit));
        assert!(workload.largest_fitting(&[], workload.kernel, 1).is_none());
    }
}
