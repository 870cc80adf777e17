//! Lengths with units, and the pixel pitch that turns physical lengths into
//! pixels.
//!
//! The paper gives the bloom width on the film (R ≈ 30–120 µm) while images are
//! sampled in pixels; the link is the pixel pitch, sensor width / image width.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::{Error, Result};

/// The unit a length was given in.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Unit {
    /// Pixels of the image the kernel is meant for.
    Px,
    /// Micrometres on the sensor (or film).
    Um,
    /// Millimetres on the sensor (or film).
    Mm,
}

impl Unit {
    fn suffix(self) -> &'static str {
        match self {
            Unit::Px => "px",
            Unit::Um => "um",
            Unit::Mm => "mm",
        }
    }
}

/// A positive, finite length in pixels or on the sensor, as written in a
/// config file: `"10.4px"`, `"60um"`, `"60µm"`, `"0.06mm"`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Length {
    /// The number as written.
    pub value: f64,
    /// Its unit.
    pub unit: Unit,
}

impl Length {
    /// A length in pixels.
    pub fn px(value: f64) -> Self {
        Length {
            value,
            unit: Unit::Px,
        }
    }

    /// A length in micrometres on the sensor.
    pub fn um(value: f64) -> Self {
        Length {
            value,
            unit: Unit::Um,
        }
    }

    /// A length in millimetres on the sensor.
    pub fn mm(value: f64) -> Self {
        Length {
            value,
            unit: Unit::Mm,
        }
    }

    /// Times `factor` if it is in pixels (for an image resampled by
    /// `factor`); a length on the sensor does not change.
    pub fn scaled_px(self, factor: f64) -> Length {
        match self.unit {
            Unit::Px => Length::px(self.value * factor),
            Unit::Um | Unit::Mm => self,
        }
    }

    /// This length in pixels. Physical units need the pixel pitch in mm
    /// (sensor width / image width); `what` names the parameter for the error
    /// when there is none.
    pub fn to_px(self, pitch_mm: Option<f64>, what: &str) -> Result<f64> {
        let mm = match self.unit {
            Unit::Px => return Ok(self.value),
            Unit::Um => self.value * 1e-3,
            Unit::Mm => self.value,
        };
        match pitch_mm {
            Some(pitch) => Ok(mm / pitch),
            None => Err(Error::needs_sensor_width(format!("{what} \"{self}\""))),
        }
    }
}

impl fmt::Display for Length {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}{}", self.value, self.unit.suffix())
    }
}

impl FromStr for Length {
    type Err = Error;

    fn from_str(text: &str) -> Result<Self> {
        let refuse = |reason| Error::LengthSyntax {
            text: text.to_string(),
            reason,
        };
        let trimmed = text.trim();
        let (number, unit) = [
            ("px", Unit::Px),
            ("um", Unit::Um),
            ("µm", Unit::Um),
            ("μm", Unit::Um),
            ("mm", Unit::Mm),
        ]
        .iter()
        .find_map(|(suffix, unit)| {
            // "15PX" and "60UM" mean what they say; µ has no upper case.
            let at = trimmed.len().checked_sub(suffix.len())?;
            let (number, end) = (trimmed.get(..at)?, trimmed.get(at..)?);
            end.eq_ignore_ascii_case(suffix)
                .then(|| (number.trim_end(), *unit))
        })
        .ok_or_else(|| refuse("no unit"))?;
        let value: f64 = number.parse().map_err(|_| refuse("not a number"))?;
        if !value.is_finite() || value <= 0.0 {
            return Err(refuse("a length must be a finite number above 0"));
        }
        Ok(Length { value, unit })
    }
}

impl<'de> Deserialize<'de> for Length {
    fn deserialize<D: Deserializer<'de>>(deserializer: D) -> std::result::Result<Self, D::Error> {
        struct Visitor;
        impl serde::de::Visitor<'_> for Visitor {
            type Value = Length;
            fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
                f.write_str("a length string such as \"10.4px\", \"60um\" or \"0.06mm\"")
            }
            fn visit_str<E: serde::de::Error>(self, v: &str) -> std::result::Result<Length, E> {
                v.parse().map_err(E::custom)
            }
            fn visit_f64<E: serde::de::Error>(self, v: f64) -> std::result::Result<Length, E> {
                Err(E::custom(format!(
                    "length {v} has no unit; write it as a string with px, um or mm, e.g. \"{v}px\""
                )))
            }
            fn visit_i64<E: serde::de::Error>(self, v: i64) -> std::result::Result<Length, E> {
                self.visit_f64(v as f64)
            }
        }
        deserializer.deserialize_any(Visitor)
    }
}

impl Serialize for Length {
    /// As a config file writes it, `"10.4px"`: Rust prints the shortest
    /// decimal that reads back as the same number.
    fn serialize<S: Serializer>(&self, serializer: S) -> std::result::Result<S::Ok, S::Error> {
        serializer.collect_str(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_every_unit() {
        assert_eq!("10.4px".parse::<Length>().unwrap(), Length::px(10.4));
        assert_eq!("60um".parse::<Length>().unwrap(), Length::um(60.0));
        assert_eq!("60µm".parse::<Length>().unwrap(), Length::um(60.0));
        assert_eq!(" 60 um ".parse::<Length>().unwrap(), Length::um(60.0));
        assert_eq!("0.06mm".parse::<Length>().unwrap(), Length::mm(0.06));
        assert_eq!("15PX".parse::<Length>().unwrap(), Length::px(15.0));
        assert_eq!("60UM".parse::<Length>().unwrap(), Length::um(60.0));
        assert_eq!("0.06Mm".parse::<Length>().unwrap(), Length::mm(0.06));
    }

    #[test]
    fn refuses_bad_lengths() {
        for text in [
            "10",
            "px",
            "abcpx",
            "-3px",
            "0um",
            "infmm",
            "NaNpx",
            "3 furlongs",
        ] {
            let err = text.parse::<Length>().unwrap_err().to_string();
            assert!(err.contains(text.trim()), "{err}");
            assert!(err.contains("px, um (or µm) or mm"), "{err}");
        }
    }

    #[test]
    fn physical_units_become_pixels_through_the_pitch() {
        // 36 mm over 6000 px: 6 µm pitch, so 60 µm = 0.06 mm = 10 px.
        let pitch = Some(36.0 / 6000.0);
        for length in [Length::um(60.0), Length::mm(0.06)] {
            assert!((length.to_px(pitch, "radius").unwrap() - 10.0).abs() < 1e-9);
        }
        assert_eq!(Length::px(7.0).to_px(None, "radius").unwrap(), 7.0);
    }

    #[test]
    fn physical_units_without_camera_say_so() {
        let err = Length::um(60.0)
            .to_px(None, "bloom radius")
            .unwrap_err()
            .to_string();
        assert!(err.contains("bloom radius \"60um\""), "{err}");
        assert!(err.contains("sensor_width_mm"), "{err}");
    }
}
