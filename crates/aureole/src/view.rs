//! Where each pixel of a picture looks: the projection of a perspective
//! camera or of a fisheye, the field of view, and Radiance's `VIEW=`
//! options that say both in a rendered picture's header.
//!
//! Directions are in the camera's frame: z along the line of sight, y up
//! the picture, x to its right (Radiance's `vdir`, `vup` and `vdir × vup`).
//! A projection maps the angle θ from the line of sight to a radius g(θ)
//! on the image plane; the picture spans 2·g(h/2) across and 2·g(v/2) down,
//! for a field of view of h × v degrees, as Radiance's `vwrays` has it.

use std::f64::consts::PI;
use std::fmt;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::math::sin_cos;

/// How a camera or fisheye maps the angle θ off its axis onto the picture.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Projection {
    /// A pinhole camera: r = tan θ (Radiance `-vtv`).
    Perspective,
    /// The angular fisheye: r = θ (Radiance `-vta`), the one daylight glare
    /// studies render.
    #[serde(alias = "angular")]
    Equidistant,
    /// The equal-area fisheye: r = 2 sin(θ/2); most photographic fisheyes.
    Equisolid,
    /// r = 2 tan(θ/2) (Radiance's planisphere, `-vts`).
    Stereographic,
    /// r = sin θ (Radiance's hemispherical fisheye, `-vth`).
    #[serde(alias = "hemispherical")]
    Orthographic,
}

impl Projection {
    /// Every projection, with the names a config file and the command line
    /// use.
    pub const ALL: [(Projection, &'static str); 5] = [
        (Projection::Perspective, "perspective"),
        (Projection::Equidistant, "equidistant"),
        (Projection::Equisolid, "equisolid"),
        (Projection::Stereographic, "stereographic"),
        (Projection::Orthographic, "orthographic"),
    ];

    /// Its name as written in a config file.
    pub fn name(self) -> &'static str {
        Projection::ALL
            .iter()
            .find(|(p, _)| *p == self)
            .map_or("", |(_, n)| n)
    }

    /// The projection named `name` (also `angular` and `fisheye` for the
    /// equidistant fisheye, `hemispherical` for the orthographic).
    pub fn from_name(name: &str) -> Option<Projection> {
        match name {
            "angular" | "fisheye" => Some(Projection::Equidistant),
            "hemispherical" => Some(Projection::Orthographic),
            _ => Projection::ALL
                .iter()
                .find(|(_, n)| *n == name)
                .map(|(p, _)| *p),
        }
    }

    /// The widest field of view it can show, degrees.
    pub fn widest_deg(self) -> f64 {
        match self {
            Projection::Perspective => 179.0,
            Projection::Orthographic => 180.0,
            Projection::Stereographic => 359.0,
            Projection::Equidistant | Projection::Equisolid => 360.0,
        }
    }

    /// g(θ): the radius on the image plane of a direction θ off the axis.
    pub fn radius(self, theta: f64) -> f64 {
        match self {
            Projection::Perspective => libm::tan(theta),
            Projection::Equidistant => theta,
            Projection::Equisolid => 2.0 * libm::sin(theta / 2.0),
            Projection::Stereographic => 2.0 * libm::tan(theta / 2.0),
            Projection::Orthographic => libm::sin(theta),
        }
    }

    /// The radius of the rim, where the projection shows the direction
    /// farthest from its axis (behind the eye, or 90° for the orthographic);
    /// `None` for those that go on without one.
    pub fn edge(self) -> Option<f64> {
        match self {
            Projection::Equidistant => Some(PI),
            Projection::Equisolid => Some(2.0),
            Projection::Orthographic => Some(1.0),
            Projection::Perspective | Projection::Stereographic => None,
        }
    }

    /// θ at radius `r` of the image plane, `None` beyond the projection's
    /// edge.
    pub fn angle_at(self, r: f64) -> Option<f64> {
        self.angle_and_density(r)
            .map(|(cos, sin, _)| libm::atan2(sin, cos))
    }

    /// (θ, dΩ/dA): the angle off the axis at radius `r` of the image plane
    /// and the solid angle per unit of its area there, `None` beyond the
    /// projection's edge.
    #[inline]
    fn angle_and_density(self, r: f64) -> Option<(f64, f64, f64)> {
        // At the rim itself an orthographic fisheye's density is infinite.
        if self.edge().is_some_and(|edge| r >= edge) {
            return None;
        }
        // dΩ = sin θ · dθ/dr / r · dA for a radial projection.
        match self {
            Projection::Equidistant => {
                let (s, c) = sin_cos(r);
                let density = if r < 1e-8 { 1.0 } else { s / r };
                Some((c, s, density))
            }
            Projection::Equisolid => {
                // sin(θ/2) = r/2: cos θ = 1 − r²/2, and the area is kept.
                let c = 1.0 - r * r / 2.0;
                Some((c, (1.0 - c * c).max(0.0).sqrt(), 1.0))
            }
            Projection::Stereographic => {
                // tan(θ/2) = r/2: cos θ = (1 − r²/4)/(1 + r²/4).
                let q = r * r / 4.0;
                let c = (1.0 - q) / (1.0 + q);
                let half_cos2 = 1.0 / (1.0 + q);
                Some((c, (1.0 - c * c).max(0.0).sqrt(), half_cos2 * half_cos2))
            }
            Projection::Orthographic => {
                let c = (1.0 - r * r).sqrt();
                Some((c, r, 1.0 / c))
            }
            Projection::Perspective => {
                let c = 1.0 / (1.0 + r * r).sqrt();
                Some((c, r * c, c * c * c))
            }
        }
    }
}

/// A picture's view: projection and field of view, and the shift and lift
/// of its centre (Radiance's `-vs`, `-vl`, in picture widths and heights).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct View {
    /// How directions map onto the picture.
    pub projection: Projection,
    /// Field of view across the picture, degrees.
    pub horizontal_deg: f64,
    /// Field of view down the picture, degrees.
    pub vertical_deg: f64,
    /// The picture's centre moved right, in picture widths.
    #[serde(default)]
    pub shift: f64,
    /// The picture's centre moved up, in picture heights.
    #[serde(default)]
    pub lift: f64,
}

impl View {
    /// A fisheye (or camera) of `fov_deg` across and down.
    pub fn new(projection: Projection, fov_deg: f64) -> View {
        View {
            projection,
            horizontal_deg: fov_deg,
            vertical_deg: fov_deg,
            shift: 0.0,
            lift: 0.0,
        }
    }

    /// The view of Radiance's view options, as a picture's `VIEW=` header
    /// line or `rpict`'s command line holds them (`-vta -vh 180 -vv 180`).
    /// Position, direction and up (`-vp -vd -vu`) place the view in a
    /// scene and say nothing of its pixels: they are read past, as are the
    /// clipping planes (`-vo -va`). Later options override earlier ones.
    pub fn from_radiance(text: &str) -> Result<View> {
        let refuse = |message: String| Error::View {
            view: text.trim().to_string(),
            message,
        };
        let mut projection = None;
        let (mut h, mut v, mut shift, mut lift) = (None, None, 0.0, 0.0);
        let mut words = text.split_whitespace();
        while let Some(word) = words.next() {
            let mut number = |name: &str| -> Result<f64> {
                let value = words
                    .next()
                    .ok_or_else(|| refuse(format!("{name} has no value")))?;
                value
                    .parse::<f64>()
                    .ok()
                    .filter(|x| x.is_finite())
                    .ok_or_else(|| refuse(format!("{name} {value:?} is not a number")))
            };
            match word {
                "-vtv" => projection = Some(Projection::Perspective),
                "-vta" => projection = Some(Projection::Equidistant),
                "-vth" => projection = Some(Projection::Orthographic),
                "-vts" => projection = Some(Projection::Stereographic),
                "-vtl" | "-vtc" => {
                    return Err(refuse(format!(
                        "{word} ({}) has no eye at one point to evaluate glare from; allowed: -vtv, -vta, -vth, -vts",
                        if word == "-vtl" { "parallel" } else { "cylindrical panorama" }
                    )))
                }
                "-vh" => h = Some(number(word)?),
                "-vv" => v = Some(number(word)?),
                "-vs" => shift = number(word)?,
                "-vl" => lift = number(word)?,
                "-vo" | "-va" => {
                    number(word)?;
                }
                "-vp" | "-vd" | "-vu" => {
                    for _ in 0..3 {
                        number(word)?;
                    }
                }
                w if w.starts_with("-vt") => {
                    return Err(refuse(format!(
                        "view type {w} is not known; allowed: -vtv, -vta, -vth, -vts"
                    )))
                }
                // `rpict` and `rvu` write their own name first, and other
                // options may follow: none changes the pixels' directions.
                _ => {}
            }
        }
        let projection = projection.ok_or_else(|| {
            refuse("it gives no view type (-vtv, -vta, -vth or -vts)".to_string())
        })?;
        // Radiance's defaults: 45° for a camera, 180° for a fisheye.
        let fallback = if projection == Projection::Perspective {
            45.0
        } else {
            180.0
        };
        let view = View {
            projection,
            horizontal_deg: h.unwrap_or(fallback),
            vertical_deg: v.unwrap_or(fallback),
            shift,
            lift,
        };
        view.check().map_err(|e| match e {
            Error::View { message, .. } => refuse(message),
            other => other,
        })?;
        Ok(view)
    }

    /// Radiance's options for this view, as `rpict` takes them.
    pub fn to_radiance(&self) -> String {
        let kind = match self.projection {
            Projection::Perspective => "-vtv",
            Projection::Equidistant | Projection::Equisolid => "-vta",
            Projection::Stereographic => "-vts",
            Projection::Orthographic => "-vth",
        };
        format!(
            "{kind} -vh {} -vv {} -vs {} -vl {}",
            self.horizontal_deg, self.vertical_deg, self.shift, self.lift
        )
    }

    /// Refuses a field of view the projection cannot show, and shifts
    /// that are not finite.
    pub fn check(&self) -> Result<()> {
        let widest = self.projection.widest_deg();
        for (name, value) in [
            ("horizontal field of view", self.horizontal_deg),
            ("vertical field of view", self.vertical_deg),
        ] {
            if !(value > 0.0 && value <= widest) {
                return Err(Error::View {
                    view: self.to_string(),
                    message: format!(
                        "{name} {value}° is not allowed: a {} view shows above 0° and at most {widest}°",
                        self.projection.name()
                    ),
                });
            }
        }
        if !(self.shift.is_finite() && self.lift.is_finite()) {
            return Err(Error::View {
                view: self.to_string(),
                message: "shift and lift must be finite numbers".into(),
            });
        }
        Ok(())
    }

    /// The geometry of a `width` × `height` picture through this view.
    pub fn pixels(&self, width: usize, height: usize) -> Pixels {
        let across = 2.0
            * self
                .projection
                .radius(self.horizontal_deg.to_radians() / 2.0);
        let down = 2.0 * self.projection.radius(self.vertical_deg.to_radians() / 2.0);
        let (w, h) = (width.max(1) as f64, height.max(1) as f64);
        Pixels {
            projection: self.projection,
            width,
            height,
            step_x: across / w,
            step_y: down / h,
            shift_x: self.shift * across,
            shift_y: self.lift * down,
        }
    }
}

impl fmt::Display for View {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} {}°×{}°",
            self.projection.name(),
            self.horizontal_deg,
            self.vertical_deg
        )?;
        if self.shift != 0.0 || self.lift != 0.0 {
            write!(f, " shifted {} lifted {}", self.shift, self.lift)?;
        }
        Ok(())
    }
}

/// Where a picture's pixels look and how much of the sphere each covers.
#[derive(Debug, Clone, Copy)]
pub struct Pixels {
    projection: Projection,
    width: usize,
    height: usize,
    /// One pixel's width and height on the image plane.
    step_x: f64,
    step_y: f64,
    /// The image plane's point at the picture's centre.
    shift_x: f64,
    shift_y: f64,
}

/// One pixel seen from the eye.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sight {
    /// The unit direction, camera frame (x right, y up, z ahead).
    pub direction: [f64; 3],
    /// The solid angle the pixel covers, sr.
    pub solid_angle: f64,
}

impl Pixels {
    /// The image plane's point of a position in pixels (column and row
    /// from the top left, pixel centres at half-integers).
    #[inline]
    fn plane(&self, x: f64, y: f64) -> (f64, f64) {
        (
            (x - self.width as f64 / 2.0) * self.step_x + self.shift_x,
            (self.height as f64 / 2.0 - y) * self.step_y + self.shift_y,
        )
    }

    /// The direction and solid angle at a position in pixels (column and
    /// row from the top left; the centre of pixel (i, j) is at (i + ½,
    /// j + ½)); `None` where the projection shows nothing.
    #[inline]
    pub fn sight(&self, x: f64, y: f64) -> Option<Sight> {
        let (px, py) = self.plane(x, y);
        self.sight_on_plane(px, py, 1.0)
    }

    /// [`Pixels::sight`], or where the projection shows nothing, the sight
    /// at the nearest point of its rim: the directions of a coarse grid
    /// whose cells straddle a fisheye's edge.
    pub fn sight_nearest(&self, x: f64, y: f64) -> Sight {
        let (px, py) = self.plane(x, y);
        self.sight_on_plane(px, py, 1.0)
            .or_else(|| {
                let r = (px * px + py * py).sqrt();
                let edge = self.projection.edge()?;
                self.sight_on_plane(px, py, edge * (1.0 - 1e-9) / r)
            })
            .unwrap_or(Sight {
                direction: [0.0, 0.0, 1.0],
                solid_angle: 0.0,
            })
    }

    /// The sight at the image plane's point (`px`, `py`) moved `k` times
    /// as far from the centre.
    #[inline]
    fn sight_on_plane(&self, px: f64, py: f64, k: f64) -> Option<Sight> {
        let r = (px * px + py * py).sqrt();
        let (cos, sin, density) = self.projection.angle_and_density(r * k)?;
        let (ux, uy) = if r > 0.0 {
            (px / r, py / r)
        } else {
            (0.0, 0.0)
        };
        Some(Sight {
            direction: [sin * ux, sin * uy, cos],
            solid_angle: density * self.step_x * self.step_y,
        })
    }

    /// The picture's size in pixels.
    pub fn size(&self) -> (usize, usize) {
        (self.width, self.height)
    }

    /// The sight of pixel (column, row), from the top left.
    #[inline]
    pub fn pixel(&self, column: usize, row: usize) -> Option<Sight> {
        self.sight(column as f64 + 0.5, row as f64 + 0.5)
    }

    /// The position in pixels (column and row from the top left) where the
    /// picture shows `direction` (camera frame), if it does.
    pub fn locate(&self, direction: [f64; 3]) -> Option<(f64, f64)> {
        let [x, y, z] = direction;
        let norm = (x * x + y * y + z * z).sqrt();
        if norm == 0.0 {
            return None;
        }
        let theta = libm::acos((z / norm).clamp(-1.0, 1.0));
        if self.projection == Projection::Perspective && theta >= PI / 2.0 {
            return None;
        }
        let r = self.projection.radius(theta);
        let side = (x * x + y * y).sqrt();
        let (ux, uy) = if side > 0.0 {
            (x / side, y / side)
        } else {
            (0.0, 0.0)
        };
        let (px, py) = (r * ux - self.shift_x, r * uy - self.shift_y);
        Some((
            px / self.step_x + self.width as f64 / 2.0,
            self.height as f64 / 2.0 - py / self.step_y,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn angle_off_axis(s: Sight) -> f64 {
        libm::acos(s.direction[2]).to_degrees()
    }

    #[test]
    fn the_edge_of_a_180_degree_fisheye_looks_90_degrees_off_the_axis() {
        for (projection, _) in Projection::ALL {
            if projection == Projection::Perspective {
                continue;
            }
            let pixels = View::new(projection, 180.0).pixels(1000, 1000);
            // Just inside the picture's edge: every projection shows it
            // (the orthographic's rim itself is 90° exactly, where its
            // density has no bound).
            let theta = pixels
                .sight(1000.0 - 1e-9, 500.0)
                .map(angle_off_axis)
                .unwrap_or_else(|| panic!("{projection:?} shows nothing at its edge"));
            assert!((theta - 90.0).abs() < 1e-2, "{projection:?}: {theta}");
        }
    }

    #[test]
    fn solid_angles_of_a_hemisphere_add_up_to_2_pi() {
        for (projection, _) in Projection::ALL {
            let fov = if projection == Projection::Perspective {
                90.0
            } else {
                180.0
            };
            let n = 600;
            let pixels = View::new(projection, fov).pixels(n, n);
            let mut total = 0.0;
            for j in 0..n {
                for i in 0..n {
                    if let Some(s) = pixels.pixel(i, j) {
                        if s.direction[2] >= 0.0 {
                            total += s.solid_angle;
                        }
                    }
                }
            }
            // A 90° camera sees a square cone: 4·asin(sin²45°) = 2π/3.
            let expected = if projection == Projection::Perspective {
                2.0 * PI / 3.0
            } else {
                2.0 * PI
            };
            // The orthographic fisheye's rim pixels squeeze the most sky.
            let tolerance = if projection == Projection::Orthographic {
                3e-3
            } else {
                2e-3
            };
            assert!(
                (total / expected - 1.0).abs() < tolerance,
                "{projection:?}: {total} against {expected}"
            );
        }
    }

    #[test]
    fn locate_finds_the_pixel_a_direction_came_from() {
        for (projection, _) in Projection::ALL {
            let mut view = View::new(projection, 150.0);
            view.vertical_deg = 120.0;
            view.shift = 0.05;
            view.lift = -0.1;
            let pixels = view.pixels(640, 480);
            for (x, y) in [(10.5, 20.5), (320.0, 240.0), (600.25, 400.75)] {
                let Some(s) = pixels.sight(x, y) else {
                    continue;
                };
                let (bx, by) = pixels.locate(s.direction).unwrap();
                assert!(
                    (bx - x).abs() < 1e-6 && (by - y).abs() < 1e-6,
                    "{projection:?}: ({x}, {y}) came back as ({bx}, {by})"
                );
            }
        }
    }

    #[test]
    fn radiance_views_are_read_and_bad_ones_refused_in_one_line() {
        let view = View::from_radiance(
            "rpict -vta -vp 3 3.8 1.2 -vd 0 -1 0 -vu 0 0 1 -vh 180 -vv 170 -vo 0 -va 0 -vs 0 -vl 0.1",
        )
        .unwrap();
        assert_eq!(view.projection, Projection::Equidistant);
        assert_eq!((view.horizontal_deg, view.vertical_deg), (180.0, 170.0));
        assert_eq!(view.lift, 0.1);
        assert_eq!(
            View::from_radiance("-vtv").unwrap().horizontal_deg,
            45.0,
            "Radiance's default"
        );
        for (bad, says) in [
            ("-vtl -vh 10 -vv 10", "parallel"),
            ("-vh 180 -vv 180", "no view type"),
            ("-vta -vh wide", "\"wide\" is not a number"),
            ("-vtv -vh 180", "at most 179°"),
            ("-vtq", "-vtq is not known"),
        ] {
            let message = View::from_radiance(bad).unwrap_err().to_string();
            assert!(message.contains(says), "{bad}: {message}");
            assert!(!message.contains('\n'), "{message}");
        }
    }
}
