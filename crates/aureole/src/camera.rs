//! The camera's geometry, the `[camera]` table: what turns lengths on the
//! sensor and angles in the scene into pixels. ("Camera" alone is the
//! whole chain a user picks: a preset, a config, Python's `Camera`.)

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::view::{Projection, View};

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
    /// A wide view's projection (a fisheye): the eye's glare is then
    /// spread over the sphere of directions ([`crate::pipeline::sphere`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub projection: Option<Projection>,
    /// The angle the image's width spans, degrees, with `projection`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub field_of_view_deg: Option<f64>,
    /// The angle its height spans; by default the same scale as across.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub field_of_view_vertical_deg: Option<f64>,
}

impl CameraGeometry {
    /// Checks every given field: positive and finite, f-number at least 0.5
    /// (the limit of a lens in air).
    pub fn validate(&self) -> Result<()> {
        let [sensor, focal, stop, _, across, down] = crate::schema::CAMERA else {
            return Ok(());
        };
        for (parameter, value) in [
            (sensor, self.sensor_width_mm),
            (focal, self.focal_length_mm),
            (stop, self.f_number),
            (across, self.field_of_view_deg),
            (down, self.field_of_view_vertical_deg),
        ] {
            if let Some(v) = value {
                parameter.check("camera", v)?;
            }
        }
        if let Some(projection) = self.projection {
            let widest = projection.widest_deg();
            for (parameter, value) in [
                (across, self.field_of_view_deg),
                (down, self.field_of_view_vertical_deg),
            ] {
                if let Some(v) = value.filter(|v| *v > widest) {
                    return Err(Error::Parameter {
                        effect: "camera".into(),
                        name: parameter.name,
                        value: v.to_string(),
                        allowed: parameter.allowed,
                    });
                }
            }
        }
        Ok(())
    }

    /// Takes a picture's own `view` (a Radiance picture's header) as its
    /// projection and field of view.
    pub fn take_view(&mut self, view: &View) {
        self.projection = Some(view.projection);
        self.field_of_view_deg = Some(view.horizontal_deg);
        self.field_of_view_vertical_deg = Some(view.vertical_deg);
    }

    /// The wide view of a `width` × `height` image, when `projection` is
    /// given (its field of view then required); `None` for a camera known
    /// by its sensor and focal length alone.
    pub fn view(&self, width: usize, height: usize) -> Result<Option<View>> {
        let Some(projection) = self.projection else {
            return Ok(None);
        };
        let across = self.field_of_view_deg.ok_or(Error::NeedsCamera {
            what: format!("a view through the {} projection", projection.name()),
            field: "field_of_view_deg",
            why: "the angle the image's width spans sets every pixel's direction",
        })?;
        // The same scale down as across: g(v/2) = g(h/2)·height/width.
        let down = self.field_of_view_vertical_deg.unwrap_or_else(|| {
            if width == height {
                return across;
            }
            let r =
                projection.radius(across.to_radians() / 2.0) * height as f64 / width.max(1) as f64;
            2.0 * projection
                .angle_at(r)
                .unwrap_or(std::f64::consts::PI)
                .to_degrees()
        });
        let view = View {
            projection,
            horizontal_deg: across,
            vertical_deg: down.min(projection.widest_deg()),
            shift: 0.0,
            lift: 0.0,
        };
        view.check()?;
        Ok(Some(view))
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
        self.projection = other.projection.or(self.projection);
        self.field_of_view_deg = other.field_of_view_deg.or(self.field_of_view_deg);
        self.field_of_view_vertical_deg = other
            .field_of_view_vertical_deg
            .or(self.field_of_view_vertical_deg);
    }

    pub(crate) fn require_focal_length(&self, what: &str) -> Result<f64> {
        self.focal_length_mm.ok_or_else(|| Error::NeedsCamera {
            what: what.to_string(),
            field: "focal_length_mm",
            why: "angles from the optical axis come from the distance on the sensor and the focal length",
        })
    }
}
