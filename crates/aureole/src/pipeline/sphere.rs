//! The eye's glare over a wide view: the CIE's veil spread on the sphere
//! of directions, for pictures whose pixels cover unequal angles
//! (fisheyes, wide perspectives), where no one kernel in pixels holds.
//!
//! The veil a bright pixel j lays on a pixel i is L_j·ω_j·g(φ_ij): its
//! light times the eye's PSF g (the CIE equation over its integral on the
//! sphere, sr⁻¹) at the angle φ between them. Summed directly that is
//! (bright pixels) × (pixels) terms; instead the PSF is cut into bands of
//! angle by smooth windows that add up to one (docs/physics.md §5):
//!
//! - up to 8 cells of the finest grid (a cell is one pixel), pixel to pixel,
//!   exactly; within two pixels of a bright one, averaged over the
//!   receiving pixel's area;
//! - each coarser band, 4–16 cells of its grid (cells of 2ˡ × 2ˡ pixels),
//!   between the grid's cells: the bright light of a cell gathered at its
//!   centroid, the veil found at the cells' centres and interpolated to the
//!   pixels. Within a band a cell is at most a quarter of the angle apart,
//!   and the band's PSF is smooth on that scale: gathering and
//!   interpolating each err by about 0.75·(cell/φ)², under 1 % of the veil
//!   (tests/sphere.rs compares with the direct sum).

use rayon::prelude::*;

use super::threshold::spread_fraction;
use crate::control::Cancel;
use crate::error::{Error, Result};
use crate::image::{Image, Layout, PixelLuminance};
use crate::optics::Eye;
use crate::view::{Pixels, Sight, View};

/// A band begins this many of its cells from the light (and its window
/// reaches full height at twice that).
const BAND_START: f64 = 4.0;
/// The most the widest and the narrowest angle between neighbouring
/// pixels may differ (an equidistant fisheye's are 1.6 apart at 180°).
const MOST_UNEQUAL: f64 = 6.0;
/// A reach that bounds nothing (the coarsest band's, every cell).
const UNBOUNDED: i64 = i64::MAX / 4;
/// The coarsest grid has at most this many cells across.
const TOP_CELLS: usize = 24;
/// Pixels this close (in pixels, each way) to a bright one average the
/// PSF over their area: beyond, a point sample errs by under 1.5 % (the
/// steepest term, θ⁻³, curves by 12/r²: r²/24 of that).
const STENCIL: i64 = 5;

/// Samples across a pixel for that average, `reach` pixels (each way)
/// from the light: more where the PSF curves more.
fn subsamples(reach: i64) -> usize {
    if reach <= 2 {
        6
    } else {
        3
    }
}
/// Pixels of a block that shares one stencil: at most this many, and
/// fewer where one spans more than [`STENCIL_ANGLE`] radians.
const STENCIL_BLOCK: u32 = 16;
/// The widest block one stencil serves, radians (1°): the geometry varies
/// by well under 1 % across it.
const STENCIL_ANGLE: f64 = 0.017_453_292_519_943_295;

/// 0 up to 1, 1 from 2, a smooth step between.
fn window(x: f64) -> f64 {
    if x <= 1.0 {
        0.0
    } else if x >= 2.0 {
        1.0
    } else {
        let s = x - 1.0;
        s * s * (3.0 - 2.0 * s)
    }
}

/// The angle between two unit vectors, accurate when small.
fn angle(a: [f64; 3], b: [f64; 3]) -> f64 {
    let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
    2.0 * libm::asin(((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt() / 2.0).min(1.0))
}

/// A bright pixel, or a cell of them: where it is, its direction (the
/// centroid of its light's) and its light ω·L per channel (file units × sr).
#[derive(Debug, Clone, Copy)]
struct Light {
    column: u32,
    row: u32,
    direction: [f64; 3],
    light: [f64; 3],
    /// A bright pixel's pixels each way within which the first band
    /// reaches, from the spacing about it (a cell's is unused).
    reach: i64,
}

/// Lights sorted by row and column, and where each row's begin.
struct Rows {
    lights: Vec<Light>,
    starts: Vec<usize>,
}

impl Rows {
    fn new(mut lights: Vec<Light>, height: usize) -> Rows {
        lights.sort_by_key(|l| (l.row, l.column));
        let mut starts = vec![lights.len(); height + 1];
        for (i, l) in lights.iter().enumerate().rev() {
            starts[l.row as usize] = i;
        }
        for r in (0..height).rev() {
            starts[r] = starts[r].min(starts[r + 1]);
        }
        Rows { lights, starts }
    }

    /// Where row `row`'s lights lie in `lights`.
    fn row(&self, row: usize) -> std::ops::Range<usize> {
        self.starts[row]..self.starts[row + 1]
    }

    /// The lights of rows `from..=to` (clamped).
    fn between(&self, from: i64, to: i64) -> &[Light] {
        let last = self.starts.len() as i64 - 2;
        let (from, to) = (from.max(0), to.min(last));
        if from > to {
            return &[];
        }
        &self.lights[self.starts[from as usize]..self.starts[to as usize + 1]]
    }
}

/// What the spread did: the picture and the light in and out (Σ Y·ω, file
/// units × sr).
#[derive(Debug, Clone)]
pub struct Spread {
    /// The picture with the veil.
    pub image: Image,
    /// Σ Y·ω of the input.
    pub energy_in: f64,
    /// Σ Y·ω of the output.
    pub energy_out: f64,
    /// Pixels with light spread.
    pub spread_pixels: usize,
}

/// The PSF and the angles that set its bands.
struct Psf<'a> {
    eye: &'a Eye,
    /// 1 / the equation's integral over the sphere.
    norm: f64,
    /// The widest angle one pixel spans, radians.
    widest: f64,
}

impl Psf<'_> {
    /// g(φ), sr⁻¹: the equation over its integral on the whole sphere, so
    /// that what a light spreads is what it loses, wherever it lies.
    fn g(&self, phi: f64) -> f64 {
        self.eye.veiling(phi.to_degrees()) * self.norm
    }

    /// The start of level `l`'s band, radians.
    fn start(&self, level: u32) -> f64 {
        BAND_START * self.widest * f64::from(1u32 << level)
    }

    /// The part of g that level `level` carries, `top` the coarsest; level
    /// 0 is pixel to pixel.
    fn band(&self, level: u32, top: u32, phi: f64) -> f64 {
        let above = if level == 0 {
            1.0
        } else {
            window(phi / self.start(level))
        };
        let below = if level == top {
            0.0
        } else {
            window(phi / self.start(level + 1))
        };
        let w = above - below;
        if w == 0.0 {
            0.0
        } else {
            self.g(phi) * w
        }
    }
}

/// A band of the PSF tabulated against the squared chord |a − b|² between
/// two unit vectors (2 sin(φ/2))², 256 entries an octave, read by the
/// bits of the float: the pairs' inner loops take no trigonometry. Linear
/// between entries, it errs by about 2·10⁻⁶ of the θ⁻³ term.
struct Table {
    base: u64,
    values: Vec<f64>,
}

/// The bits below a table's entries: 256 an octave.
const TABLE_SHIFT: u32 = 44;

impl Table {
    fn new(psf: &Psf, level: u32, top: u32, smallest: f64) -> Table {
        let low = (2.0 * libm::sin(smallest / 2.0)).powi(2);
        let base = low.to_bits() >> TABLE_SHIFT;
        let end = 4.0f64.to_bits() >> TABLE_SHIFT;
        let values = (base..=end + 1)
            .map(|k| {
                let c2 = f64::from_bits(k << TABLE_SHIFT).min(4.0);
                psf.band(level, top, 2.0 * libm::asin(c2.sqrt() / 2.0))
            })
            .collect();
        Table { base, values }
    }

    /// The band between unit vectors `a` and `b`.
    #[inline]
    fn at(&self, a: [f64; 3], b: [f64; 3]) -> f64 {
        let d = [a[0] - b[0], a[1] - b[1], a[2] - b[2]];
        let c2 = d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
        let bits = c2.to_bits();
        let k = (bits >> TABLE_SHIFT).saturating_sub(self.base) as usize;
        if k + 1 >= self.values.len() {
            return self.values[self.values.len() - 1];
        }
        if (bits >> TABLE_SHIFT) < self.base {
            return self.values[0];
        }
        let frac = (bits & ((1u64 << TABLE_SHIFT) - 1)) as f64 / (1u64 << TABLE_SHIFT) as f64;
        self.values[k] + (self.values[k + 1] - self.values[k]) * frac
    }
}

/// The narrowest and widest angle between neighbouring pixels, over a
/// sample of the picture (the widest at most 4× the median: a hemispherical
/// fisheye's rim squeezes without bound).
fn spacing(pixels: &Pixels) -> (f64, f64) {
    let (w, h) = pixels.size();
    let step = (w.min(h) / 64).max(1);
    let mut steps = Vec::new();
    for row in (0..h.saturating_sub(1)).step_by(step) {
        for column in (0..w.saturating_sub(1)).step_by(step) {
            let (Some(a), Some(b), Some(c)) = (
                pixels.pixel(column, row),
                pixels.pixel(column + 1, row),
                pixels.pixel(column, row + 1),
            ) else {
                continue;
            };
            steps.push(angle(a.direction, b.direction));
            steps.push(angle(a.direction, c.direction));
        }
    }
    if steps.is_empty() {
        return (1.0, 1.0);
    }
    steps.sort_by(f64::total_cmp);
    let median = steps[steps.len() / 2];
    let widest = steps[steps.len() - 1].min(4.0 * median);
    (steps[0].max(widest * 1e-3), widest)
}

/// The PSF averaged over pixel (column, row)'s area, from light at `from`,
/// with `count`² samples.
fn averaged(
    pixels: &Pixels,
    psf: &Psf,
    from: [f64; 3],
    column: i64,
    row: i64,
    count: usize,
) -> f64 {
    let n = count as f64;
    let mut sum = 0.0;
    for sy in 0..count {
        for sx in 0..count {
            let x = column as f64 + (sx as f64 + 0.5) / n;
            let y = row as f64 + (sy as f64 + 0.5) / n;
            sum += psf.g(angle(pixels.sight_nearest(x, y).direction, from));
        }
    }
    sum / (n * n)
}

/// The stencils of the blocks with bright pixels: the PSF averaged over
/// the pixels within [`STENCIL`] of a block's centre pixel.
fn stencils(
    pixels: &Pixels,
    psf: &Psf,
    bright: &Rows,
    block: u32,
) -> std::collections::HashMap<(u32, u32), Vec<f64>> {
    let mut blocks: Vec<(u32, u32)> = bright
        .lights
        .iter()
        .map(|l| (l.column / block, l.row / block))
        .collect();
    blocks.sort_unstable();
    blocks.dedup();
    let side = (2 * STENCIL + 1) as usize;
    blocks
        .into_par_iter()
        .map(|(bx, by)| {
            let cx = i64::from(bx * block + block / 2);
            let cy = i64::from(by * block + block / 2);
            let from = pixels
                .sight_nearest(cx as f64 + 0.5, cy as f64 + 0.5)
                .direction;
            let mut weights = vec![0.0; side * side];
            for dy in -STENCIL..=STENCIL {
                for dx in -STENCIL..=STENCIL {
                    if (dx, dy) != (0, 0) {
                        let count = subsamples(dx.abs().max(dy.abs()));
                        weights[((dy + STENCIL) as usize) * side + (dx + STENCIL) as usize] =
                            averaged(pixels, psf, from, cx + dx, cy + dy, count);
                    }
                }
            }
            ((bx, by), weights)
        })
        .collect()
}

/// The bright light gathered into cells of 2ˡ × 2ˡ pixels.
fn gather(bright: &[Light], level: u32, height_cells: usize) -> Rows {
    type Sums = ([f64; 3], [f64; 3], i64);
    let mut cells: std::collections::BTreeMap<(u32, u32), Sums> = std::collections::BTreeMap::new();
    for l in bright {
        let key = (l.row >> level, l.column >> level);
        let entry = cells.entry(key).or_insert(([0.0; 3], [0.0; 3], 0));
        let weight: f64 = l.light.iter().sum();
        for c in 0..3 {
            entry.0[c] += l.light[c];
            entry.1[c] += l.direction[c] * weight;
        }
        entry.2 = entry.2.max(l.reach);
    }
    let lights = cells
        .into_iter()
        .map(|((row, column), (light, d, reach))| {
            let n = (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt().max(1e-300);
            Light {
                column,
                row,
                direction: [d[0] / n, d[1] / n, d[2] / n],
                light,
                // A band reaches as many of its cells as the first band
                // reaches pixels, and the centroid lies anywhere in its cell.
                reach: reach.saturating_add(1),
            }
        })
        .collect();
    Rows::new(lights, height_cells)
}

/// The veil of band `level` at the centres of its grid's cells.
fn coarse_band(
    pixels: &Pixels,
    table: &Table,
    cells: &Rows,
    level: u32,
    reach: i64,
    cancel: &Cancel,
) -> (usize, Vec<[f32; 3]>) {
    let (w, h) = pixels.size();
    let size = 1usize << level;
    let (wl, hl) = (w.div_ceil(size), h.div_ceil(size));
    let rows: Vec<Vec<[f32; 3]>> = (0..hl)
        .into_par_iter()
        .map(|cy| {
            let mut row = vec![[0.0f32; 3]; wl];
            if cancel.is_cancelled() {
                return row;
            }
            let near = cells.between(cy as i64 - reach, cy as i64 + reach);
            if near.is_empty() {
                return row;
            }
            let centre = |cx: usize| {
                let half = size as f64 / 2.0;
                pixels
                    .sight_nearest(
                        ((cx * size) as f64 + half).min(w as f64),
                        ((cy * size) as f64 + half).min(h as f64),
                    )
                    .direction
            };
            let directions: Vec<[f64; 3]> = (0..wl).map(centre).collect();
            let mut sums = vec![[0.0f64; 3]; wl];
            for cell in near {
                // The coarsest band takes every angle: no cell's reach bounds it.
                let reach = if reach >= UNBOUNDED {
                    reach
                } else {
                    reach.min(cell.reach)
                };
                if (cy as i64 - i64::from(cell.row)).abs() > reach {
                    continue;
                }
                let lo = (i64::from(cell.column) - reach).max(0);
                let hi = (i64::from(cell.column) + reach).min(wl as i64 - 1);
                for cx in (lo..=hi).map(|c| c as usize) {
                    let weight = table.at(directions[cx], cell.direction);
                    if weight != 0.0 {
                        for (sum, light) in sums[cx].iter_mut().zip(cell.light) {
                            *sum += light * weight;
                        }
                    }
                }
            }
            for (out, sum) in row.iter_mut().zip(&sums) {
                *out = sum.map(|v| v as f32);
            }
            row
        })
        .collect();
    (wl, rows.into_iter().flatten().collect())
}

/// Spreads the light of `image`'s pixels brighter than `threshold` (cd/m²,
/// with a soft `knee` as [`spread_fraction`]) through `eye` over the sphere
/// of the directions `view` gives its pixels; `scale` is cd/m² per file
/// unit. Bright pixels keep the PSF's light within their own solid angle.
pub fn spread_eye(
    image: &Image,
    scale: f64,
    view: &View,
    eye: &Eye,
    threshold: f64,
    knee: f64,
    cancel: &Cancel,
) -> Result<Spread> {
    view.check()?;
    let (w, h) = (image.width, image.height);
    let pixels = view.pixels(w, h);
    let (narrowest, widest) = spacing(&pixels);
    // The bands reach as many pixels as the narrowest spacing packs into
    // their angle: a view whose pixels differ too much would cost without
    // bound.
    if widest > MOST_UNEQUAL * narrowest {
        return Err(Error::View {
            view: view.to_string(),
            message: format!(
                "its pixels' angles differ {:.0}-fold across the picture (at most {MOST_UNEQUAL:.0} for the eye over the sphere): a perspective wider than about 110° or a fisheye near 360°; give a narrower view, or the perspective as a camera ([camera] sensor_width_mm and focal_length_mm)",
                widest / narrowest
            ),
        });
    }
    let psf = Psf {
        eye,
        norm: 1.0 / eye.sphere(),
        widest,
    };
    let y = PixelLuminance::of(image);
    let channels = image.planes.len().min(3);
    let value = |c: usize, i: usize| f64::from(image.planes[c.min(channels - 1)][i]);
    let mut top = 0u32;
    while w.max(h).div_ceil(1 << top) > TOP_CELLS {
        top += 1;
    }
    // The first band reaches 8 of the first grid's widest cells; in pixels,
    // as many as the spacing about a bright pixel packs into that angle,
    // less a margin for the spacing's change across it.
    let first_band = 2.0 * psf.start(1);
    let reach = (first_band / narrowest).ceil() as i64 + 1;
    let direct_reach = if top == 0 { UNBOUNDED } else { reach };
    let local_reach = |column: usize, row: usize, here: [f64; 3]| -> i64 {
        let step = |c: usize, r: usize| pixels.pixel(c, r).map(|s| angle(s.direction, here));
        let across =
            step(column + 1, row).or_else(|| column.checked_sub(1).and_then(|c| step(c, row)));
        let down =
            step(column, row + 1).or_else(|| row.checked_sub(1).and_then(|r| step(column, r)));
        match (across, down) {
            (Some(a), Some(b)) if a.min(b) > 0.0 => {
                ((first_band / (0.85 * a.min(b))).ceil() as i64 + 1).min(direct_reach)
            }
            _ => direct_reach,
        }
    };
    // The bright pixels, and what each keeps.
    let found: Vec<Vec<(Light, f64)>> = (0..h)
        .into_par_iter()
        .map(|row| {
            let mut out = Vec::new();
            for column in 0..w {
                let i = row * w + column;
                let frac = spread_fraction(f64::from(y.at(i)) * scale, threshold, knee);
                if frac <= 0.0 {
                    continue;
                }
                let Some(s) = pixels.pixel(column, row) else {
                    continue;
                };
                let frac = f64::from(frac);
                let light = [0, 1, 2].map(|c| value(c, i) * frac * s.solid_angle);
                let radius = (s.solid_angle / std::f64::consts::PI).sqrt().to_degrees();
                let keep = (eye.within(radius) * psf.norm).clamp(0.0, 1.0);
                out.push((
                    Light {
                        column: column as u32,
                        row: row as u32,
                        direction: s.direction,
                        light,
                        reach: if top == 0 {
                            direct_reach
                        } else {
                            local_reach(column, row, s.direction)
                        },
                    },
                    frac * (1.0 - keep),
                ));
            }
            out
        })
        .collect();
    cancel.check()?;
    // Found row by row, left to right: in the order `Rows` keeps, so the
    // share each spreads lies beside its light.
    let (lights, spreads): (Vec<Light>, Vec<f64>) = found.into_iter().flatten().unzip();
    let bright = Rows::new(lights, h);
    // Bands of the grids, coarsest first.
    let mut grids = Vec::new();
    for level in 1..=top {
        let size = 1usize << level;
        let cells = gather(&bright.lights, level, h.div_ceil(size));
        // A band reaches 4× its start, 16 of the widest cells: as many of
        // the narrowest as that angle holds, on every level.
        let reach_cells = if level == top { UNBOUNDED } else { reach };
        let table = Table::new(&psf, level, top, narrowest / 4.0);
        grids.push((
            level,
            coarse_band(&pixels, &table, &cells, level, reach_cells, cancel),
        ));
        cancel.check()?;
    }
    let block = ((STENCIL_ANGLE / widest) as u32).clamp(1, STENCIL_BLOCK);
    let stencils = stencils(&pixels, &psf, &bright, block);
    let direct = Table::new(&psf, 0, top, narrowest / 4.0);
    let side = (2 * STENCIL + 1) as usize;
    let weights: Vec<f64> = match image.layout {
        Layout::Rgb => image.luminance_weights().map(f64::from).to_vec(),
        Layout::Luminance => vec![1.0],
    };
    let rows: Vec<(Vec<Vec<f32>>, f64, f64)> = (0..h)
        .into_par_iter()
        .map(|row| {
            let mut veil = vec![[0.0f64; 3]; w];
            if cancel.is_cancelled() {
                return (Vec::new(), 0.0, 0.0);
            }
            let sights: Vec<Option<Sight>> = (0..w).map(|c| pixels.pixel(c, row)).collect();
            let near = bright.between(row as i64 - direct_reach, row as i64 + direct_reach);
            if !near.is_empty() {
                for l in near {
                    let dy = row as i64 - i64::from(l.row);
                    if dy.abs() > l.reach {
                        continue;
                    }
                    // Only rows within the stencil of the light look it up.
                    let stencil = (dy.abs() <= STENCIL)
                        .then(|| &stencils[&(l.column / block, l.row / block)]);
                    let lo = (i64::from(l.column) - l.reach).max(0);
                    let hi = (i64::from(l.column) + l.reach).min(w as i64 - 1);
                    for column in lo..=hi {
                        let dx = column - i64::from(l.column);
                        if dx == 0 && dy == 0 {
                            continue;
                        }
                        let Some(d) = sights[column as usize].map(|s| s.direction) else {
                            continue;
                        };
                        let weight = match stencil {
                            Some(weights) if dx.abs() <= STENCIL => {
                                weights[((dy + STENCIL) as usize) * side + (dx + STENCIL) as usize]
                            }
                            _ => direct.at(d, l.direction),
                        };
                        for (v, light) in veil[column as usize].iter_mut().zip(l.light) {
                            *v += light * weight;
                        }
                    }
                }
            }
            for (level, (wl, grid)) in &grids {
                let size = (1usize << level) as f64;
                let hl = grid.len() / wl;
                let v = ((row as f64 + 0.5) / size - 0.5).clamp(0.0, (hl - 1) as f64);
                let (v0, fv) = (v.floor() as usize, v - v.floor());
                let v1 = (v0 + 1).min(hl - 1);
                for (column, out) in veil.iter_mut().enumerate() {
                    let u = ((column as f64 + 0.5) / size - 0.5).clamp(0.0, (wl - 1) as f64);
                    let (u0, fu) = (u.floor() as usize, u - u.floor());
                    let u1 = (u0 + 1).min(wl - 1);
                    for c in 0..3 {
                        let at = |uu: usize, vv: usize| f64::from(grid[vv * wl + uu][c]);
                        out[c] += (1.0 - fv) * ((1.0 - fu) * at(u0, v0) + fu * at(u1, v0))
                            + fv * ((1.0 - fu) * at(u0, v1) + fu * at(u1, v1));
                    }
                }
            }
            // The picture: what stays, and the veil.
            let mut spread_here = vec![0.0; w];
            for k in bright.row(row) {
                spread_here[bright.lights[k].column as usize] = spreads[k];
            }
            let mut out = vec![Vec::with_capacity(w); channels];
            let (mut energy_in, mut energy_out) = (0.0, 0.0);
            for (column, v) in veil.iter().enumerate() {
                let i = row * w + column;
                let (mut y_in, mut y_out) = (0.0, 0.0);
                for (c, plane) in out.iter_mut().enumerate() {
                    let input = value(c, i);
                    let result = input * (1.0 - spread_here[column]) + v[c];
                    y_in += weights[c] * input;
                    y_out += weights[c] * result;
                    plane.push(result as f32);
                }
                let omega = sights[column].map_or(0.0, |s| s.solid_angle);
                energy_in += y_in * omega;
                energy_out += y_out * omega;
            }
            (out, energy_in, energy_out)
        })
        .collect();
    cancel.check()?;
    let (mut energy_in, mut energy_out) = (0.0, 0.0);
    let mut planes = vec![Vec::with_capacity(w * h); channels];
    for (values, e_in, e_out) in rows {
        energy_in += e_in;
        energy_out += e_out;
        for (plane, row) in planes.iter_mut().zip(values) {
            plane.extend_from_slice(&row);
        }
    }
    let result = Image {
        width: w,
        height: h,
        layout: image.layout,
        planes,
        alpha: image.alpha.clone(),
        white_luminance: image.white_luminance,
        primaries: image.primaries,
    };
    Ok(Spread {
        image: result,
        energy_in,
        energy_out,
        spread_pixels: bright.lights.len(),
    })
}
