//! Film halation: light that crosses the film base, reflects off its back
//! surface and exposes the emulsion again from behind (docs/physics.md §10).
//!
//! The emulsion's grains scatter part of each layer's light towards the
//! base, diffusely (Lambertian: cos θ per solid angle). A ray at θ from the
//! normal comes back to its layer L tan θ from where it left, with
//! L = 2(d + z): down through the base of thickness d and the emulsion
//! below the layer (its depth z above the base; gelatin and base have
//! nearly the same index, so the ray does not bend between them) and back.
//! It returns with the base–air interface's Fresnel reflectance R(θ), which
//! is 1 beyond the critical angle (total internal reflection), and with the
//! emulsion's round-trip transmission T at normal incidence raised to
//! 1/cos θ for the longer oblique path. Per unit area of the layer, at
//! r = L tan θ:
//!
//!   h(r) = R(θ) T^(1/cos θ) cos⁴θ / (π L²),   ε = ∫ h dA
//!          = ∫₀^{π/2} 2 sin θ cos θ R(θ) T^(1/cos θ) dθ,
//!
//! and the kernel is (1 − ε) δ + ε h / Σh per channel: the halo's light
//! leaves the core. Anti-halation backing (remjet) is index-matched to the
//! base and absorbs what enters it, so with it no ray is totally reflected
//! and only a residual share comes back at any angle.

use serde::{Deserialize, Serialize};

use crate::schema::{flag, fraction, length, Default, Kind, Parameter};

use super::shape::{self, SpreadShape, Supersampling, CHUNK_POINTS};
use super::whole::{self, Whole, Window};
use super::{Context, Model, Source};
use crate::check;
use crate::error::Result;
use crate::math;
use crate::units::Length;

/// Halation parameters, as in an `[[effect]]` table with
/// `type = "halation"`. Every one has a default: a 35 mm motion-picture
/// stock's triacetate base without its backing.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Halation {
    /// d: the thickness of the film base.
    #[serde(default = "base_thickness")]
    pub base_thickness: Length,
    /// R₀: the reflectance of the base's back surface (base–air) at normal
    /// incidence; the base's refractive index, and so its critical angle,
    /// follow from it: n = (1 + √R₀)/(1 − √R₀).
    #[serde(default = "reflectance")]
    pub reflectance: f64,
    /// Whether the base carries its anti-halation backing (remjet).
    #[serde(default)]
    pub remjet: bool,
    /// The share of the light reaching the backing that it returns, at any
    /// angle, when `remjet` is on.
    #[serde(default = "remjet_residual")]
    pub remjet_residual: f64,
    /// z of the red-sensitive layer above the base (the nearest).
    #[serde(default = "red_depth")]
    pub red_depth: Length,
    /// z of the green-sensitive layer above the base.
    #[serde(default = "green_depth")]
    pub green_depth: Length,
    /// z of the blue-sensitive layer above the base (the farthest).
    #[serde(default = "blue_depth")]
    pub blue_depth: Length,
    /// T of the red layer's light: the share the emulsion scatters towards
    /// the base and lets back to the layer, at normal incidence.
    #[serde(default = "red_transmission")]
    pub red_transmission: f64,
    /// T of the green layer's light.
    #[serde(default = "green_transmission")]
    pub green_transmission: f64,
    /// T of the blue layer's light (through the yellow filter both ways).
    #[serde(default = "blue_transmission")]
    pub blue_transmission: f64,
}

fn base_thickness() -> Length {
    Length::um(130.0)
}
fn reflectance() -> f64 {
    0.04
}
fn remjet_residual() -> f64 {
    0.005
}
fn red_depth() -> Length {
    Length::um(4.0)
}
fn green_depth() -> Length {
    Length::um(9.0)
}
fn blue_depth() -> Length {
    Length::um(14.0)
}
fn red_transmission() -> f64 {
    0.5
}
fn green_transmission() -> f64 {
    0.3
}
fn blue_transmission() -> f64 {
    0.2
}

const BASE_THICKNESS: Parameter = length(
    "base_thickness",
    Default::Length("130um"),
    "d: the film base's thickness (triacetate 110–140 µm, polyester 100 µm)",
);

const REFLECTANCE: Parameter = Parameter {
    name: "reflectance",
    kind: Kind::Number,
    low: Some((0.0, false)),
    high: Some((0.5, true)),
    default: Default::Number(0.04),
    unit: "",
    allowed: "a reflectance above 0 and at most 0.5 (0.04 for a base of index 1.5)",
    about: "R₀: the base's back surface at normal incidence; sets the critical angle too",
};

const REMJET: Parameter = flag(
    "remjet",
    false,
    "the anti-halation backing: on, only a trace of halo; off, a red halo",
);

const REMJET_RESIDUAL: Parameter = fraction(
    "remjet_residual",
    Default::Number(0.005),
    "the share of the light the backing returns, when remjet is on",
);

const RED_DEPTH: Parameter = length(
    "red_depth",
    Default::Length("4um"),
    "z: the red-sensitive layer's height above the base (the nearest)",
);
const GREEN_DEPTH: Parameter = length(
    "green_depth",
    Default::Length("9um"),
    "z: the green-sensitive layer's height above the base",
);
const BLUE_DEPTH: Parameter = length(
    "blue_depth",
    Default::Length("14um"),
    "z: the blue-sensitive layer's height above the base (the farthest)",
);

const RED_TRANSMISSION: Parameter = fraction(
    "red_transmission",
    Default::Number(0.5),
    "T: the share of red light scattered to the base and back to its layer",
);
const GREEN_TRANSMISSION: Parameter = fraction(
    "green_transmission",
    Default::Number(0.3),
    "T: the share of green light scattered to the base and back to its layer",
);
const BLUE_TRANSMISSION: Parameter = fraction(
    "blue_transmission",
    Default::Number(0.2),
    "T: the share of blue light scattered to the base and back (yellow filter twice)",
);

impl Model for Halation {
    const KIND: &'static str = "halation";
    const PARAMETERS: &'static [Parameter] = &[
        BASE_THICKNESS,
        REFLECTANCE,
        REMJET,
        REMJET_RESIDUAL,
        RED_DEPTH,
        GREEN_DEPTH,
        BLUE_DEPTH,
        RED_TRANSMISSION,
        GREEN_TRANSMISSION,
        BLUE_TRANSMISSION,
    ];

    fn validate(&self) -> Result<()> {
        REFLECTANCE.check("halation", self.reflectance)?;
        REMJET_RESIDUAL.check("halation", self.remjet_residual)?;
        RED_TRANSMISSION.check("halation", self.red_transmission)?;
        GREEN_TRANSMISSION.check("halation", self.green_transmission)?;
        BLUE_TRANSMISSION.check("halation", self.blue_transmission)
    }

    fn planes(&self) -> usize {
        3
    }

    fn source(&self, context: &Context) -> Result<Source> {
        self.validate()?;
        let base = self
            .base_thickness
            .to_px(context.pitch_mm, "halation base_thickness")?;
        let layers = [
            (self.red_depth, "halation red_depth", self.red_transmission),
            (
                self.green_depth,
                "halation green_depth",
                self.green_transmission,
            ),
            (
                self.blue_depth,
                "halation blue_depth",
                self.blue_transmission,
            ),
        ];
        let mut planes: Vec<(f64, Box<dyn SpreadShape>)> = Vec::with_capacity(3);
        for (depth, what, transmission) in layers {
            let depth = depth.to_px(context.pitch_mm, what)?;
            let shape = HaloShape::new(2.0 * (base + depth), self.back(), transmission);
            check::range(
                "halation",
                "base_thickness",
                shape.path,
                shape.path >= 1e-3,
                "with the layer's depth, at least 0.0005 px once converted to pixels",
            )?;
            planes.push((share(shape.back, transmission), Box::new(shape)));
        }
        Ok(Source::Shapes(planes))
    }

    fn scale_pixels(&mut self, factor: f64) {
        for length in [
            &mut self.base_thickness,
            &mut self.red_depth,
            &mut self.green_depth,
            &mut self.blue_depth,
        ] {
            *length = length.scaled_px(factor);
        }
    }
}

impl Halation {
    /// The base's refractive index, from its normal reflectance.
    pub fn base_index(&self) -> f64 {
        let root = self.reflectance.sqrt();
        (1.0 + root) / (1.0 - root)
    }

    /// The share ε of each layer's light (R, G, B) that the base returns to
    /// it: what the halo takes from the core.
    pub fn shares(&self) -> [f64; 3] {
        [
            self.red_transmission,
            self.green_transmission,
            self.blue_transmission,
        ]
        .map(|transmission| share(self.back(), transmission))
    }

    fn back(&self) -> Back {
        if self.remjet {
            Back::Backing(self.remjet_residual)
        } else {
            Back::Air(self.base_index())
        }
    }
}

/// What lies behind the base.
#[derive(Debug, Clone, Copy)]
enum Back {
    /// Air: Fresnel reflection of a base of this index, total beyond the
    /// critical angle.
    Air(f64),
    /// The index-matched backing, returning this share at any angle.
    Backing(f64),
}

impl Back {
    /// The share of unpolarised light at `cos_theta` from the normal,
    /// inside the base, that comes back.
    fn reflectance(self, cos_theta: f64) -> f64 {
        match self {
            Back::Backing(share) => share,
            Back::Air(n) => {
                let sin_t = n * (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
                if sin_t >= 1.0 {
                    return 1.0;
                }
                let cos_t = (1.0 - sin_t * sin_t).sqrt();
                let s = (n * cos_theta - cos_t) / (n * cos_theta + cos_t);
                let p = (cos_theta - n * cos_t) / (cos_theta + n * cos_t);
                0.5 * (s * s + p * p)
            }
        }
    }

    /// cos θ at which total reflection begins, or `None`.
    fn critical_cos(self) -> Option<f64> {
        match self {
            Back::Air(n) => Some((1.0 - 1.0 / (n * n)).sqrt()),
            Back::Backing(_) => None,
        }
    }
}

/// The share ε of a layer's light that `back` returns to it with the
/// emulsion's transmission T (the same for any path length):
/// ∫₀¹ 2u R(u) T^(1/u) du with u = cos θ, by Simpson's rule on each side of
/// the critical angle, where R jumps to 1.
fn share(back: Back, transmission: f64) -> f64 {
    let log_transmission = math::ln(transmission);
    let integrand = |u: f64| {
        if u <= 0.0 {
            0.0
        } else {
            2.0 * u * back.reflectance(u) * oblique(log_transmission, u)
        }
    };
    let simpson = |a: f64, b: f64| {
        const N: usize = 4096;
        let h = (b - a) / N as f64;
        let inner: f64 = (1..N)
            .map(|i| integrand(a + i as f64 * h) * if i % 2 == 1 { 4.0 } else { 2.0 })
            .sum();
        (integrand(a) + integrand(b) + inner) * h / 3.0
    };
    match back.critical_cos() {
        Some(c) => simpson(0.0, c) + simpson(c, 1.0),
        None => simpson(0.0, 1.0),
    }
}

/// T^(1/cos θ), the transmission along a path at θ, from ln T: the
/// crate's own exp rather than the platform's pow, so that every machine
/// computes the same bits (and one exp, not pow's log and exp, per
/// pixel).
fn oblique(log_transmission: f64, cos: f64) -> f64 {
    math::exp(log_transmission / cos)
}

/// One layer's halo in pixels.
struct HaloShape {
    /// L = 2(d + z) in pixels: a ray at θ returns L tan θ away.
    path: f64,
    back: Back,
    /// ln T of the emulsion's transmission at normal incidence.
    log_transmission: f64,
    /// The radius of the total-reflection ring in pixels, if there is one.
    ring: Option<f64>,
    /// The grid away from the ring, the same at every radius.
    smooth: Supersampling,
}

impl HaloShape {
    fn new(path: f64, back: Back, transmission: f64) -> HaloShape {
        let log_transmission = math::ln(transmission);
        // Away from the ring h is smooth on the scale L: |h''/h| is at
        // most about 24/L², plus the oblique transmission's (ln T / L)².
        // An opaque layer (T = 0) counts as T = 10⁻³⁰⁰.
        let log_t = log_transmission.max(math::ln(1e-300));
        let curvature = (24.0 + log_t * log_t) / (path * path);
        HaloShape {
            path,
            back,
            log_transmission,
            ring: back.critical_cos().map(|c| path * (1.0 - c * c).sqrt() / c),
            smooth: Supersampling::for_curvature(curvature, 32),
        }
    }

    /// h(r) up to the constant 1/(πL²).
    fn at(&self, r: f64) -> f64 {
        let q = r / self.path;
        let cos = 1.0 / (1.0 + q * q).sqrt();
        let cos2 = cos * cos;
        self.back.reflectance(cos) * oblique(self.log_transmission, cos) * cos2 * cos2
    }
}

impl SpreadShape for HaloShape {
    fn radial(&self) -> bool {
        true
    }

    fn density(&self, x: f64, y: f64) -> f64 {
        self.at((x * x + y * y).sqrt())
    }

    /// Over the plane by quadrature, on the scale L and split at the ring
    /// of total reflection, where h steps.
    fn whole(&self, _window: &Window) -> Whole {
        let ring: Vec<f64> = self.ring.into_iter().collect();
        Whole::Plane(whole::radial_plane(|r| self.at(r), self.path, &ring))
    }

    /// [`HaloShape::at`] in passes over the points (the angle; the
    /// oblique transmission; the reflectance and the rest), so that the
    /// processor overlaps the points' exponentials.
    fn density_at(&self, xs: &[f64], ys: &[f64], out: &mut [f64]) {
        shape::in_chunks(xs, ys, out, |xs, ys, out| {
            let mut cos = [0.0; CHUNK_POINTS];
            for ((cos, &x), &y) in cos.iter_mut().zip(xs).zip(ys) {
                let q = (x * x + y * y).sqrt() / self.path;
                *cos = 1.0 / (1.0 + q * q).sqrt();
            }
            for (f, &cos) in out.iter_mut().zip(&cos) {
                *f = oblique(self.log_transmission, cos);
            }
            for (f, &cos) in out.iter_mut().zip(&cos) {
                let cos2 = cos * cos;
                *f = self.back.reflectance(cos) * *f * cos2 * cos2;
            }
        });
    }

    fn grid(&self, x: f64, y: f64) -> Supersampling {
        let r = (x * x + y * y).sqrt();
        // The step at the ring is sampled finely in the pixels it crosses.
        match self.ring {
            Some(ring) if (r - ring).abs() <= std::f64::consts::SQRT_2 => Supersampling::square(32),
            _ => self.smooth,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::shape::assert_rows_agree;

    #[test]
    fn the_halo_in_chunks_of_points_is_its_density_to_the_bit() {
        for (path, back, transmission) in [
            (40.0, Back::Air(1.5), 0.3),
            (7.5, Back::Backing(0.005), 0.5),
            (120.0, Back::Air(1.6), 0.0),
        ] {
            let shape = HaloShape::new(path, back, transmission);
            // Across the ring (36 and 96 px out) and beyond it.
            let rows = [0.0, 3.5, 17.0, 40.0].map(|y| (-5.0, y, 140));
            assert_rows_agree(&shape, rows.into_iter(), |_, _| {});
        }
    }

    #[test]
    fn fresnel_reflectance_is_r0_at_normal_incidence_and_total_beyond_the_critical_angle() {
        let back = Back::Air(1.5);
        assert!((back.reflectance(1.0) - 0.04).abs() < 1e-12);
        let c = back.critical_cos().unwrap();
        assert!((c - (1.0f64 - 1.0 / 2.25).sqrt()).abs() < 1e-12);
        assert_eq!(back.reflectance(c * 0.999), 1.0);
        assert!(back.reflectance(c * 1.001) < 1.0);
        let halation = Halation {
            reflectance: 0.04,
            ..toml::from_str("").unwrap()
        };
        assert!((halation.base_index() - 1.5).abs() < 1e-12);
    }

    #[test]
    fn the_share_is_the_lambertian_fraction_beyond_the_critical_angle_when_nothing_absorbs() {
        // T = 1 and R = 1 beyond θc, 0 below (R₀ → 0 is not allowed, so
        // the sub-critical Fresnel part is compared separately): the
        // Lambertian share beyond θc is 1 − sin²θc = 1 − 1/n².
        let n: f64 = 1.5;
        let beyond = 1.0 - 1.0 / (n * n);
        let below = share(Back::Air(n), 1.0) - beyond;
        assert!(
            below > 0.04 * (1.0 / (n * n)) && below < 0.2 / (n * n),
            "{below}"
        );
    }
}
