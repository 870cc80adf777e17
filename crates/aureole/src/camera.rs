//! The camera's geometry, the `[camera]` table: what turns lengths on the
//! sensor and angles in the scene into pixels. ("Camera" alone is the
//! whole chain a user picks: a preset, a config, Python's `Camera`.)

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The geometry of the camera that recorded (or renders) the image: its
/// sensor width, focal length and f-number. Every field is optional in a
/// config file; each is needed only by what uses it.
#[derive(Debug, Clone, Copy, Default, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct CameraGeometry {
    /// Width of the sensor (or film) in mm; the image width spans it.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub sensor_width_mm: Option<f64>,
    /// Focal length in mm: turns distances on the sensor into angles.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub focal_length_mm: Option<f64>,
    /// f-number N (focal length / pupil diameter), for diffraction.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub f_number: Option<f64>,
}

impl CameraGeometry {
    /// Checks every given field: positive and finite, f-number at least 0.5
    /// (the limit of a lens in air).
    pub fn validate(&self) -> Result<()> {
        let [sensor, focal, stop] = crate::schema::CAMERA else {
            return Ok(());
        };
        for (parameter, value) in [
            (sensor, self.sensor_width_mm),
            (focal, self.focal_length_mm),
            (stop, self.f_number),
        ] {
            if let Some(v) = value {
                parameter.check("camera", v)?;
            }
        }
        Ok(())
    }

    /// Pixel pitch in mm for an image `image_width_px` wide, if the sensor
    /// width is known.
    pub fn pixel_pitch_mm(&self, image_width_px: usize) -> Option<f64> {
        self.sensor_width_mm.map(|w| w / image_width_px as f64)
    }

    /// Fields later set in `other` replace ours; the others stay.
    pub fn merge(&mut self, other: &CameraGeometry) {
        self.sensor_width_mm = other.sensor_width_mm.or(self.sensor_width_mm);
        self.focal_length_mm = other.focal_length_mm.or(self.focal_length_mm);
        self.f_number = other.f_number.or(self.f_number);
    }

    pub(crate) fn require_focal_length(&self, what: &str) -> Result<f64> {
        self.focal_length_mm.ok_or_else(|| Error::NeedsCamera {
            what: what.to_string(),
            field: "focal_length_mm",
            why: "angles from the optical axis come from the distance on the sensor and the focal length",
        })
    }
}
