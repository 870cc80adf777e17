//! The glare figures lighting designers report for a view, from an HDR
//! picture in cd/m² and where its pixels look ([`View`]): the vertical
//! illuminance at the eye E_v, the glare sources, the background
//! luminance, and the daylight glare probability (DGP), DGI, UGR, VCP and
//! CGI, as Radiance's `evalglare` 3.05 defines and finds them, so that a
//! figure from aureole and one from evalglare mean the same.
//!
//! - Every pixel within 90° of the line of sight counts: its luminance L
//!   (cd/m²), its direction and the solid angle ω it covers.
//!   E_v = Σ L·cos θ·ω; the mean luminance is Σ L·ω / Σ ω.
//! - A pixel brighter than the threshold is a source pixel: by default
//!   2000 cd/m² (evalglare's default since 2.05), or a multiple of the
//!   mean luminance, or of a task area's (5 when a task is given).
//! - Source pixels within half the search angle (evalglare's `-r`, 0.2 rad
//!   by default: its code compares twice the angle) of each other are one
//!   source. Pixels above the peak limit (50 000 cd/m², evalglare's `-Y`)
//!   are split off their source into sources of their own, the sun apart
//!   from the sky about it.
//! - The background luminance is the light the sources do not give:
//!   L_b = (E_v − E_dir)/π, E_dir the sources' share of E_v (evalglare's
//!   default since 2.05, the CIE's way).

pub mod indices;
mod sources;

use rayon::prelude::*;
use serde::Serialize;

pub use sources::Run;

use crate::control::Cancel;
use crate::error::{Error, Result};
use crate::image::{Image, PixelLuminance};
use crate::view::{Pixels, View};
use indices::Seen;

/// What makes a pixel part of a glare source.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Threshold {
    /// Brighter than this luminance, cd/m².
    Luminance(f64),
    /// Brighter than this multiple of the task area's mean luminance, or
    /// of the whole view's without a task.
    Multiple(f64),
}

/// A task area: the pixels within a cone about a point of the picture.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Task {
    /// Column of its centre, from the left.
    pub column: f64,
    /// Row of its centre, from the top (evalglare counts from the bottom).
    pub row: f64,
    /// The cone's full opening angle, radians (as evalglare's `-t`).
    pub angle: f64,
}

/// How to find the sources.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct RatingOptions {
    /// The source threshold; `None` is evalglare's default: 2000 cd/m², or
    /// 5× the task's luminance when a task is given.
    pub threshold: Option<Threshold>,
    /// A task area, whose luminance sets a threshold given as a multiple.
    pub task: Option<Task>,
    /// evalglare's search radius `-r`, radians: pixels within half of it
    /// are one source.
    pub search_angle: f64,
    /// Pixels at least this bright become sources of their own (evalglare's
    /// `-Y`); `None` keeps them in their source (`-x`).
    pub peak_limit: Option<f64>,
}

impl Default for RatingOptions {
    fn default() -> Self {
        RatingOptions {
            threshold: None,
            task: None,
            search_angle: 0.2,
            peak_limit: Some(50_000.0),
        }
    }
}

impl RatingOptions {
    /// Refuses a threshold, search angle or peak limit that is not a
    /// positive number, and a task cone wider than a half space.
    pub fn check(&self) -> Result<()> {
        let refuse = |name: &'static str, value: f64, allowed: &'static str| {
            Err(Error::Parameter {
                effect: "glare".into(),
                name,
                value: value.to_string(),
                allowed,
            })
        };
        let positive = |v: f64| v.is_finite() && v > 0.0;
        match self.threshold {
            Some(Threshold::Luminance(l)) if !positive(l) => {
                return refuse("threshold", l, "a luminance above 0 cd/m²")
            }
            Some(Threshold::Multiple(m)) if !positive(m) => {
                return refuse("multiple", m, "a factor above 0")
            }
            _ => {}
        }
        if !positive(self.search_angle) || self.search_angle > std::f64::consts::PI {
            return refuse(
                "search",
                self.search_angle,
                "an angle above 0 and at most π radians",
            );
        }
        if let Some(p) = self.peak_limit.filter(|p| !positive(*p)) {
            return refuse("peak", p, "a luminance above 0 cd/m²");
        }
        if let Some(t) = &self.task {
            if !(t.column.is_finite() && t.row.is_finite()) {
                return refuse(
                    "task position",
                    f64::NAN,
                    "a column and row, finite numbers",
                );
            }
            if !positive(t.angle) || t.angle > std::f64::consts::PI {
                return refuse(
                    "task angle",
                    t.angle,
                    "the task cone's full opening, above 0 and at most π radians",
                );
            }
        }
        Ok(())
    }
}

/// One glare source.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Source {
    /// Its direction from the eye (camera frame: x right, y up, z ahead),
    /// at its pixels' centre weighted by L·ω.
    pub direction: [f64; 3],
    /// That centre in the picture: column and row from the top left.
    pub position: [f64; 2],
    /// Degrees off the line of sight.
    pub angle_deg: f64,
    /// Solid angle, sr.
    pub solid_angle: f64,
    /// Mean luminance, cd/m².
    pub luminance: f64,
    /// Its brightest pixel, cd/m².
    pub max_luminance: f64,
    /// Guth's position index at its centre.
    pub position_index: f64,
    /// Its share of the vertical illuminance, lx.
    pub illuminance: f64,
    /// Pixels.
    pub pixels: usize,
    /// Its pixels, for drawing it.
    #[serde(skip)]
    pub runs: Vec<Run>,
}

/// The glare figures of one view.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Rating {
    /// The picture's size.
    pub width: usize,
    /// The picture's size.
    pub height: usize,
    /// Where its pixels look.
    pub view: View,
    /// The source threshold applied, cd/m².
    pub threshold: f64,
    /// The task area's mean luminance, cd/m², where one was given.
    pub task_luminance: Option<f64>,
    /// Vertical illuminance at the eye E_v, lx.
    pub vertical_illuminance: f64,
    /// The sources' share of it, lx.
    pub direct_illuminance: f64,
    /// Mean luminance of the field of view, cd/m².
    pub mean_luminance: f64,
    /// Background luminance L_b = (E_v − E_dir)/π, cd/m².
    pub background_luminance: f64,
    /// The solid angle the picture covers (within 90° of the line of
    /// sight), sr.
    pub solid_angle: f64,
    /// Its brightest pixel, cd/m².
    pub max_luminance: f64,
    /// Daylight glare probability: below 0.35 imperceptible, 0.35–0.40
    /// perceptible, 0.40–0.45 disturbing, above intolerable.
    pub dgp: f64,
    /// Daylight glare index.
    pub dgi: f64,
    /// Unified glare rating.
    pub ugr: f64,
    /// Visual comfort probability, %.
    pub vcp: f64,
    /// CIE glare index.
    pub cgi: f64,
    /// The discomfort glare rating behind VCP.
    pub dgr: f64,
    /// Veiling luminance of the sources after Stiles and Holladay,
    /// Σ 10·E/θ² (θ in degrees), cd/m².
    pub veiling_luminance: f64,
    /// The sources, the brightest first.
    pub sources: Vec<Source>,
}

/// What the whole view adds up to.
#[derive(Debug, Clone, Copy, Default)]
struct Totals {
    illuminance: f64,
    flux: f64,
    solid_angle: f64,
    max: f64,
}

/// The luminance of pixel `i`, cd/m².
fn luminance_at(y: &PixelLuminance, scale: f64, i: usize) -> f64 {
    f64::from(y.at(i)) * scale
}

/// Adds up the view row by row (rows in parallel, added in order: the
/// same bits every run). Only pixels within 90° of the line of sight
/// count. A view symmetric about its centre line computes each pixel's
/// geometry once for the two halves of a row.
fn totals(
    image: &Image,
    scale: f64,
    pixels: &Pixels,
    symmetric: bool,
    cancel: &Cancel,
) -> Result<Totals> {
    let (w, h) = (image.width, image.height);
    let y = PixelLuminance::of(image);
    let rows: Vec<Totals> = (0..h)
        .into_par_iter()
        .map(|row| {
            let mut t = Totals::default();
            if cancel.is_cancelled() {
                return t;
            }
            let mut geometry = vec![(0.0, 0.0); w];
            let computed = if symmetric { w.div_ceil(2) } else { w };
            for (column, g) in geometry.iter_mut().enumerate().take(computed) {
                if let Some(s) = pixels.pixel(column, row) {
                    if s.direction[2] >= 0.0 {
                        *g = (s.direction[2] * s.solid_angle, s.solid_angle);
                    }
                }
            }
            for column in computed..w {
                geometry[column] = geometry[w - 1 - column];
            }
            for (column, &(cos_omega, omega)) in geometry.iter().enumerate() {
                if omega == 0.0 {
                    continue;
                }
                let l = luminance_at(&y, scale, row * w + column);
                t.illuminance += l * cos_omega;
                t.flux += l * omega;
                t.solid_angle += omega;
                t.max = t.max.max(l);
            }
            t
        })
        .collect();
    cancel.check()?;
    Ok(rows.iter().fold(Totals::default(), |a, b| Totals {
        illuminance: a.illuminance + b.illuminance,
        flux: a.flux + b.flux,
        solid_angle: a.solid_angle + b.solid_angle,
        max: a.max.max(b.max),
    }))
}

/// The mean luminance within the task's cone.
fn task_luminance(
    image: &Image,
    scale: f64,
    pixels: &Pixels,
    task: &Task,
    cancel: &Cancel,
) -> Result<f64> {
    let centre = pixels
        .sight(task.column + 0.5, task.row + 0.5)
        .ok_or_else(|| Error::View {
            view: format!("task at column {} row {}", task.column, task.row),
            message: "the task's centre is outside the picture's view".into(),
        })?
        .direction;
    let near = libm::cos(task.angle / 2.0);
    let y = PixelLuminance::of(image);
    let w = image.width;
    let rows: Vec<(f64, f64)> = (0..image.height)
        .into_par_iter()
        .map(|row| {
            let mut sum = (0.0, 0.0);
            for column in 0..w {
                let Some(s) = pixels.pixel(column, row) else {
                    continue;
                };
                let d = s.direction;
                if d[0] * centre[0] + d[1] * centre[1] + d[2] * centre[2] >= near {
                    sum.0 += luminance_at(&y, scale, row * w + column) * s.solid_angle;
                    sum.1 += s.solid_angle;
                }
            }
            sum
        })
        .collect();
    cancel.check()?;
    let (flux, omega) = rows.iter().fold((0.0, 0.0), |a, b| (a.0 + b.0, a.1 + b.1));
    Ok(if omega > 0.0 { flux / omega } else { 0.0 })
}

/// What a source adds up, pixel by pixel.
#[derive(Debug, Clone, Default)]
struct Tally {
    pixels: usize,
    solid_angle: f64,
    flux: f64,
    weighted: [f64; 2],
    illuminance: f64,
    max: f64,
    runs: Vec<Run>,
}

impl Tally {
    fn add(&mut self, column: u32, row: u32, l: f64, cos: f64, omega: f64) {
        self.pixels += 1;
        self.solid_angle += omega;
        self.flux += l * omega;
        self.weighted[0] += (f64::from(column) + 0.5) * l * omega;
        self.weighted[1] += (f64::from(row) + 0.5) * l * omega;
        self.illuminance += l * cos * omega;
        self.max = self.max.max(l);
        match self.runs.last_mut() {
            Some(r) if r.row == row && r.end == column => r.end += 1,
            _ => self.runs.push(Run {
                row,
                start: column,
                end: column + 1,
            }),
        }
    }

    fn source(self, pixels: &Pixels) -> Option<Source> {
        if self.pixels == 0 || self.flux <= 0.0 {
            return None;
        }
        let position = [self.weighted[0] / self.flux, self.weighted[1] / self.flux];
        let direction = pixels.sight(position[0], position[1])?.direction;
        Some(Source {
            direction,
            position,
            angle_deg: libm::acos(direction[2].clamp(-1.0, 1.0)).to_degrees(),
            solid_angle: self.solid_angle,
            luminance: self.flux / self.solid_angle,
            max_luminance: self.max,
            position_index: indices::position_index(direction),
            illuminance: self.illuminance,
            pixels: self.pixels,
            runs: self.runs,
        })
    }
}

/// The glare sources: pixels above `threshold`, grouped; the peaks split
/// off their groups.
fn find_sources(
    image: &Image,
    scale: f64,
    pixels: &Pixels,
    threshold: f64,
    options: &RatingOptions,
    max: f64,
    cancel: &Cancel,
) -> Result<Vec<Source>> {
    let (w, h) = (image.width, image.height);
    let y = PixelLuminance::of(image);
    let ahead = |c: usize, r: usize| pixels.pixel(c, r).is_some_and(|s| s.direction[2] >= 0.0);
    let bright = sources::runs(
        w,
        h,
        |c, r| luminance_at(&y, scale, r * w + c) > threshold && ahead(c, r),
        cancel,
    )?;
    let join = options.search_angle / 2.0;
    let groups = sources::group(&bright, h, pixels, join, cancel)?;
    let count = groups.iter().max().map_or(0, |g| *g as usize + 1);
    // evalglare splits the peaks only when the view's brightest pixel is
    // above the limit.
    let limit = options.peak_limit.filter(|l| max > *l);
    let (peaks, peak_groups) = match limit {
        Some(limit) => {
            // The peaks are source pixels: found among them alone.
            let runs = sources::within(&bright, |c, r| luminance_at(&y, scale, r * w + c) >= limit);
            let groups = sources::group(&runs, h, pixels, join, cancel)?;
            (runs, groups)
        }
        None => (Vec::new(), Vec::new()),
    };
    let peak_count = peak_groups.iter().max().map_or(0, |g| *g as usize + 1);
    let mut tallies = vec![Tally::default(); count + peak_count];
    let mut p = 0;
    for (run, &group) in bright.iter().zip(&groups) {
        for column in run.start..run.end {
            let i = run.row as usize * w + column as usize;
            let l = luminance_at(&y, scale, i);
            let Some(s) = pixels.pixel(column as usize, run.row as usize) else {
                continue;
            };
            while p < peaks.len() && (peaks[p].row, peaks[p].end) <= (run.row, column) {
                p += 1;
            }
            let in_peak = peaks
                .get(p)
                .is_some_and(|k| k.row == run.row && k.start <= column && column < k.end);
            let tally = if in_peak {
                count + peak_groups[p] as usize
            } else {
                group as usize
            };
            tallies[tally].add(column, run.row, l, s.direction[2], s.solid_angle);
        }
        if run.row % 512 == 0 {
            cancel.check()?;
        }
    }
    let mut found: Vec<Source> = tallies
        .into_iter()
        .filter_map(|t| t.source(pixels))
        .collect();
    found.sort_by(|a, b| b.luminance.total_cmp(&a.luminance));
    Ok(found)
}

/// Rates the glare of `image` (its luminance times `scale` is cd/m²) seen
/// through `view`.
pub fn rate(
    image: &Image,
    scale: f64,
    view: &View,
    options: &RatingOptions,
    cancel: &Cancel,
) -> Result<Rating> {
    view.check()?;
    if !(scale.is_finite() && scale > 0.0) {
        return Err(Error::Parameter {
            effect: "glare".into(),
            name: "input_scale",
            value: scale.to_string(),
            allowed: "cd/m² per file unit, a finite number above 0",
        });
    }
    options.check()?;
    let pixels = view.pixels(image.width, image.height);
    let totals = totals(image, scale, &pixels, view.shift == 0.0, cancel)?;
    let mean = if totals.solid_angle > 0.0 {
        totals.flux / totals.solid_angle
    } else {
        0.0
    };
    let task_luminance = options
        .task
        .map(|task| task_luminance(image, scale, &pixels, &task, cancel))
        .transpose()?;
    let threshold = match options.threshold {
        Some(Threshold::Luminance(l)) => l,
        Some(Threshold::Multiple(m)) => m * task_luminance.unwrap_or(mean),
        None => task_luminance.map_or(2000.0, |t| 5.0 * t),
    };
    let sources = find_sources(
        image, scale, &pixels, threshold, options, totals.max, cancel,
    )?;
    let direct: f64 = sources.iter().map(|s| s.illuminance).sum();
    let ev = totals.illuminance;
    let background = (ev - direct) / std::f64::consts::PI;
    let seen: Vec<Seen> = sources
        .iter()
        .map(|s| Seen {
            luminance: s.luminance,
            solid_angle: s.solid_angle,
            position_index: s.position_index,
        })
        .collect();
    let any = !seen.is_empty();
    let or_zero = |v: f64| if any { v } else { 0.0 };
    let dgr = or_zero(indices::dgr(mean, &seen));
    Ok(Rating {
        width: image.width,
        height: image.height,
        view: *view,
        threshold,
        task_luminance,
        vertical_illuminance: ev,
        direct_illuminance: direct,
        mean_luminance: mean,
        background_luminance: background,
        solid_angle: totals.solid_angle,
        max_luminance: totals.max,
        dgp: indices::dgp(ev, &seen),
        dgi: or_zero(indices::dgi(background, &seen)),
        ugr: or_zero(indices::ugr(background, &seen)),
        vcp: if any { indices::vcp(dgr) } else { 100.0 },
        cgi: or_zero(indices::cgi(ev, direct, &seen)),
        dgr,
        veiling_luminance: sources
            .iter()
            .map(|s| 10.0 * s.illuminance / (s.angle_deg * s.angle_deg).max(1e-16))
            .sum(),
        sources,
    })
}
