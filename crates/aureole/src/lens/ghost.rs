//! A distant source's ghosts on the sensor, rasterised from a bundle of
//! real rays (Hullin et al., SIGGRAPH 2011): a grid of rays over the
//! entrance pupil is traced along a path; each cell of four neighbouring
//! rays that all arrive carries the light of its patch of the pupil,
//! times the mean of their weights, spread evenly over the quadrilateral
//! they land on, so that the irradiance follows the bundle's compression
//! and stretching (docs/physics.md §12). The light is in units of what
//! the direct path brings to the source's own image: a ghost's pixels
//! sum to its path's power over the image's.

use super::canvas::{Canvas, Patch, Quads};
use super::trace::{Arrival, Layout, Path, Route, Vector};

/// A sensor of `width`×`height` pixels of `pitch_mm`, the optical axis
/// through `centre` (the display window's centre: a frame's overscan lies
/// beyond it); rows run downwards, the image's y upwards.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensor {
    /// Pixels across.
    pub width: usize,
    /// Pixels down.
    pub height: usize,
    /// The pixel pitch, mm.
    pub pitch_mm: f64,
    /// Where the axis meets it: (column, row), pixel i spanning [i, i + 1).
    pub centre: (f64, f64),
}

impl Sensor {
    /// A sensor of `width`×`height` pixels of `pitch_mm`, the axis through
    /// its centre.
    pub fn centred(width: usize, height: usize, pitch_mm: f64) -> Sensor {
        Sensor {
            width,
            height,
            pitch_mm,
            centre: (0.5 * width as f64, 0.5 * height as f64),
        }
    }

    /// (column, row) in pixels of a point of the image plane (mm), pixel
    /// i spanning [i, i + 1).
    pub(crate) fn pixel(&self, at: Vector) -> (f64, f64) {
        (
            self.centre.0 + at[0] / self.pitch_mm,
            self.centre.1 - at[1] / self.pitch_mm,
        )
    }
}

/// Cells across the square of the pupil a path's light passes, where
/// its bundle is traced.
pub const GRID: usize = 48;

/// Cells across the whole entrance (the first surface's clear aperture
/// as the source sees it), where each path's light is first looked for.
const COARSE: usize = 32;

/// Cells a rim crosses are cut into this many pieces along each side:
/// the rim's light is then counted to 1/`RIM` of a cell rather than to a
/// whole one.
const RIM: usize = 8;

/// A square of the entrance pupil's plane, in units of the pupil's
/// radius.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Square {
    centre: (f64, f64),
    half: f64,
}

impl Square {
    /// The pupil point at grid position (i, j) of `cells` across,
    /// fractional within a cell.
    fn point(&self, cells: usize, i: f64, j: f64) -> (f64, f64) {
        let step = 2.0 * self.half / cells as f64;
        (
            self.centre.0 - self.half + i * step,
            self.centre.1 - self.half + j * step,
        )
    }

    /// The square every ray that enters the lens from direction `field`
    /// comes through: the first surface's clear aperture, seen from the
    /// entrance pupil's plane along the field.
    fn entrance(layout: &Layout, field: Vector) -> Square {
        let (z_pupil, radius) = layout.pupil;
        let (z_first, semi) = layout.entrance();
        let back = (z_pupil - z_first) / field[2];
        Square {
            centre: (back * field[0] / radius, back * field[1] / radius),
            half: semi / radius,
        }
    }
}

/// Where in the pupil the light of `route` passes, looked for on a coarse
/// grid over the whole entrance: the square about the cells whose rays
/// may pass between them ([`may_pass`]), a coarse cell wider each way;
/// `None` where no light passes.
pub fn search(layout: &Layout, route: &Route, field: Vector) -> Option<Square> {
    let entrance = Square::entrance(layout, field);
    let side = COARSE + 1;
    let rays: Vec<Option<Arrival>> = (0..side * side)
        .map(|k| {
            let (px, py) = entrance.point(COARSE, (k % side) as f64, (k / side) as f64);
            layout.follow_unclipped(route, layout.collimated(field, (px, py)))
        })
        .collect();
    let (mut lo, mut hi) = ((usize::MAX, usize::MAX), (0, 0));
    for j in 0..COARSE {
        for i in 0..COARSE {
            let corners =
                [(0, 0), (1, 0), (1, 1), (0, 1)].map(|(di, dj)| rays[(j + dj) * side + i + di]);
            if may_pass(layout, &corners) {
                lo = (lo.0.min(i), lo.1.min(j));
                hi = (hi.0.max(i + 1), hi.1.max(j + 1));
            }
        }
    }
    if lo.0 > hi.0 {
        return None;
    }
    let step = 2.0 * entrance.half / COARSE as f64;
    let (a, b) = (
        entrance.point(COARSE, lo.0 as f64 - 1.0, lo.1 as f64 - 1.0),
        entrance.point(COARSE, hi.0 as f64 + 1.0, hi.1 as f64 + 1.0),
    );
    Some(Square {
        centre: (0.5 * (a.0 + b.0), 0.5 * (a.1 + b.1)),
        half: 0.5 * (b.0 - a.0).max(b.1 - a.1).max(step),
    })
}

/// Whether light may pass between the rays of a cell's corners that
/// arrive: their margins within the apertures, stretched by a quarter of
/// their spread, reach 0, and at each of the path's crossings of the
/// stop's plane the box of their crossings, a quarter wider, meets the
/// circle about the opening.
fn may_pass(layout: &Layout, corners: &[Option<Arrival>; 4]) -> bool {
    let alive = || corners.iter().flatten();
    let Some(first) = alive().next() else {
        return false;
    };
    let (low, high) = alive().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), a| {
        (l.min(a.margin), h.max(a.margin))
    });
    if high + 0.25 * (high - low) < 0.0 {
        return false;
    }
    let radius = layout.opening;
    (0..first.stop.points().len()).all(|k| {
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for a in alive() {
            let p = a.stop.points()[k];
            lo = [lo[0].min(p[0]), lo[1].min(p[1])];
            hi = [hi[0].max(p[0]), hi[1].max(p[1])];
        }
        let grow = [0.125 * (hi[0] - lo[0]), 0.125 * (hi[1] - lo[1])];
        let nearest = [
            0.0f64.clamp(lo[0] - grow[0], hi[0] + grow[0]),
            0.0f64.clamp(lo[1] - grow[1], hi[1] + grow[1]),
        ];
        nearest[0] * nearest[0] + nearest[1] * nearest[1] <= radius * radius
    })
}

/// Bilinear interpolation between a cell's corners (0, 0), (1, 0), (1, 1)
/// and (0, 1), at (s, t).
fn bilinear<const N: usize>(corners: [[f64; N]; 4], (s, t): (f64, f64)) -> [f64; N] {
    let w = [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t];
    std::array::from_fn(|n| (0..4).map(|k| w[k] * corners[k][n]).sum())
}

/// A bundle of rays from a distant source along one path: a grid over the
/// square of the pupil its light passes.
struct Bundle<'l, 'a> {
    layout: &'l Layout<'a>,
    route: Route,
    field: Vector,
    square: Square,
    /// The (GRID + 1)² rays, rows of constant pupil y, not stopped by the
    /// stop's opening (the cells clip it between them).
    rays: Vec<Option<Arrival>>,
}

impl<'l, 'a> Bundle<'l, 'a> {
    fn new(layout: &'l Layout<'a>, route: Route, field: Vector, square: Square) -> Bundle<'l, 'a> {
        let side = GRID + 1;
        let mut bundle = Bundle {
            layout,
            route,
            field,
            square,
            rays: Vec::with_capacity(side * side),
        };
        for j in 0..side {
            for i in 0..side {
                let ray = bundle.collimated(i as f64, j as f64);
                bundle
                    .rays
                    .push(layout.follow_unclipped(&bundle.route, ray));
            }
        }
        bundle
    }

    /// The ray at grid position (i, j), fractional within a cell.
    fn collimated(&self, i: f64, j: f64) -> super::trace::Ray {
        let pupil = self.square.point(GRID, i, j);
        self.layout.collimated(self.field, pupil)
    }

    /// The light through a cell of the grid, per unit of the source's
    /// irradiance: its area across the beam (the pupil plane's area times
    /// the cosine of the field angle).
    fn cell_area(&self) -> f64 {
        let step = 2.0 * self.square.half / GRID as f64 * self.layout.pupil.1;
        step * step * self.field[2]
    }

    /// Whether every aperture passes a ray, the stop's opening at every
    /// crossing.
    fn passes(&self, arrival: &Arrival) -> bool {
        arrival.margin >= 0.0 && arrival.stop.points().iter().all(|&p| self.layout.opens(p))
    }

    /// `visit(corners, area)` for every cell whose light arrives: a cell
    /// whose corners all pass every aperture as it is; one an aperture's
    /// rim crosses as the pieces of it whose centres pass, between its
    /// corners ([`Bundle::between`]); one some of whose corners miss a
    /// surface altogether as the pieces of it that arrive, traced anew
    /// ([`Bundle::rim`]).
    fn for_each_cell(&self, mut visit: impl FnMut(&[(Vector, f64); 4], f64)) {
        let side = GRID + 1;
        let area = self.cell_area();
        for j in 0..GRID {
            for i in 0..GRID {
                let at = |di: usize, dj: usize| self.rays[(j + dj) * side + i + di];
                match [at(0, 0), at(1, 0), at(1, 1), at(0, 1)] {
                    [Some(a), Some(b), Some(c), Some(d)] => {
                        let corners = [a, b, c, d];
                        if corners.iter().all(|c| self.passes(c)) {
                            visit(&corners.map(|c| (c.at, c.weight)), area);
                        } else if may_pass(self.layout, &corners.map(Some)) {
                            self.between(&corners, area, &mut visit);
                        }
                    }
                    [None, None, None, None] => {}
                    // A rim beyond which rays miss a surface, where light
                    // may pass about it.
                    corners => {
                        if may_pass(self.layout, &corners) {
                            self.rim(i, j, area, &mut visit);
                        }
                    }
                }
            }
        }
    }

    /// A cell an aperture's rim crosses, its corners all arriving: cut
    /// into RIM² pieces, each landing between the corners, kept where its
    /// centre's margin and crossings of the stop's plane, between the
    /// corners', pass. The rims are then as sharp as the pieces, with no
    /// ray traced anew.
    fn between(
        &self,
        corners: &[Arrival; 4],
        area: f64,
        visit: &mut impl FnMut(&[(Vector, f64); 4], f64),
    ) {
        let crossings = corners[0].stop.points().len();
        let landing = corners.map(|c| [c.at[0], c.at[1], c.at[2], c.weight]);
        let piece = area / (RIM * RIM) as f64;
        let at = |u: usize, v: usize| {
            let l = bilinear(landing, (u as f64 / RIM as f64, v as f64 / RIM as f64));
            ([l[0], l[1], l[2]], l[3])
        };
        for v in 0..RIM {
            for u in 0..RIM {
                let centre = ((u as f64 + 0.5) / RIM as f64, (v as f64 + 0.5) / RIM as f64);
                let margin = bilinear(corners.map(|c| [c.margin]), centre)[0];
                let passes = margin >= 0.0
                    && (0..crossings).all(|k| {
                        let xy = bilinear(corners.map(|c| c.stop.points()[k]), centre);
                        self.layout.opens(xy)
                    });
                if passes {
                    visit(
                        &[at(u, v), at(u + 1, v), at(u + 1, v + 1), at(u, v + 1)],
                        piece,
                    );
                }
            }
        }
    }

    /// A cell beyond some of whose corners rays miss a surface (or are
    /// reflected wholly), cut into RIM² pieces traced anew, clipped by
    /// every aperture; a piece still crossed carries the share of its
    /// corners that arrive, landing on them (those stopped replaced by the
    /// mean of the others).
    fn rim(&self, i: usize, j: usize, area: f64, visit: &mut impl FnMut(&[(Vector, f64); 4], f64)) {
        let side = RIM + 1;
        let mut rays = Vec::with_capacity(side * side);
        for v in 0..side {
            for u in 0..side {
                let (x, y) = (
                    i as f64 + u as f64 / RIM as f64,
                    j as f64 + v as f64 / RIM as f64,
                );
                rays.push(self.layout.follow(&self.route, self.collimated(x, y)));
            }
        }
        let piece = area / (RIM * RIM) as f64;
        for v in 0..RIM {
            for u in 0..RIM {
                let at = |du: usize, dv: usize| rays[(v + dv) * side + u + du];
                let corners = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
                let alive: Vec<(Vector, f64)> = corners.iter().flatten().copied().collect();
                if alive.is_empty() {
                    continue;
                }
                let n = alive.len() as f64;
                let mean = [0, 1, 2].map(|k| alive.iter().map(|c| c.0[k]).sum::<f64>() / n);
                visit(&corners.map(|c| c.unwrap_or((mean, 0.0))), piece);
            }
        }
    }
}

/// The light the direct path brings to the image from a source in
/// direction `field`, per unit of its irradiance: what a ghost's light is
/// counted against.
pub fn direct_light(layout: &Layout, field: Vector, nm: f64) -> f64 {
    let route = layout.route(Path::Direct, nm);
    let Some(square) = search(layout, &route, field) else {
        return 0.0;
    };
    let mut light = 0.0;
    Bundle::new(layout, route, field, square)
        .for_each_cell(|corners, area| light += area * mean_weight(corners));
    light
}

fn mean_weight(corners: &[(Vector, f64); 4]) -> f64 {
    corners.iter().map(|c| c.1).sum::<f64>() / 4.0
}

/// Adds to `plane` (the sensor's pixels, rows downwards) the ghost of
/// `path` of a source in direction `field` at `nm`, scaled by `scale`
/// over `direct` (the [`direct_light`] of that source): the pixels gain
/// `scale` × the ghost's light / the image's. Returns the light added
/// (including what falls outside the sensor, which is dropped).
pub fn add_ghost(
    layout: &Layout,
    path: Path,
    (field, nm): (Vector, f64),
    (direct, scale): (f64, f64),
    sensor: &Sensor,
    plane: &mut [f64],
) -> f64 {
    let square = search(layout, &layout.route(path, nm), field);
    let patch = draw(layout, (path, square), (field, nm), (direct, scale), sensor);
    let mut canvas = Canvas::new(*sensor, 1);
    canvas.add(&patch, 0, 1.0);
    for (p, v) in plane.iter_mut().zip(&canvas.finish()[0]) {
        *p += v;
    }
    patch.light
}

/// As [`add_ghost`], onto a patch of the box of pixels the ghost covers,
/// at the level its cells land about a pixel wide ([`Patch::draw`]): a
/// small ghost takes a small patch, not a whole frame, and a large one a
/// coarse patch. `square` is where in the pupil the path's light passes
/// ([`search`]; none: no light).
fn draw(
    layout: &Layout,
    (path, square): (Path, Option<Square>),
    (field, nm): (Vector, f64),
    (direct, scale): (f64, f64),
    sensor: &Sensor,
) -> Patch {
    let mut quads: Quads = Vec::new();
    let mut light = 0.0;
    if let Some(square) = square {
        Bundle::new(layout, layout.route(path, nm), field, square).for_each_cell(
            |corners, area| {
                let share = scale * area * mean_weight(corners) / direct;
                light += share;
                quads.push((*corners, share));
            },
        );
    }
    Patch::draw(&quads, light, sensor, GRID)
}

/// The unit direction of a distant source `x` degrees right of the axis
/// and `y` degrees above it (as seen through the lens: tan x and tan y
/// its image's offsets over the focal length), +z into the lens.
pub fn direction(x: f64, y: f64) -> Vector {
    let (tx, ty) = (libm::tan(x.to_radians()), libm::tan(y.to_radians()));
    let norm = (tx * tx + ty * ty + 1.0).sqrt();
    [tx / norm, ty / norm, 1.0 / norm]
}

/// The light a ghost is traced in: three wavelengths, each channel's
/// sensitivity-weighted mean (R, G, B), or 17 from 380 to 780 nm, each
/// with its weight in R, G and B (the spectral apertures' light,
/// docs/physics.md §6).
pub fn light(spectral: bool) -> Vec<(f64, Vec<f64>)> {
    use crate::optics::aperture::spectrum;
    if spectral {
        spectrum::Light::Spectral.wavelengths()
    } else {
        spectrum::mean_wavelengths()
            .iter()
            .enumerate()
            .map(|(c, &nm)| {
                let mut weights = vec![0.0; 3];
                weights[c] = 1.0;
                (nm, weights)
            })
            .collect()
    }
}

/// A source's ghosts on a sensor.
#[derive(Debug, Clone)]
pub struct Rendered {
    /// One plane per channel of the light, rows downwards: each pixel the
    /// light it receives over the light of the source's own image in that
    /// channel (a source of even spectral power: white light).
    pub planes: Vec<Vec<f64>>,
    /// Each channel's ghost light over its image's, including what falls
    /// beyond the sensor.
    pub light: Vec<f64>,
    /// Each path's light over the image's (the channels' mean), the
    /// brightest first.
    pub ranked: Vec<(Path, f64)>,
}

/// Every ghost of a distant source in direction `field`, on `sensor`, in
/// `light` (its wavelengths, each with its weight in every channel, as
/// [`light`] gives): [`trace`], painted at the source's brightness.
pub fn render(
    layout: &Layout,
    field: Vector,
    sensor: &Sensor,
    light: &[(f64, Vec<f64>)],
    control: &mut crate::control::Control,
) -> crate::Result<Rendered> {
    let traced = trace(layout, field, sensor, light, control)?;
    let channels = traced.light.len();
    let mut canvas = Canvas::new(*sensor, channels);
    let identity: Vec<Vec<f64>> = (0..channels)
        .map(|t| (0..channels).map(|c| f64::from(u8::from(t == c))).collect())
        .collect();
    traced.paint(&mut canvas, &identity);
    Ok(Rendered {
        planes: canvas.finish(),
        light: traced.light,
        ranked: traced.ranked,
    })
}

/// A source's ghosts traced, each path's at each wavelength drawn at the
/// light of an image of 1 in each channel, to be painted at the source's
/// own.
#[derive(Debug, Clone)]
pub struct Traced {
    /// (wavelength, its ghost of each path), in the order traced.
    patches: Vec<(usize, Patch)>,
    /// For each wavelength, its share of each channel's image.
    shares: Vec<Vec<f64>>,
    /// Each channel's ghost light over its image's, including what falls
    /// beyond the sensor.
    pub light: Vec<f64>,
    /// Each path's light over the image's (the channels' mean), the
    /// brightest first.
    pub ranked: Vec<(Path, f64)>,
}

impl Traced {
    /// Adds the ghosts to `canvas`: its plane t gets Σ_c mix[t][c] ×
    /// channel c's ghosts (each pixel its light over channel c's image).
    pub fn paint(&self, canvas: &mut Canvas, mix: &[Vec<f64>]) {
        for (k, patch) in &self.patches {
            for (target, row) in mix.iter().enumerate() {
                let scale: f64 = row.iter().zip(&self.shares[*k]).map(|(m, s)| m * s).sum();
                canvas.add(patch, target, scale);
            }
        }
    }
}

/// Every ghost of a distant source in direction `field`, on `sensor`, in
/// `light`. The paths are traced in parallel and kept in their order: the
/// same bits on any number of threads.
pub fn trace(
    layout: &Layout,
    field: Vector,
    sensor: &Sensor,
    light: &[(f64, Vec<f64>)],
    control: &mut crate::control::Control,
) -> crate::Result<Traced> {
    use rayon::prelude::*;
    let paths = layout.ghosts();
    let channels = light.first().map_or(0, |(_, w)| w.len());
    // Each channel's image: its weights times the direct path's light.
    let directs: Vec<f64> = light
        .iter()
        .map(|&(nm, _)| direct_light(layout, field, nm))
        .collect();
    let images: Vec<f64> = (0..channels)
        .map(|c| light.iter().zip(&directs).map(|((_, w), d)| w[c] * d).sum())
        .collect();
    let shares: Vec<Vec<f64>> = light
        .iter()
        .map(|(_, weights)| {
            (0..channels)
                .map(|c| {
                    if images[c] > 0.0 {
                        weights[c] / images[c]
                    } else {
                        0.0
                    }
                })
                .collect()
        })
        .collect();
    // Where each path's light passes the pupil, looked for once at the
    // middle wavelength: the bundle's square is a coarse cell wider than
    // it each way, which the dispersion's shifts stay within.
    let middle = light.get(light.len() / 2).map_or(550.0, |l| l.0);
    let squares: Vec<Option<Square>> = paths
        .par_iter()
        .map(|&path| search(layout, &layout.route(path, middle), field))
        .collect();
    let mut patches = Vec::new();
    let mut ranked = vec![0.0; paths.len()];
    let mut totals = vec![0.0; channels];
    for (k, (nm, _)) in light.iter().enumerate() {
        control.check()?;
        if directs[k] > 0.0 {
            // Paths a few at a time, each drawn on its own patch, kept in
            // the paths' order; cancellation is heard between.
            let size = rayon::current_num_threads().max(1) * 2;
            for (c, chunk) in paths.chunks(size).enumerate() {
                control.check()?;
                let drawn: Vec<Patch> = chunk
                    .par_iter()
                    .zip(&squares[c * size..])
                    .map(|(&path, &square)| {
                        draw(layout, (path, square), (field, *nm), (1.0, 1.0), sensor)
                    })
                    .collect();
                for (p, patch) in drawn.into_iter().enumerate() {
                    for (channel, share) in shares[k].iter().enumerate() {
                        ranked[c * size + p] += share * patch.light / channels as f64;
                        totals[channel] += share * patch.light;
                    }
                    patches.push((k, patch));
                }
            }
        }
        control.report((k + 1) as f64 / light.len() as f64);
    }
    let mut ranked: Vec<(Path, f64)> = paths.into_iter().zip(ranked).collect();
    ranked.sort_by(|a, b| b.1.total_cmp(&a.1));
    Ok(Traced {
        patches,
        shares,
        light: totals,
        ranked,
    })
}
