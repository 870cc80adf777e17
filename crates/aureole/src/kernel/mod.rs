//! Discrete, normalised convolution kernels from PSFs (docs/physics.md §2).
//!
//! Each effect's f is averaged over every pixel's area (supersampled where it
//! changes fast, [`raster`]), normalised by its light over the whole plane
//! and weighted by ε, with the unspread (1 − ε) at the centre:
//! K = (1 − ε)·[centre] + ε·F/∫f, so ΣK is 1 less the light that falls
//! beyond the kernel, which leaves the frame. Diffraction patterns come
//! whole from [`diffraction`], in the same shares. The effects of a chain
//! compose by convolution ([`split`]).

mod coarse;
pub mod diffraction;
pub mod profile;
mod radial;
mod raster;
mod split;

use crate::camera::CameraGeometry;
use rayon::prelude::*;

use crate::control::{Cancel, Control};
use crate::convolve::Composing;
use crate::error::{Error, Result};
use crate::image::sum_f64;
use crate::optics::{Context, Effect, Source};
pub use crate::sending::Sending;
use raster::plane_sum;
use split::SplitKernel;

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
    /// What sends the light the kernel spreads.
    pub sending: Sending,
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
            sending: Sending::Pixel,
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
        // Capped first: an image too large for a full kernel runs with a
        // capped one.
        let full = (
            image_width.saturating_mul(2).saturating_sub(1),
            image_height.saturating_mul(2).saturating_sub(1),
        );
        let (width, height) = match max {
            Some((w, h)) => (full.0.min(w.max(1)), full.1.min(h.max(1))),
            None => full,
        };
        Ok(Extent::new(width, height)?.with_image_width(image_width))
    }

    /// The same kernel size for an image `image_width` pixels wide.
    pub fn with_image_width(self, image_width: usize) -> Extent {
        Extent {
            image_width: image_width.max(1),
            ..self
        }
    }

    /// The same kernel for light that `sending` sends.
    pub fn sent_by(self, sending: Sending) -> Extent {
        Extent { sending, ..self }
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

    /// Column and row (from the top) of the centre.
    pub fn centre(&self) -> (usize, usize) {
        (self.width / 2, self.height / 2)
    }
}

/// A convolution kernel: one plane per channel (one for an achromatic PSF,
/// three, linear Rec.709 R, G, B, for a coloured one), each summing to the
/// share of its PSF's light that falls within it: 1 less the light that
/// would leave the frame.
/// Planes are row-major, top row first; the centre is at column `width / 2`,
/// row `height / 2`.
#[derive(Debug, Clone, PartialEq)]
pub struct Kernel {
    width: usize,
    height: usize,
    planes: Vec<Vec<f32>>,
}

impl Kernel {
    /// A kernel from planes (1 or 3, row-major, top row first, centre at
    /// column `width/2` and row `height/2`), e.g. a measured PSF. Each plane
    /// is normalised to ΣK = 1 (one that sums to 1 within f32 rounding is
    /// kept as it is); planes must be finite and non-negative with a
    /// positive sum.
    pub fn from_planes(width: usize, height: usize, planes: Vec<Vec<f32>>) -> Result<Kernel> {
        Kernel::checked(width, height, planes, true)
    }

    /// A kernel whose planes each hold the share of their PSF's light
    /// that falls within them, at most 1, as [`build`] makes them and a
    /// kernel file records them: kept as they are, so that the light a
    /// small frame cannot hold still leaves it. A plane summing to more
    /// than 1 (beyond f32 rounding) is refused.
    pub fn from_shares(width: usize, height: usize, planes: Vec<Vec<f32>>) -> Result<Kernel> {
        Kernel::checked(width, height, planes, false)
    }

    fn checked(
        width: usize,
        height: usize,
        planes: Vec<Vec<f32>>,
        normalise: bool,
    ) -> Result<Kernel> {
        Extent::new(width, height)?;
        let refuse = |message: &str| Error::Parameter {
            effect: "kernel".to_string(),
            name: "planes",
            value: message.to_string(),
            allowed: if normalise {
                "1 or 3 planes of width×height finite, non-negative weights with a positive sum"
            } else {
                "1 or 3 planes of width×height finite, non-negative weights, each summing to more than 0 and at most 1"
            },
        };
        if planes.len() != 1 && planes.len() != 3 {
            return Err(refuse(&format!("{} planes", planes.len())));
        }
        let mut checked = Vec::with_capacity(planes.len());
        for mut plane in planes {
            if plane.len() != width * height {
                return Err(refuse(&format!("a plane of {} values", plane.len())));
            }
            // Row by row, each row checked and summed while it is in cache;
            // the sums as `plane_sum` adds them.
            let rows: Vec<(f64, bool)> = plane
                .par_chunks(width.max(1))
                .map(|row| {
                    let bad = row.iter().any(|v| !v.is_finite() || *v < 0.0);
                    (sum_f64(row), bad)
                })
                .collect();
            if rows.iter().any(|&(_, bad)| bad) {
                return Err(refuse("a negative or non-finite weight"));
            }
            let sum: f64 = rows.iter().map(|&(sum, _)| sum).sum();
            if sum <= 0.0 {
                return Err(refuse("a plane of zeros"));
            }
            // A plane normalised before (a PFM kernel `psf` wrote whole)
            // sums to 1 to within its own rounding; dividing again would
            // move weights by an ulp, and `apply --kernel` would no longer
            // give the bytes of the camera the kernel was built from.
            let near_one = (sum - 1.0).abs() <= f64::from(f32::EPSILON);
            if !normalise && sum > 1.0 && !near_one {
                return Err(refuse(&format!("a plane summing to {sum}")));
            }
            if normalise && !near_one {
                plane
                    .par_iter_mut()
                    .for_each(|v| *v = (f64::from(*v) / sum) as f32);
            }
            checked.push(plane);
        }
        Ok(Kernel {
            width,
            height,
            planes: checked,
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

    /// The planes, one per colour channel (or one for all).
    pub fn planes(&self) -> &[Vec<f32>] {
        &self.planes
    }

    /// Whether the kernel has a plane per colour channel.
    pub fn is_coloured(&self) -> bool {
        self.planes.len() > 1
    }

    /// The weight of plane `plane` at offset (dx, dy) pixels from the
    /// centre, y up; 0 outside.
    pub fn at(&self, plane: usize, dx: i64, dy: i64) -> f32 {
        let (cx, cy) = self.centre();
        let (i, j) = (cx as i64 + dx, cy as i64 - dy);
        if i < 0 || j < 0 || i >= self.width as i64 || j >= self.height as i64 {
            return 0.0;
        }
        self.planes[plane][j as usize * self.width + i as usize]
    }

    /// K at the centre, one weight per plane.
    pub fn centre_weights(&self) -> Vec<f32> {
        let (cx, cy) = self.centre();
        let at = cy * self.width + cx;
        self.planes.iter().map(|plane| plane[at]).collect()
    }

    /// ΣK of one plane, in f64 (the same bits on any number of threads).
    pub fn sum(&self, plane: usize) -> f64 {
        plane_sum(&self.planes[plane], self.width)
    }

    /// The light beyond the (2r + 1)² window around the centre, the most of
    /// any plane; `None` when the window does not fit in the kernel.
    pub fn beyond(&self, r: usize) -> Option<f64> {
        self.beyond_each(&[r]).pop().flatten()
    }

    /// [`Kernel::beyond`] for each radius of `radii`, the planes summed once.
    pub fn beyond_each(&self, radii: &[usize]) -> Vec<Option<f64>> {
        let (w, h) = (self.width, self.height);
        let (cx, cy) = self.centre();
        let sums: Vec<f64> = (0..self.planes.len()).map(|c| self.sum(c)).collect();
        radii
            .iter()
            .map(|&r| {
                if r > cx.min(cy).min(w - 1 - cx).min(h - 1 - cy) {
                    return None;
                }
                let beyond = self.planes.iter().zip(&sums).map(|(plane, sum)| {
                    let inside: f64 = (cy - r..=cy + r)
                        .map(|j| sum_f64(&plane[j * w + cx - r..=j * w + cx + r]))
                        .sum();
                    (sum - inside).max(0.0)
                });
                Some(beyond.fold(0.0, f64::max))
            })
            .collect()
    }
}

/// Builds the kernel of the optical chain `effects`, in order, at `extent`;
/// `seed` drives the random parts (corona rays), and the effects convolve
/// one another where `composing` says. `control` hears the fraction built
/// and may cancel.
pub fn build(
    camera: &CameraGeometry,
    effects: &[Effect],
    seed: u64,
    extent: &Extent,
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Kernel> {
    if effects.is_empty() {
        return Err(Error::NoEffect);
    }
    camera.validate()?;
    let pitch_mm = camera.pixel_pitch_mm(extent.image_width);
    let share = 1.0 / effects.len() as f64;
    let mut chain: Option<SplitKernel> = None;
    for (index, effect) in effects.iter().enumerate() {
        let context = Context {
            camera,
            pitch_mm,
            seed,
            index_of_kind: effects[..index]
                .iter()
                .filter(|e| e.kind() == effect.kind())
                .count(),
            kernel_size: (extent.width, extent.height),
            sending: extent.sending,
        };
        let start = index as f64 * share;
        // Rasterising takes most of an effect's time, composing the rest.
        let mut rasterising = control.part(start, start + 0.8 * share);
        let psf = match effect.source(&context)? {
            Source::Shape(epsilon, shape) => {
                SplitKernel::from_shape(epsilon, shape.as_ref(), extent, &mut rasterising)?
            }
            Source::Shapes(planes) => SplitKernel::from_shapes(&planes, extent, &mut rasterising)?,
            Source::Pattern(planes) => SplitKernel::from_pattern(planes, extent),
            Source::Diffraction {
                optics,
                light,
                pitch_mm,
            } => SplitKernel::from_pattern(
                diffraction::pattern(
                    &optics,
                    light,
                    (extent, pitch_mm),
                    composing,
                    &mut rasterising,
                )?,
                extent,
            ),
        };
        let mut part = control.part(start + 0.8 * share, start + share);
        chain = Some(match chain {
            None => psf,
            Some(before) => before.then(&psf, composing, &mut part)?,
        });
        part.report(1.0);
    }
    chain.map(SplitKernel::into_kernel).ok_or(Error::NoEffect)
}

/// The diffraction kernel of any pupil and filter (`optics`) at `pitch_mm`
/// per pixel: each plane the pixel-averaged |Â(x/(λf))|², summed over
/// `light`, each plane the share of the light that falls within `extent`.
pub fn diffraction_kernel(
    optics: &crate::optics::aperture::Optics,
    light: crate::optics::aperture::spectrum::Light,
    extent: &Extent,
    pitch_mm: f64,
) -> Result<Kernel> {
    let cancel = Cancel::new();
    let pattern = diffraction::pattern(
        optics,
        light,
        (extent, pitch_mm),
        &mut Composing::cpu(),
        &mut Control::quiet(&cancel),
    )?;
    Ok(SplitKernel::from_pattern(pattern, extent).into_kernel())
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
    fn empty_and_huge_extents_are_refused() {
        assert!(Extent::new(0, 5).is_err());
        assert!(Extent::new(5, 0).is_err());
        assert!(Extent::for_image(0, 5).is_err());
        let e = Extent::new(1 << 15, 1 << 14).unwrap_err().to_string();
        assert!(e.contains("32768x16384") && e.contains("2^28"), "{e}");
    }
}
