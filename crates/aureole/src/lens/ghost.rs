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
use super::passage::{coarse, found, front, may_pass, search, Square};
use super::trace::{Arrival, Layout, Path, Ray, Route, Vector};
use crate::control::Cancel;

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
pub const GRID: usize = 32;

/// A cell a rim crosses keeps the share of its RIM² points that pass
/// ([`Bundle::between`]), or, where it must be traced anew, is cut into
/// RIM × RIM pieces ([`Bundle::rim`]): the rim's light is then counted to
/// a piece of a cell rather than to a whole one.
const RIM: usize = 8;

/// A cell a rim crosses is drawn in this many pieces along each side.
const PIECES: usize = 4;

/// A bundle at another wavelength beside one traced is traced at every
/// STRIDE-th ray each way ([`Bundle::beside`]).
const STRIDE: usize = 2;

/// A value interpolated bilinearly over a cell, as a + b s + c t + d s t.
#[derive(Debug, Clone, Copy)]
struct Bilinear([f64; 4]);

impl Bilinear {
    /// Through the values at the corners (0, 0), (1, 0), (1, 1), (0, 1).
    fn through([v0, v1, v2, v3]: [f64; 4]) -> Bilinear {
        Bilinear([v0, v1 - v0, v3 - v0, v0 - v1 + v2 - v3])
    }

    fn at(&self, (s, t): (f64, f64)) -> f64 {
        let [a, b, c, d] = self.0;
        a + b * s + (c + d * s) * t
    }
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
        let rays = layout.follow_unclipped_all(&route, &square.rays(layout, field, GRID, 1));
        Bundle {
            layout,
            route,
            field,
            square,
            rays,
        }
    }

    /// This bundle along `route`, the same path at another wavelength,
    /// given its rays at every STRIDE-th grid position each way
    /// (`traced`, [`Square::rays`]); the others
    /// this bundle's moved by the difference between the two bundles
    /// at the traced rays about them, interpolated. Dispersion moves a
    /// bundle's rays little and smoothly, so that the difference varies
    /// far less across a cell than the rays do. A ray where any of those
    /// rays is stopped is traced.
    fn beside(&self, route: Route, traced: &[Option<Arrival>]) -> Bundle<'l, 'a> {
        let (side, coarse) = (GRID + 1, GRID / STRIDE + 1);
        let mut bundle = Bundle {
            layout: self.layout,
            route,
            field: self.field,
            square: self.square,
            rays: vec![None; side * side],
        };
        let mut missing = Vec::new();
        for j in 0..side {
            for i in 0..side {
                let k = j * side + i;
                let (a, b) = (i / STRIDE, j / STRIDE);
                if i % STRIDE == 0 && j % STRIDE == 0 {
                    bundle.rays[k] = traced[b * coarse + a];
                    continue;
                }
                let (s, t) = (
                    (i % STRIDE) as f64 / STRIDE as f64,
                    (j % STRIDE) as f64 / STRIDE as f64,
                );
                let (a1, b1) = ((a + 1).min(coarse - 1), (b + 1).min(coarse - 1));
                let about = [
                    ((1.0 - s) * (1.0 - t), a, b),
                    (s * (1.0 - t), a1, b),
                    (s * t, a1, b1),
                    ((1.0 - s) * t, a, b1),
                ]
                .map(|(w, a, b)| {
                    (
                        w,
                        traced[b * coarse + a],
                        self.rays[STRIDE * (b * side + a)],
                    )
                });
                // Where this bundle's ray and every one about it are
                // stopped, so is the other's: the rims are between.
                if self.rays[k].is_none()
                    && about.iter().all(|(_, a, b)| a.is_none() && b.is_none())
                {
                    continue;
                }
                let about: Option<Vec<_>> =
                    about.iter().map(|&(w, a, b)| Some((w, a?, b?))).collect();
                match self.rays[k]
                    .zip(about)
                    .and_then(|(ray, about)| moved(&ray, &about))
                {
                    Some(ray) => bundle.rays[k] = Some(ray),
                    None => missing.push(k),
                }
            }
        }
        let starts: Vec<_> = missing
            .iter()
            .map(|&k| bundle.collimated((k % side) as f64, (k / side) as f64))
            .collect();
        let traced = self.layout.follow_unclipped_all(&bundle.route, &starts);
        for (&k, ray) in missing.iter().zip(traced) {
            bundle.rays[k] = ray;
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
                            self.between(
                                &corners,
                                (area, [2 * i >= GRID, 2 * j >= GRID]),
                                &mut visit,
                            );
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
    /// into PIECES² pieces, each landing between the corners and carrying
    /// the share of the cell's RIM² points within it whose margin and
    /// crossings of the stop's plane, between the corners', pass. The
    /// points are a Hammersley set, each piece holding as many, so that a
    /// rim along the grid, as a blade's edge may lie, is counted to
    /// 1/RIM² of a cell, not to a row of points; the rim is drawn as sharp
    /// as the pieces, and no ray is traced anew. In the grid's far half
    /// each way (`mirrored`) the points are mirrored, so that they are as
    /// symmetric as the grid, about the line to the source (and, for a
    /// source on the axis, across it).
    fn between(
        &self,
        corners: &[Arrival; 4],
        (area, mirrored): (f64, [bool; 2]),
        visit: &mut impl FnMut(&[(Vector, f64); 4], f64),
    ) {
        const POINTS: usize = RIM * RIM;
        let crossings = corners[0].stop.points().len();
        let landing: [Bilinear; 4] = std::array::from_fn(|n| {
            Bilinear::through(corners.map(|c| if n < 3 { c.at[n] } else { c.weight }))
        });
        let at = |u: usize, v: usize| {
            let st = (u as f64 / PIECES as f64, v as f64 / PIECES as f64);
            let [x, y, z, weight] = landing.map(|l| l.at(st));
            ([x, y, z], weight)
        };
        let margin = Bilinear::through(corners.map(|c| c.margin));
        let stop: [[Bilinear; 2]; 3] = std::array::from_fn(|n| {
            [0, 1].map(|xy| {
                Bilinear::through(corners.map(|c| c.stop.points().get(n).map_or(0.0, |p| p[xy])))
            })
        });
        let piece = |t: f64| ((t * PIECES as f64) as usize).min(PIECES - 1);
        let mut passing = [0usize; PIECES * PIECES];
        for k in 0..POINTS {
            let reversed = (k as u32).reverse_bits() >> (32 - POINTS.trailing_zeros());
            let (x, y) = (
                (k as f64 + 0.5) / POINTS as f64,
                (f64::from(reversed) + 0.5) / POINTS as f64,
            );
            let centre = (
                if mirrored[0] { 1.0 - x } else { x },
                if mirrored[1] { 1.0 - y } else { y },
            );
            let passes = margin.at(centre) >= 0.0
                && stop[..crossings]
                    .iter()
                    .all(|[x, y]| self.layout.opens([x.at(centre), y.at(centre)]));
            if passes {
                passing[piece(centre.1) * PIECES + piece(centre.0)] += 1;
            }
        }
        let point = area / POINTS as f64;
        for (p, &count) in passing.iter().enumerate().filter(|(_, &c)| c > 0) {
            let (u, v) = (p % PIECES, p / PIECES);
            visit(
                &[at(u, v), at(u + 1, v), at(u + 1, v + 1), at(u, v + 1)],
                point * count as f64,
            );
        }
    }

    /// A cell beyond some of whose corners rays miss a surface (or are
    /// reflected wholly), cut into RIM² pieces traced anew, clipped by
    /// every aperture; a piece still crossed carries the share of its
    /// corners that arrive, landing on them (those stopped replaced by the
    /// mean of the others).
    fn rim(&self, i: usize, j: usize, area: f64, visit: &mut impl FnMut(&[(Vector, f64); 4], f64)) {
        let side = RIM + 1;
        let starts: Vec<Ray> = (0..side * side)
            .map(|k| {
                let (u, v) = (k % side, k / side);
                self.collimated(
                    i as f64 + u as f64 / RIM as f64,
                    j as f64 + v as f64 / RIM as f64,
                )
            })
            .collect();
        // Side by side, then clipped: a ray every aperture passes lands
        // where it would clipped along the way.
        let rays: Vec<Option<(Vector, f64)>> = self
            .layout
            .follow_unclipped_all(&self.route, &starts)
            .into_iter()
            .map(|a| a.filter(|a| self.passes(a)).map(|a| (a.at, a.weight)))
            .collect();
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

/// `ray` moved by the difference between the pairs `about` (each its
/// weight, a ray of another bundle and the same ray of `ray`'s), or
/// `None` where their crossings of the stop's plane do not match.
fn moved(ray: &Arrival, about: &[(f64, Arrival, Arrival)]) -> Option<Arrival> {
    let crossings = ray.stop.points().len();
    if about
        .iter()
        .any(|(_, a, b)| a.stop.points().len() != crossings || b.stop.points().len() != crossings)
    {
        return None;
    }
    let mean =
        |f: &dyn Fn(&Arrival) -> f64| about.iter().map(|(w, a, b)| w * (f(a) - f(b))).sum::<f64>();
    let points: Vec<[f64; 2]> = (0..crossings)
        .map(|c| {
            let p = ray.stop.points()[c];
            [
                p[0] + mean(&|a| a.stop.points()[c][0]),
                p[1] + mean(&|a| a.stop.points()[c][1]),
            ]
        })
        .collect();
    Some(Arrival {
        at: std::array::from_fn(|n| ray.at[n] + mean(&|a| a.at[n])),
        weight: (ray.weight + mean(&|a| a.weight)).max(0.0),
        margin: ray.margin + mean(&|a| a.margin),
        stop: super::trace::Crossings::at(&points),
    })
}

/// The light the direct path brings to the image from a source in
/// direction `field`, per unit of its irradiance: what a ghost's light is
/// counted against.
pub fn direct_light(layout: &Layout, field: Vector, nm: f64) -> f64 {
    direct_light_in(layout, field, nm, front(layout, field, nm))
}

/// As [`direct_light`], its light passing the pupil within `square`
/// ([`front`]).
fn direct_light_in(layout: &Layout, field: Vector, nm: f64, square: Option<Square>) -> f64 {
    let route = layout.route(Path::Direct, nm);
    let Some(square) = square else {
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
    let square = if layout.stop_first(path) {
        front(layout, field, nm)
    } else {
        search(layout, &layout.route(path, nm), field)
    };
    // Never cancelled: the one drawing is always there.
    let never = Cancel::new();
    let drawing = (sensor, &never);
    let patch = draw(
        layout,
        (&[path], square),
        (field, &[nm]),
        (direct, scale),
        drawing,
    )
    .ok()
    .and_then(|mut paths| paths.pop()?.pop())
    .unwrap_or_default();
    let mut canvas = Canvas::new(*sensor, 1);
    canvas.add(&patch, 0, 1.0);
    for (p, v) in plane.iter_mut().zip(&canvas.finish()[0]) {
        *p += v;
    }
    patch.light
}

/// As [`add_ghost`] for each of `paths` at each of the wavelengths
/// `nms`, onto a patch of the box of pixels the ghost covers, at the level
/// its cells land about half a pixel wide ([`Patch::draw`]): a small
/// ghost takes a small patch, not a whole frame, and a large one a coarse
/// patch. `square` is where in the pupil the paths' light passes at every
/// wavelength ([`search`]; none: no light). The bundles are traced at the
/// middle wavelength, and at the others by their difference from it
/// ([`Bundle::beside`]); the paths share the rays of their common way in
/// ([`Layout::follow_unclipped_routes`]).
fn draw(
    layout: &Layout,
    (paths, square): (&[Path], Option<Square>),
    (field, nms): (Vector, &[f64]),
    (direct, scale): (f64, f64),
    (sensor, cancel): (&Sensor, &Cancel),
) -> crate::Result<Vec<Vec<Patch>>> {
    use rayon::prelude::*;
    let Some(square) = square else {
        return Ok(vec![vec![Patch::default(); nms.len()]; paths.len()]);
    };
    let patch = |bundle: &Bundle| {
        let mut quads: Quads = Vec::new();
        let mut light = 0.0;
        bundle.for_each_cell(|corners, area| {
            let share = scale * area * mean_weight(corners) / direct;
            light += share;
            quads.push((*corners, share));
        });
        Patch::draw(&quads, light, sensor, 2 * GRID)
    };
    let routes = |nm| -> Vec<Route> { paths.iter().map(|&p| layout.route(p, nm)).collect() };
    let middle = nms.len() / 2;
    let at_middle = routes(nms[middle]);
    let traced = layout.follow_unclipped_routes(&at_middle, &square.rays(layout, field, GRID, 1));
    let bases: Vec<Bundle> = at_middle
        .into_iter()
        .zip(traced)
        .map(|(route, rays)| Bundle {
            layout,
            route,
            field,
            square,
            rays,
        })
        .collect();
    let mut patches = vec![Vec::with_capacity(nms.len()); paths.len()];
    for (k, &nm) in nms.iter().enumerate() {
        cancel.check()?;
        let drawn: Vec<Patch> = if k == middle {
            bases.par_iter().map(patch).collect()
        } else {
            let routes = routes(nm);
            let traced =
                layout.follow_unclipped_routes(&routes, &square.rays(layout, field, GRID, STRIDE));
            bases
                .par_iter()
                .zip(routes.into_par_iter().zip(traced))
                .map(|(base, (route, traced))| patch(&base.beside(route, &traced)))
                .collect()
        };
        for (path, drawn) in patches.iter_mut().zip(drawn) {
            path.push(drawn);
        }
    }
    Ok(patches)
}

/// The unit direction of a distant source `x` degrees right of the axis
/// and `y` degrees above it (as seen through the lens: tan x and tan y
/// its image's offsets over the focal length), +z into the lens.
pub fn direction(x: f64, y: f64) -> Vector {
    towards((libm::tan(x.to_radians()), libm::tan(y.to_radians())))
}

/// The unit direction whose tangents right of the axis and above it are
/// (tx, ty), +z into the lens.
pub(crate) fn towards((tx, ty): (f64, f64)) -> Vector {
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
    // Where the light that meets the stop first enters the pupil, at
    // each wavelength: the direct path's and most ghosts' ([`front`]).
    let fronts: Vec<Option<Square>> = light
        .par_iter()
        .map(|&(nm, _)| front(layout, field, nm))
        .collect();
    let directs: Vec<f64> = light
        .par_iter()
        .zip(&fronts)
        .map(|(&(nm, _), &square)| direct_light_in(layout, field, nm, square))
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
    // Where each path's light passes the pupil, at every wavelength. A
    // path that meets the stop first passes within where the direct
    // path's light reaches it. The others are looked for at the middle
    // wavelength: the bundle's square is a coarse cell wider than their
    // light each way, which the dispersion's shifts stay within.
    let middle = light.get(light.len() / 2).map_or(550.0, |l| l.0);
    let front = Square::cover(fronts);
    let (first, others): (Vec<usize>, Vec<usize>) =
        (0..paths.len()).partition(|&p| layout.stop_first(paths[p]));
    let entrance = Square::entrance(layout, field);
    let routes: Vec<Route> = others
        .iter()
        .map(|&p| layout.route(paths[p], middle))
        .collect();
    let searched = layout.follow_unclipped_routes(&routes, &coarse(layout, field, entrance));
    let nms: Vec<f64> = light.iter().map(|l| l.0).collect();
    // The paths that meet the stop first together, sharing their way in;
    // then every other on its own; kept in the paths' order. Each hears
    // the cancellation before it starts.
    let cancel = control.cancel();
    cancel.check()?;
    let group: Vec<Path> = first.iter().map(|&p| paths[p]).collect();
    let together = draw(
        layout,
        (&group, front),
        (field, &nms),
        (1.0, 1.0),
        (sensor, &cancel),
    )?;
    let alone: Vec<Vec<Patch>> = others
        .par_iter()
        .zip(&searched)
        .map(|(&p, rays)| {
            cancel.check()?;
            let one = (&paths[p..=p], found(layout, entrance, rays));
            Ok(draw(layout, one, (field, &nms), (1.0, 1.0), (sensor, &cancel))?.swap_remove(0))
        })
        .collect::<crate::Result<_>>()?;
    let mut drawn = vec![Vec::new(); paths.len()];
    for (p, patches) in first
        .into_iter()
        .zip(together)
        .chain(others.into_iter().zip(alone))
    {
        drawn[p] = patches;
    }
    control.report(1.0);
    let mut patches = Vec::new();
    let mut ranked = vec![0.0; paths.len()];
    let mut totals = vec![0.0; channels];
    for k in (0..light.len()).filter(|&k| directs[k] > 0.0) {
        for (p, path) in drawn.iter_mut().enumerate() {
            let patch = std::mem::take(&mut path[k]);
            for (channel, share) in shares[k].iter().enumerate() {
                ranked[p] += share * patch.light / channels as f64;
                totals[channel] += share * patch.light;
            }
            patches.push((k, patch));
        }
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
