//! The physical models of the camera's optical chain (docs/physics.md
//! §2–6), one module each, and the registry that names them.
//!
//! A PSF is P(r, φ) = (1 − ε) δ(r) + ε f(r, φ): a fraction ε of the light is
//! spread by f, the rest stays where it fell. Each model gives ε and the
//! shape of f (or, for diffraction, the whole pattern) and f's light over
//! the whole plane (`whole`); [`crate::kernel`] averages f over pixel
//! areas and divides it by that light, so constant factors of f never
//! matter and the light beyond the kernel leaves.
//!
//! A new effect is one module with a type that implements [`Model`], and
//! one line in the [`effects!`] list below: the config schema, the list of
//! types in error messages, the kernel builder and the memory estimate all
//! come from there.

pub mod aperture;
pub mod bloom;
pub mod corona;
pub mod eye;
pub mod halation;
pub mod measured;
pub(crate) mod shape;
pub mod vos;
pub(crate) mod whole;

pub use aperture::{Aperture, Filter};
pub use bloom::Bloom;
pub use corona::{Corona, RayFactors};
pub use eye::Eye;
pub use halation::Halation;
pub use measured::Measured;
pub use vos::Vos;

use serde::de::Error as _;
use serde::Deserialize;

use crate::camera::CameraGeometry;
use crate::error::Result;
use crate::sending::Sending;
use aperture::{spectrum::Light, Optics};
use shape::SpreadShape;

/// What the kernel builder knows when it asks a model for its PSF.
pub(crate) struct Context<'a> {
    /// The camera of the configuration.
    pub camera: &'a CameraGeometry,
    /// The pixel pitch in mm of the image the kernel is for (sensor width /
    /// image width), when the camera has a sensor width.
    pub pitch_mm: Option<f64>,
    /// The seed of the configuration's randomness.
    pub seed: u64,
    /// How many effects of the same type come before this one in the
    /// chain: each draws its own random numbers from the one seed.
    pub index_of_kind: usize,
    /// The size of the kernel being built, width × height in pixels.
    pub kernel_size: (usize, usize),
    /// What sends the light the kernel spreads.
    pub sending: Sending,
}

/// The random stream of the `index`-th effect of one type in a chain: each
/// draws its own numbers from the config's one seed.
pub(crate) fn stream(seed: u64, index: usize) -> u64 {
    seed.wrapping_add((index as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15))
}

/// An effect ready to rasterise.
pub(crate) enum Source {
    /// ε and the shape of f: K = (1 − ε)·δ + ε·F/ΣF.
    Shape(f64, Box<dyn SpreadShape>),
    /// One ε and shape per colour plane (R, G, B).
    Shapes(Vec<(f64, Box<dyn SpreadShape>)>),
    /// All of K, one plane per colour, rasterised at the kernel's extent
    /// and normalised.
    Pattern(Vec<Vec<f64>>),
    /// A diffraction pattern, all of K, from the pupil and filter in
    /// `optics`, integrated over `light`, at `pitch_mm` per pixel.
    Diffraction {
        optics: Optics,
        light: Light,
        pitch_mm: f64,
    },
}

/// One physical model of the optical chain, as a config file's
/// `[[effect]]` table describes it.
pub(crate) trait Model:
    Clone + PartialEq + std::fmt::Debug + serde::de::DeserializeOwned
{
    /// The `type` a config file names it by.
    const KIND: &'static str;

    /// Its parameters, in the order a config lists them: what `validate`
    /// checks and what a front end shows.
    const PARAMETERS: &'static [crate::schema::Parameter];

    /// Checks every parameter against its allowed range.
    fn validate(&self) -> Result<()>;

    /// How many planes its PSF has: three (R, G, B) for light integrated
    /// over the spectrum, one otherwise.
    fn planes(&self) -> usize {
        1
    }

    /// Its PSF, for the kernel builder to rasterise.
    fn source(&self, context: &Context) -> Result<Source>;

    /// The bytes its own pattern takes while it is built, for kernel planes
    /// of `plane_bytes` each (f32), besides the chain built before it.
    fn building_bytes(&self, plane_bytes: u64) -> u64 {
        plane_bytes * self.planes() as u64 + plane_bytes / 2
    }

    /// The bytes its building holds beside its planes, whatever their
    /// size: a star filter's orders, as many for a thumbnail as for 4K.
    fn fixed_building_bytes(&self, _context: &Context) -> u64 {
        0
    }

    /// How far from the centre, in pixels, its PSF can hold light; `None`
    /// when it may reach the whole kernel. Composing the chain cuts the
    /// transforms to the shorter reach, which the memory estimate follows.
    fn reach_px(&self, _context: &Context) -> Option<f64> {
        None
    }

    /// Its lengths given in pixels, times `factor` (for an image resampled
    /// by it); lengths on the sensor follow the pitch by themselves.
    fn scale_pixels(&mut self, _factor: f64) {}
}

/// The registry: the effect enum, its dispatch to each [`Model`], the list
/// of type names and the reading of an `[[effect]]` table, from one list.
macro_rules! effects {
    ($($(#[$doc:meta])* $variant:ident($model:ty),)*) => {
        /// One optical element of the camera's chain. A config file writes
        /// it as an `[[effect]]` table whose `type` names it (see
        /// [`EFFECT_TYPES`]).
        #[derive(Debug, Clone, PartialEq)]
        pub enum Effect {
            $($(#[$doc])* $variant($model),)*
        }

        /// The effect types a config file may name.
        pub const EFFECT_TYPES: &[&str] = &[$(<$model as Model>::KIND,)*];

        /// Each effect type with its parameters.
        pub const EFFECT_PARAMETERS: &[(&str, &[crate::schema::Parameter])] =
            &[$((<$model as Model>::KIND, <$model as Model>::PARAMETERS),)*];

        impl Effect {
            /// The effect's type as written in a config file.
            pub fn kind(&self) -> &'static str {
                match self {
                    $(Effect::$variant(_) => <$model as Model>::KIND,)*
                }
            }

            /// How many planes its PSF has: three (R, G, B) for diffraction
            /// computed over the spectrum, one otherwise.
            pub fn planes(&self) -> usize {
                match self {
                    $(Effect::$variant(model) => model.planes(),)*
                }
            }

            /// Checks every parameter against its allowed range.
            pub fn validate(&self) -> Result<()> {
                match self {
                    $(Effect::$variant(model) => model.validate(),)*
                }
            }

            pub(crate) fn source(&self, context: &Context) -> Result<Source> {
                match self {
                    $(Effect::$variant(model) => model.source(context),)*
                }
            }

            /// Its lengths given in pixels, times `factor`: the same effect
            /// on an image resampled by `factor` (a preview).
            pub fn scale_pixels(&mut self, factor: f64) {
                match self {
                    $(Effect::$variant(model) => model.scale_pixels(factor),)*
                }
            }

            pub(crate) fn building_bytes(&self, plane_bytes: u64) -> u64 {
                match self {
                    $(Effect::$variant(model) => model.building_bytes(plane_bytes),)*
                }
            }

            pub(crate) fn fixed_building_bytes(&self, context: &Context) -> u64 {
                match self {
                    $(Effect::$variant(model) => model.fixed_building_bytes(context),)*
                }
            }

            pub(crate) fn reach_px(&self, context: &Context) -> Option<f64> {
                match self {
                    $(Effect::$variant(model) => model.reach_px(context),)*
                }
            }

            /// Reads an `[[effect]]` table: its `type` names the model, the
            /// other keys are the model's parameters. The error is serde's
            /// (unknown type, field or value), for the config reader to place.
            pub fn from_table(mut table: toml::Table) -> std::result::Result<Effect, toml::de::Error> {
                let kind = match table.remove("type") {
                    Some(toml::Value::String(kind)) => kind,
                    Some(other) => {
                        return Err(toml::de::Error::custom(format!(
                            "`type` = {other} is not a string; write one of {}",
                            EFFECT_TYPES.iter().map(|k| format!("\"{k}\"")).collect::<Vec<_>>().join(", ")
                        )))
                    }
                    None => return Err(toml::de::Error::missing_field("type")),
                };
                $(
                    if kind == <$model as Model>::KIND {
                        return <$model>::deserialize(toml::Value::Table(table)).map(Effect::$variant);
                    }
                )*
                Err(toml::de::Error::unknown_variant(&kind, EFFECT_TYPES))
            }

            /// The `[[effect]]` table that reads back as this effect: its
            /// `type`, then the parameters that differ from their defaults.
            pub fn to_table(&self) -> toml::Table {
                let mut table = toml::Table::new();
                table.insert("type".to_string(), toml::Value::String(self.kind().to_string()));
                let parameters = match self {
                    $(Effect::$variant(model) => toml::Table::try_from(model),)*
                };
                table.extend(parameters.into_iter().flatten());
                let keys: Vec<String> = table.keys().filter(|k| *k != "type").cloned().collect();
                for key in keys {
                    let Some(value) = table.remove(&key) else { continue };
                    // A key is left out when the effect reads the same
                    // without it: a default.
                    if Effect::from_table(table.clone()).ok().as_ref() != Some(self) {
                        table.insert(key, value);
                    }
                }
                table
            }
        }

        $(
            impl From<$model> for Effect {
                fn from(model: $model) -> Effect {
                    Effect::$variant(model)
                }
            }
        )*
    };
}

effects! {
    /// Scattering in the lens and the emulsion (paper Eq. 6).
    Bloom(Bloom),
    /// Star rays (paper Eq. 7).
    Corona(Corona),
    /// Human-eye glare after Vos (paper §3).
    Vos(Vos),
    /// The eye's disability glare by the CIE's general equation.
    Eye(Eye),
    /// Diffraction on the stop and on filters, computed from the pupil
    /// (paper §2).
    Aperture(Aperture),
    /// Light reflected from the film base back into the emulsion.
    Halation(Halation),
    /// A measured or external PSF, from a picture a front end reads.
    Image(Measured),
}
