//! The eye's disability glare by the CIE's general disability glare
//! equation (CIE 146:2002, after Vos and van den Berg, CIE 135/1-1999;
//! docs/physics.md §5): the veiling luminance a point source of glare
//! illuminance E makes at θ degrees from it, for an observer of `age`
//! years and eye pigmentation p,
//!
//! ```text
//! L/E = [1 − 0.08 (A/70)⁴] · [9.2·10⁶ / (1 + (θ/0.0046)²)^1.5 + 1.5·10⁵ / (1 + (θ/0.045)²)^1.5]
//!     + [1 + 1.6 (A/70)⁴] · { 400 / (1 + (θ/0.1)²) + 3·10⁻⁸ θ²
//!                            + p [1300 / (1 + (θ/0.1)²)^1.5 + 0.8 / (1 + (θ/0.1)²)^0.5] }
//!     + 2.5·10⁻³ p                                                     (sr⁻¹)
//! ```
//!
//! valid from 0.1° to 100° and, with its first terms, the point spread
//! of a young eye all the way in: for A = 25 and p = 0 it holds 1.005 of
//! the light over the hemisphere. The kernel is that PSF normalised, in
//! the camera's visual angle: a pixel r px from the centre sees
//! θ = atan(r · pitch / f) and covers a solid angle ∝ cos³θ.

use serde::{Deserialize, Serialize};

use crate::schema::{Default, Kind, Parameter};

use super::shape::{one_point_beyond, SpreadShape, Supersampling};
use super::whole::{self, Whole, Window};
use super::{Context, Model, Source};
use crate::camera::CameraGeometry;
use crate::error::{Error, Result};

/// The CIE's disability glare, as in an `[[effect]]` table with
/// `type = "eye"`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Eye {
    /// The observer's age, years.
    #[serde(default = "twenty_five")]
    pub age: f64,
    /// The eye's pigmentation p: 0 very dark eyes, 0.5 brown, 1 light
    /// blue, 1.2 very light blue.
    #[serde(default = "brown")]
    pub pigmentation: f64,
}

fn twenty_five() -> f64 {
    25.0
}
fn brown() -> f64 {
    0.5
}

const AGE: Parameter = Parameter {
    name: "age",
    kind: Kind::Number,
    low: Some((1.0, true)),
    high: Some((100.0, true)),
    default: Default::Number(25.0),
    unit: "years",
    allowed: "an age from 1 to 100 years",
    about: "the observer's age: the eye scatters more light as it ages, (A/70)⁴",
};

const PIGMENTATION: Parameter = Parameter {
    name: "pigmentation",
    kind: Kind::Number,
    low: Some((0.0, true)),
    high: Some((1.2, true)),
    default: Default::Number(0.5),
    unit: "",
    allowed: "the CIE's p from 0 (very dark eyes) to 1.2 (very light blue eyes)",
    about: "the eye's pigmentation p: 0 very dark, 0.5 brown, 1 light blue; light through a light iris adds a wide veil",
};

impl Model for Eye {
    const KIND: &'static str = "eye";
    const PARAMETERS: &'static [Parameter] = &[AGE, PIGMENTATION];

    fn validate(&self) -> Result<()> {
        AGE.check("eye", self.age)?;
        PIGMENTATION.check("eye", self.pigmentation)
    }

    fn source(&self, context: &Context) -> Result<Source> {
        let shape = self.shape(context.camera, context.pitch_mm)?;
        let spread = 1.0 - shape.centre_share();
        Ok(Source::Shape(spread, Box::new(shape)))
    }
}

impl Eye {
    /// L_veil / E_glare, sr⁻¹, at `theta` degrees from the source.
    pub fn veiling(&self, theta: f64) -> f64 {
        let aged = (self.age / 70.0).powi(4);
        let q = |width: f64| 1.0 + (theta / width) * (theta / width);
        // x^1.5 as x√x: no platform power function.
        let three_halves = |x: f64| x * x.sqrt();
        let near = q(0.1);
        (1.0 - 0.08 * aged) * (9.2e6 / three_halves(q(0.0046)) + 1.5e5 / three_halves(q(0.045)))
            + (1.0 + 1.6 * aged)
                * (400.0 / near
                    + 3e-8 * theta * theta
                    + self.pigmentation * (1300.0 / three_halves(near) + 0.8 / near.sqrt()))
            + 2.5e-3 * self.pigmentation
    }

    /// The light of the equation within `theta` degrees of its centre, sr
    /// times sr⁻¹, on the tangent plane (θ small: ∫ 2πθ′dθ′), in closed
    /// form term by term.
    pub fn within(&self, theta: f64) -> f64 {
        let aged = (self.age / 70.0).powi(4);
        // ∫₀^θ 2πt dt / (1 + (t/w)²)^k for k = 1.5, 1 and 0.5.
        let ratio = |w: f64| 1.0 + (theta / w) * (theta / w);
        let steep = |w: f64| std::f64::consts::TAU * w * w * (1.0 - 1.0 / ratio(w).sqrt());
        let log = |w: f64| std::f64::consts::PI * w * w * libm::log(ratio(w));
        let shallow = |w: f64| std::f64::consts::TAU * w * w * (ratio(w).sqrt() - 1.0);
        let disc = std::f64::consts::PI * theta * theta;
        let degrees = (1.0 - 0.08 * aged) * (9.2e6 * steep(0.0046) + 1.5e5 * steep(0.045))
            + (1.0 + 1.6 * aged)
                * (400.0 * log(0.1)
                    + 3e-8 * std::f64::consts::PI * theta.powi(4) / 2.0
                    + self.pigmentation * (1300.0 * steep(0.1) + 0.8 * shallow(0.1)))
            + 2.5e-3 * self.pigmentation * disc;
        // The integral ran over degrees: a square degree is (π/180)² sr.
        degrees * (std::f64::consts::PI / 180.0).powi(2)
    }

    /// The light of the equation over the hemisphere, ∫ L/E dΩ, by
    /// Simpson's rule in ln θ (the terms vary over decades of θ).
    pub fn hemisphere(&self) -> f64 {
        self.light_within(90.0)
    }

    /// The light of the equation over the whole sphere of directions
    /// about its source, its terms carried on past 100° to 180°.
    pub fn sphere(&self) -> f64 {
        self.light_within(180.0)
    }

    /// ∫ L/E dΩ within `degrees` of the source.
    fn light_within(&self, degrees: f64) -> f64 {
        const STEPS: usize = 8192;
        let (low, high) = (libm::log(1e-6), libm::log(degrees));
        let h = (high - low) / STEPS as f64;
        let at = |k: usize| {
            let theta = libm::exp(low + h * k as f64);
            // dΩ = 2π sin θ dθ, θ in radians, dθ = θ d(ln θ).
            let radians = theta.to_radians();
            self.veiling(theta) * std::f64::consts::TAU * libm::sin(radians) * radians
        };
        let inner: f64 = (1..STEPS)
            .map(|k| if k % 2 == 1 { 4.0 } else { 2.0 } * at(k))
            .sum();
        // Below 10⁻⁶ degrees the equation is flat: a disc.
        self.within(1e-6) + h / 3.0 * (at(0) + inner + at(STEPS))
    }

    fn shape(&self, camera: &CameraGeometry, pitch_mm: Option<f64>) -> Result<EyeShape> {
        self.validate()?;
        let focal = camera.require_focal_length("eye glare")?;
        let pitch = pitch_mm.ok_or_else(|| Error::needs_sensor_width("eye glare".into()))?;
        Ok(EyeShape {
            eye: self.clone(),
            radians_per_px: pitch / focal,
        })
    }
}

struct EyeShape {
    eye: Eye,
    /// tan θ per pixel of distance: pitch / focal length.
    radians_per_px: f64,
}

impl EyeShape {
    /// The share of the PSF's light within the centre pixel (a disc of its
    /// area): what the kernel keeps there unspread.
    fn centre_share(&self) -> f64 {
        let radius = (self.radians_per_px / std::f64::consts::PI.sqrt()).to_degrees();
        (self.eye.within(radius) / self.eye.hemisphere()).clamp(0.0, 1.0)
    }
}

/// The steepest power of the equation's terms, θ⁻³: its n(n + 1).
const STEEPEST: f64 = 12.0;

impl SpreadShape for EyeShape {
    fn radial(&self) -> bool {
        true
    }

    fn density(&self, x: f64, y: f64) -> f64 {
        let t = (x * x + y * y).sqrt() * self.radians_per_px;
        // cos(atan t) = 1/√(1 + t²), without a cosine.
        let c = 1.0 / (1.0 + t * t).sqrt();
        self.eye.veiling(libm::atan(t).to_degrees()) * c * c * c
    }

    /// Outside the window, by quadrature on panels that double from the
    /// nearest edge, as Vos's.
    fn whole(&self, window: &Window) -> Whole {
        let at = |r: f64| self.density(r, 0.0);
        Whole::Beyond(whole::radial_beyond(at, window, window.nearest(), &[]))
    }

    fn one_point_squared(&self) -> f64 {
        one_point_beyond(STEEPEST, 0.0)
    }

    fn grid(&self, x: f64, y: f64) -> Supersampling {
        let r_near = ((x * x + y * y).sqrt() - std::f64::consts::FRAC_1_SQRT_2).max(0.25);
        Supersampling::for_curvature(STEEPEST / (r_near * r_near), 32)
    }

    fn spreads_centre(&self) -> bool {
        // The centre pixel keeps the light the equation puts within it
        // (`centre_share`), unspread.
        false
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_closed_form_within_a_radius_is_the_quadrature_of_the_equation() {
        for (age, pigmentation) in [(25.0, 0.0), (70.0, 1.0), (45.0, 0.5)] {
            let eye = Eye { age, pigmentation };
            for radius in [0.003, 0.05, 0.4, 2.0] {
                // Midpoints in t on the tangent plane, in square degrees.
                let steps = 200_000;
                let h = radius / steps as f64;
                let sum: f64 = (0..steps)
                    .map(|k| {
                        let t = (k as f64 + 0.5) * h;
                        eye.veiling(t) * std::f64::consts::TAU * t * h
                    })
                    .sum::<f64>()
                    * (std::f64::consts::PI / 180.0).powi(2);
                let closed = eye.within(radius);
                assert!(
                    (closed / sum - 1.0).abs() < 1e-6,
                    "{age} {pigmentation} {radius}: {closed} {sum}"
                );
            }
        }
    }
}
