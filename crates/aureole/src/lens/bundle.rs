//! A bundle of real rays from a distant source along one path through a
//! lens (Hullin et al., SIGGRAPH 2011): a grid over the square of the
//! pupil its light passes, traced without the stop's opening, whose cells
//! clip the opening and every aperture's rim between their rays and carry
//! their patch of the pupil's light to the quadrilateral they land on
//! (docs/physics.md §12).

use std::borrow::Cow;

use super::canvas::{Patch, Quads};
use super::ghost::Sensor;
use super::passage::{may_pass, Square};
use super::trace::{Arrival, Layout, Path, Ray, Route, Vector};
use crate::control::Cancel;
use crate::optics::aperture::pupil::{Crossing, Side};

/// Cells across the square of the pupil a path's light passes, where
/// its bundle is traced.
pub(super) const GRID: usize = 32;

/// A bundle's (GRID + 1)² rays, rows of constant pupil y; `None` where a
/// ray misses a surface or is reflected wholly.
pub(super) type BundleRays = Vec<Option<Arrival>>;

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
pub(super) struct Bundle<'l, 'a> {
    pub layout: &'l Layout<'a>,
    pub route: Route,
    pub field: Vector,
    pub square: Square,
    /// The (GRID + 1)² rays, rows of constant pupil y, not stopped by the
    /// stop's opening (the cells clip it between them): traced, or kept
    /// from a trace through another stop ([`Rays`]).
    pub rays: Cow<'l, [Option<Arrival>]>,
}

impl<'l, 'a> Bundle<'l, 'a> {
    pub fn new(
        layout: &'l Layout<'a>,
        route: Route,
        field: Vector,
        square: Square,
    ) -> Bundle<'l, 'a> {
        let rays = layout.follow_unclipped_all(&route, &square.rays(layout, field, GRID, 1));
        Bundle {
            layout,
            route,
            field,
            square,
            rays: Cow::Owned(rays),
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
        let mut rays: BundleRays = vec![None; side * side];
        let mut missing = Vec::new();
        for j in 0..side {
            for i in 0..side {
                let k = j * side + i;
                let (a, b) = (i / STRIDE, j / STRIDE);
                if i % STRIDE == 0 && j % STRIDE == 0 {
                    rays[k] = traced[b * coarse + a];
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
                    Some(ray) => rays[k] = Some(ray),
                    None => missing.push(k),
                }
            }
        }
        // The same square and source: the same starting rays.
        let starts: Vec<_> = missing
            .iter()
            .map(|&k| self.collimated((k % side) as f64, (k / side) as f64))
            .collect();
        for (&k, ray) in missing
            .iter()
            .zip(self.layout.follow_unclipped_all(&route, &starts))
        {
            rays[k] = ray;
        }
        Bundle {
            layout: self.layout,
            route,
            field: self.field,
            square: self.square,
            rays: Cow::Owned(rays),
        }
    }

    /// The ray at grid position (i, j), fractional within a cell.
    fn collimated(&self, i: f64, j: f64) -> Ray {
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

    /// The light through every cell that arrives, per unit of the
    /// source's irradiance: each cell's area times its rays' mean weight.
    pub fn light(&self) -> f64 {
        let mut light = 0.0;
        self.for_each_cell(|corners, area| light += area * mean_weight(corners));
        light
    }

    /// `visit(corners, area)` for every cell whose light arrives: a cell
    /// whose corners all pass every aperture as it is; one an aperture's
    /// rim crosses as the pieces of it whose centres pass, between its
    /// corners ([`Bundle::between`]); one some of whose corners miss a
    /// surface altogether as the pieces of it that arrive, traced anew
    /// ([`Bundle::rim`]).
    pub fn for_each_cell(&self, mut visit: impl FnMut(&[(Vector, f64); 4], f64)) {
        let side = GRID + 1;
        let area = self.cell_area();
        // Each ray is a corner of up to four cells: tested once.
        let passing: Vec<bool> = self
            .rays
            .iter()
            .map(|ray| ray.as_ref().is_some_and(|a| self.passes(a)))
            .collect();
        for j in 0..GRID {
            for i in 0..GRID {
                let index = |di: usize, dj: usize| (j + dj) * side + i + di;
                let at = |di: usize, dj: usize| self.rays[index(di, dj)];
                match [at(0, 0), at(1, 0), at(1, 1), at(0, 1)] {
                    [Some(a), Some(b), Some(c), Some(d)] => {
                        let corners = [a, b, c, d];
                        if [(0, 0), (1, 0), (1, 1), (0, 1)]
                            .iter()
                            .all(|&(di, dj)| passing[index(di, dj)])
                        {
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
        // Every point is a mean of the corners with weights of 0 or more:
        // margins of 0 or more at the corners pass them all, and below 0
        // none; an opening that is sure to pass, or to stop, the corners'
        // crossings does the same to theirs. Those tests are left out, and
        // a crossing across the opening's rim meets only the edges there.
        let margins_pass = corners.iter().all(|c| c.margin >= 0.0);
        if corners.iter().all(|c| c.margin < 0.0) {
            return;
        }
        let mut tested: Vec<(&[Bilinear; 2], Crossing)> = Vec::with_capacity(crossings);
        for (n, xy) in stop[..crossings].iter().enumerate() {
            match self
                .layout
                .side_between(&corners.map(|c| c.stop.points()[n]))
            {
                Side::Within => {}
                Side::Beyond => return,
                Side::Across(crossing) => tested.push((xy, crossing)),
            }
        }
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
            let passes = (margins_pass || margin.at(centre) >= 0.0)
                && tested
                    .iter()
                    .all(|([x, y], crossing)| crossing.opens([x.at(centre), y.at(centre)]));
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

/// A bundle's ghost, each of its cells' light `scale` × its share of the
/// pupil over `direct`, onto a patch of the box of pixels the ghost
/// covers, at the level its cells land about half a pixel wide
/// ([`Patch::draw`]): a small ghost takes a small patch, not a whole
/// frame, and a large one a coarse patch.
pub(super) fn draw_bundle(bundle: &Bundle, (direct, scale): (f64, f64), sensor: &Sensor) -> Patch {
    let mut quads: Quads = Vec::with_capacity(GRID * GRID);
    let mut light = 0.0;
    bundle.for_each_cell(|corners, area| {
        let share = scale * area * mean_weight(corners) / direct;
        light += share;
        quads.push((*corners, share));
    });
    Patch::draw(&quads, light, sensor, 2 * GRID)
}

/// `each` of the bundles of `paths` at each of the wavelengths `nms`
/// over `square`, where in the pupil the paths' light passes at every
/// wavelength ([`super::passage::search`]), unclipped (path, then
/// wavelength): what it makes of a bundle (drawn, kept), while the bundle
/// is fresh in the cache. The bundles are traced at the middle
/// wavelength, and at the others by their difference from it
/// ([`Bundle::beside`]); the paths share the rays of their common way in
/// ([`Layout::follow_unclipped_routes`]).
pub(super) fn follow<T: Send>(
    layout: &Layout,
    (paths, square): (&[Path], Square),
    (field, nms): (Vector, &[f64]),
    cancel: &Cancel,
    each: &(impl Fn(Bundle) -> T + Sync),
) -> crate::Result<Vec<Vec<T>>> {
    use rayon::prelude::*;
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
            rays: Cow::Owned(rays),
        })
        .collect();
    let mut followed: Vec<Vec<T>> = (0..paths.len())
        .map(|_| Vec::with_capacity(nms.len()))
        .collect();
    for (k, &nm) in nms.iter().enumerate() {
        cancel.check()?;
        if k == middle {
            continue;
        }
        let routes = routes(nm);
        let traced =
            layout.follow_unclipped_routes(&routes, &square.rays(layout, field, GRID, STRIDE));
        let beside: Vec<T> = bases
            .par_iter()
            .zip(routes.into_par_iter().zip(traced))
            .map(|(base, (route, traced))| each(base.beside(route, &traced)))
            .collect();
        for (path, done) in followed.iter_mut().zip(beside) {
            path.push(done);
        }
    }
    let bases: Vec<T> = bases.into_par_iter().map(each).collect();
    for (path, base) in followed.iter_mut().zip(bases) {
        path.insert(middle.min(path.len()), base);
    }
    Ok(followed)
}

fn mean_weight(corners: &[(Vector, f64); 4]) -> f64 {
    corners.iter().map(|c| c.1).sum::<f64>() / 4.0
}
