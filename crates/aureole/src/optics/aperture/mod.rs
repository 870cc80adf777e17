//! Diffraction on the camera stop and on star filters, from first principles
//! (paper §2, docs/physics.md §6): the PSF is |𝔉{pupil}|² in the focal
//! plane, PSF_λ(x) = |Â(x / (λf))|² / ((λf)² · area), per wavelength,
//! integrated over the spectrum with each channel's sensitivity. The pupil
//! and its transform are in [`pupil`], the light in [`spectrum`]; the
//! kernel's near field, far field and filter orders in
//! [`crate::kernel::diffraction`].

mod dirt;
pub(crate) mod jinc;
pub mod pupil;
pub mod spectrum;

use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

use serde::{Deserialize, Serialize};

use crate::schema::{flag, Default, Kind, Parameter};

use super::{Context, Model, Source};
use crate::camera::CameraGeometry;
use crate::check;
use crate::error::{Error, Result};
use pupil::Pupil;
use spectrum::Light;

/// The most blades a stop may have.
pub const MAX_BLADES: u32 = 64;
/// The most filter families (an 8-point star filter has four).
pub const MAX_FILTERS: usize = 6;
/// Straight segments per blade when blades are rounded.
const ARC_SEGMENTS: usize = 16;

/// A camera stop and optional filter, as in an `[[effect]]` table with
/// `type = "aperture"`. The f-number, focal length and sensor width come
/// from `[camera]`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Aperture {
    /// Straight blades of the stop (3 to 64); 0 for a circular stop.
    pub blades: u32,
    /// Rotation of the stop, degrees counter-clockwise; at 0 a blade tip
    /// points along +x.
    #[serde(default)]
    pub rotation_deg: f64,
    /// 0: straight blades … 1: a circle through the blade tips.
    #[serde(default)]
    pub roundness: f64,
    /// true: 17 wavelengths from 380 to 780 nm into linear Rec.709 R, G, B;
    /// false: one achromatic kernel at `wavelength_nm`.
    #[serde(default = "yes")]
    pub spectral: bool,
    /// The wavelength of an achromatic kernel, nm (380–780).
    #[serde(default = "green")]
    pub wavelength_nm: f64,
    /// Central obstruction (mirror lenses), as a fraction of the diameter.
    #[serde(default)]
    pub obstruction: f64,
    /// Spider vanes holding the obstruction.
    #[serde(default)]
    pub vanes: u32,
    /// Width of each vane, as a fraction of the diameter.
    #[serde(default = "vane_width")]
    pub vane_width: f64,
    /// Specks of dust in the beam on the front element.
    #[serde(default)]
    pub dust: u32,
    /// The smallest specks' diameter, µm.
    #[serde(default = "dust_min")]
    pub dust_min_um: f64,
    /// The largest specks' diameter, µm.
    #[serde(default = "dust_max")]
    pub dust_max_um: f64,
    /// Scratches on the front element.
    #[serde(default)]
    pub scratches: u32,
    /// Their length, mm, cut by the beam's edge.
    #[serde(default = "scratch_length")]
    pub scratch_length_mm: f64,
    /// Their width, µm.
    #[serde(default = "scratch_width")]
    pub scratch_width_um: f64,
    /// Their mean direction, degrees from +x.
    #[serde(default)]
    pub scratch_angle_deg: f64,
    /// How far their directions spread about it, degrees (180: any).
    #[serde(default = "scratch_spread")]
    pub scratch_spread_deg: f64,
    /// A smudge of grease: its diameter, as a fraction of the pupil's.
    #[serde(default)]
    pub grease: f64,
    /// The share of the light the smudge passes.
    #[serde(default = "grease_transmission")]
    pub grease_transmission: f64,
    /// The delay of the light through it, degrees of phase.
    #[serde(default = "grease_phase")]
    pub grease_phase_deg: f64,
    /// Star filter or grating: one family of parallel lines per entry.
    #[serde(default, rename = "filter")]
    pub filters: Vec<Filter>,
    /// An anamorphic lens's squeeze: its focal length across x is the
    /// camera's over this (1: a round lens).
    #[serde(default = "one")]
    pub squeeze: f64,
}

/// One family of parallel opaque lines on a filter in front of the lens.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Filter {
    /// Direction of the lines, degrees from +x; the rays they make are
    /// perpendicular to them.
    #[serde(default)]
    pub angle_deg: f64,
    /// d: distance between lines, µm.
    pub spacing_um: f64,
    /// e: width of each line, µm.
    pub width_um: f64,
}

impl Filter {
    /// The orders m > 0 that land within `reach_mm` of the centre at
    /// 380 nm or longer (order m lands at m·λf/d mm), at most 4000.
    fn orders_within(&self, focal: f64, reach_mm: f64) -> i64 {
        let d = self.spacing_um * 1e-3;
        ((reach_mm * d / (380e-6 * focal)).ceil() as i64).min(4000)
    }
}

fn yes() -> bool {
    true
}
fn one() -> f64 {
    1.0
}
fn green() -> f64 {
    550.0
}
fn vane_width() -> f64 {
    0.02
}
fn dust_min() -> f64 {
    20.0
}
fn dust_max() -> f64 {
    150.0
}
fn scratch_length() -> f64 {
    10.0
}
fn scratch_width() -> f64 {
    20.0
}
fn scratch_spread() -> f64 {
    180.0
}
fn grease_transmission() -> f64 {
    0.8
}
fn grease_phase() -> f64 {
    90.0
}

/// The optics an aperture kernel needs: the pupil, the focal length and
/// the filter's diffraction orders.
#[derive(Debug, Clone)]
pub struct Optics {
    /// The pupil, mm.
    pub pupil: Pupil,
    /// Pupil diameter D = f/N, mm: across y, and across x too unless
    /// stretched.
    pub diameter_mm: f64,
    /// How far the pupil is stretched along x: an anamorphic lens's
    /// squeeze (1: a round lens).
    pub stretch: f64,
    /// Focal length f, mm.
    pub focal_mm: f64,
    /// Filter orders: the spatial frequency each order is shifted by
    /// (cycles/mm) and its share of the light, |c|²; sorted by ν_y.
    pub orders: Vec<([f64; 2], f64)>,
}

const BLADES: Parameter = Parameter {
    name: "blades",
    kind: Kind::Whole,
    low: Some((0.0, true)),
    high: Some((MAX_BLADES as f64, true)),
    default: Default::Required,
    unit: "",
    allowed: "0 (a circular stop) or 3 to 64 blades",
    about: "straight blades of the stop; 0 for a circle",
};

const fn fraction(
    name: &'static str,
    (low, high): ((f64, bool), (f64, bool)),
    default: f64,
    allowed: &'static str,
    about: &'static str,
) -> Parameter {
    Parameter {
        name,
        kind: Kind::Number,
        low: Some(low),
        high: Some(high),
        default: Default::Number(default),
        unit: "",
        allowed,
        about,
    }
}

const ROUNDNESS: Parameter = fraction(
    "roundness",
    ((0.0, true), (1.0, true)),
    0.0,
    "0 (straight blades) to 1 (a circle)",
    "0 straight blades … 1 a circle through their tips",
);
const SPECTRAL: Parameter = flag(
    "spectral",
    true,
    "17 wavelengths into R, G, B; false: one, wavelength_nm",
);
const WAVELENGTH: Parameter = Parameter {
    name: "wavelength_nm",
    kind: Kind::Number,
    low: Some((380.0, true)),
    high: Some((780.0, true)),
    default: Default::Number(550.0),
    unit: "nm",
    allowed: "a visible wavelength from 380 to 780 nm",
    about: "the wavelength of an achromatic kernel (spectral = false)",
};
const OBSTRUCTION: Parameter = fraction(
    "obstruction",
    ((0.0, true), (0.95, false)),
    0.0,
    "a fraction of the diameter from 0 to below 0.95",
    "a central obstruction (mirror lenses), of the diameter",
);
const VANES: Parameter = Parameter {
    name: "vanes",
    kind: Kind::Whole,
    low: Some((0.0, true)),
    high: Some((16.0, true)),
    default: Default::Number(0.0),
    unit: "",
    allowed: "0 to 16 spider vanes",
    about: "spider vanes holding the obstruction",
};
const VANE_WIDTH: Parameter = fraction(
    "vane_width",
    ((0.0, false), (0.2, true)),
    0.02,
    "a fraction of the diameter above 0 and at most 0.2",
    "each vane's width, of the diameter",
);
const DUST: Parameter = Parameter {
    name: "dust",
    kind: Kind::Whole,
    low: Some((0.0, true)),
    high: Some((2000.0, true)),
    default: Default::Number(0.0),
    unit: "",
    allowed: "0 to 2000 specks",
    about: "specks of dust in the beam on the front element",
};
const fn micrometres(
    name: &'static str,
    (low, high): (f64, f64),
    default: f64,
    allowed: &'static str,
    about: &'static str,
) -> Parameter {
    Parameter {
        name,
        kind: Kind::Number,
        low: Some((low, true)),
        high: Some((high, true)),
        default: Default::Number(default),
        unit: "µm",
        allowed,
        about,
    }
}
const DUST_MIN: Parameter = micrometres(
    "dust_min_um",
    (1.0, 2000.0),
    20.0,
    "a diameter from 1 to 2000 µm",
    "the smallest specks' diameter",
);
const DUST_MAX: Parameter = micrometres(
    "dust_max_um",
    (1.0, 2000.0),
    150.0,
    "a diameter from 1 to 2000 µm, at least dust_min_um",
    "the largest specks' diameter; sizes are spread evenly in their logarithm",
);
const SCRATCHES: Parameter = Parameter {
    name: "scratches",
    kind: Kind::Whole,
    low: Some((0.0, true)),
    high: Some((32.0, true)),
    default: Default::Number(0.0),
    unit: "",
    allowed: "0 to 32 scratches",
    about: "scratches on the front element; each sends a streak across itself",
};
const SCRATCH_LENGTH: Parameter = Parameter {
    name: "scratch_length_mm",
    kind: Kind::Number,
    low: Some((0.1, true)),
    high: Some((200.0, true)),
    default: Default::Number(10.0),
    unit: "mm",
    allowed: "a length from 0.1 to 200 mm",
    about: "each scratch's length, cut where it leaves the beam",
};
const SCRATCH_WIDTH: Parameter = micrometres(
    "scratch_width_um",
    (1.0, 1000.0),
    20.0,
    "a width from 1 to 1000 µm",
    "each scratch's width",
);
const SCRATCH_ANGLE: Parameter = crate::schema::angle(
    "scratch_angle_deg",
    "the scratches' mean direction; their streaks run across it",
);
const SCRATCH_SPREAD: Parameter = Parameter {
    name: "scratch_spread_deg",
    kind: Kind::Number,
    low: Some((0.0, true)),
    high: Some((180.0, true)),
    default: Default::Number(180.0),
    unit: "°",
    allowed: "a spread from 0 to 180°",
    about: "how far their directions spread about it; 180: any direction",
};
const GREASE: Parameter = fraction(
    "grease",
    ((0.0, true), (0.9, true)),
    0.0,
    "a fraction of the pupil's diameter from 0 to 0.9",
    "a smudge of grease, its diameter of the pupil's; 0 for none",
);
const GREASE_TRANSMISSION: Parameter = fraction(
    "grease_transmission",
    ((0.0, true), (1.0, true)),
    0.8,
    "a fraction of the light from 0 to 1",
    "the share of the light the smudge passes",
);
const GREASE_PHASE: Parameter = Parameter {
    name: "grease_phase_deg",
    kind: Kind::Angle,
    low: None,
    high: None,
    default: Default::Number(90.0),
    unit: "°",
    allowed: "a finite angle in degrees",
    about: "the delay of the light through the smudge, in degrees of phase",
};
const SQUEEZE: Parameter = Parameter {
    name: "squeeze",
    kind: Kind::Number,
    low: Some((0.25, true)),
    high: Some((4.0, true)),
    default: Default::Number(1.0),
    unit: "",
    allowed: "an anamorphic squeeze from 0.25 to 4 (1: a round lens)",
    about: "an anamorphic lens's squeeze: its focal length across x is focal_length_mm over this, its pattern that much narrower across x",
};
const ROTATION: Parameter = crate::schema::angle(
    "rotation_deg",
    "the stop's rotation; at 0 a blade tip points along +x",
);

/// The parameters of one `[[effect.filter]]` family of lines.
pub const FILTER_PARAMETERS: &[Parameter] = &[
    crate::schema::angle(
        "angle_deg",
        "the lines' direction; their rays run perpendicular to them",
    ),
    Parameter {
        name: "spacing_um",
        kind: Kind::Number,
        low: Some((1.0, true)),
        high: Some((10_000.0, true)),
        default: Default::Required,
        unit: "µm",
        allowed: "a line spacing d from 1 to 10000 µm",
        about: "d: the distance between lines; the rays' orders lie λ/d apart",
    },
    Parameter {
        name: "width_um",
        kind: Kind::Number,
        low: Some((0.0, false)),
        high: None,
        default: Default::Required,
        unit: "µm",
        allowed: "a line width e above 0 and below the spacing",
        about: "e: each line's width; e/d sets how the light splits among the orders",
    },
];

impl Model for Aperture {
    const KIND: &'static str = "aperture";
    const PARAMETERS: &'static [Parameter] = &[
        BLADES,
        ROTATION,
        ROUNDNESS,
        SPECTRAL,
        WAVELENGTH,
        OBSTRUCTION,
        VANES,
        VANE_WIDTH,
        DUST,
        DUST_MIN,
        DUST_MAX,
        SCRATCHES,
        SCRATCH_LENGTH,
        SCRATCH_WIDTH,
        SCRATCH_ANGLE,
        SCRATCH_SPREAD,
        GREASE,
        GREASE_TRANSMISSION,
        GREASE_PHASE,
        SQUEEZE,
    ];

    /// Checks every parameter.
    fn validate(&self) -> Result<()> {
        const NAME: &str = "aperture";
        // One or two blades make no stop: the range has a hole.
        check::count(
            NAME,
            BLADES.name,
            self.blades,
            BLADES.admits(f64::from(self.blades)) && !(1..3).contains(&self.blades),
            BLADES.allowed,
        )?;
        ROTATION.check(NAME, self.rotation_deg)?;
        ROUNDNESS.check(NAME, self.roundness)?;
        WAVELENGTH.check(NAME, self.wavelength_nm)?;
        OBSTRUCTION.check(NAME, self.obstruction)?;
        VANE_WIDTH.check(NAME, self.vane_width)?;
        check::count(
            NAME,
            VANES.name,
            self.vanes,
            VANES.admits(f64::from(self.vanes)),
            VANES.allowed,
        )?;
        for (count, parameter) in [(self.dust, &DUST), (self.scratches, &SCRATCHES)] {
            check::count(
                NAME,
                parameter.name,
                count,
                parameter.admits(f64::from(count)),
                parameter.allowed,
            )?;
        }
        DUST_MIN.check(NAME, self.dust_min_um)?;
        // The largest specks are bounded by the smallest too.
        check::range(
            NAME,
            DUST_MAX.name,
            self.dust_max_um,
            DUST_MAX.admits(self.dust_max_um) && self.dust_max_um >= self.dust_min_um,
            DUST_MAX.allowed,
        )?;
        SCRATCH_LENGTH.check(NAME, self.scratch_length_mm)?;
        SCRATCH_WIDTH.check(NAME, self.scratch_width_um)?;
        SCRATCH_ANGLE.check(NAME, self.scratch_angle_deg)?;
        SCRATCH_SPREAD.check(NAME, self.scratch_spread_deg)?;
        GREASE.check(NAME, self.grease)?;
        GREASE_TRANSMISSION.check(NAME, self.grease_transmission)?;
        GREASE_PHASE.check(NAME, self.grease_phase_deg)?;
        SQUEEZE.check(NAME, self.squeeze)?;
        check::count(
            NAME,
            "filter",
            format!("{} families", self.filters.len()),
            self.filters.len() <= MAX_FILTERS,
            "at most 6 families of lines",
        )?;
        let [angle, spacing, width] = FILTER_PARAMETERS else {
            return Ok(());
        };
        for f in &self.filters {
            angle.check("aperture filter", f.angle_deg)?;
            spacing.check("aperture filter", f.spacing_um)?;
            // The width is bounded by this family's own spacing too.
            check::range(
                "aperture filter",
                width.name,
                f.width_um,
                width.admits(f.width_um) && f.width_um < f.spacing_um,
                width.allowed,
            )?;
        }
        Ok(())
    }

    fn planes(&self) -> usize {
        if self.spectral {
            3
        } else {
            1
        }
    }

    fn source(&self, context: &Context) -> Result<Source> {
        let pitch_mm = context
            .pitch_mm
            .ok_or_else(|| Error::needs_sensor_width("aperture diffraction".into()))?;
        let reach = orders_reach(pitch_mm, context.kernel_size);
        let seed = super::stream(context.seed, context.index_of_kind);
        Ok(Source::Diffraction {
            optics: self.optics(context.camera, reach, seed)?,
            light: self.light(),
            pitch_mm,
        })
    }

    /// The pattern in f64 (2 plane bytes per plane) beside its f32 planes:
    /// measured, `psf` of a 4K lens kernel peaks at 3 planes' bytes in one
    /// wavelength and 7 over the spectrum.
    ///
    /// Through a filter (kernel/diffraction/orders.rs) come, beside the
    /// pattern: the filtered planes in f64 (2 plane bytes each), every
    /// plane's comb of orders in f32 (1 each), for the plane at work the
    /// light they move in f64 (2), and the f32 convolution that spreads the
    /// comb: the result and the spectrum with its buffers (about 4).
    fn building_bytes(&self, plane_bytes: u64) -> u64 {
        let planes = self.planes() as u64;
        let pattern = plane_bytes * (2 * planes + 1);
        let filter = if self.filters.is_empty() {
            0
        } else {
            plane_bytes * (2 * planes + 8)
        };
        pattern + filter
    }

    /// A star filter's orders while they are listed (32 bytes each, and
    /// the list they grow from) and while their cores are corrected (the
    /// list, 24 bytes each, their ranks, 8, and a plane's corrected orders,
    /// 48 bytes each): at most 96 bytes per order, counted before the
    /// faintest pairs are dropped. Measured, `psf --preset
    /// star-filter-6pt` for a 64 px wide image peaks at 84 MB of heap with
    /// 1.06 million orders of the 2.2 million counted here.
    fn fixed_building_bytes(&self, context: &Context) -> u64 {
        let (Some(pitch_mm), Some(focal)) = (context.pitch_mm, context.camera.focal_length_mm)
        else {
            return 0;
        };
        if self.filters.is_empty() {
            return 0;
        }
        let reach_mm = self.filter_reach(orders_reach(pitch_mm, context.kernel_size));
        let moved = self
            .filters
            .iter()
            .map(|family| 2 * family.orders_within(focal, reach_mm) as u64);
        let (alone, squares) = moved.fold((0, 0), |(sum, squares), m| (sum + m, squares + m * m));
        // Σ_{f<g} m_f·m_g, the orders two families move together.
        let pairs = (alone * alone - squares) / 2;
        96 * (1 + alone + pairs)
    }
}

/// How far out in mm a filter's orders are kept: as far as the corners of
/// a kernel of `size` px reach.
pub(crate) fn orders_reach(pitch_mm: f64, (width, height): (usize, usize)) -> f64 {
    pitch_mm * ((width * width + height * height) as f64).sqrt() / 2.0
}

/// The optics of the first aperture in `config`'s chain, its dirt drawn
/// from the config's seed as for its kernel (without a filter's orders);
/// `None` without an aperture.
pub fn first_optics(config: &crate::Config) -> Result<Option<Optics>> {
    config
        .first_aperture()
        .map(|a| a.optics(&config.camera, 0.0, super::stream(config.seed, 0)))
        .transpose()
}

impl Aperture {
    /// A stop of `blades` (0: round) with every other parameter at its
    /// default: spectral, unturned, clean, without filter.
    pub fn new(blades: u32) -> Aperture {
        Aperture {
            blades,
            rotation_deg: 0.0,
            roundness: 0.0,
            spectral: yes(),
            wavelength_nm: green(),
            obstruction: 0.0,
            vanes: 0,
            vane_width: vane_width(),
            dust: 0,
            dust_min_um: dust_min(),
            dust_max_um: dust_max(),
            scratches: 0,
            scratch_length_mm: scratch_length(),
            scratch_width_um: scratch_width(),
            scratch_angle_deg: 0.0,
            scratch_spread_deg: scratch_spread(),
            grease: 0.0,
            grease_transmission: grease_transmission(),
            grease_phase_deg: grease_phase(),
            filters: Vec::new(),
            squeeze: one(),
        }
    }

    /// The light the pattern integrates: the spectrum into R, G, B, or one
    /// wavelength.
    pub fn light(&self) -> Light {
        if self.spectral {
            Light::Spectral
        } else {
            Light::Monochrome(self.wavelength_nm)
        }
    }

    /// The pupil and orders for `camera`, with the orders that land within
    /// `reach_mm` of the centre at 380 nm or longer, and the dirt drawn
    /// from `seed`.
    pub fn optics(&self, camera: &CameraGeometry, reach_mm: f64, seed: u64) -> Result<Optics> {
        self.validate()?;
        let need = |field, why| Error::NeedsCamera {
            what: "aperture diffraction".into(),
            field,
            why,
        };
        let focal = camera.focal_length_mm.ok_or_else(|| {
            need(
                "focal_length_mm",
                "the pupil's diameter is f/N, and the pattern's scale λf",
            )
        })?;
        let n = camera
            .f_number
            .ok_or_else(|| need("f_number", "the pupil's diameter is f/N"))?;
        let diameter = focal / n;
        // An anamorphic lens's pattern is a round one's of the stop and
        // the filter stretched along x (pupil/oval.rs; its orders in
        // `orders`).
        let pupil = self.pupil(diameter / 2.0, seed)?;
        Ok(Optics {
            pupil: if self.squeeze == 1.0 {
                pupil
            } else {
                pupil.stretched(self.squeeze)
            },
            diameter_mm: diameter,
            stretch: self.squeeze,
            focal_mm: focal,
            orders: self.orders(focal, self.filter_reach(reach_mm)),
        })
    }

    /// How far out the filter's orders are listed to land within
    /// `reach_mm` of the centre: farther by the squeeze, which moves them
    /// in across x.
    fn filter_reach(&self, reach_mm: f64) -> f64 {
        reach_mm * self.squeeze.max(1.0)
    }

    /// The stop alone, of circumradius `radius` mm: its blades, their
    /// rotation and roundness (what clips a lens's ghosts).
    pub fn stop(&self, radius: f64) -> Pupil {
        let mut pupil = Pupil::new();
        self.outline(&mut pupil, radius);
        pupil
    }

    /// Adds the blades' opening of circumradius `radius` to `pupil`;
    /// returns the radius of the circle it inscribes.
    fn outline(&self, pupil: &mut Pupil, radius: f64) -> f64 {
        let rotation = self.rotation_deg.to_radians();
        if self.blades == 0 {
            pupil.add_disc([0.0, 0.0], radius, true);
            radius
        } else {
            let n = self.blades as usize;
            let apothem = radius * libm::cos(PI / n as f64);
            let segments = if self.roundness > 0.0 {
                ARC_SEGMENTS
            } else {
                1
            };
            let mut vertices = Vec::with_capacity(n * segments);
            for k in 0..n {
                let start = rotation + TAU * k as f64 / n as f64;
                let middle = start + PI / n as f64;
                for s in 0..segments {
                    let theta = start + TAU / n as f64 * s as f64 / segments as f64;
                    let straight = apothem / libm::cos(theta - middle);
                    let r = (1.0 - self.roundness) * straight + self.roundness * radius;
                    vertices.push([r * libm::cos(theta), r * libm::sin(theta)]);
                }
            }
            pupil.add_sampled_polygon(&vertices, true, segments);
            (1.0 - self.roundness) * apothem + self.roundness * radius
        }
    }

    /// The stop of circumradius `radius` mm, with obstruction, vanes and
    /// dirt drawn from `seed`.
    fn pupil(&self, radius: f64, seed: u64) -> Result<Pupil> {
        let mut pupil = Pupil::new();
        let rotation = self.rotation_deg.to_radians();
        let inner_radius = self.outline(&mut pupil, radius);
        let obstruction = self.obstruction * radius;
        if obstruction > 0.0 {
            pupil.add_disc([0.0, 0.0], obstruction, false);
        }
        let half_width = self.vane_width * radius;
        // Vanes run from the obstruction (or near the centre, where they
        // would overlap) to the inscribed circle, within the open pupil.
        let start = obstruction.max(2.0 * half_width);
        let mut vanes = Vec::new();
        for v in 0..self.vanes {
            let angle = rotation + TAU * v as f64 / self.vanes as f64;
            let (s, c) = libm::sincos(angle);
            let corner = |along: f64, across: f64| [along * c - across * s, along * s + across * c];
            if inner_radius > start {
                pupil.add_polygon(
                    &[
                        corner(start, -half_width),
                        corner(inner_radius, -half_width),
                        corner(inner_radius, half_width),
                        corner(start, half_width),
                    ],
                    false,
                );
                vanes.push(dirt::Strip {
                    start: corner(start, 0.0),
                    end: corner(inner_radius, 0.0),
                    half: half_width,
                });
            }
        }
        let clearance = dirt::Clearance {
            // Rounded blades are sampled by chords, which cut inside the
            // curve's inscribed circle by at most 4·10⁻⁴ of the radius.
            inner: inner_radius * (1.0 - 1e-3),
            obstruction,
            vanes,
        };
        dirt::add(&self.dirt(), radius, &clearance, seed, &mut pupil)?;
        Ok(pupil)
    }

    /// The dirt, in mm and radians.
    fn dirt(&self) -> dirt::Dirt {
        let amplitude = self.grease_transmission.sqrt();
        let phase = self.grease_phase_deg.to_radians();
        dirt::Dirt {
            dust: self.dust,
            dust_diameters: [self.dust_min_um * 1e-3, self.dust_max_um * 1e-3],
            scratches: self.scratches,
            scratch_length: self.scratch_length_mm,
            scratch_width: self.scratch_width_um * 1e-3,
            scratch_angle: self.scratch_angle_deg.to_radians(),
            scratch_spread: self.scratch_spread_deg.to_radians(),
            grease: self.grease,
            grease_amplitude: [amplitude * libm::cos(phase), amplitude * libm::sin(phase)],
        }
    }

    /// Diffraction orders of the filter families: a family of opaque lines
    /// of width e every d transmits T = Σ c_m e^(2πi m s/d) with
    /// c₀ = 1 − e/d, c_m = −(e/d)·sinc(πme/d). Orders are kept alone or in
    /// pairs of families (triple products are weaker than 10⁻⁶ of the light).
    /// An anamorphic lens's filter is stretched with its stop along x
    /// (pupil/oval.rs), so that its orders lie `squeeze` times closer
    /// across x; `reach_mm` is [`Aperture::filter_reach`]'s.
    fn orders(&self, focal: f64, reach_mm: f64) -> Vec<([f64; 2], f64)> {
        // (frequency shift, weight, families with a non-zero order)
        let mut orders = vec![([0.0, 0.0], 1.0, 0u8)];
        for family in &self.filters {
            let (d, e) = (family.spacing_um * 1e-3, family.width_um * 1e-3);
            let normal = (family.angle_deg + 90.0).to_radians();
            let (s, c) = libm::sincos(normal);
            let count = family.orders_within(focal, reach_mm);
            let coefficient = |m: i64| {
                if m == 0 {
                    1.0 - e / d
                } else {
                    let z = PI * m as f64 * e / d;
                    -(e / d) * libm::sin(z) / z
                }
            };
            // Each order's share and shift once, not once per order it
            // multiplies: a star filter's families make millions of pairs.
            let steps: Vec<(f64, [f64; 2], bool)> = (-count..=count)
                .map(|m| {
                    let shift = m as f64 / d;
                    (
                        coefficient(m).powi(2),
                        [shift * c / self.squeeze, shift * s],
                        m != 0,
                    )
                })
                .collect();
            // An order already moved by two families stays where it is
            // (m = 0 only), without a pass over the others.
            let unmoved = &steps[count as usize..=count as usize];
            let choices = |used: u8| if used >= 2 { unmoved } else { &steps[..] };
            let kept = |weight: f64, share: f64| weight * share >= 1e-12;
            // Counted first: the list, grown as it is filled, would leave
            // the memory of every smaller list it outgrew in the heap.
            let length = orders
                .iter()
                .map(|&(_, weight, used)| {
                    choices(used)
                        .iter()
                        .filter(|(share, ..)| kept(weight, *share))
                        .count()
                })
                .sum();
            let mut next = Vec::with_capacity(length);
            for &(nu, weight, used) in &orders {
                for &(share, [dx, dy], moved) in choices(used) {
                    if kept(weight, share) {
                        let w = weight * share;
                        next.push(([nu[0] + dx, nu[1] + dy], w, used + u8::from(moved)));
                    }
                }
            }
            orders = next;
        }
        let mut orders: Vec<([f64; 2], f64)> =
            orders.into_iter().map(|(nu, w, _)| (nu, w)).collect();
        // By ν_y (then ν_x and share, so that equal orders are alike): the
        // orders of one wavelength that land in a band of the kernel's rows
        // lie together (kernel/diffraction/orders.rs).
        orders.par_sort_unstable_by(|(a, wa), (b, wb)| {
            (a[1].total_cmp(&b[1]))
                .then(a[0].total_cmp(&b[0]))
                .then(wa.total_cmp(wb))
        });
        orders
    }
}
