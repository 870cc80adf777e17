//! How much memory a run will take, known before anything large is
//! allocated. How much a front end may use is the front end's to say.

pub use crate::bytes::format_bytes;

use crate::config::Config;
use crate::convolve::{compose_bytes, footprint, Backend, Footprint, Load, Precision};
use crate::error::{Fit, Result};
use crate::kernel::Extent;
use crate::optics::{Context, Effect};

/// The peak memory of applying a camera to one image, in bytes, and the
/// stage where it peaks.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Estimate {
    /// Bytes at the peak.
    pub bytes: u64,
    /// The stage that peaks, in words ("building the kernel", …).
    pub stage: &'static str,
}

/// What looking for a GPU holds: Vulkan's loader and the drivers installed
/// (Mesa's radv links LLVM), 55–60 MB resident more than `--device cpu`
/// where Debian's mesa-vulkan-drivers are installed (`bench/memory.py`).
pub const GPU_DRIVERS: u64 = 64 << 20;

/// `bytes` at the peak `stage`, with an eighth and the program's own
/// baseline added to stay on the safe side.
fn with_margin(bytes: u64, stage: &'static str) -> Estimate {
    const BASELINE: u64 = 16 << 20;
    Estimate {
        bytes: bytes + bytes / 8 + BASELINE,
        stage,
    }
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
    /// Where the engine computes.
    pub backend: Backend,
    /// How far each effect's light reaches from the centre, in pixels
    /// (the first [`REACHES`] effects; `u32::MAX` for the whole kernel).
    pub reaches: [u32; REACHES],
    /// The most bytes an effect's building holds beside its planes,
    /// whatever their size (a star filter's orders).
    pub fixed: u64,
}

/// The effects whose reach a [`Workload`] records; later ones count as
/// reaching the whole kernel.
pub const REACHES: usize = 8;

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
        Ok(Workload::of_extent(
            config, &extent, width, height, planes, alpha,
        ))
    }

    /// The workload of building `config`'s kernel at `extent` alone (what
    /// `aureole psf` does): no image.
    pub fn of_kernel(config: &Config, extent: &Extent) -> Workload {
        Workload::of_extent(config, extent, 0, 0, 0, false)
    }

    fn of_extent(
        config: &Config,
        extent: &Extent,
        width: usize,
        height: usize,
        planes: usize,
        alpha: bool,
    ) -> Workload {
        let pitch_mm = config.camera.pixel_pitch_mm(extent.image_width);
        let mut reaches = [u32::MAX; REACHES];
        let mut fixed = 0;
        for (index, effect) in config.effects.iter().enumerate() {
            let context = Context {
                camera: &config.camera,
                pitch_mm,
                seed: config.seed,
                index_of_kind: config.effects[..index]
                    .iter()
                    .filter(|e| e.kind() == effect.kind())
                    .count(),
                kernel_size: (extent.width, extent.height),
                sending: extent.sending,
            };
            fixed = effect.fixed_building_bytes(&context).max(fixed);
            let px = effect.reach_px(&context).filter(|r| r.is_finite());
            if let (Some(reach), Some(px)) = (reaches.get_mut(index), px) {
                *reach = px.ceil().clamp(0.0, f64::from(u32::MAX - 1)) as u32;
            }
        }
        Workload {
            width,
            height,
            planes,
            alpha,
            kernel: (extent.width, extent.height),
            kernel_planes: config.effects.iter().map(Effect::planes).max().unwrap_or(1),
            backend: Backend::default(),
            reaches,
            fixed,
        }
    }

    /// The peak memory of building the kernel of `effects` (empty when the
    /// kernel is loaded from a file) and applying it to the image. The
    /// model counts the large buffers of each stage, a kernel's composition
    /// as if every effect's light reached the whole extent (it is cut to
    /// the shorter reach once built); an eighth and the program's own
    /// baseline are added to stay on the safe side, and measured peaks of
    /// whole runs lie below it (`bench/memory.py`).
    pub fn estimate(&self, effects: &[Effect]) -> Estimate {
        let pixels = self.width as u64 * self.height as u64;
        let planes = self.planes as u64 + u64::from(self.alpha);
        let image = pixels * planes * 4;
        let kernel = self.kernel_bytes();
        let building = self.building(effects);

        // Then the plan (the kernel, and what its engine holds, split for
        // a night scene's lamps) and the output planes stay until the
        // result is written.
        let engine = self.footprint(Precision::Single, true);
        let plan = kernel + engine.spreading + image;
        let stages = [
            ("reading", 2 * image),
            ("building the kernel", building),
            ("transforming the kernel", kernel + engine.preparing),
            ("convolving", plan + image / 3),
            ("writing", plan + image + image / 2),
        ];
        let (stage, peak) = stages
            .into_iter()
            .max_by_key(|(_, bytes)| *bytes)
            .unwrap_or(("convolving", 0));
        // The input image stays in memory throughout.
        with_margin(image + peak, stage)
    }

    /// The peak memory of building the kernel of `effects` and writing it
    /// (`aureole psf`), with [`Workload::estimate`]'s margin.
    pub fn estimate_kernel(&self, effects: &[Effect]) -> Estimate {
        let building = self.building(effects);
        // The kernel is held while a file of it is encoded beside it.
        let writing = 2 * self.kernel_bytes();
        if building >= writing {
            with_margin(building, "building the kernel")
        } else {
            with_margin(writing, "writing the kernel")
        }
    }

    /// The kernel's f32 planes.
    fn kernel_bytes(&self) -> u64 {
        self.kernel.0 as u64 * self.kernel.1 as u64 * 4 * self.kernel_planes as u64
    }

    /// The peak of building the kernel of `effects`: the chain so far and
    /// the next effect's layers; to compose them, the plane that reaches
    /// less far cut to its reach, what the composition holds for it and
    /// the result; a diffraction pattern is held in f64 before it becomes
    /// f32.
    fn building(&self, effects: &[Effect]) -> u64 {
        let (kw, kh) = (self.kernel.0 as u64, self.kernel.1 as u64);
        let layer = kw * kh * 4;
        let reach = |index: usize| self.reaches.get(index).copied().unwrap_or(u32::MAX);
        let mut building = 0u64;
        let mut chain = 0u64;
        let mut chain_reach = reach(0);
        for (index, effect) in effects.iter().enumerate() {
            let layers = effect.planes() as u64;
            let pattern = effect.building_bytes(layer);
            let composing = if index > 0 {
                let shorter = u64::from(chain_reach.min(reach(index)));
                let cut = (
                    (2 * shorter + 1).min(kw) as usize,
                    (2 * shorter + 1).min(kh) as usize,
                );
                compose_bytes(cut, self.kernel)
                    + (cut.0 * cut.1) as u64 * 4
                    + layer * chain.max(layers)
            } else {
                0
            };
            building = building.max(layer * chain + pattern + composing + self.fixed);
            chain = chain.max(layers);
            chain_reach = chain_reach.max(reach(index));
        }
        building
    }

    /// The peak memory of applying `effects` with each effect's glare in a
    /// layer of its own ([`crate::Session::apply_layers`]): the plan of the
    /// chain up to each effect held at once, each counted at the most its
    /// own run needs, and the frames held beside the runs (a layer per
    /// effect, the total, and the chain before).
    pub fn estimate_layers(&self, effects: &[Effect]) -> u64 {
        let colour = self.width as u64 * self.height as u64 * self.planes as u64 * 4;
        let runs: u64 = (1..=effects.len())
            .map(|n| self.estimate(&effects[..n]).bytes)
            .sum();
        runs + (effects.len() as u64 + 2) * colour
    }

    /// What the f64 engine adds to [`Workload::estimate`] when a scene's
    /// range needs it: what it holds at its peak in place of the f32
    /// engine's whole (not split) kernel, with the same margin.
    pub fn double_extra(&self) -> u64 {
        let double = self.footprint(Precision::Double, false);
        let single = self.footprint(Precision::Single, false);
        let bytes = double
            .preparing
            .max(double.spreading)
            .saturating_sub(single.spreading);
        bytes + bytes / 8
    }

    /// What the engine of `precision` holds for this workload.
    fn footprint(&self, precision: Precision, split: bool) -> Footprint {
        let load = Load {
            image: (self.width, self.height),
            planes: self.planes,
            kernel: self.kernel,
            kernel_planes: self.kernel_planes,
            split,
        };
        footprint((self.backend, precision), &load)
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
            backend: Backend::Cpu,
            reaches: [u32::MAX; REACHES],
            fixed: 0,
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

    #[test]
    fn a_coronas_reach_cuts_the_composition_it_takes_part_in() {
        let mut config = Config::default();
        config.merge(
            crate::presets::find("paper-fig5-both")
                .unwrap()
                .config()
                .unwrap(),
        );
        let workload = Workload::of_config(&config, 3840, 2160, 3, false, None).unwrap();
        // The bloom reaches the whole kernel, the corona's rays fade within
        // a few hundred pixels of the centre.
        assert_eq!(workload.reaches[0], u32::MAX);
        assert!(
            workload.reaches[1] > 15 && workload.reaches[1] < 2000,
            "{:?}",
            workload.reaches
        );
        let uncut = Workload {
            reaches: [u32::MAX; REACHES],
            ..workload
        };
        let (cut, whole) = (
            workload.estimate(&config.effects),
            uncut.estimate(&config.effects),
        );
        assert_eq!(whole.stage, "building the kernel");
        assert!(cut.bytes < whole.bytes, "{cut:?} {whole:?}");
    }

    #[test]
    fn a_star_filters_orders_are_counted_whatever_the_images_size() {
        for preset in ["star-filter-4pt", "star-filter-6pt", "star-filter-8pt"] {
            let mut config = Config::default();
            config.merge(crate::presets::find(preset).unwrap().config().unwrap());
            let Some(Effect::Aperture(aperture)) = config.effects.first() else {
                panic!("{preset} starts with an aperture");
            };
            let mut fixed = Vec::new();
            for (width, height) in [(64, 36), (1280, 720)] {
                let workload = Workload::of_config(&config, width, height, 3, false, None).unwrap();
                let pitch_mm = config.camera.pixel_pitch_mm(width).unwrap();
                let reach = crate::optics::aperture::orders_reach(pitch_mm, workload.kernel);
                let orders = aperture.optics(&config.camera, reach, 0).unwrap().orders;
                assert!(
                    workload.fixed >= 96 * orders.len() as u64,
                    "{preset} at {width}x{height}: {} bytes for {} orders",
                    workload.fixed,
                    orders.len()
                );
                fixed.push(workload.fixed);
            }
            // The orders fill the same millimetres of the sensor however
            // many pixels cover them.
            assert!(
                fixed[0] > 10 << 20 && fixed[0] * 10 > fixed[1] * 9,
                "{fixed:?}"
            );
        }
    }
}
