//! Human-eye glare after Vos (paper §3, docs/physics.md §5).
//!
//! P(θ) = a δ(θ) + k / θⁿ on the hemisphere, θ the angle from the optical
//! axis. A pixel at r px from the centre sees θ = atan(r · pitch / f) and
//! covers a solid angle ∝ cos³θ, so the kernel's spread part is
//! θ⁻ⁿ cos³θ, normalised in discrete space (a = 1 − ε).

use serde::{Deserialize, Serialize};

use crate::schema::{Default, Kind, Parameter, EPSILON};

use super::shape::{SpreadShape, Supersampling};
use super::{Context, Model, Source};
use crate::camera::Camera;
use crate::error::{Error, Result};

/// Vos glare parameters, as in an `[[effect]]` table with `type = "vos"`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Vos {
    /// ε: fraction of the light that is scattered, 0…1.
    pub epsilon: f64,
    /// n: the falloff exponent of k / θⁿ, from 1.5 to 3.
    #[serde(default = "two")]
    pub exponent: f64,
}

fn two() -> f64 {
    2.0
}

const EXPONENT: Parameter = Parameter {
    name: "exponent",
    kind: Kind::Number,
    low: Some((1.5, true)),
    high: Some((3.0, true)),
    default: Default::Number(2.0),
    unit: "",
    allowed: "a number from 1.5 to 3 (Vos's range for k/θⁿ)",
    about: "n in k/θⁿ: how fast the glare falls off with the angle",
};

impl Model for Vos {
    const KIND: &'static str = "vos";
    const PARAMETERS: &'static [Parameter] = &[EPSILON, EXPONENT];

    /// Checks ε ∈ [0, 1] and n ∈ [1.5, 3].
    fn validate(&self) -> Result<()> {
        EPSILON.check("vos", self.epsilon)?;
        EXPONENT.check("vos", self.exponent)
    }

    fn source(&self, context: &Context) -> Result<Source> {
        Ok(Source::Shape(
            self.epsilon,
            Box::new(self.shape(context.camera, context.pitch_mm)?),
        ))
    }
}

impl Vos {
    fn shape(&self, camera: &Camera, pitch_mm: Option<f64>) -> Result<VosShape> {
        self.validate()?;
        let focal = camera.require_focal_length("vos glare")?;
        let pitch = pitch_mm.ok_or_else(|| Error::needs_sensor_width("vos glare".into()))?;
        Ok(VosShape {
            radians_per_px: pitch / focal,
            exponent: self.exponent,
        })
    }
}

struct VosShape {
    /// tan θ per pixel of distance: pitch / focal length.
    radians_per_px: f64,
    exponent: f64,
}

impl SpreadShape for VosShape {
    fn mirror_symmetric(&self) -> bool {
        true
    }

    fn density(&self, x: f64, y: f64) -> f64 {
        let theta = libm::atan((x * x + y * y).sqrt() * self.radians_per_px);
        let c = libm::cos(theta);
        libm::pow(theta, -self.exponent) * c * c * c
    }

    fn grid(&self, x: f64, y: f64) -> Supersampling {
        // |f''/f| of r⁻ⁿ is about n(n + 1)/r², largest at the pixel's nearest
        // point to the centre.
        let r_near = ((x * x + y * y).sqrt() - std::f64::consts::FRAC_1_SQRT_2).max(0.25);
        Supersampling::for_curvature(
            self.exponent * (self.exponent + 1.0) / (r_near * r_near),
            32,
        )
    }

    fn spreads_centre(&self) -> bool {
        // ∫ θ⁻ⁿ θ dθ diverges at 0 for n ≥ 2: the formula holds outside the
        // centre pixel, and what stays within half a pixel is unspread light.
        false
    }
}
