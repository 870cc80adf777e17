//! Lens prescriptions: the surfaces of a real lens in order, as a patent
//! prints them (radius of curvature, thickness to the next surface, the
//! glass after it by n_d and V_d, clear semi-aperture), with the stop among
//! them and each surface's anti-reflection coating. What lens ghosts are
//! traced through (docs/physics.md §12); [`paraxial`] gives a lens's focal
//! length, back focus and pupils.
//!
//! A lens file is TOML (docs/lenses.md has the schema):
//!
//! ```
//! let lens = aureole::lens::Lens::parse(r#"
//!     name = "A thin biconvex singlet"
//!     [[surface]]
//!     stop = true
//!     semi_aperture = 10.0
//!     [[surface]]
//!     radius = 103.0
//!     thickness = 4.0
//!     n_d = 1.5168
//!     v_d = 64.17
//!     semi_aperture = 12.0
//!     [[surface]]
//!     radius = -103.0
//!     thickness = 96.0
//!     semi_aperture = 12.0
//! "#, "singlet.toml")?;
//! let first = lens.paraxial()?;
//! assert!((first.focal_length - 100.0).abs() < 1.0);
//! # Ok::<(), aureole::Error>(())
//! ```

mod bundle;
pub mod canvas;
pub mod coating;
pub mod effect;
pub mod ghost;
pub mod paraxial;
mod parse;
pub mod passage;
pub mod shipped;
pub mod trace;

pub use paraxial::Paraxial;

/// The Fraunhofer d line (helium), nm: where n_d is given.
pub const D_LINE_NM: f64 = 587.5618;
/// The F line (hydrogen), nm.
pub const F_LINE_NM: f64 = 486.1327;
/// The C line (hydrogen), nm.
pub const C_LINE_NM: f64 = 656.2725;

/// MgF₂'s index, the single-layer coating's default.
pub const MGF2_INDEX: f64 = 1.38;
/// The wavelength a single layer is a quarter wave thick at by default, nm.
pub const DESIGN_NM: f64 = 550.0;

/// A lens: its surfaces from the front (the object side) to the back.
#[derive(Debug, Clone, PartialEq)]
pub struct Lens {
    /// What the lens is, in words.
    pub name: String,
    /// Where its prescription comes from, when a patent.
    pub patent: Option<Patent>,
    /// Millimetres per unit of the prescription's lengths: a patent
    /// normalised to f = 100 made as a 50 mm lens has 0.5.
    pub mm_per_unit: f64,
    /// The surfaces, front first; exactly one is the stop.
    pub surfaces: Vec<Surface>,
}

/// A patent's example, and what it states of it, in the prescription's
/// units: the tests hold the paraxial trace to these.
#[derive(Debug, Clone, PartialEq)]
pub struct Patent {
    /// Its number, as printed (e.g. `US 2,701,982`).
    pub number: String,
    /// Which example of it (e.g. `Example 1`, `Table 3`).
    pub example: String,
    /// The effective focal length it states.
    pub focal_length: Option<f64>,
    /// The back focal distance it states (last surface to focus).
    pub back_focus: Option<f64>,
    /// The f-number it states.
    pub f_number: Option<f64>,
}

/// One surface, and what follows it up to the next.
#[derive(Debug, Clone, PartialEq)]
pub struct Surface {
    /// Radius of curvature, positive when its centre lies behind it
    /// (towards the image); `None` for a plane. Across the x–z plane only
    /// where `radius_y` is given.
    pub radius: Option<f64>,
    /// An anamorphic surface's radius across the y–z plane, where it
    /// differs from `radius` (`Some(None)`: flat that way): a cylinder
    /// when one of the two is flat, else a torus, the y–z section's circle
    /// turned about an axis parallel to y through the x–z section's
    /// centre. `None`: the surface is turned about the lens's axis.
    pub radius_y: Option<Option<f64>>,
    /// Distance along the axis to the next surface (after the last: to
    /// the image plane as designed, 0 where not given).
    pub thickness: f64,
    /// What fills the space after it.
    pub medium: Medium,
    /// Clear semi-aperture: light farther from the axis is stopped.
    pub semi_aperture: f64,
    /// Its anti-reflection coating.
    pub coating: Coating,
    /// Whether it is the aperture stop (a plane in the medium before it,
    /// whose opening the camera's blades shape).
    pub stop: bool,
}

/// What fills the space after a surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Medium {
    /// Air (n = 1).
    Air,
    /// A glass by its index at the d line and its Abbe number; without an
    /// Abbe number (pbrt's lens files give none) it does not disperse.
    Glass {
        /// n_d.
        n_d: f64,
        /// V_d = (n_d − 1) / (n_F − n_C).
        v_d: Option<f64>,
    },
}

impl Surface {
    /// Its curvatures across the x–z and the y–z plane, per unit of the
    /// prescription: 1/R, 0 where flat.
    pub fn curvatures(&self) -> (f64, f64) {
        let of = |r: Option<f64>| r.map_or(0.0, |r| 1.0 / r);
        (of(self.radius), of(self.radius_y.unwrap_or(self.radius)))
    }

    /// Whether it is turned about the lens's axis (a sphere or a plane).
    pub fn is_round(&self) -> bool {
        self.radius_y.is_none_or(|y| y == self.radius)
    }
}

impl Medium {
    /// The index at `nm`: two-term Cauchy, n = A + B/λ², through n_d with
    /// n_F − n_C = (n_d − 1)/V_d, which is what n_d and V_d say of a glass.
    pub fn index_at(&self, nm: f64) -> f64 {
        match *self {
            Medium::Air => 1.0,
            Medium::Glass { n_d, v_d: None } => n_d,
            Medium::Glass {
                n_d,
                v_d: Some(v_d),
            } => {
                let inverse_square = |l: f64| 1.0 / (l * l);
                let b = (n_d - 1.0) / v_d / (inverse_square(F_LINE_NM) - inverse_square(C_LINE_NM));
                n_d + b * (inverse_square(nm) - inverse_square(D_LINE_NM))
            }
        }
    }

    /// Whether this is glass.
    pub fn is_glass(&self) -> bool {
        matches!(self, Medium::Glass { .. })
    }
}

/// An anti-reflection coating: thin layers on the surface, the first
/// facing the air (or the medium in front), or none.
#[derive(Debug, Clone, PartialEq)]
pub enum Coating {
    /// Bare glass.
    None,
    /// Thin layers, from the front medium's side inwards.
    Layers(Vec<Layer>),
}

impl Coating {
    /// One layer of index `index`, a quarter wave thick at `design_nm`.
    pub fn quarter_wave(index: f64, design_nm: f64) -> Coating {
        Coating::Layers(vec![Layer {
            index,
            thickness_nm: design_nm / (4.0 * index),
        }])
    }

    /// The usual single layer: MgF₂, a quarter wave at 550 nm.
    pub fn magnesium_fluoride() -> Coating {
        Coating::quarter_wave(MGF2_INDEX, DESIGN_NM)
    }

    /// The coating a surface between `before` and `after` takes when its
    /// prescription gives none: `usual` where it separates air from
    /// glass; none where it is cemented (glass on both sides) or between
    /// airs (the stop).
    pub fn unless_given(before: Medium, after: Medium, usual: &Coating) -> Coating {
        if before.is_glass() != after.is_glass() {
            usual.clone()
        } else {
            Coating::None
        }
    }
}

/// One thin layer of a coating.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Layer {
    /// Its refractive index (taken as the same at every wavelength).
    pub index: f64,
    /// Its physical thickness, nm.
    pub thickness_nm: f64,
}

impl Lens {
    /// Parses and checks a lens file's text; `source_name` starts every
    /// error message, with the line and column.
    pub fn parse(text: &str, source_name: &str) -> crate::Result<Lens> {
        parse::lens(text, source_name)
    }

    /// The lens from surfaces made elsewhere (an importer), checked as a
    /// file's are; `source_name` starts its error messages.
    pub fn from_surfaces(
        name: String,
        patent: Option<Patent>,
        surfaces: Vec<Surface>,
        source_name: &str,
    ) -> crate::Result<Lens> {
        let lens = Lens {
            name,
            patent,
            mm_per_unit: 1.0,
            surfaces,
        };
        parse::check(&lens).map_err(|message| crate::Error::Lens {
            name: source_name.to_string(),
            message,
        })?;
        Ok(lens)
    }

    /// The index of the stop among the surfaces.
    pub fn stop(&self) -> usize {
        self.surfaces.iter().position(|s| s.stop).unwrap_or(0)
    }

    /// The paraxial data at the d line, in the prescription's units, in
    /// the y–z plane: an anamorphic lens is named by its vertical focal
    /// length, as cinema's are.
    pub fn paraxial(&self) -> crate::Result<Paraxial> {
        paraxial::trace(self, D_LINE_NM, paraxial::Meridian::Y)
    }

    /// The same in the x–z plane: the same as [`Lens::paraxial`] unless
    /// the lens is anamorphic.
    pub fn paraxial_x(&self) -> crate::Result<Paraxial> {
        paraxial::trace(self, D_LINE_NM, paraxial::Meridian::X)
    }

    /// Whether some surface is not turned about the axis.
    pub fn is_anamorphic(&self) -> bool {
        !self.surfaces.iter().all(Surface::is_round)
    }

    /// The anamorphic squeeze: the vertical focal length over the
    /// horizontal (1 for a round lens; 2 for a lens that puts twice the
    /// width of its height's view on the sensor).
    pub fn squeeze(&self) -> crate::Result<f64> {
        Ok(self.paraxial()?.focal_length / self.paraxial_x()?.focal_length)
    }

    /// The medium in front of surface `i`: air before the first.
    pub fn medium_before(&self, i: usize) -> Medium {
        i.checked_sub(1)
            .and_then(|j| self.surfaces.get(j))
            .map_or(Medium::Air, |s| s.medium)
    }

    /// The file text of this lens in the TOML schema that
    /// [`Lens::parse`] reads: what an importer writes.
    pub fn to_toml(&self) -> String {
        parse::to_toml(self)
    }
}
