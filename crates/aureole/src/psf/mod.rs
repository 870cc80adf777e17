//! The paper's point spread functions (MODEL.md §2–5).
//!
//! A PSF is P(r, φ) = (1 − ε) δ(r) + ε f(r, φ): a fraction ε of the light is
//! spread by f, the rest stays where it fell. Each effect here gives ε and the
//! shape of f; [`crate::kernel`] averages f over pixel areas and normalises it
//! in discrete space, so constant factors of f never matter.

pub mod aperture;
pub mod bloom;
pub mod corona;
pub mod pupil;
pub mod spectrum;
pub mod vos;

pub use aperture::{Aperture, Filter};
pub use bloom::Bloom;
pub use corona::{Corona, RayFactors};
pub use vos::Vos;

use serde::Deserialize;

use crate::camera::Camera;
use crate::error::{Error, Result};

/// One optical element of the camera's chain. A config file writes it as an
/// `[[effect]]` table whose `type` is `bloom`, `corona` or `vos`.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(tag = "type", rename_all = "lowercase")]
pub enum Effect {
    /// Scattering in the lens and the emulsion (paper Eq. 6).
    Bloom(Bloom),
    /// Star rays (paper Eq. 7).
    Corona(Corona),
    /// Human-eye glare after Vos (paper §3).
    Vos(Vos),
    /// Diffraction on the stop and on filters, computed from the pupil
    /// (paper §2, MODEL.md §6).
    Aperture(Aperture),
}

/// The effect types a config file may name.
pub const EFFECT_TYPES: &[&str] = &["bloom", "corona", "vos", "aperture"];

impl Effect {
    /// The effect's type as written in a config file.
    pub fn kind(&self) -> &'static str {
        match self {
            Effect::Bloom(_) => "bloom",
            Effect::Corona(_) => "corona",
            Effect::Vos(_) => "vos",
            Effect::Aperture(_) => "aperture",
        }
    }

    /// How many channels its PSF has: three (R, G, B) for diffraction
    /// computed over the spectrum, one otherwise.
    pub fn channels(&self) -> usize {
        match self {
            Effect::Aperture(a) if a.spectral => 3,
            _ => 1,
        }
    }

    /// Checks every parameter against its allowed range.
    pub fn validate(&self) -> Result<()> {
        match self {
            Effect::Bloom(b) => b.validate(),
            Effect::Corona(c) => c.validate(),
            Effect::Vos(v) => v.validate(),
            Effect::Aperture(a) => a.validate(),
        }
    }

    /// What the kernel builder rasterises for this effect. `pitch_mm` is the
    /// pixel pitch of the image the kernel is for; `corona_index` counts the
    /// coronas before this one, so that each corona of a chain draws its own
    /// rays from the one seed.
    pub(crate) fn source(
        &self,
        camera: &Camera,
        pitch_mm: Option<f64>,
        seed: u64,
        corona_index: usize,
    ) -> Result<Source> {
        Ok(match self {
            Effect::Bloom(b) => Source::Shape(b.epsilon, Box::new(b.shape(pitch_mm)?)),
            Effect::Corona(c) => {
                Source::Shape(c.epsilon, Box::new(c.shape(pitch_mm, seed, corona_index)?))
            }
            Effect::Vos(v) => Source::Shape(v.epsilon, Box::new(v.shape(camera, pitch_mm)?)),
            // Aperture::optics validates it, right when it is rasterised.
            Effect::Aperture(a) => {
                let pitch = pitch_mm
                    .ok_or_else(|| Error::needs_sensor_width("aperture diffraction".into()))?;
                Source::Diffraction(a.clone(), pitch)
            }
        })
    }
}

/// An effect ready to rasterise.
pub(crate) enum Source {
    /// ε and the shape of f: K = (1 − ε)·δ + ε·F/ΣF.
    Shape(f64, Box<dyn SpreadShape>),
    /// A diffraction pattern at this pixel pitch (mm): all of K.
    Diffraction(Aperture, f64),
}

/// The spread function f of an effect, in pixel coordinates, as the kernel
/// rasteriser needs it.
pub(crate) trait SpreadShape: Sync {
    /// f at (x, y) pixels from the centre, y up, up to a constant factor.
    fn density(&self, x: f64, y: f64) -> f64;

    /// Samples along x and along y needed to average f over the pixel
    /// centred at (x, y): more where f changes fast within the pixel, and in
    /// the direction it changes fastest.
    fn samples(&self, x: f64, y: f64) -> Samples;

    /// Whether f puts light in the centre pixel. A PSF singular at the
    /// centre leaves the light that moves by less than half a pixel in the
    /// unspread part.
    fn spreads_centre(&self) -> bool {
        true
    }

    /// Whether f(x, y) = f(|x|, |y|), so that a quarter of the kernel can
    /// be computed and mirrored.
    fn mirror_symmetric(&self) -> bool {
        false
    }

    /// Whether f is exactly 0 (in f64) everywhere in the pixel centred at
    /// (x, y), so that its mean is 0 without sampling. Only a cheap,
    /// conservative test belongs here: false is always correct.
    fn vanishes_over_pixel(&self, _x: f64, _y: f64) -> bool {
        false
    }

    /// On the row of pixels centred at height y: ranges of x (pixel
    /// centres, inclusive) outside which f is exactly 0 over every pixel,
    /// or `None` where any pixel may be lit. Like
    /// [`SpreadShape::vanishes_over_pixel`], a conservative, cheap answer.
    fn lit_spans(&self, _y: f64) -> Option<Vec<(f64, f64)>> {
        None
    }
}

/// A supersampling grid: `x` columns by `y` rows of samples in a pixel.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) struct Samples {
    pub x: u32,
    pub y: u32,
}

impl Samples {
    /// The same count along both axes.
    pub fn square(m: u32) -> Samples {
        Samples { x: m, y: m }
    }
}

/// Refuses `value` unless it is finite and `ok` holds, naming the parameter
/// and the allowed range.
pub(crate) fn check_range(
    effect: &str,
    name: &'static str,
    value: f64,
    ok: bool,
    allowed: &'static str,
) -> Result<()> {
    check_count(effect, name, value, value.is_finite() && ok, allowed)
}

/// Refuses a whole-number parameter unless `ok` holds.
pub(crate) fn check_count(
    effect: &str,
    name: &'static str,
    value: impl ToString,
    ok: bool,
    allowed: &'static str,
) -> Result<()> {
    if ok {
        Ok(())
    } else {
        Err(Error::Parameter {
            effect: effect.to_string(),
            name,
            value: value.to_string(),
            allowed,
        })
    }
}

pub(crate) fn check_epsilon(effect: &str, epsilon: f64) -> Result<()> {
    check_range(
        effect,
        "epsilon",
        epsilon,
        (0.0..=1.0).contains(&epsilon),
        "a fraction of the light from 0 to 1",
    )
}

/// Refuses an angle in degrees unless it is finite.
pub(crate) fn check_angle(effect: &str, name: &'static str, degrees: f64) -> Result<()> {
    check_range(effect, name, degrees, true, "a finite angle in degrees")
}

/// Samples per axis so that the midpoint rule's relative error, about
/// (h²/24)·|f''/f| with h = 1/m, stays near 10⁻³ for a curvature
/// `relative_curvature` = |f''/f| in px⁻².
pub(crate) fn samples_for_curvature(relative_curvature: f64, max: u32) -> u32 {
    let m = (relative_curvature / 0.024).sqrt().ceil();
    if m.is_finite() {
        (m as u32).clamp(1, max)
    } else {
        max
    }
}
