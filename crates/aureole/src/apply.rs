//! Applying the camera to an image (MODEL.md §7–8): the light of pixels
//! brighter than the threshold is spread by the kernel, the rest stays:
//! O = I·[Y ≤ T] + K ⊛ (I·[Y > T]). A [`Plan`] builds the kernel and its
//! spectrum once for an image size and applies them to any number of images.

use rayon::prelude::*;

use crate::config::Config;
use crate::convolve::plan::Convolver;
use crate::error::{Error, Result};
use crate::image::{Image, Layout, REC709_LUMINANCE};
use crate::kernel::{Extent, Kernel};

/// How the light is split and what is written.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ApplyOptions {
    /// Threshold T in cd/m²: pixels whose luminance is at or below it keep
    /// their light in place.
    pub threshold: f64,
    /// Soft knee, relative to T: between T and T·(1 + knee) the spread
    /// fraction rises smoothly from 0 to 1. 0 is the paper's hard threshold.
    pub knee: f64,
    /// cd/m² per file unit: what the threshold is compared with.
    pub scale: f64,
    /// Write only the light the camera adds (output − input), for
    /// compositing additively over the original.
    pub glare_only: bool,
}

impl Default for ApplyOptions {
    fn default() -> Self {
        ApplyOptions {
            threshold: 0.0,
            knee: 0.0,
            scale: 1.0,
            glare_only: false,
        }
    }
}

/// The result of applying a plan.
#[derive(Debug, Clone)]
pub struct Applied {
    /// The camera's image (or only its glare), in the input's units.
    pub image: Image,
    /// Σ luminance of the input, file units.
    pub energy_in: f64,
    /// Σ luminance of the camera's image, file units: the input's less what
    /// was spread beyond the frame.
    pub energy_out: f64,
    /// How many pixels were above the threshold and spread.
    pub spread_pixels: usize,
}

/// The kernel of an optical chain for one image size, with its spectrum.
pub struct Plan {
    width: usize,
    height: usize,
    kernel: Kernel,
    /// K at the centre, per kernel channel: applied exactly, pixel by pixel.
    centres: Vec<f32>,
    /// Convolves with the rest of K, the light that moves. Leaving the
    /// (1 − ε) peak out of the FFT keeps its f32 round-off ~1/ε times smaller.
    convolver: Convolver,
}

impl Plan {
    /// Builds the kernel for `width`×`height` images, by default large
    /// enough that light from any pixel reaches every other ((2W − 1)×(2H − 1)),
    /// or at most `max_extent`, and transforms it.
    pub fn new(
        config: &Config,
        width: usize,
        height: usize,
        max_extent: Option<(usize, usize)>,
    ) -> Result<Plan> {
        let mut extent = Extent::for_image(width, height)?;
        if let Some((w, h)) = max_extent {
            extent = extent.capped(w, h);
        }
        Ok(Plan::from_kernel(config.kernel(&extent)?, width, height))
    }

    /// A plan for `width`×`height` images with a kernel built before (e.g.
    /// by `aureole psf`, read back from a file): kernels are cacheable.
    pub fn from_kernel(kernel: Kernel, width: usize, height: usize) -> Plan {
        let (centres, spread) = kernel.split_centre();
        let convolver = Convolver::new(&spread, width, height);
        Plan {
            width,
            height,
            kernel,
            centres,
            convolver,
        }
    }

    /// The kernel in use.
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// Applies the camera to `image` (which must have the plan's size);
    /// `progress` hears the fraction done, 0 to 1.
    pub fn apply(
        &self,
        image: &Image,
        options: &ApplyOptions,
        progress: &mut dyn FnMut(f64),
    ) -> Result<Applied> {
        if (image.width, image.height) != (self.width, self.height) {
            return Err(Error::SizeMismatch {
                expected: (self.width, self.height),
                found: (image.width, image.height),
            });
        }
        let threshold = options.threshold / options.scale;
        let knee = options.knee;
        let fractions: Vec<f32> = image
            .luminance()
            .par_iter()
            .map(|&y| spread_fraction(f64::from(y), threshold, knee))
            .collect();
        let spread_pixels = fractions.iter().filter(|&&f| f > 0.0).count();
        let energy_in = image.total_luminance();

        let mut output = image.clone_without_planes();
        if spread_pixels == 0 {
            output.planes = image.planes.clone();
        } else {
            let steps = self.convolutions(image.layout) as f64;
            let mut done = 0.0;
            // With every pixel spread (threshold 0, the complete camera) the
            // plane is its own bright part and nothing stays: no copies.
            let everything =
                spread_pixels == fractions.len() && fractions.iter().all(|&f| f == 1.0);
            for (c, plane) in image.planes.iter().enumerate() {
                let mut step = |_| {
                    done += 1.0;
                    progress(done / steps);
                };
                if everything {
                    output
                        .planes
                        .push(self.spread(plane, c, image.layout, &mut step));
                    continue;
                }
                let bright: Vec<f32> = plane
                    .par_iter()
                    .zip(&fractions)
                    .map(|(v, f)| v * f)
                    .collect();
                let mut spread = self.spread(&bright, c, image.layout, &mut step);
                spread
                    .par_iter_mut()
                    .zip(plane)
                    .zip(&bright)
                    .for_each(|((s, v), b)| *s += v - b);
                output.planes.push(spread);
            }
        }
        progress(1.0);
        let energy_out = output.total_luminance();
        if options.glare_only {
            for (out, input) in output.planes.iter_mut().zip(&image.planes) {
                out.par_iter_mut().zip(input).for_each(|(o, i)| *o -= i);
            }
        }
        Ok(Applied {
            image: output,
            energy_in,
            energy_out,
            spread_pixels,
        })
    }

    /// How many convolutions an image of `layout` takes.
    fn convolutions(&self, layout: Layout) -> usize {
        match (layout, self.convolver.channels()) {
            (Layout::Rgb, _) => 3,
            (Layout::Luminance, k) => k,
        }
    }

    /// The bright part of colour plane `c` through the kernel. A coloured
    /// kernel spreads a luminance image as Y = Σ w_c K_c ⊛ Y.
    fn spread(
        &self,
        bright: &[f32],
        c: usize,
        layout: Layout,
        step: &mut dyn FnMut(()),
    ) -> Vec<f32> {
        let kernels = self.convolver.channels();
        let through = |k: usize| {
            let mut out = self.convolver.convolve(bright, k);
            let centre = self.centres[k];
            out.par_iter_mut()
                .zip(bright)
                .for_each(|(o, b)| *o += centre * b);
            out
        };
        match (layout, kernels) {
            (_, 1) | (Layout::Rgb, _) => {
                let out = through(c.min(kernels - 1));
                step(());
                out
            }
            (Layout::Luminance, _) => {
                let mut sum = vec![0f32; bright.len()];
                for (k, weight) in REC709_LUMINANCE.iter().enumerate().take(kernels) {
                    let part = through(k);
                    sum.par_iter_mut()
                        .zip(&part)
                        .for_each(|(s, p)| *s += weight * p);
                    step(());
                }
                sum
            }
        }
    }
}

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
