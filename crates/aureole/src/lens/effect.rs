//! `type = "ghosts"`: a config's lens ghosts. Ghosts move with their
//! source, so they are no kernel: the pipeline gives them a stage of their
//! own before the kernel's (docs/physics.md §12), fed by the scene's
//! bright sources. This is what a config says of them, and the optics a
//! frame of a given width traces them through: the lens at the camera's
//! focal length, its stop at the camera's f-number shaped by the chain's
//! aperture blades.

use std::path::{Path, PathBuf};

use serde::Deserialize;

use super::ghost::{self, Sensor};
use super::trace::Layout;
use super::{shipped, Lens};
use crate::camera::CameraGeometry;
use crate::error::{Error, Result};
use crate::optics::aperture::pupil::Pupil;
use crate::optics::Aperture;
use crate::schema::{flag, Default, Kind, Parameter};

/// The `type` a config names the ghosts by.
pub const KIND: &str = "ghosts";

/// The ghosts' parameters, as a front end shows them.
pub const PARAMETERS: &[Parameter] = &[LENS, SOURCES, THRESHOLD, SPECTRAL];

const LENS: Parameter = Parameter {
    name: "lens",
    kind: Kind::Text,
    low: None,
    high: None,
    default: Default::Required,
    unit: "",
    allowed: "a shipped lens's name, a lens file (.toml) or the lens's tables inline",
    about: "The lens whose surfaces reflect: a shipped lens (docs/lenses.md lists them) or a prescription file.",
};

const SOURCES: Parameter = Parameter {
    name: "sources",
    kind: Kind::Whole,
    low: Some((1.0, true)),
    high: Some((256.0, true)),
    default: Default::Number(16.0),
    unit: "",
    allowed: "a whole number of sources from 1 to 256",
    about: "How many of the brightest sources throw ghosts.",
};

const THRESHOLD: Parameter = Parameter {
    name: "threshold",
    kind: Kind::Number,
    low: Some((0.0, false)),
    high: None,
    default: Default::Number(1000.0),
    unit: "cd/m²",
    allowed: "a luminance in cd/m² above 0",
    about: "Pixels brighter than this are light sources; touching ones make one source.",
};

const SPECTRAL: Parameter = flag(
    "spectral",
    false,
    "Trace 17 wavelengths from 380 to 780 nm rather than one per channel.",
);

/// The lens a config's ghosts are traced through, and how it was named.
#[derive(Debug, Clone, PartialEq)]
pub struct LensChoice {
    /// How the config names it.
    pub named: Named,
    /// The prescription.
    pub lens: Lens,
}

/// How a config names its lens.
#[derive(Debug, Clone, PartialEq)]
pub enum Named {
    /// A shipped lens, by name.
    Shipped(String),
    /// A lens file (its path as resolved from the config's folder).
    File(PathBuf),
    /// The lens's tables written in the config.
    Inline,
}

/// A config's lens ghosts.
#[derive(Debug, Clone, PartialEq)]
pub struct Ghosts {
    /// The lens.
    pub lens: LensChoice,
    /// How many of the brightest sources throw ghosts.
    pub sources: u32,
    /// cd/m² above which a pixel is a source.
    pub threshold: f64,
    /// Whether to trace 17 wavelengths rather than one per channel.
    pub spectral: bool,
}

/// The `[[effect]]` table of `type = "ghosts"`, as serde reads it.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct Table {
    lens: toml::Value,
    #[serde(default = "sixteen")]
    sources: u32,
    #[serde(default = "thousand")]
    threshold: f64,
    #[serde(default)]
    spectral: bool,
}

fn sixteen() -> u32 {
    16
}

fn thousand() -> f64 {
    1000.0
}

impl Table {
    /// The ghosts, their lens read (a path relative to `folder`, the
    /// config's; refused without one) and every value checked.
    pub(crate) fn resolve(self, folder: Option<&Path>) -> Result<Ghosts> {
        SOURCES.check(KIND, f64::from(self.sources))?;
        THRESHOLD.check(KIND, self.threshold)?;
        let lens = match self.lens {
            toml::Value::String(name) => match shipped::find(&name) {
                Some(found) => LensChoice {
                    named: Named::Shipped(name),
                    lens: found.lens()?,
                },
                None if name.ends_with(".toml") => {
                    let Some(folder) = folder else {
                        return Err(Error::Parameter {
                            effect: KIND.to_string(),
                            name: "lens",
                            value: format!("{name:?}"),
                            allowed: "here a shipped lens's name or the lens's tables inline: no lens files are read",
                        });
                    };
                    // Absolute, so that the config written back (a
                    // camera sent to another process) finds it too.
                    let joined = folder.join(&name);
                    let path = std::path::absolute(&joined).unwrap_or(joined);
                    let text = std::fs::read_to_string(&path).map_err(|e| Error::io(&path, e))?;
                    LensChoice {
                        lens: Lens::parse(&text, &path.display().to_string())?,
                        named: Named::File(path),
                    }
                }
                None => {
                    return Err(Error::UnknownLens {
                        suggestion: crate::error::closest(
                            &name,
                            shipped::LENSES.iter().map(|l| l.name),
                        ),
                        name,
                        available: shipped::names(),
                    })
                }
            },
            toml::Value::Table(table) => LensChoice {
                lens: Lens::parse(&table.to_string(), "the config's inline lens")?,
                named: Named::Inline,
            },
            other => {
                return Err(Error::Parameter {
                    effect: KIND.to_string(),
                    name: "lens",
                    value: other.to_string(),
                    allowed: LENS.allowed,
                })
            }
        };
        Ok(Ghosts {
            lens,
            sources: self.sources,
            threshold: self.threshold,
            spectral: self.spectral,
        })
    }
}

impl Ghosts {
    /// The `[[effect]]` table that reads back as these ghosts.
    pub fn to_table(&self) -> toml::Table {
        let mut table = toml::Table::new();
        table.insert("type".into(), KIND.into());
        let lens = match &self.lens.named {
            Named::Shipped(name) => toml::Value::String(name.clone()),
            Named::File(path) => toml::Value::String(path.display().to_string()),
            Named::Inline => toml::from_str::<toml::Table>(&self.lens.lens.to_toml())
                .map_or_else(|_| toml::Value::String(String::new()), toml::Value::Table),
        };
        table.insert("lens".into(), lens);
        if self.sources != sixteen() {
            table.insert("sources".into(), i64::from(self.sources).into());
        }
        if self.threshold != thousand() {
            table.insert("threshold".into(), self.threshold.into());
        }
        if self.spectral {
            table.insert("spectral".into(), true.into());
        }
        table
    }

    /// The optics a frame whose display window is `width` pixels across
    /// traces its ghosts through ([`GhostOptics::new`]).
    pub fn optics(
        &self,
        camera: &CameraGeometry,
        aperture: Option<&Aperture>,
        width: usize,
    ) -> Result<GhostOptics> {
        GhostOptics::new(&self.lens.lens, camera, aperture, width, self.spectral)
    }
}

/// What one frame's ghosts are traced through.
#[derive(Debug, Clone)]
pub struct GhostOptics {
    /// The lens at the camera's focal length.
    pub lens: Lens,
    /// The stop's opening, mm in its plane.
    stop: Pupil,
    /// The radius of the circle about the stop's opening, mm.
    radius: f64,
    /// The f-number traced at.
    pub f_number: f64,
    /// The focal lengths across x and y, mm (the two differ for an
    /// anamorphic lens).
    pub focal_mm: (f64, f64),
    /// The pixel pitch, mm.
    pub pitch_mm: f64,
    /// The wavelengths, each with its weight in R, G and B.
    pub light: Vec<(f64, Vec<f64>)>,
}

impl GhostOptics {
    /// `lens` for a frame whose display window is `width` pixels across:
    /// scaled to `camera`'s focal length (its own without one), its stop
    /// at the camera's f-number (no wider than the lens opens) shaped by
    /// `aperture`'s blades (round without one), traced at R, G and B or,
    /// `spectral`, at 17 wavelengths.
    pub fn new(
        lens: &Lens,
        camera: &CameraGeometry,
        aperture: Option<&Aperture>,
        width: usize,
        spectral: bool,
    ) -> Result<GhostOptics> {
        let pitch_mm = camera
            .pixel_pitch_mm(width)
            .ok_or_else(|| Error::NeedsCamera {
                what: "ghosts".into(),
                field: "sensor_width_mm",
                why: "the ghosts' places and sizes on the sensor are in mm",
            })?;
        let mut lens = lens.clone();
        let paraxial = lens.paraxial()?;
        let across = lens.paraxial_x()?;
        // The stop's diffraction and the ghosts are one lens's: an
        // anamorphic lens squeezes both.
        let squeeze = paraxial.focal_length / across.focal_length;
        if let Some(stated) = aperture.map(|a| a.squeeze) {
            if (stated / squeeze - 1.0).abs() > 0.005 {
                return Err(Error::Lens {
                    name: lens.name.clone(),
                    message: format!(
                        "it squeezes {squeeze:.3} but the aperture's squeeze is {stated}: write squeeze = {squeeze:.3} in the aperture effect, so that its diffraction is this lens's"
                    ),
                });
            }
        }
        if let Some(focal) = camera.focal_length_mm {
            lens.mm_per_unit = focal / paraxial.focal_length;
        }
        let stop = &lens.surfaces[lens.stop()];
        let open = stop.semi_aperture * lens.mm_per_unit;
        let f_number = camera
            .f_number
            .map_or(paraxial.f_number, |n| n.max(paraxial.f_number));
        let radius = open * paraxial.f_number / f_number;
        let round = Aperture::new(0);
        let pupil = aperture.unwrap_or(&round).stop(radius);
        let mm = lens.mm_per_unit;
        let focal_mm = (across.focal_length * mm, paraxial.focal_length * mm);
        Ok(GhostOptics {
            lens,
            stop: pupil,
            radius,
            f_number,
            focal_mm,
            pitch_mm,
            light: ghost::light(spectral),
        })
    }

    /// Whether rays traced through these optics are those of `other`:
    /// the same lens, circle about the stop and wavelengths, whatever the
    /// stop's opening within the circle ([`crate::lens::ghost::Rays`]).
    pub fn traces_like(&self, other: &GhostOptics) -> bool {
        self.lens == other.lens
            && self.radius == other.radius
            && self.focal_mm == other.focal_mm
            && self.light == other.light
    }

    /// The lens set out for tracing, its stop the camera's, its surfaces'
    /// reflectances tabulated at the light's wavelengths.
    pub fn layout(&self) -> Result<Layout<'_>> {
        let nms: Vec<f64> = self.light.iter().map(|(nm, _)| *nm).collect();
        Ok(Layout::new(&self.lens)?
            .with_stop(self.stop.clone(), self.radius)
            .with_wavelengths(&nms))
    }

    /// A sensor of `width`×`height` pixels of this pitch, the axis at
    /// `centre` (column, row).
    pub fn sensor(&self, (width, height): (usize, usize), centre: (f64, f64)) -> Sensor {
        Sensor {
            width,
            height,
            pitch_mm: self.pitch_mm,
            centre,
        }
    }
}
