//! Bloom: light scattered in the lens and the film emulsion (paper Eq. 6,
//! docs/physics.md §3).
//!
//! f_b(r) = (β − 1) / (π R²) · (1 + (r/R)²)^(−β), the Moffat profile, whose
//! integral over the plane is 1 for β > 1.

use serde::{Deserialize, Serialize};

use crate::schema::{length, Default, Kind, Parameter, EPSILON};

use super::shape::{one_point_beyond, SpreadShape, Supersampling};
use super::whole::{Whole, Window};
use super::{Context, Model, Source};
use crate::check;
use crate::error::Result;
use crate::math;
use crate::units::Length;

/// Bloom parameters, as in an `[[effect]]` table with `type = "bloom"`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Bloom {
    /// ε: fraction of the light that is scattered, 0…1.
    pub epsilon: f64,
    /// β: falloff exponent, > 1 (the paper uses 3–5, Fig. 4 uses 2).
    pub beta: f64,
    /// R: width of the scattering, e.g. 30–120 µm on the film or pixels.
    pub radius: Length,
}

const BETA: Parameter = Parameter {
    name: "beta",
    kind: Kind::Number,
    low: Some((1.0, false)),
    high: Some((100.0, true)),
    default: Default::Required,
    unit: "",
    allowed: "a number above 1 and at most 100 (β ≤ 1 spreads infinite energy)",
    about: "β: how fast the halo falls off, (1 + r²/R²)^-β",
};

const RADIUS: Parameter = length(
    "radius",
    Default::Required,
    "R: the halo's width (30–120 µm on film)",
);

impl Model for Bloom {
    const KIND: &'static str = "bloom";
    const PARAMETERS: &'static [Parameter] = &[EPSILON, BETA, RADIUS];

    fn scale_pixels(&mut self, factor: f64) {
        self.radius = self.radius.scaled_px(factor);
    }

    /// Checks ε ∈ [0, 1] and β > 1 (β ≤ 1 spreads infinite energy).
    fn validate(&self) -> Result<()> {
        EPSILON.check("bloom", self.epsilon)?;
        BETA.check("bloom", self.beta)
    }

    fn source(&self, context: &Context) -> Result<Source> {
        Ok(Source::Shape(
            self.epsilon,
            Box::new(self.shape(context.pitch_mm)?),
        ))
    }
}

impl Bloom {
    /// The profile's value at r pixels for a radius of `radius_px`, with
    /// the paper's normalisation ε(β − 1)/(πR²): what a kernel pixel at that
    /// distance should hold when nothing leaves the kernel.
    pub fn density_at(&self, r: f64, radius_px: f64) -> f64 {
        let q = r / radius_px;
        self.epsilon * (self.beta - 1.0) / (std::f64::consts::PI * radius_px * radius_px)
            * math::power(1.0 + q * q, -self.beta)
    }

    fn shape(&self, pitch_mm: Option<f64>) -> Result<BloomShape> {
        self.validate()?;
        let radius = self.radius.to_px(pitch_mm, "bloom radius")?;
        check::range(
            "bloom",
            "radius",
            radius,
            radius >= 1e-3,
            "at least 0.001 px once converted to pixels",
        )?;
        Ok(BloomShape {
            radius,
            beta: self.beta,
            // The curvature bound of `grid`: 2β(2β + 1)/(R² + r²).
            one_point_squared: one_point_beyond(
                2.0 * self.beta * (2.0 * self.beta + 1.0),
                radius * radius,
            ),
        })
    }
}

struct BloomShape {
    radius: f64,
    beta: f64,
    /// Beyond this squared distance a pixel's grid is one point.
    one_point_squared: f64,
}

impl SpreadShape for BloomShape {
    fn radial(&self) -> bool {
        true
    }

    fn density(&self, x: f64, y: f64) -> f64 {
        let q2 = (x * x + y * y) / (self.radius * self.radius);
        math::power(1.0 + q2, -self.beta)
    }

    /// ∫ 2πr (1 + r²/R²)^−β dr = πR²/(β − 1).
    fn whole(&self, _window: &Window) -> Whole {
        Whole::Plane(std::f64::consts::PI * self.radius * self.radius / (self.beta - 1.0))
    }

    fn one_point_squared(&self) -> f64 {
        self.one_point_squared
    }

    fn grid(&self, x: f64, y: f64) -> Supersampling {
        // |f''/f| of (1 + r²/R²)^−β is at most about 2β(2β + 1)/(R² + r²),
        // taken at the pixel's nearest point to the centre.
        let r_near = ((x * x + y * y).sqrt() - std::f64::consts::FRAC_1_SQRT_2).max(0.0);
        let curvature = 2.0 * self.beta * (2.0 * self.beta + 1.0)
            / (self.radius * self.radius + r_near * r_near);
        Supersampling::for_curvature(curvature, 64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::shape::assert_rows_agree;

    #[test]
    fn one_sample_where_the_grid_is_one_point_and_f_is_the_density() {
        for (beta, radius) in [(2.0, 10.0), (1.01, 0.3), (4.5, 120.0), (100.0, 2.0)] {
            let shape = Bloom {
                epsilon: 0.05,
                beta,
                radius: Length::px(radius),
            }
            .shape(None)
            .unwrap();
            // Out to 2000 px, where even β = 100 is one point.
            let rows = (0..200).map(|j| (-3.0, f64::from(j) * 6.6, 1700));
            let [ones, _, dark] = assert_rows_agree(&shape, rows, |_, _| {});
            assert_eq!(dark, 0, "a bloom lights every pixel");
            assert!(ones > 50_000, "β {beta}: {ones}");
        }
    }
}
