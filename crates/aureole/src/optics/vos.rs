//! Human-eye glare after Vos (paper §3, docs/physics.md §5).
//!
//! P(θ) = a δ(θ) + k / θⁿ on the hemisphere, θ the angle from the optical
//! axis. A pixel at r px from the centre sees θ = atan(r · pitch / f) and
//! covers a solid angle ∝ cos³θ, so the kernel's spread part is
//! θ⁻ⁿ cos³θ, normalised in discrete space (a = 1 − ε).

use serde::{Deserialize, Serialize};

use crate::schema::{Default, Kind, Parameter, EPSILON};

use super::shape::{one_point_beyond, SpreadShape, Supersampling};
use super::whole::{self, Whole, Window};
use super::{Context, Model, Source};
use crate::camera::CameraGeometry;
use crate::error::{Error, Result};
use crate::math;

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
    fn shape(&self, camera: &CameraGeometry, pitch_mm: Option<f64>) -> Result<VosShape> {
        self.validate()?;
        let focal = camera.require_focal_length("vos glare")?;
        let pitch = pitch_mm.ok_or_else(|| Error::needs_sensor_width("vos glare".into()))?;
        Ok(VosShape {
            radians_per_px: pitch / focal,
            exponent: self.exponent,
            // The curvature bound of `grid`: n(n + 1)/r².
            one_point_squared: one_point_beyond(self.exponent * (self.exponent + 1.0), 0.0),
        })
    }
}

struct VosShape {
    /// tan θ per pixel of distance: pitch / focal length.
    radians_per_px: f64,
    exponent: f64,
    /// Beyond this squared distance a pixel's grid is one point.
    one_point_squared: f64,
}

impl SpreadShape for VosShape {
    fn radial(&self) -> bool {
        true
    }

    fn density(&self, x: f64, y: f64) -> f64 {
        let t = (x * x + y * y).sqrt() * self.radians_per_px;
        // cos(atan t) = 1/√(1 + t²), without a cosine.
        let c = 1.0 / (1.0 + t * t).sqrt();
        math::power(libm::atan(t), -self.exponent) * c * c * c
    }

    /// Outside the window, by quadrature on panels that double from the
    /// nearest edge: f is a power of r there, then falls as r⁻³ where the
    /// sensor's flatness turns angles into ever longer distances.
    fn whole(&self, window: &Window) -> Whole {
        let at = |r: f64| self.density(r, 0.0);
        Whole::Beyond(whole::radial_beyond(at, window, window.nearest(), &[]))
    }

    fn one_point_squared(&self) -> f64 {
        self.one_point_squared
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::shape::assert_rows_agree;

    #[test]
    fn one_sample_where_the_grid_is_one_point_and_f_is_the_density() {
        let camera = CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: None,
            ..CameraGeometry::default()
        };
        for exponent in [1.5, 2.0, 2.7, 3.0] {
            let vos = Vos {
                epsilon: 0.05,
                exponent,
            };
            let shape = vos.shape(&camera, Some(0.009)).unwrap();
            let rows = (0..300).map(|j| (0.5, f64::from(j) * 0.29, 300));
            let [ones, _, dark] = assert_rows_agree(&shape, rows, |_, _| {});
            assert_eq!(dark, 0, "glare lights every pixel");
            assert!(ones > 50_000, "n {exponent}: {ones}");
        }
    }

    #[test]
    fn the_density_is_the_angles_power_law_with_its_cosines() {
        // θ⁻ⁿ cos³θ with θ = atan(r·pitch/f), against libm's functions.
        let camera = CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: None,
            ..CameraGeometry::default()
        };
        let shape = Vos {
            epsilon: 0.05,
            exponent: 2.5,
        }
        .shape(&camera, Some(0.009))
        .unwrap();
        for r in [0.3, 1.0, 17.0, 400.0, 5000.0, 60000.0] {
            let theta = libm::atan(r * 0.009 / 50.0);
            let expected = libm::pow(theta, -2.5) * libm::cos(theta).powi(3);
            let f = shape.density(r, 0.0);
            assert!((f / expected - 1.0).abs() < 1e-14, "{r}: {f} vs {expected}");
        }
    }
}
