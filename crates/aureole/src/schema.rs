//! Every effect's parameters, declared once: what a front end shows as a
//! control (unit, allowed range, default, a line about it), and what the
//! effect's `validate` checks values against.

use crate::check;
use crate::error::Result;

/// What kind of value a parameter holds.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kind {
    /// A real number.
    Number,
    /// A whole number.
    Whole,
    /// An angle in degrees.
    Angle,
    /// A length with its unit: `"10.4px"`, `"60um"`, `"0.06mm"`.
    Length,
    /// true or false.
    Flag,
    /// Words: a file's name, a choice.
    Text,
}

/// A parameter's value when a config leaves it out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Default {
    /// The config must give it.
    Required,
    /// This number.
    Number(f64),
    /// This length, as a config writes it.
    Length(&'static str),
    /// This flag.
    Flag(bool),
    /// These words.
    Text(&'static str),
}

/// One parameter of an effect or of the camera.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Parameter {
    /// Its key in a config file.
    pub name: &'static str,
    /// What it holds.
    pub kind: Kind,
    /// The lowest value allowed, and whether that value itself is.
    pub low: Option<(f64, bool)>,
    /// The highest value allowed, and whether that value itself is.
    pub high: Option<(f64, bool)>,
    /// Its value when left out.
    pub default: Default,
    /// Its unit for a person (empty for a pure number).
    pub unit: &'static str,
    /// What is allowed, as an error message says it.
    pub allowed: &'static str,
    /// What it does, in a line.
    pub about: &'static str,
}

impl Parameter {
    /// Whether `value` lies in the allowed range.
    pub fn admits(&self, value: f64) -> bool {
        let above = match self.low {
            Some((low, true)) => value >= low,
            Some((low, false)) => value > low,
            None => true,
        };
        let below = match self.high {
            Some((high, true)) => value <= high,
            Some((high, false)) => value < high,
            None => true,
        };
        value.is_finite() && above && below
    }

    /// Refuses `value` outside the range, naming `section` and this
    /// parameter.
    pub(crate) fn check(&self, section: &str, value: f64) -> Result<()> {
        check::range(section, self.name, value, self.admits(value), self.allowed)
    }
}

/// The fraction of the light an effect spreads, which every effect has.
pub const EPSILON: Parameter = fraction(
    "epsilon",
    Default::Required,
    "the fraction of the light spread",
);

/// A fraction of the light, 0 to 1.
pub(crate) const fn fraction(
    name: &'static str,
    default: Default,
    about: &'static str,
) -> Parameter {
    Parameter {
        name,
        kind: Kind::Number,
        low: Some((0.0, true)),
        high: Some((1.0, true)),
        default,
        unit: "",
        allowed: "a fraction of the light from 0 to 1",
        about,
    }
}

/// An angle in degrees: any finite value.
pub(crate) const fn angle(name: &'static str, about: &'static str) -> Parameter {
    Parameter {
        name,
        kind: Kind::Angle,
        low: None,
        high: None,
        default: Default::Number(0.0),
        unit: "°",
        allowed: "a finite angle in degrees",
        about,
    }
}

/// A switch, on (`true`) or off, by default `on`.
pub(crate) const fn flag(name: &'static str, on: bool, about: &'static str) -> Parameter {
    Parameter {
        name,
        kind: Kind::Flag,
        low: None,
        high: None,
        default: Default::Flag(on),
        unit: "",
        allowed: "true or false",
        about,
    }
}

/// A length in px, or µm/mm on the sensor: any above 0.
pub(crate) const fn length(name: &'static str, default: Default, about: &'static str) -> Parameter {
    Parameter {
        name,
        kind: Kind::Length,
        low: Some((0.0, false)),
        high: None,
        default,
        unit: "px, um or mm",
        allowed: "a length above 0: px, or µm/mm on the sensor",
        about,
    }
}

/// The `[camera]` table's parameters.
pub const CAMERA: &[Parameter] = &[
    Parameter {
        name: "sensor_width_mm",
        kind: Kind::Number,
        low: Some((0.0, false)),
        high: None,
        default: Default::Required,
        unit: "mm",
        allowed: "a finite number above 0",
        about: "the width of the sensor the image spans: µm and mm become pixels through it",
    },
    Parameter {
        name: "focal_length_mm",
        kind: Kind::Number,
        low: Some((0.0, false)),
        high: None,
        default: Default::Required,
        unit: "mm",
        allowed: "a finite number above 0",
        about: "turns distances on the sensor into angles",
    },
    Parameter {
        name: "f_number",
        kind: Kind::Number,
        low: Some((0.5, true)),
        high: None,
        default: Default::Required,
        unit: "",
        allowed: "a finite number of at least 0.5",
        about: "the stop: diffraction widens as it closes",
    },
    Parameter {
        name: "projection",
        kind: Kind::Text,
        low: None,
        high: None,
        default: Default::Required,
        unit: "",
        allowed: "perspective, equidistant (angular), equisolid, stereographic or orthographic (hemispherical)",
        about: "a wide view's projection (a fisheye): the eye's glare is then spread over the sphere of directions",
    },
    Parameter {
        name: "field_of_view_deg",
        kind: Kind::Angle,
        low: Some((0.0, false)),
        high: Some((360.0, true)),
        default: Default::Required,
        unit: "°",
        allowed: "an angle above 0° and at most the projection's widest (360° for a fisheye, 179° for a perspective)",
        about: "the angle the image's width spans, with projection",
    },
    Parameter {
        name: "field_of_view_vertical_deg",
        kind: Kind::Angle,
        low: Some((0.0, false)),
        high: Some((360.0, true)),
        default: Default::Required,
        unit: "°",
        allowed: "an angle above 0° and at most the projection's widest",
        about: "the angle the image's height spans (default: the same scale as across)",
    },
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges_admit_what_they_say() {
        let p = Parameter {
            low: Some((0.0, false)),
            high: Some((1.0, true)),
            ..EPSILON
        };
        assert!(!p.admits(0.0) && p.admits(1e-9) && p.admits(1.0) && !p.admits(1.0 + 1e-9));
        assert!(!EPSILON.admits(f64::NAN) && EPSILON.admits(0.0));
    }

    #[test]
    fn each_default_the_schema_shows_is_the_one_a_config_gets() {
        // An example of each effect with every defaulted key written out
        // as the schema gives it reads as the example without them.
        for (kind, parameters) in crate::optics::EFFECT_PARAMETERS {
            let example = crate::presets::example_of(kind)
                .and_then(|name| crate::presets::find(name).ok())
                .and_then(|preset| preset.config().ok())
                .and_then(|config| config.effects.into_iter().find(|e| e.kind() == *kind))
                .or_else(|| {
                    // A measured PSF needs a file: no preset can hold one.
                    let table: toml::Table =
                        toml::from_str("type = \"image\"\nfile = \"star.exr\"\npitch_um = 4.0")
                            .ok()?;
                    crate::optics::Effect::from_table(table)
                        .ok()
                        .filter(|e| e.kind() == *kind)
                })
                .unwrap_or_else(|| panic!("no preset has a {kind}"));
            let mut table = example.to_table();
            for p in *parameters {
                let value = match (p.default, p.kind) {
                    (Default::Required, _) => continue,
                    (Default::Number(v), Kind::Whole) => toml::Value::Integer(v as i64),
                    (Default::Number(v), _) => toml::Value::Float(v),
                    (Default::Length(text) | Default::Text(text), _) => {
                        toml::Value::String(text.into())
                    }
                    (Default::Flag(flag), _) => toml::Value::Boolean(flag),
                };
                table.entry(p.name).or_insert(value);
            }
            let written = crate::optics::Effect::from_table(table).unwrap();
            assert_eq!(written, example, "{kind}");
        }
    }

    #[test]
    fn every_effect_declares_its_parameters_and_each_default_is_allowed() {
        for (kind, parameters) in crate::optics::EFFECT_PARAMETERS {
            assert!(!parameters.is_empty(), "{kind}");
            for p in *parameters {
                if let Default::Number(v) = p.default {
                    assert!(p.admits(v), "{kind}.{}: default {v}", p.name);
                }
            }
        }
    }
}
