//! Discrete, normalised convolution kernels from PSFs (MODEL.md §2).
//!
//! Each effect's f is averaged over every pixel's area (supersampled where it
//! changes fast), normalised in discrete space and weighted by ε, with the
//! unspread (1 − ε) at the centre: K = (1 − ε)·[centre] + ε·F/ΣF, so ΣK = 1.
//! The effects of a chain compose by convolution.

mod diffraction;
pub mod profile;

use rayon::prelude::*;

use crate::camera::Camera;
use crate::convolve::plan::Convolver;
use crate::error::{Error, Result};
use crate::image::sum_f64;
use crate::psf::aperture::Optics;
use crate::psf::{spectrum, Effect, Samples, Source, SpreadShape};

/// The most pixels a kernel may have (2²⁸: 2 GiB per f64 plane while it is
/// built).
pub const MAX_KERNEL_PIXELS: usize = 1 << 28;

/// The size of a kernel, and the width of the image it is meant for (which
/// sets the pixel pitch, sensor width / image width, for physical lengths).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Extent {
    /// Kernel width in pixels; the centre is at column `width / 2`.
    pub width: usize,
    /// Kernel height in pixels; the centre is at row `height / 2` from the top.
    pub height: usize,
    /// Width in pixels of the image the kernel is for.
    pub image_width: usize,
}

impl Extent {
    /// A `width`×`height` kernel for an image as wide as the kernel.
    pub fn new(width: usize, height: usize) -> Result<Extent> {
        let refuse = |allowed| Error::KernelSize {
            width,
            height,
            allowed,
        };
        if width == 0 || height == 0 {
            return Err(refuse("width and height must be at least 1"));
        }
        if width.saturating_mul(height) > MAX_KERNEL_PIXELS {
            return Err(refuse("at most 2^28 (268 million) pixels"));
        }
        Ok(Extent {
            width,
            height,
            image_width: width,
        })
    }

    /// The kernel an `image_width`×`image_height` image needs so that light
    /// from any pixel can reach every other: (2W − 1)×(2H − 1).
    pub fn for_image(image_width: usize, image_height: usize) -> Result<Extent> {
        let extent = Extent::new(
            (2 * image_width).saturating_sub(1),
            (2 * image_height).saturating_sub(1),
        )?;
        Ok(extent.with_image_width(image_width))
    }

    /// [`Extent::for_image`], at most `max` (width, height) when given: the
    /// extent a plan builds for an image.
    pub fn for_image_within(
        image_width: usize,
        image_height: usize,
        max: Option<(usize, usize)>,
    ) -> Result<Extent> {
        let extent = Extent::for_image(image_width, image_height)?;
        Ok(match max {
            Some((w, h)) => extent.capped(w, h),
            None => extent,
        })
    }

    /// The same kernel size for an image `image_width` pixels wide.
    pub fn with_image_width(self, image_width: usize) -> Extent {
        Extent {
            image_width: image_width.max(1),
            ..self
        }
    }

    /// At most `max_width`×`max_height`, keeping the centre in the middle.
    pub fn capped(self, max_width: usize, max_height: usize) -> Extent {
        let cap = |n: usize, max: usize| if n > max { max.max(1) } else { n };
        Extent {
            width: cap(self.width, max_width),
            height: cap(self.height, max_height),
            ..self
        }
    }

    fn centre(&self) -> (usize, usize) {
        (self.width / 2, self.height / 2)
    }
}

/// A convolution kernel: one plane per channel (one for an achromatic PSF,
/// three, linear Rec.709 R, G, B, for a coloured one), each summing to 1.
/// Planes are row-major, top row first; the centre is at column `width / 2`,
/// row `height / 2`.
#[derive(Debug, Clone, PartialEq)]
pub struct Kernel {
    width: usize,
    height: usize,
    channels: Vec<Vec<f32>>,
}

impl Kernel {
    /// A kernel from planes (1 or 3, row-major, top row first, centre at
    /// column `width/2` and row `height/2`), e.g. a measured PSF. Each plane
    /// is normalised to ΣK = 1; planes must be finite and non-negative with a
    /// positive sum.
    pub fn from_planes(width: usize, height: usize, channels: Vec<Vec<f32>>) -> Result<Kernel> {
        Extent::new(width, height)?;
        let refuse = |message: &str| Error::Parameter {
            effect: "kernel".to_string(),
            name: "planes",
            value: message.to_string(),
            allowed:
                "1 or 3 planes of width×height finite, non-negative weights with a positive sum",
        };
        if channels.len() != 1 && channels.len() != 3 {
            return Err(refuse(&format!("{} planes", channels.len())));
        }
        let mut normalised = Vec::with_capacity(channels.len());
        for plane in channels {
            if plane.len() != width * height {
                return Err(refuse(&format!("a plane of {} values", plane.len())));
            }
            if plane.iter().any(|v| !v.is_finite() || *v < 0.0) {
                return Err(refuse("a negative or non-finite weight"));
            }
            let sum: f64 = plane.iter().map(|&v| f64::from(v)).sum();
            if sum <= 0.0 {
                return Err(refuse("a plane of zeros"));
            }
            normalised.push(plane.iter().map(|&v| (f64::from(v) / sum) as f32).collect());
        }
        Ok(Kernel {
            width,
            height,
            channels: normalised,
        })
    }

    /// Width in pixels.
    pub fn width(&self) -> usize {
        self.width
    }

    /// Height in pixels.
    pub fn height(&self) -> usize {
        self.height
    }

    /// Column and row (from the top) of the centre.
    pub fn centre(&self) -> (usize, usize) {
        (self.width / 2, self.height / 2)
    }

    /// The planes, one per channel.
    pub fn channels(&self) -> &[Vec<f32>] {
        &self.channels
    }

    /// Whether the kernel has a plane per colour channel.
    pub fn is_coloured(&self) -> bool {
        self.channels.len() > 1
    }

    /// The weight at offset (dx, dy) pixels from the centre, y up; 0 outside.
    pub fn at(&self, channel: usize, dx: i64, dy: i64) -> f32 {
        let (cx, cy) = self.centre();
        let (i, j) = (cx as i64 + dx, cy as i64 - dy);
        if i < 0 || j < 0 || i >= self.width as i64 || j >= self.height as i64 {
            return 0.0;
        }
        self.channels[channel][j as usize * self.width + i as usize]
    }

    /// K at the centre, one weight per channel.
    pub(crate) fn centre_weights(&self) -> Vec<f32> {
        let (cx, cy) = self.centre();
        let at = cy * self.width + cx;
        self.channels.iter().map(|plane| plane[at]).collect()
    }

    /// ΣK of one channel, in f64.
    pub fn sum(&self, channel: usize) -> f64 {
        self.channels[channel].iter().map(|&v| f64::from(v)).sum()
    }
}

/// The light a diffraction kernel integrates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Light {
    /// 380–780 nm into linear Rec.709 R, G, B (three planes).
    Spectral,
    /// One wavelength in nm (one plane).
    Monochrome(f64),
}

impl Light {
    fn samples(self) -> diffraction::Spectrum {
        match self {
            Light::Spectral => spectrum::samples()
                .into_iter()
                .map(|(l, w)| (l, w.to_vec()))
                .collect(),
            Light::Monochrome(nm) => vec![(nm, vec![1.0])],
        }
    }
}

/// The diffraction kernel of any pupil (`optics`) at `pitch_mm` per pixel:
/// each channel the pixel-averaged |Â(x/(λf))|², summed over `light`,
/// normalised to ΣK = 1.
pub fn diffraction_kernel(optics: &Optics, light: Light, extent: &Extent, pitch_mm: f64) -> Kernel {
    Psf::from_planes(
        diffraction::rasterise(optics, &light.samples(), extent, pitch_mm),
        extent,
    )
    .into_kernel()
}

/// Builds the kernel of the optical chain `effects`, in order, at `extent`.
/// `seed` drives the corona rays.
pub fn build(camera: &Camera, effects: &[Effect], seed: u64, extent: &Extent) -> Result<Kernel> {
    if effects.is_empty() {
        return Err(Error::NoEffect);
    }
    camera.validate()?;
    let pitch = camera.pixel_pitch_mm(extent.image_width);
    let mut coronas = 0;
    let mut chain: Option<Psf> = None;
    for effect in effects {
        let source = effect.source(camera, pitch, seed, coronas)?;
        if matches!(effect, Effect::Corona(_)) {
            coronas += 1;
        }
        let psf = match source {
            Source::Shape(epsilon, shape) => Psf::from_shape(epsilon, shape.as_ref(), extent),
            Source::Diffraction(aperture, pitch) => {
                let reach = pitch
                    * ((extent.width * extent.width + extent.height * extent.height) as f64).sqrt()
                    / 2.0;
                let optics = aperture.optics(camera, reach)?;
                let light = if aperture.spectral {
                    Light::Spectral
                } else {
                    Light::Monochrome(aperture.wavelength_nm)
                };
                Psf::from_planes(
                    diffraction::rasterise(&optics, &light.samples(), extent, pitch),
                    extent,
                )
            }
        };
        chain = Some(match chain {
            None => psf,
            Some(before) => before.then(&psf),
        });
    }
    chain.map(Psf::into_kernel).ok_or(Error::NoEffect)
}

/// A PSF on the kernel grid, kept as (unspread weight at the centre) +
/// (spread plane) per channel, so that composing never mixes the large
/// centre weight into the round-off of the small spread values.
struct Psf {
    extent: Extent,
    channels: Vec<Layer>,
}

struct Layer {
    centre: f64,
    /// f32 like the kernel it becomes: half the memory of f64 while a 4K
    /// chain is built, and sums over it run in f64.
    spread: Vec<f32>,
}

impl Psf {
    fn from_shape(epsilon: f64, shape: &dyn SpreadShape, extent: &Extent) -> Psf {
        let spread = if epsilon > 0.0 {
            rasterise(shape, extent)
        } else {
            None
        };
        let layer = match spread {
            Some(mut f) => {
                f.par_iter_mut()
                    .for_each(|v| *v = (epsilon * f64::from(*v)) as f32);
                Layer {
                    centre: 1.0 - epsilon,
                    spread: f,
                }
            }
            // Nothing spread, or nowhere to spread it within the extent: all
            // light stays.
            None => Layer {
                centre: 1.0,
                spread: vec![0.0; extent.width * extent.height],
            },
        };
        Psf {
            extent: *extent,
            channels: vec![layer],
        }
    }

    /// A PSF that is all pattern (no unspread part): planes summing to 1.
    fn from_planes(planes: Vec<Vec<f64>>, extent: &Extent) -> Psf {
        Psf {
            extent: *extent,
            channels: planes
                .into_iter()
                .map(|plane| Layer {
                    centre: 0.0,
                    spread: plane.iter().map(|&v| v as f32).collect(),
                })
                .collect(),
        }
    }

    /// This PSF followed by `next` in the optical chain: their convolution.
    /// (a δ + S) ⊛ (b δ + T) = ab δ + a T + b S + S ⊛ T, where S ⊛ T keeps the
    /// mass ΣS·ΣT within the extent, like any spread light. A plane of one
    /// channel pairs with every channel of the other.
    fn then(&self, next: &Psf) -> Psf {
        let count = self.channels.len().max(next.channels.len());
        let channels = (0..count)
            .map(|c| {
                let a = &self.channels[c.min(self.channels.len() - 1)];
                let b = &next.channels[c.min(next.channels.len() - 1)];
                let width = self.extent.width;
                let mass = plane_sum(&a.spread, width) * plane_sum(&b.spread, width);
                let mut twice = if mass > 0.0 {
                    compose(&a.spread, &b.spread, &self.extent)
                } else {
                    vec![0.0; a.spread.len()]
                };
                // FFT round-off leaves tiny negatives where the true value
                // is ~0; light is never negative.
                twice.par_iter_mut().for_each(|v| *v = v.max(0.0));
                let kept = plane_sum(&twice, width);
                let scale = if kept > 0.0 { mass / kept } else { 0.0 };
                twice
                    .par_iter_mut()
                    .zip(&a.spread)
                    .zip(&b.spread)
                    .for_each(|((v, &s), &t)| {
                        *v = (a.centre * f64::from(t)
                            + b.centre * f64::from(s)
                            + f64::from(*v) * scale) as f32;
                    });
                Layer {
                    centre: a.centre * b.centre,
                    spread: twice,
                }
            })
            .collect();
        Psf {
            extent: self.extent,
            channels,
        }
    }

    fn into_kernel(self) -> Kernel {
        let extent = self.extent;
        let (cx, cy) = extent.centre();
        let centre = cy * extent.width + cx;
        let channels = self
            .channels
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
            channels,
        }
    }
}

/// S ⊛ T over the extent, both centred: the linear convolution in f32 (the
/// plans of `apply`, zero padded so that nothing wraps). Its round-off,
/// ~10⁻⁷ of the largest value, stays far below what the f32 convolution of
/// an image with the kernel adds anyway.
fn compose(s: &[f32], t: &[f32], extent: &Extent) -> Vec<f32> {
    let size = (extent.width, extent.height);
    Convolver::for_plane(t, size, extent.width, extent.height).convolve(s, 0)
}

/// f averaged over every pixel's area and normalised to ΣF = 1; `None` when
/// f puts nothing inside the extent. A mirror-symmetric f is computed on a
/// quarter and mirrored.
fn rasterise(shape: &dyn SpreadShape, extent: &Extent) -> Option<Vec<f32>> {
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = extent.centre();
    let mut plane = vec![0f32; width * height];
    if shape.mirror_symmetric() {
        // Offsets 0..=reach along each axis cover both sides of the centre.
        let (reach_x, reach_y) = (cx.max(width - 1 - cx), cy.max(height - 1 - cy));
        let mut quarter = vec![0.0; (reach_x + 1) * (reach_y + 1)];
        quarter
            .par_chunks_mut(reach_x + 1)
            .enumerate()
            .for_each(|(dy, row)| {
                for (dx, value) in row.iter_mut().enumerate() {
                    *value = pixel_mean(shape, dx as f64, dy as f64, (dx, dy) == (0, 0)) as f32;
                }
            });
        plane
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(j, row)| {
                let dy = j.abs_diff(cy);
                let source = &quarter[dy * (reach_x + 1)..(dy + 1) * (reach_x + 1)];
                for (i, value) in row.iter_mut().enumerate() {
                    *value = source[i.abs_diff(cx)];
                }
            });
    } else {
        plane
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(j, row)| {
                let y = cy as f64 - j as f64;
                let spans = shape.lit_spans(y);
                for (i, value) in row.iter_mut().enumerate() {
                    let x = i as f64 - cx as f64;
                    // Pixels outside the lit spans stay 0.
                    if let Some(spans) = &spans {
                        if !spans.iter().any(|&(a, b)| a <= x && x <= b) {
                            continue;
                        }
                    }
                    *value = pixel_mean(shape, x, y, (i, j) == (cx, cy)) as f32;
                }
            });
    }
    let total = plane_sum(&plane, width);
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    let scale = 1.0 / total;
    plane
        .par_iter_mut()
        .for_each(|v| *v = (f64::from(*v) * scale) as f32);
    Some(plane)
}

/// Σ of a plane in f64: row sums in parallel, added in row order, so the
/// same bits with any number of threads.
fn plane_sum(plane: &[f32], width: usize) -> f64 {
    let rows: Vec<f64> = plane.par_chunks(width.max(1)).map(sum_f64).collect();
    rows.iter().sum()
}

/// The mean of f over the pixel centred at (x, y) (`centre`: the kernel's
/// centre pixel).
fn pixel_mean(shape: &dyn SpreadShape, x: f64, y: f64, centre: bool) -> f64 {
    if centre {
        if !shape.spreads_centre() {
            return 0.0;
        }
        // An even count keeps samples off r = 0, where the direction φ is
        // undefined.
        let m = shape.samples(x, y);
        let even = |n: u32| n.max(16) + n.max(16) % 2;
        let grid = Samples {
            x: even(m.x),
            y: even(m.y),
        };
        return pixel_average(shape, x, y, grid);
    }
    if shape.vanishes_over_pixel(x, y) {
        return 0.0;
    }
    pixel_average(shape, x, y, shape.samples(x, y))
}

/// The mean of f over the pixel centred at (x, y), by the midpoint rule on
/// the given grid.
fn pixel_average(shape: &dyn SpreadShape, x: f64, y: f64, grid: Samples) -> f64 {
    if grid.x <= 1 && grid.y <= 1 {
        return shape.density(x, y);
    }
    let (mx, my) = (grid.x.max(1), grid.y.max(1));
    let (step_x, step_y) = (1.0 / f64::from(mx), 1.0 / f64::from(my));
    let mut sum = 0.0;
    for a in 0..my {
        let sy = y - 0.5 + (f64::from(a) + 0.5) * step_y;
        for b in 0..mx {
            let sx = x - 0.5 + (f64::from(b) + 0.5) * step_x;
            sum += shape.density(sx, sy);
        }
    }
    sum / f64::from(mx * my)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_image_needs_twice_its_size_less_one() {
        let extent = Extent::for_image(1920, 1080).unwrap();
        assert_eq!(
            (extent.width, extent.height, extent.image_width),
            (3839, 2159, 1920)
        );
        assert_eq!(extent.centre(), (1919, 1079));
        let capped = extent.capped(1001, 4000);
        assert_eq!(
            (capped.width, capped.height, capped.image_width),
            (1001, 2159, 1920)
        );
    }

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
        for (w, h) in [(1, 1), (5, 4), (8, 7), (12, 9), (3, 16)] {
            let s: Vec<f32> = (0..w * h).map(|i| (i * 37 % 11) as f32 + 0.25).collect();
            let t: Vec<f32> = (0..w * h).map(|i| (i * 13 % 7) as f32 + 0.5).collect();
            let fast = compose(&s, &t, &Extent::new(w, h).unwrap());
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

    #[test]
    fn empty_and_huge_extents_are_refused() {
        assert!(Extent::new(0, 5).is_err());
        assert!(Extent::new(5, 0).is_err());
        assert!(Extent::for_image(0, 5).is_err());
        let e = Extent::new(1 << 15, 1 << 14).unwrap_err().to_string();
        assert!(e.contains("32768x16384") && e.contains("2^28"), "{e}");
    }
}
