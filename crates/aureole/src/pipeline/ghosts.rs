//! The ghost stage (docs/physics.md §12): lens ghosts move with their
//! source, so they are no kernel. The scene's bright sources (touching
//! pixels above the ghosts' threshold, one source each, the brightest
//! first) are each traced through every two-reflection path of the lens;
//! their ghosts are added to the scene and their light taken from the
//! source, before the kernel's chain spreads the whole.

use std::collections::VecDeque;

use rayon::prelude::*;

use crate::control::Control;
use crate::error::Result;
use crate::image::{Image, Layout as Planes, PixelLuminance};
use crate::lens::canvas::Canvas;
use crate::lens::effect::{GhostOptics, Ghosts};
use crate::lens::ghost::{towards, Rays, Sensor, Traced};
use crate::lens::trace::{Layout, Path, Vector};

/// Where a frame's display window lies in its pixels: a frame with
/// overscan holds pixels beyond it, whose sources throw ghosts too, while
/// the optical axis and the sensor's width are the display window's.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DisplayWindow {
    /// Its first column, in the frame's pixels (negative when it starts
    /// left of the frame).
    pub x: i64,
    /// Its first row.
    pub y: i64,
    /// Its width in pixels.
    pub width: usize,
    /// Its height in pixels.
    pub height: usize,
}

impl DisplayWindow {
    /// The whole of a `width`×`height` frame.
    pub fn whole(width: usize, height: usize) -> DisplayWindow {
        DisplayWindow {
            x: 0,
            y: 0,
            width,
            height,
        }
    }

    /// Where the optical axis meets the frame: (column, row).
    fn centre(&self) -> (f64, f64) {
        (
            self.x as f64 + 0.5 * self.width as f64,
            self.y as f64 + 0.5 * self.height as f64,
        )
    }
}

/// What a frame's ghosts were.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GhostSummary {
    /// Sources above the threshold.
    pub found: usize,
    /// Of those, the ones traced (the brightest, up to the config's count).
    pub traced: usize,
    /// Paths of two reflections per source.
    pub paths: usize,
    /// The f-number traced at.
    pub f_number: f64,
    /// The ghosts' light over the traced sources' (luminance).
    pub light: f64,
}

/// The rays of a frame's sources, kept from one trace for the next
/// ([`Rays`]): a change of the stop's blades, rotation or roundness draws
/// the ghosts anew from them, the same bytes as traced, without tracing.
/// Anything else the rays depend on (the lens, the f-number, the
/// wavelengths, a source's place) traces again.
#[derive(Debug, Clone, Default)]
pub struct KeptRays {
    /// What they were traced through.
    optics: Option<GhostOptics>,
    /// Each source's, the brightest first.
    sources: Vec<std::sync::Arc<Rays>>,
    /// The most bytes they may hold: sources beyond are traced each time.
    limit: u64,
    /// The sources of the last frame drawn from kept rays.
    reused: usize,
}

impl KeptRays {
    /// None kept yet, at most `limit` bytes of them.
    pub fn new(limit: u64) -> KeptRays {
        KeptRays {
            limit,
            ..KeptRays::default()
        }
    }

    /// The bytes they hold.
    pub fn bytes(&self) -> u64 {
        self.sources.iter().map(|rays| rays.bytes()).sum()
    }

    /// How many of the last frame's sources were drawn from kept rays.
    pub fn reused(&self) -> usize {
        self.reused
    }

    /// The rays kept for a source in direction `field` through `optics`.
    fn of(&self, optics: &GhostOptics, field: Vector) -> Option<std::sync::Arc<Rays>> {
        let same = self
            .optics
            .as_ref()
            .is_some_and(|kept| kept.traces_like(optics));
        same.then(|| {
            self.sources
                .iter()
                .find(|rays| rays.are_for(field, &optics.light))
                .cloned()
        })
        .flatten()
    }

    /// Keeps `traced` (a frame's sources' rays through `optics`, the
    /// brightest first) as far as the limit allows, instead of the last.
    fn keep(&mut self, optics: &GhostOptics, traced: Vec<std::sync::Arc<Rays>>) {
        let mut bytes = 0;
        self.sources = traced
            .into_iter()
            .take_while(|rays| {
                bytes += rays.bytes();
                bytes <= self.limit
            })
            .collect();
        self.optics = Some(optics.clone());
    }
}

/// A bright source: touching pixels above the threshold.
#[derive(Debug, Clone)]
struct Source {
    /// Its pixels.
    pixels: Vec<usize>,
    /// Its luminance-weighted centre, (column, row), pixel i spanning
    /// [i, i + 1).
    centre: (f64, f64),
    /// Σ luminance over its pixels (file units).
    luminance: f64,
}

/// The sources of `image`: 8-connected pixels whose luminance is above
/// `level` (file units), the brightest first.
fn sources(image: &Image, level: f64) -> Vec<Source> {
    let (width, height) = (image.width, image.height);
    let luminance = PixelLuminance::of(image);
    let bright = |i: usize| f64::from(luminance.at(i)) > level;
    let mut seen = vec![false; width * height];
    let mut found = Vec::new();
    let mut queue = VecDeque::new();
    for start in 0..width * height {
        if seen[start] || !bright(start) {
            continue;
        }
        seen[start] = true;
        queue.push_back(start);
        let mut source = Source {
            pixels: Vec::new(),
            centre: (0.0, 0.0),
            luminance: 0.0,
        };
        let (mut sx, mut sy) = (0.0, 0.0);
        while let Some(i) = queue.pop_front() {
            let y = f64::from(luminance.at(i));
            let (col, row) = (i % width, i / width);
            source.pixels.push(i);
            source.luminance += y;
            sx += y * (col as f64 + 0.5);
            sy += y * (row as f64 + 0.5);
            for dr in -1i64..=1 {
                for dc in -1i64..=1 {
                    let (c, r) = (col as i64 + dc, row as i64 + dr);
                    if c < 0 || r < 0 || c >= width as i64 || r >= height as i64 {
                        continue;
                    }
                    let j = r as usize * width + c as usize;
                    if !seen[j] && bright(j) {
                        seen[j] = true;
                        queue.push_back(j);
                    }
                }
            }
        }
        source.centre = (sx / source.luminance, sy / source.luminance);
        found.push(source);
    }
    // Ties keep their order in the frame: the same sources every run.
    found.sort_by(|a, b| b.luminance.total_cmp(&a.luminance));
    found
}

/// The direction of a distant source whose image the lens forms at
/// `target` (mm on the sensor, y upwards): the chief ray aimed by a few
/// Newton steps from the paraxial guess, so that the ghosts line up with
/// the source's own image whatever the lens's distortion.
fn aim(layout: &Layout, focal_mm: (f64, f64), target: (f64, f64), nm: f64) -> Vector {
    let lands = |t: (f64, f64)| {
        layout
            .trace(Path::Direct, layout.collimated(towards(t), (0.0, 0.0)), nm)
            .map(|(at, _)| (at[0], at[1]))
    };
    // The image is upright in the frame as the camera shows it: a source
    // right of the axis is seen through the lens from the right.
    let mut t = (target.0 / focal_mm.0, target.1 / focal_mm.1);
    for _ in 0..6 {
        let Some(at) = lands(t) else { break };
        let step = (
            (target.0 - at.0) / focal_mm.0,
            (target.1 - at.1) / focal_mm.1,
        );
        t = (t.0 + step.0, t.1 + step.1);
        if step.0.abs().max(step.1.abs()) < 1e-9 {
            break;
        }
    }
    towards(t)
}

/// `source`'s ghosts (`drawn`) painted on `canvas` and their light taken
/// out of the source's pixels in `scene`: the input is what the lens
/// brought from the source, its own image and its ghosts together.
/// Returns the ghosts' share of its luminance over its image's.
fn share_out(
    image: &Image,
    (scene, canvas): (&mut Image, &mut Canvas),
    source: &Source,
    drawn: &Traced,
) -> f64 {
    let weights = image.luminance_weights().map(f64::from);
    let y_share: f64 = weights.iter().zip(&drawn.light).map(|(w, g)| w * g).sum();
    // Each channel's share of the source.
    let shares: Vec<f64> = match image.layout {
        Planes::Rgb => drawn.light.clone(),
        Planes::Luminance => vec![y_share],
    };
    let mut mix = Vec::with_capacity(scene.planes.len());
    for (c, plane) in scene.planes.iter_mut().enumerate() {
        let g = shares[c];
        let power: f64 = source
            .pixels
            .iter()
            .map(|&i| f64::from(image.planes[c][i]))
            .sum();
        let direct = power / (1.0 + g);
        for &i in &source.pixels {
            plane[i] -= (f64::from(image.planes[c][i]) * g / (1.0 + g)) as f32;
        }
        mix.push(match image.layout {
            Planes::Rgb => (0..3).map(|k| if k == c { direct } else { 0.0 }).collect(),
            Planes::Luminance => weights.iter().map(|w| w * direct).collect(),
        });
    }
    drawn.paint(canvas, &mix);
    y_share
}

/// `image` with the ghosts of its brightest sources, traced through
/// `optics`: each source's ghosts add its light times each path's share,
/// and the source keeps the rest, so that no light is made (what falls
/// beyond the frame leaves it). `scale` is cd/m² per file unit.
pub(crate) fn add_ghosts(
    image: &Image,
    (scale, window): (f64, DisplayWindow),
    (ghosts, optics): (&Ghosts, &GhostOptics),
    kept: &mut KeptRays,
    control: &mut Control,
) -> Result<(Image, GhostSummary)> {
    let layout = optics.layout()?;
    let sensor: Sensor = optics.sensor((image.width, image.height), window.centre());
    let found = sources(image, ghosts.threshold / scale);
    let traced = found.len().min(ghosts.sources as usize);
    let green = optics.light[optics.light.len() / 2].0;
    let mut scene = image.clone();
    // Every source's ghosts on one canvas, its levels added up once.
    let mut canvas = Canvas::new(sensor, image.planes.len());
    let (mut ghost_light, mut source_light) = (0.0, 0.0);
    // Sources a few at a time, side by side (each source's tracing has
    // parts too small to share out among every core), painted in order.
    let cancel = control.cancel();
    let batch = rayon::current_num_threads().max(1);
    let mut done = 0;
    let (mut rays, mut reused) = (Vec::with_capacity(traced), 0);
    for sources in found[..traced].chunks(batch) {
        control.check()?;
        // Rays are kept for as many sources as the limit holds.
        let keep = rays
            .iter()
            .map(|r: &std::sync::Arc<Rays>| r.bytes())
            .sum::<u64>()
            < kept.limit;
        let traced_here: Vec<(Option<std::sync::Arc<Rays>>, bool, Traced)> = sources
            .par_iter()
            .map(|source| {
                let target = (
                    (source.centre.0 - sensor.centre.0) * sensor.pitch_mm,
                    (sensor.centre.1 - source.centre.1) * sensor.pitch_mm,
                );
                // An anamorphic lens's two focal lengths: each way its own.
                let field = aim(&layout, optics.focal_mm, target, green);
                if let Some(rays) = kept.of(optics, field) {
                    let drawn = rays.draw(&layout, &sensor, &optics.light, &cancel)?;
                    return Ok((Some(rays), true, drawn));
                }
                let light = (&sensor, optics.light.as_slice());
                let (drawn, rays) = Rays::trace_drawn(&layout, field, light, keep, &cancel)?;
                Ok((rays.map(std::sync::Arc::new), false, drawn))
            })
            .collect::<Result<_>>()?;
        done += sources.len();
        control.report(done as f64 / traced as f64);
        for (source, (source_rays, kept_before, drawn)) in sources.iter().zip(traced_here) {
            rays.extend(source_rays);
            reused += usize::from(kept_before);
            let y_share = share_out(image, (&mut scene, &mut canvas), source, &drawn);
            ghost_light += source.luminance * y_share / (1.0 + y_share);
            source_light += source.luminance;
        }
    }
    control.check()?;
    kept.keep(optics, rays);
    kept.reused = reused;
    for (plane, ghosts) in scene.planes.iter_mut().zip(canvas.finish()) {
        for (value, ghost) in plane.iter_mut().zip(ghosts) {
            *value += ghost as f32;
        }
    }
    control.report(1.0);
    Ok((
        scene,
        GhostSummary {
            found: found.len(),
            traced,
            paths: layout.ghosts().len(),
            f_number: optics.f_number,
            light: if source_light > 0.0 {
                ghost_light / source_light
            } else {
                0.0
            },
        },
    ))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::image::Layout as Planes;

    #[test]
    fn touching_pixels_make_one_source_and_the_brightest_comes_first() {
        let mut image = Image::filled(20, 10, Planes::Luminance, 1.0);
        for (i, value) in [(22, 50.0), (23, 50.0), (43, 100.0), (57, 80.0)] {
            image.planes[0][i] = value;
        }
        let found = sources(&image, 10.0);
        assert_eq!(found.len(), 2);
        assert_eq!(found[0].pixels.len(), 3);
        assert_eq!(found[0].luminance, 200.0);
        assert_eq!(found[1].pixels, [57]);
        assert_eq!(found[1].centre, (17.5, 2.5));
    }
}
