//! A measured or external PSF (docs/physics.md §11): a picture of a point
//! of light (a photographed star or pinhole, a PSF from an optical design
//! program) taken as the kernel, per channel, resampled from its own pixel
//! pitch to the frame's with the light conserved.
//!
//! The library reads no files: a front end reads the picture and hands its
//! planes over ([`Measured::load`]). Its background is estimated from the
//! picture's border: the median is the black level, subtracted, and
//! 1.4826 times the median absolute deviation about it the noise σ; what
//! stays below `floor` σ is dark, and so is what the light above it does
//! not join to the centre: a picture of 10⁵ pixels holds a hundred noise
//! spikes above 3σ, which would otherwise spread as a veil over the
//! whole frame.

use std::sync::Arc;

use serde::{Deserialize, Serialize};

use super::{Context, Model, Source};
use crate::check;
use crate::error::{Error, Result};
use crate::schema::{Default, Kind, Parameter};
use crate::sending::Sending;

/// A PSF picture as a front end read it: planes of width × height, top row
/// first, one (luminance) or three (R, G, B).
#[derive(Debug, Clone, PartialEq)]
pub struct Picture {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// Its planes, in the file's units.
    pub planes: Vec<Vec<f32>>,
}

/// A measured PSF, as in an `[[effect]]` table with `type = "image"`.
#[derive(Debug, Clone, PartialEq, Deserialize, Serialize)]
#[serde(deny_unknown_fields)]
pub struct Measured {
    /// The picture's file, as the front end that reads it resolves it.
    pub file: String,
    /// Its pixel pitch on the sensor, µm.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pitch_um: Option<f64>,
    /// Or the angle its width spans, degrees (with `[camera]`
    /// `focal_length_mm`).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub field_of_view_deg: Option<f64>,
    /// Where its centre lies: "brightest", "centroid" or "x,y" in its
    /// pixels (0,0 the top-left pixel's centre).
    #[serde(default = "brightest")]
    pub centre: String,
    /// What stays dark: light below this many σ of the border's noise.
    #[serde(default = "three")]
    pub floor: f64,
    /// The picture, once a front end has read it.
    #[serde(skip)]
    pub picture: Option<Arc<Picture>>,
}

fn brightest() -> String {
    "brightest".into()
}
fn three() -> f64 {
    3.0
}

const FILE: Parameter = Parameter {
    name: "file",
    kind: Kind::Text,
    low: None,
    high: None,
    default: Default::Required,
    unit: "",
    allowed: "an image file (EXR, PFM, TIFF, PNG …) of one point of light",
    about: "the PSF: a photographed star or pinhole, or a design program's PSF",
};
const PITCH: Parameter = Parameter {
    name: "pitch_um",
    kind: Kind::Number,
    low: Some((0.0, false)),
    high: Some((1000.0, true)),
    default: Default::Required,
    unit: "µm",
    allowed: "a pitch above 0 and at most 1000 µm (or give field_of_view_deg)",
    about: "the picture's pixel pitch on the sensor",
};
const FIELD: Parameter = Parameter {
    name: "field_of_view_deg",
    kind: Kind::Number,
    low: Some((0.0, false)),
    high: Some((170.0, true)),
    default: Default::Required,
    unit: "°",
    allowed: "an angle above 0 and at most 170° (or give pitch_um)",
    about: "or the angle its width spans, with [camera] focal_length_mm",
};
const CENTRE: Parameter = Parameter {
    name: "centre",
    kind: Kind::Text,
    low: None,
    high: None,
    default: Default::Text("brightest"),
    unit: "",
    allowed: "\"brightest\", \"centroid\" or \"x,y\" in the picture's pixels",
    about: "where the point of light lies in the picture",
};
const FLOOR: Parameter = Parameter {
    name: "floor",
    kind: Kind::Number,
    low: Some((0.0, true)),
    high: Some((1000.0, true)),
    default: Default::Number(3.0),
    unit: "σ",
    allowed: "0 to 1000 times the border's noise",
    about: "light below this many σ of the border's noise stays dark",
};

/// Where a picture's point of light lies.
enum Centre {
    Brightest,
    Centroid,
    /// In its pixels, (0, 0) the top-left pixel's centre.
    At([f64; 2]),
}

/// The border's share of each side that measures the background.
const BORDER: usize = 16;

/// What was found in a picture: per plane its background and noise, and
/// the centre.
#[derive(Debug, Clone, PartialEq)]
pub struct Survey {
    /// The centre, in the picture's pixels.
    pub centre: [f64; 2],
    /// Per plane: the black level (the border's median) and the noise σ.
    pub background: Vec<(f64, f64)>,
    /// Per plane, the light above the floor, of the light above the black
    /// level.
    pub kept: Vec<f64>,
}

/// The `type` a config names a measured PSF by.
pub const KIND: &str = "image";

impl Model for Measured {
    const KIND: &'static str = KIND;
    const PARAMETERS: &'static [Parameter] = &[FILE, PITCH, FIELD, CENTRE, FLOOR];

    fn validate(&self) -> Result<()> {
        const NAME: &str = "image";
        check::count(
            NAME,
            FILE.name,
            format!("{:?}", self.file),
            !self.file.trim().is_empty(),
            FILE.allowed,
        )?;
        match (self.pitch_um, self.field_of_view_deg) {
            (Some(pitch), None) => PITCH.check(NAME, pitch)?,
            (None, Some(angle)) => FIELD.check(NAME, angle)?,
            (pitch, angle) => check::count(
                NAME,
                PITCH.name,
                format!("{pitch:?} with field_of_view_deg = {angle:?}"),
                false,
                "one of pitch_um (µm per pixel) and field_of_view_deg, not both nor neither",
            )?,
        }
        check::count(
            NAME,
            CENTRE.name,
            format!("{:?}", self.centre),
            self.centre_rule().is_some(),
            CENTRE.allowed,
        )?;
        FLOOR.check(NAME, self.floor)
    }

    fn planes(&self) -> usize {
        self.picture.as_ref().map_or(3, |p| p.planes.len())
    }

    fn source(&self, context: &Context) -> Result<Source> {
        self.validate()?;
        let to = context
            .pitch_mm
            .ok_or_else(|| Error::needs_sensor_width("a measured PSF".into()))?;
        let picture = self.picture()?;
        let from = match (self.pitch_um, self.field_of_view_deg) {
            (Some(pitch), _) => pitch * 1e-3,
            (None, angle) => {
                let focal = context.camera.focal_length_mm.ok_or(Error::NeedsCamera {
                    what: "a measured PSF's field_of_view_deg".into(),
                    field: "focal_length_mm",
                    why: "the angle its width spans is a width on the sensor at f",
                })?;
                let half = angle.unwrap_or_default().to_radians() / 2.0;
                2.0 * focal * libm::tan(half) / picture.width as f64
            }
        };
        let (planes, survey) = self.cleaned(picture)?;
        let (width, height) = context.kernel_size;
        let mut normalised = Vec::with_capacity(planes.len());
        for plane in &planes {
            let mut kernel = resample(
                plane,
                (picture.width, picture.height),
                survey.centre,
                from,
                (width, height),
                to,
                context.sending,
            );
            // The picture's light, not the kernel's: what falls beyond the
            // kernel leaves the frame.
            let total: f64 = plane.iter().sum();
            if total <= 0.0 || !kernel.iter().any(|&v| v > 0.0) {
                return Err(self.refuse("no light of it falls within the kernel"));
            }
            kernel.iter_mut().for_each(|v| *v /= total);
            normalised.push(kernel);
        }
        Ok(Source::Pattern(normalised))
    }
}

impl Measured {
    /// The PSF in `file`, `pitch_um` per pixel, centred on its brightest
    /// pixel, dark below 3 σ of its border's noise; not yet read.
    pub fn new(file: String, pitch_um: f64) -> Measured {
        Measured {
            file,
            pitch_um: Some(pitch_um),
            field_of_view_deg: None,
            centre: brightest(),
            floor: three(),
            picture: None,
        }
    }

    /// Hands over the picture a front end read from `file`.
    pub fn load(&mut self, picture: Picture) {
        self.picture = Some(Arc::new(picture));
    }

    /// Its background, noise and centre, and the light kept above the
    /// floor.
    pub fn survey(&self) -> Result<Survey> {
        self.validate()?;
        Ok(self.cleaned(self.picture()?)?.1)
    }

    fn picture(&self) -> Result<&Picture> {
        self.picture.as_deref().ok_or_else(|| {
            self.refuse("it has not been read: the library reads no files, a front end loads it")
        })
    }

    fn refuse(&self, why: &str) -> Error {
        Error::MeasuredPsf {
            file: self.file.clone(),
            why: why.into(),
        }
    }

    /// How `centre` finds the point of light; `None` for words it does not
    /// know.
    fn centre_rule(&self) -> Option<Centre> {
        match self.centre.as_str() {
            "brightest" => Some(Centre::Brightest),
            "centroid" => Some(Centre::Centroid),
            given => {
                let (x, y) = given.split_once(',')?;
                let (x, y) = (x.trim().parse::<f64>().ok()?, y.trim().parse::<f64>().ok()?);
                (x.is_finite() && y.is_finite()).then_some(Centre::At([x, y]))
            }
        }
    }

    /// The planes less their black level, dark below the floor, in f64,
    /// and what was found.
    fn cleaned(&self, picture: &Picture) -> Result<(Vec<Vec<f64>>, Survey)> {
        let (w, h) = (picture.width, picture.height);
        if w == 0 || h == 0 || picture.planes.iter().any(|p| p.len() != w * h) {
            return Err(self.refuse("its planes do not match its size"));
        }
        if picture.planes.iter().flatten().any(|v| !v.is_finite()) {
            return Err(self.refuse("it holds samples that are not finite numbers"));
        }
        let (bw, bh) = ((w / BORDER).max(1), (h / BORDER).max(1));
        let border = |i: usize| {
            let (x, y) = (i % w, i / w);
            x < bw || y < bh || x >= w - bw || y >= h - bh
        };
        let mut background = Vec::new();
        let mut above_black = Vec::new();
        let mut planes = Vec::new();
        for plane in &picture.planes {
            let mut edge: Vec<f64> = (0..w * h)
                .filter(|&i| border(i))
                .map(|i| f64::from(plane[i]))
                .collect();
            let black = median(&mut edge);
            let mut deviations: Vec<f64> = edge.iter().map(|v| (v - black).abs()).collect();
            let sigma = 1.4826 * median(&mut deviations);
            let line = self.floor * sigma;
            let above = plane.iter().map(|&v| (f64::from(v) - black).max(0.0));
            above_black.push(above.clone().sum::<f64>());
            planes.push(
                above
                    .map(|v| if v > line { v } else { 0.0 })
                    .collect::<Vec<_>>(),
            );
            background.push((black, sigma));
        }
        let mut light: Vec<f64> = (0..w * h)
            .map(|i| planes.iter().map(|p| p[i]).sum())
            .collect();
        let brightest = (0..w * h).fold(0, |best, i| if light[i] > light[best] { i } else { best });
        if light[brightest] <= 0.0 {
            return Err(self.refuse("no light stands above its background's floor"));
        }
        // What joins the brightest pixel through light above the floor.
        let joined = joined(&light, w, h, brightest);
        for (i, keep) in joined.iter().enumerate() {
            if !keep {
                light[i] = 0.0;
                for plane in &mut planes {
                    plane[i] = 0.0;
                }
            }
        }
        let kept = planes
            .iter()
            .zip(&above_black)
            .map(|(plane, all)| {
                if *all > 0.0 {
                    plane.iter().sum::<f64>() / all
                } else {
                    0.0
                }
            })
            .collect();
        let centre = match self.centre_rule() {
            Some(Centre::At(point)) => point,
            Some(Centre::Centroid) => {
                let total: f64 = light.iter().sum();
                let (mut x, mut y) = (0.0, 0.0);
                for (i, v) in light.iter().enumerate() {
                    x += v * (i % w) as f64;
                    y += v * (i / w) as f64;
                }
                [x / total, y / total]
            }
            // Validation has refused any other words.
            Some(Centre::Brightest) | None => [(brightest % w) as f64, (brightest / w) as f64],
        };
        Ok((
            planes,
            Survey {
                centre,
                background,
                kept,
            },
        ))
    }
}

/// The pixels of a `w` × `h` picture that a path of lit pixels (8 ways)
/// joins to `start`.
fn joined(light: &[f64], w: usize, h: usize, start: usize) -> Vec<bool> {
    let mut seen = vec![false; w * h];
    let mut stack = vec![start];
    seen[start] = true;
    while let Some(i) = stack.pop() {
        let (x, y) = ((i % w) as i64, (i / w) as i64);
        for (dx, dy) in [
            (-1, -1),
            (0, -1),
            (1, -1),
            (-1, 0),
            (1, 0),
            (-1, 1),
            (0, 1),
            (1, 1),
        ] {
            let (nx, ny) = (x + dx, y + dy);
            if nx < 0 || ny < 0 || nx >= w as i64 || ny >= h as i64 {
                continue;
            }
            let n = ny as usize * w + nx as usize;
            if !seen[n] && light[n] > 0.0 {
                seen[n] = true;
                stack.push(n);
            }
        }
    }
    seen
}

fn median(values: &mut [f64]) -> f64 {
    if values.is_empty() {
        return 0.0;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    }
}

/// `plane` (`size`, pixels `from` mm wide, its point of light at `centre`)
/// on a kernel of `extent` with pixels `to` mm wide, its centre at
/// (⌊W/2⌋, ⌊H/2⌋): each picture pixel a uniform square of light, which
/// the kernel pixels take over their squares (a point `sending`) or under
/// their tents (a pixel, docs/physics.md §2). Either sums to 1 everywhere,
/// so no light is made or lost where both hold it.
fn resample(
    plane: &[f64],
    size: (usize, usize),
    centre: [f64; 2],
    from: f64,
    extent: (usize, usize),
    to: f64,
    sending: Sending,
) -> Vec<f64> {
    let columns = overlaps(size.0, centre[0], from, extent.0, to, sending);
    let rows = overlaps(size.1, centre[1], from, extent.1, to, sending);
    // Along x first: each picture row onto the kernel's columns.
    let mut across = vec![0.0; size.1 * extent.0];
    for t in 0..size.1 {
        let source = &plane[t * size.0..(t + 1) * size.0];
        let out = &mut across[t * extent.0..(t + 1) * extent.0];
        for (s, shares) in columns.iter().enumerate() {
            let v = source[s];
            if v != 0.0 {
                for &(i, share) in shares {
                    out[i] += v * share;
                }
            }
        }
    }
    let mut result = vec![0.0; extent.0 * extent.1];
    for (t, shares) in rows.iter().enumerate() {
        let source = &across[t * extent.0..(t + 1) * extent.0];
        for &(j, share) in shares {
            let out = &mut result[j * extent.0..(j + 1) * extent.0];
            for (o, v) in out.iter_mut().zip(source) {
                *o += v * share;
            }
        }
    }
    result
}

/// Per picture pixel along one axis, the kernel pixels whose squares or
/// tents it meets and the share of its light in each.
fn overlaps(
    count: usize,
    centre: f64,
    from: f64,
    extent: usize,
    to: f64,
    sending: Sending,
) -> Vec<Vec<(usize, f64)>> {
    let under = match sending {
        Sending::Point => under_square,
        Sending::Pixel => under_tent,
    };
    let middle = (extent / 2) as f64;
    (0..count)
        .map(|s| {
            // The picture pixel's edges in kernel pixels, the kernel's
            // pixel i centred at i + ½ and its tent spanning i − ½ to
            // i + 1½.
            let a = (s as f64 - 0.5 - centre) * from / to + middle + 0.5;
            let b = (s as f64 + 0.5 - centre) * from / to + middle + 0.5;
            let first = (a - 0.5).floor().max(0.0) as usize;
            let last = ((b + 0.5).ceil().max(0.0) as usize).min(extent);
            (first..last)
                .filter_map(|i| {
                    let c = i as f64 + 0.5;
                    let share = (under(b - c) - under(a - c)) / (b - a);
                    (share > 0.0).then_some((i, share))
                })
                .collect()
        })
        .collect()
}

/// ∫ of the unit square [−½, ½] from −∞ to v.
fn under_square(v: f64) -> f64 {
    (v + 0.5).clamp(0.0, 1.0)
}

/// ∫ of the tent max(0, 1 − |u|) from −∞ to v.
fn under_tent(v: f64) -> f64 {
    if v <= -1.0 {
        0.0
    } else if v <= 0.0 {
        0.5 * (1.0 + v) * (1.0 + v)
    } else if v < 1.0 {
        1.0 - 0.5 * (1.0 - v) * (1.0 - v)
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn resampling_keeps_the_light_that_falls_on_the_kernel() {
        let plane: Vec<f64> = (0..35).map(|i| (i % 7) as f64 + 1.0).collect();
        let total: f64 = plane.iter().sum();
        for sending in [Sending::Point, Sending::Pixel] {
            for to in [0.3, 1.0, 1.7, 4.0] {
                let out = resample(&plane, (7, 5), [3.0, 2.0], 1.0, (41, 41), to, sending);
                let sum: f64 = out.iter().sum();
                assert!((sum - total).abs() < 1e-9 * total, "{to}: {sum}");
            }
        }
        // At the same pitch, centred, a point is the picture itself; a
        // pixel's lone point of light keeps ¾ per axis and gives ⅛ to each
        // side: its square under the tents.
        let same = resample(&plane, (7, 5), [3.0, 2.0], 1.0, (7, 5), 1.0, Sending::Point);
        for (a, b) in same.iter().zip(&plane) {
            assert!((a - b).abs() < 1e-12);
        }
        let mut point = vec![0.0; 25];
        point[12] = 1.0;
        let same = resample(&point, (5, 5), [2.0, 2.0], 1.0, (5, 5), 1.0, Sending::Pixel);
        let axis = [0.0, 0.125, 0.75, 0.125, 0.0];
        for (k, v) in same.iter().enumerate() {
            assert!((v - axis[k % 5] * axis[k / 5]).abs() < 1e-12, "{k}: {v}");
        }
    }
}
