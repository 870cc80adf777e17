//! Where ghosts are drawn: a sensor's pixels at several resolutions. A
//! ghost is drawn at the level whose pixels are about as large as a
//! piece of its bundle's cells lands (each level's pixels twice the
//! last's across), so that a ghost spread over half a 4K frame costs what
//! a small one does; the levels are added up once, each interpolated
//! bilinearly onto the sensor's own pixels, which keeps every level's
//! light (docs/physics.md §12). A large ghost's edge is then as soft as
//! half of one of its cells, a sixty-fourth of it.

use super::ghost::Sensor;
use super::trace::Vector;

/// The most pieces a quadrilateral is cut into along each side when it
/// lands larger than a pixel.
const MOST_PIECES: usize = 64;

/// The coarsest level: pixels 2⁶ = 64 of the sensor's across.
const COARSEST: usize = 6;

/// The quadrilaterals a ghost's bundle lands on, each (its corners on
/// the image plane with their weights, its light).
pub(crate) type Quads = Vec<([(Vector, f64); 4], f64)>;

/// A ghost drawn on the pixels of the box it covers, at one level.
#[derive(Debug, Clone, Default)]
pub(crate) struct Patch {
    /// The level: pixels 2^level of the sensor's across.
    level: usize,
    /// The box's first column and row at that level, and its width.
    x0: usize,
    y0: usize,
    width: usize,
    /// Its pixels, rows downwards.
    values: Vec<f64>,
    /// Its light, including what falls beyond the sensor.
    pub light: f64,
}

impl Patch {
    /// `quads` (holding `light` together) drawn on `sensor` at the level
    /// whose pixels are about as wide as `cells` across the quads' extent
    /// (twice the bundle's: its rims are drawn sharper than its cells).
    pub(crate) fn draw(quads: &Quads, light: f64, sensor: &Sensor, cells: usize) -> Patch {
        let Some((lo, hi)) = extent(quads, sensor) else {
            return Patch {
                light,
                ..Patch::default()
            };
        };
        let cell = (hi.0 - lo.0).max(hi.1 - lo.1) / cells as f64;
        // ⌊log₂ cell⌋: pixels no wider than a cell lands.
        let level = if cell >= 2.0 {
            (libm::floor(libm::log2(cell)) as usize).min(COARSEST)
        } else {
            0
        };
        let sensor = at_level(sensor, level);
        let scale = 1.0 / (1u64 << level) as f64;
        let clip = |v: f64, n: usize| v.clamp(0.0, n as f64) as usize;
        // The pixels the quads' corners reach, and the one beyond each
        // side that the bilinear shares touch, within the sensor.
        let (x0, y0) = (
            clip((lo.0 * scale).floor() - 1.0, sensor.width),
            clip((lo.1 * scale).floor() - 1.0, sensor.height),
        );
        let (x1, y1) = (
            clip((hi.0 * scale).ceil() + 1.0, sensor.width),
            clip((hi.1 * scale).ceil() + 1.0, sensor.height),
        );
        let (width, height) = (x1.saturating_sub(x0), y1.saturating_sub(y0));
        let mut values = vec![0.0; width * height];
        for (corners, share) in quads {
            spread_at(
                &mut values,
                (width, height),
                &sensor,
                (x0, y0),
                corners,
                *share,
            );
        }
        Patch {
            level,
            x0,
            y0,
            width,
            values,
            light,
        }
    }
}

/// The box (columns, rows of the sensor's pixels) the quads' corners
/// reach; `None` for none.
fn extent(quads: &Quads, sensor: &Sensor) -> Option<((f64, f64), (f64, f64))> {
    let (mut lo, mut hi) = (
        (f64::INFINITY, f64::INFINITY),
        (f64::NEG_INFINITY, f64::NEG_INFINITY),
    );
    for (corners, _) in quads {
        for c in corners {
            let (x, y) = sensor.pixel(c.0);
            lo = (lo.0.min(x), lo.1.min(y));
            hi = (hi.0.max(x), hi.1.max(y));
        }
    }
    (lo.0 <= hi.0 && lo.1 <= hi.1).then_some((lo, hi))
}

/// The sensor of pixels 2^level as wide: as many as cover it.
fn at_level(sensor: &Sensor, level: usize) -> Sensor {
    let size = 1usize << level;
    Sensor {
        width: sensor.width.div_ceil(size),
        height: sensor.height.div_ceil(size),
        pitch_mm: sensor.pitch_mm * size as f64,
        centre: (sensor.centre.0 / size as f64, sensor.centre.1 / size as f64),
    }
}

/// A sensor's pixels at every level, one plane per channel each.
#[derive(Debug, Clone)]
pub struct Canvas {
    sensor: Sensor,
    /// By level, then channel; a level no ghost was drawn at is empty.
    levels: Vec<Vec<Vec<f64>>>,
}

impl Canvas {
    /// A black canvas of `channels` planes over `sensor`.
    pub fn new(sensor: Sensor, channels: usize) -> Canvas {
        Canvas {
            sensor,
            levels: vec![vec![Vec::new(); channels]; COARSEST + 1],
        }
    }

    /// Adds `patch` times `scale` to channel `channel`.
    pub(crate) fn add(&mut self, patch: &Patch, channel: usize, scale: f64) {
        if patch.width == 0 || scale == 0.0 {
            return;
        }
        let level = at_level(&self.sensor, patch.level);
        let plane = &mut self.levels[patch.level][channel];
        if plane.is_empty() {
            *plane = vec![0.0; level.width * level.height];
        }
        for (r, row) in patch.values.chunks(patch.width).enumerate() {
            let start = (patch.y0 + r) * level.width + patch.x0;
            for (p, v) in plane[start..start + patch.width].iter_mut().zip(row) {
                *p += scale * v;
            }
        }
    }

    /// The sensor's own pixels, one plane per channel: every level
    /// interpolated bilinearly onto them and added, in order, row by row
    /// (one pass over each plane).
    pub fn finish(self) -> Vec<Vec<f64>> {
        let (width, height) = (self.sensor.width, self.sensor.height);
        let mut levels = self.levels.into_iter();
        let first = levels.next().unwrap_or_default();
        let coarser: Vec<Vec<Vec<f64>>> = levels.collect();
        first
            .into_iter()
            .enumerate()
            .map(|(channel, plane)| {
                let mut plane = if plane.is_empty() {
                    vec![0.0; width * height]
                } else {
                    plane
                };
                let drawn: Vec<Upsampled> = coarser
                    .iter()
                    .enumerate()
                    .filter(|(_, level)| !level[channel].is_empty())
                    .map(|(index, level)| Upsampled::new(&level[channel], &self.sensor, index + 1))
                    .collect();
                if !drawn.is_empty() {
                    for (y, row) in plane.chunks_mut(width).enumerate() {
                        for level in &drawn {
                            level.add_row(y, row);
                        }
                    }
                }
                plane
            })
            .collect()
    }
}

/// A plane of pixels 2^level as wide as the sensor's, to be interpolated
/// bilinearly between its pixels' centres (held to the edge beyond the
/// outer ones) and divided among the fine pixels each covers: its light
/// is kept, every coarse pixel's shares summing to one.
struct Upsampled<'a> {
    coarse: &'a [f64],
    /// The coarse plane's width and height.
    size: (usize, usize),
    /// 2^level.
    scale: f64,
    /// Per fine column: the coarse columns it lies between, and how far.
    columns: Vec<(usize, usize, f64)>,
}

impl Upsampled<'_> {
    fn new<'a>(coarse: &'a [f64], sensor: &Sensor, level: usize) -> Upsampled<'a> {
        let at = at_level(sensor, level);
        let scale = (1usize << level) as f64;
        let columns = (0..sensor.width)
            .map(|x| between(x, at.width, scale))
            .collect();
        Upsampled {
            coarse,
            size: (at.width, at.height),
            scale,
            columns,
        }
    }

    /// Adds the plane's share to the fine pixels of row `y`.
    fn add_row(&self, y: usize, row: &mut [f64]) {
        let (cw, ch) = self.size;
        let per_pixel = 1.0 / (self.scale * self.scale);
        let (r0, r1, fy) = between(y, ch, self.scale);
        let (a, b) = (&self.coarse[r0 * cw..][..cw], &self.coarse[r1 * cw..][..cw]);
        for (value, &(c0, c1, fx)) in row.iter_mut().zip(&self.columns) {
            let top = a[c0] + fx * (a[c1] - a[c0]);
            let bottom = b[c0] + fx * (b[c1] - b[c0]);
            *value += per_pixel * (top + fy * (bottom - top));
        }
    }
}

/// Where fine pixel `k`'s centre falls between two of `n` coarse ones
/// `size` times as wide, and how far: coarse i and i + 1 by (1 − f, f),
/// held at the edges.
fn between(k: usize, n: usize, size: f64) -> (usize, usize, f64) {
    let at = (k as f64 + 0.5) / size - 0.5;
    if at <= 0.0 {
        (0, 0, 0.0)
    } else if at >= (n - 1) as f64 {
        (n - 1, n - 1, 0.0)
    } else {
        let i = at as usize;
        (i, i + 1, at - i as f64)
    }
}

/// `light` spread evenly over the quadrilateral the four `corners` land
/// on: cut until each piece is smaller than a pixel, each piece's light
/// going to the pixels about its centre, bilinearly (which keeps its
/// centroid); into `plane`, a box of `size` pixels whose first is the
/// sensor's `origin`.
fn spread_at(
    plane: &mut [f64],
    size: (usize, usize),
    sensor: &Sensor,
    origin: (usize, usize),
    corners: &[(Vector, f64); 4],
    light: f64,
) {
    let px = corners.map(|c| {
        let (x, y) = sensor.pixel(c.0);
        (x - origin.0 as f64, y - origin.1 as f64)
    });
    let longest = (0..4)
        .map(|k| {
            let (a, b) = (px[k], px[(k + 1) % 4]);
            ((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt()
        })
        .fold(0.0, f64::max);
    let pieces = (longest.ceil() as usize).clamp(1, MOST_PIECES);
    let share = light / (pieces * pieces) as f64;
    let centre = |k: usize| (k as f64 + 0.5) / pieces as f64;
    for v in 0..pieces {
        let t = centre(v);
        for s in (0..pieces).map(centre) {
            let w = [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t];
            let x = (0..4).map(|k| w[k] * px[k].0).sum();
            let y = (0..4).map(|k| w[k] * px[k].1).sum();
            deposit(plane, size, (x, y), share);
        }
    }
}

/// `light` at the point (column, row) shared bilinearly among the four
/// pixels whose centres surround it, in a plane of `width`×`height`;
/// what falls beyond it is dropped.
fn deposit(plane: &mut [f64], (width, height): (usize, usize), (x, y): (f64, f64), light: f64) {
    let (fx, fy) = (x - 0.5, y - 0.5);
    // Wholly beyond the plane (or not a number): nothing to share.
    if !(fx >= -1.0 && fy >= -1.0 && fx < width as f64 && fy < height as f64) {
        return;
    }
    // ⌊f⌋ by truncating f + 1 ≥ 0: a conversion, not a call to `floor`.
    let (x0, y0) = ((fx + 1.0) as i64 - 1, (fy + 1.0) as i64 - 1);
    let (ax, ay) = (fx - x0 as f64, fy - y0 as f64);
    let (w, h) = (width as i64, height as i64);
    if x0 >= 0 && y0 >= 0 && x0 + 1 < w && y0 + 1 < h {
        // Wholly within: the four pixels without a test each.
        let (left, right) = (light * (1.0 - ax), light * ax);
        let (top, bottom) = plane[(y0 * w + x0) as usize..].split_at_mut(width);
        top[0] += left * (1.0 - ay);
        top[1] += right * (1.0 - ay);
        bottom[0] += left * ay;
        bottom[1] += right * ay;
        return;
    }
    for (dx, wx) in [(0, 1.0 - ax), (1, ax)] {
        for (dy, wy) in [(0, 1.0 - ay), (1, ay)] {
            let (cx, cy) = (x0 + dx, y0 + dy);
            if cx >= 0 && cy >= 0 && cx < w && cy < h {
                plane[(cy * w + cx) as usize] += light * wx * wy;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_coarse_level_keeps_its_light_on_the_sensors_pixels() {
        // Every coarse pixel, the edges' too, where the interpolation is
        // held, on a sensor the coarsest pixels tile.
        let sensor = Sensor::centred(128, 64, 0.01);
        for level in 1..=COARSEST {
            let coarse = at_level(&sensor, level);
            for (x, y) in [
                (0, 0),
                (coarse.width / 2, coarse.height / 2),
                (coarse.width - 1, 0),
            ] {
                let mut values = vec![0.0; coarse.width * coarse.height];
                values[y * coarse.width + x] = 1.0;
                let mut fine = vec![0.0; 128 * 64];
                let upsampled = Upsampled::new(&values, &sensor, level);
                for (y, row) in fine.chunks_mut(128).enumerate() {
                    upsampled.add_row(y, row);
                }
                let sum: f64 = fine.iter().sum();
                assert!((sum - 1.0).abs() < 1e-12, "level {level} at {x},{y}: {sum}");
            }
        }
    }
}
