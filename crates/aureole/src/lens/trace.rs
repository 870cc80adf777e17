//! Real rays through a prescription: exact refraction and reflection at
//! spherical, cylindrical and toric surfaces (no paraxial approximation),
//! clipped at every
//! surface's clear semi-aperture, the weight of a ray multiplied by each
//! surface's Fresnel transmittance or reflectance on the way
//! (docs/physics.md §12). A path is the light's way through the lens: the
//! direct one, refracted by every surface in turn, or a ghost, reflected
//! at one surface back towards the front and at an earlier one forwards
//! again.

use super::{coating, Coating, Lens};
use crate::optics::aperture::pupil::{Pupil, Side};

/// A point or a direction: x, y across the axis, z along it (mm, from the
/// first surface's vertex, towards the image).
pub type Vector = [f64; 3];

/// A ray: where it is, and its unit direction.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Ray {
    /// A point of the ray.
    pub point: Vector,
    /// Its unit direction.
    pub direction: Vector,
}

/// Where a ray crossed the stop's plane on its path, in order: once on
/// the direct path, up to three times on a ghost's (forwards, back and
/// forwards again).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Crossings {
    points: [[f64; 2]; 3],
    count: usize,
}

impl Crossings {
    fn push(&mut self, point: [f64; 2]) {
        if let Some(slot) = self.points.get_mut(self.count) {
            *slot = point;
            self.count += 1;
        }
    }

    /// The crossings at `points` (the first three).
    pub fn at(points: &[[f64; 2]]) -> Crossings {
        let mut crossings = Crossings::default();
        for &p in points {
            crossings.push(p);
        }
        crossings
    }

    /// The points, mm in the stop's plane.
    pub fn points(&self) -> &[[f64; 2]] {
        &self.points[..self.count]
    }
}

/// A ray arrived on the image plane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Arrival {
    /// Where it lands, mm.
    pub at: Vector,
    /// The share of its light that arrives.
    pub weight: f64,
    /// How far within every surface's clear semi-aperture it passed: the
    /// least of 1 − r²/semi² over the surfaces it met, negative where one
    /// of them stops it.
    pub margin: f64,
    /// Where it crossed the stop's plane.
    pub stop: Crossings,
}

/// The light's way through a lens.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Path {
    /// Refracted by every surface in turn: the image.
    Direct,
    /// Reflected back at surface `second`, then forwards again at the
    /// earlier surface `first`: a ghost (surfaces counted from 0).
    Ghost {
        /// The surface that sends the light forwards again.
        first: usize,
        /// The surface that reflects it back.
        second: usize,
    },
}

/// What happens at one surface on a path.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Event {
    /// Refraction through surface `s`, going forwards (towards the image)
    /// or backwards.
    Through { s: usize, forwards: bool },
    /// Reflection at surface `s`, arriving forwards or backwards.
    Reflect { s: usize, forwards: bool },
}

/// A path worked out at one wavelength: the surfaces it meets in order,
/// each with what a ray needs there.
#[derive(Debug, Clone)]
pub struct Route {
    steps: Vec<Step>,
    nm: f64,
}

impl Route {
    /// The route up to the stop and no further: the light of every path
    /// that meets the stop before its reflections passes there
    /// ([`Layout::stop_first`]).
    pub fn to_stop(&self) -> Route {
        let end = self
            .steps
            .iter()
            .position(|s| s.stop)
            .map_or(self.steps.len(), |k| k + 1);
        Route {
            steps: self.steps[..end].to_vec(),
            nm: self.nm,
        }
    }
}

/// One surface met on a [`Route`].
#[derive(Debug, Clone)]
struct Step {
    /// Which surface it is, met forwards or not, reflecting or not: two
    /// routes with the same steps so far have followed the same rays.
    event: (usize, bool, bool),
    /// Its vertex, mm.
    z: f64,
    /// Its shape.
    figure: Figure,
    /// Its clear semi-aperture, mm.
    semi: f64,
    /// 1/semi², mm⁻².
    reach: f64,
    /// Whether it is the stop, whose opening may be the camera's blades.
    stop: bool,
    /// The indices the light comes from and goes into.
    indices: (f64, f64),
    /// Their ratio, n_in/n_out.
    mu: f64,
    /// Its coating's layers as the light meets them; `None`: it reflects
    /// nothing (the stop).
    layers: Option<Vec<super::Layer>>,
    /// Its reflectance tabulated at the route's wavelength, where the
    /// layout has it ([`Layout::with_wavelengths`]).
    table: Option<std::sync::Arc<coating::Table>>,
    /// Whether the light is reflected here rather than refracted.
    reflect: bool,
}

/// A surface's reflectance tables, forwards and backwards (none for the
/// stop).
type Tables = [Option<std::sync::Arc<coating::Table>>; 2];

/// A lens set out for tracing: each surface's vertex on the axis, in mm.
#[derive(Debug, Clone)]
pub struct Layout<'a> {
    lens: &'a Lens,
    /// z of each surface's vertex, mm.
    vertices: Vec<f64>,
    /// z of the image plane, mm.
    pub image: f64,
    /// The entrance pupil: z of its centre and its radius, mm.
    pub pupil: (f64, f64),
    /// The stop's opening (mm, in its plane), where the camera shapes it:
    /// else the stop's clear semi-aperture.
    stop: Option<Pupil>,
    /// The radius of the circle about the stop's opening, mm.
    pub opening: f64,
    /// Each surface's reflectance tabulated, forwards and backwards, at
    /// the wavelengths [`Layout::with_wavelengths`] was given.
    tables: Vec<(f64, Vec<Tables>)>,
    /// z in front of every surface, mm, where rays start: none bulges
    /// forwards by more than its clear semi-aperture.
    front: f64,
}

impl<'a> Layout<'a> {
    /// `lens` in mm, its image plane at its paraxial focus (d line).
    pub fn new(lens: &'a Lens) -> crate::Result<Layout<'a>> {
        let paraxial = lens.paraxial()?;
        let mm = lens.mm_per_unit;
        let pupil = (
            paraxial.entrance_pupil * mm,
            paraxial.entrance_pupil_radius * mm,
        );
        // An anamorphic lens focuses its two planes apart, by as little as
        // its design allows: the sensor lies midway, where the blur is
        // least.
        let back_focus = 0.5 * (paraxial.back_focus + lens.paraxial_x()?.back_focus);
        let mut layout = Layout::with_image(lens, 0.0, pupil);
        layout.image = layout.vertices.last().copied().unwrap_or(0.0) + back_focus * mm;
        Ok(layout)
    }

    /// `lens` in mm with its image plane at z = `image` (mm) and the
    /// entrance pupil given: for a system that forms no image of its own
    /// (a stack of plates).
    pub fn with_image(lens: &'a Lens, image: f64, pupil: (f64, f64)) -> Layout<'a> {
        let mm = lens.mm_per_unit;
        let mut z = 0.0;
        let vertices = lens
            .surfaces
            .iter()
            .map(|s| {
                let here = z;
                z += s.thickness * mm;
                here
            })
            .collect::<Vec<f64>>();
        let widest = lens
            .surfaces
            .iter()
            .map(|s| s.semi_aperture * mm)
            .fold(0.0, f64::max);
        Layout {
            lens,
            vertices,
            image,
            pupil,
            stop: None,
            opening: lens.surfaces[lens.stop()].semi_aperture * mm,
            tables: Vec::new(),
            front: -(widest + 1.0),
        }
    }

    /// The same, its stop's opening `stop` (mm in the stop's plane: the
    /// camera's blades at its f-number), within a circle of `radius`,
    /// instead of the stop's clear semi-aperture. The entrance pupil stays
    /// the lens's wide open: rays are aimed in its units.
    pub fn with_stop(mut self, stop: Pupil, radius: f64) -> Layout<'a> {
        self.stop = Some(stop);
        self.opening = radius;
        self
    }

    /// The same, each surface's reflectance tabulated at the wavelengths
    /// `nms` ([`coating::Table`]): what a bundle of rays traced at them
    /// spends most of its time on otherwise.
    pub fn with_wavelengths(mut self, nms: &[f64]) -> Layout<'a> {
        self.tables = nms
            .iter()
            .map(|&nm| {
                let tables = (0..self.lens.surfaces.len())
                    .map(|s| {
                        [true, false].map(|forwards| {
                            let ((n_in, n_out), layers) = self.interface(s, forwards, nm);
                            layers.map(|layers| {
                                std::sync::Arc::new(coating::Table::new(n_in, n_out, &layers, nm))
                            })
                        })
                    })
                    .collect();
                (nm, tables)
            })
            .collect();
        self
    }

    /// Whether the stop's opening passes the point `xy` of its plane (mm).
    pub fn opens(&self, xy: [f64; 2]) -> bool {
        self.stop
            .as_ref()
            .is_none_or(|stop| stop.transmission(xy)[0] >= 0.5)
    }

    /// Where the stop's opening lies against the points between
    /// `points` ([`Pupil::side`]): all passed, none, or each to be tested.
    pub fn side_between(&self, points: &[[f64; 2]]) -> Side<'_> {
        match &self.stop {
            None => Side::Within,
            Some(stop) => stop.side(points),
        }
    }

    /// The z of the first surface's vertex and its clear semi-aperture,
    /// mm: every ray that enters the lens passes there.
    pub fn entrance(&self) -> (f64, f64) {
        let first = &self.lens.surfaces[0];
        (
            self.vertices[0],
            first.semi_aperture * self.lens.mm_per_unit,
        )
    }

    /// The ray of a distant source in direction `field` (a unit vector,
    /// +z into the lens) through the point (px, py) of the entrance pupil
    /// in units of its radius, started in front of the first surface.
    pub fn collimated(&self, field: Vector, (px, py): (f64, f64)) -> Ray {
        let (z, radius) = self.pupil;
        let at_pupil = [px * radius, py * radius, z];
        let back = (z - self.front) / field[2];
        Ray {
            point: add(at_pupil, scale(field, -back)),
            direction: field,
        }
    }

    /// The paths of two reflections, every pair of surfaces that reflect
    /// (the stop and a surface between equal media reflect nothing).
    pub fn ghosts(&self) -> Vec<Path> {
        let reflects = |s: usize| {
            let surface = &self.lens.surfaces[s];
            !surface.stop && self.lens.medium_before(s) != surface.medium
        };
        let n = self.lens.surfaces.len();
        let mut paths = Vec::new();
        for second in 0..n {
            for first in 0..second {
                if reflects(first) && reflects(second) {
                    paths.push(Path::Ghost { first, second });
                }
            }
        }
        paths
    }

    /// Whether `path` crosses the stop on its way in, before either
    /// reflection: then its light enters where the direct path's passes
    /// the surfaces up to the stop ([`Route::to_stop`]).
    pub fn stop_first(&self, path: Path) -> bool {
        match path {
            Path::Direct => true,
            Path::Ghost { second, .. } => second > self.lens.stop(),
        }
    }

    /// The surfaces a path meets, in order.
    fn events(&self, path: Path) -> Vec<Event> {
        let n = self.lens.surfaces.len();
        let through = |s, forwards| Event::Through { s, forwards };
        match path {
            Path::Direct => (0..n).map(|s| through(s, true)).collect(),
            Path::Ghost { first, second } => (0..second)
                .map(|s| through(s, true))
                .chain([Event::Reflect {
                    s: second,
                    forwards: true,
                }])
                .chain((first + 1..second).rev().map(|s| through(s, false)))
                .chain([Event::Reflect {
                    s: first,
                    forwards: false,
                }])
                .chain((first + 1..n).map(|s| through(s, true)))
                .collect(),
        }
    }

    /// `ray` (in the air in front of the lens) along `path` at `nm`, to
    /// the image plane: where it lands and the share of its light that
    /// arrives there, or `None` where a surface's aperture stops it, it
    /// misses a surface, or it is reflected wholly where it should pass.
    pub fn trace(&self, path: Path, ray: Ray, nm: f64) -> Option<(Vector, f64)> {
        self.follow(&self.route(path, nm), ray)
    }

    /// What `path` meets at `nm`, worked out once for every ray along it.
    pub fn route(&self, path: Path, nm: f64) -> Route {
        let mm = self.lens.mm_per_unit;
        let steps = self
            .events(path)
            .into_iter()
            .map(|event| {
                let (s, forwards, reflect) = match event {
                    Event::Through { s, forwards } => (s, forwards, false),
                    Event::Reflect { s, forwards } => (s, forwards, true),
                };
                let surface = &self.lens.surfaces[s];
                let (indices, layers) = self.interface(s, forwards, nm);
                let table = self
                    .tables
                    .iter()
                    .find(|(at, _)| *at == nm)
                    .and_then(|(_, tables)| tables[s][usize::from(!forwards)].clone());
                let semi = surface.semi_aperture * mm;
                Step {
                    event: (s, forwards, reflect),
                    z: self.vertices[s],
                    figure: Figure::of(surface, mm),
                    semi,
                    reach: 1.0 / (semi * semi),
                    stop: surface.stop,
                    indices,
                    mu: indices.0 / indices.1,
                    layers,
                    table,
                    reflect,
                }
            })
            .collect();
        Route { steps, nm }
    }

    /// Surface `s` as light meets it at `nm`, going forwards or back: the
    /// indices it comes from and goes into, and its coating's layers from
    /// the light's side in (`None`: it reflects nothing, the stop).
    fn interface(
        &self,
        s: usize,
        forwards: bool,
        nm: f64,
    ) -> ((f64, f64), Option<Vec<super::Layer>>) {
        let surface = &self.lens.surfaces[s];
        let (front, back) = (self.lens.medium_before(s), surface.medium);
        let indices = if forwards {
            (front.index_at(nm), back.index_at(nm))
        } else {
            (back.index_at(nm), front.index_at(nm))
        };
        let layers = match &surface.coating {
            _ if surface.stop => None,
            Coating::None => Some(Vec::new()),
            Coating::Layers(layers) if forwards => Some(layers.clone()),
            Coating::Layers(layers) => Some(layers.iter().rev().copied().collect()),
        };
        (indices, layers)
    }

    /// `ray` along a [`Route`], as [`Layout::trace`].
    pub fn follow(&self, route: &Route, ray: Ray) -> Option<(Vector, f64)> {
        self.walk(route, ray, true).map(|a| (a.at, a.weight))
    }

    /// `ray` along a [`Route`] as [`Layout::follow`], but stopped neither
    /// by the surfaces' clear semi-apertures nor by the stop's opening
    /// (only where it misses a surface or is reflected wholly): how far
    /// within the apertures it passed, and where it crossed the stop's
    /// plane, are kept instead, for a bundle to clip between its rays,
    /// where both vary smoothly ([`Arrival::margin`], [`Layout::opens`]).
    pub fn follow_unclipped(&self, route: &Route, ray: Ray) -> Option<Arrival> {
        self.walk(route, ray, false)
    }

    /// `rays` along a [`Route`] as [`Layout::follow_unclipped`], all
    /// together ([`Layout::follow_unclipped_routes`] of one route).
    pub fn follow_unclipped_all(&self, route: &Route, rays: &[Ray]) -> Vec<Option<Arrival>> {
        self.follow_unclipped_routes(std::slice::from_ref(route), rays)
            .pop()
            .unwrap_or_default()
    }

    /// `rays` along each of `routes` (at one wavelength) as
    /// [`Layout::follow_unclipped`], one list for each route. The rays go
    /// through each surface side by side: a ray's steps are a long chain
    /// of dependent square roots and divisions, and its neighbours keep
    /// the processor busy while it waits. The steps routes share from the
    /// start (a ghost's way in, up to its first reflection, is every
    /// other's that reflects later) are taken once for them all. The
    /// arithmetic is each ray's alone, so the bits are too.
    pub fn follow_unclipped_routes(
        &self,
        routes: &[Route],
        rays: &[Ray],
    ) -> Vec<Vec<Option<Arrival>>> {
        use rayon::prelude::*;
        let Some(nm) = routes.first().map(|r| r.nm) else {
            return Vec::new();
        };
        let members: Vec<usize> = (0..routes.len()).collect();
        let chunks: Vec<Vec<Vec<Option<Arrival>>>> = rays
            .par_chunks(256)
            .map(|chunk| {
                let mut out = vec![Vec::new(); routes.len()];
                let lanes = chunk.iter().map(|&r| Lane::new(r)).collect();
                self.branch(nm, (routes, &members), 0, lanes, &mut out);
                out
            })
            .collect();
        let mut arrivals = vec![Vec::with_capacity(rays.len()); routes.len()];
        for chunk in chunks {
            for (all, part) in arrivals.iter_mut().zip(chunk) {
                all.extend(part);
            }
        }
        arrivals
    }

    /// `lanes`, having taken the first `depth` steps of every route of
    /// `members`, on along them: the routes that end land, the others go
    /// on in groups that take the same next step.
    fn branch(
        &self,
        nm: f64,
        (routes, members): (&[Route], &[usize]),
        depth: usize,
        mut lanes: Vec<Lane>,
        out: &mut [Vec<Option<Arrival>>],
    ) {
        let mut groups: Vec<Vec<usize>> = Vec::new();
        for &m in members {
            match routes[m].steps.get(depth) {
                None => out[m] = lanes.iter().map(|l| self.land(l)).collect(),
                Some(step) => match groups
                    .iter_mut()
                    .find(|g| routes[g[0]].steps[depth].event == step.event)
                {
                    Some(group) => group.push(m),
                    None => groups.push(vec![m]),
                },
            }
        }
        let mut groups = groups.into_iter().peekable();
        while let Some(group) = groups.next() {
            // The last group takes the lanes; the others copies.
            let mut lanes = if groups.peek().is_some() {
                lanes.clone()
            } else {
                std::mem::take(&mut lanes)
            };
            // On while every route of the group goes on alike.
            let first = &routes[group[0]].steps;
            let mut at = depth;
            while at < first.len()
                && (at == depth
                    || group.iter().all(|&m| {
                        routes[m].steps.get(at).map(|s| s.event) == Some(first[at].event)
                    }))
            {
                for lane in lanes.iter_mut().filter(|l| l.alive) {
                    lane.alive = self.advance(nm, &first[at], lane, false).is_some();
                }
                at += 1;
            }
            self.branch(nm, (routes, &group), at, lanes, out);
        }
    }

    fn walk(&self, route: &Route, ray: Ray, clip: bool) -> Option<Arrival> {
        let mut lane = Lane::new(ray);
        for step in &route.steps {
            self.advance(route.nm, step, &mut lane, clip)?;
        }
        self.land(&lane)
    }

    /// `lane`'s ray through one surface of `route`; `None` where it stops
    /// there.
    #[inline(always)]
    fn advance(&self, nm: f64, step: &Step, lane: &mut Lane, clip: bool) -> Option<()> {
        let ray = &lane.ray;
        let semi = if clip { step.semi } else { f64::INFINITY };
        let point = step.figure.hit(ray, step.z, semi)?;
        let across = point[0] * point[0] + point[1] * point[1];
        lane.margin = lane.margin.min(1.0 - across * step.reach);
        if step.stop {
            if clip && !self.opens([point[0], point[1]]) {
                return None;
            }
            lane.stop.push([point[0], point[1]]);
        }
        let (n_in, n_out) = step.indices;
        // The normal, turned to point along the ray.
        let mut normal = step.figure.normal(point, step.z)?;
        if dot(normal, ray.direction) < 0.0 {
            normal = scale(normal, -1.0);
        }
        let cos_in = dot(normal, ray.direction);
        let r = step.layers.as_ref().map_or(0.0, |layers| {
            step.table
                .as_ref()
                .and_then(|t| t.at(cos_in))
                .unwrap_or_else(|| coating::reflectance(n_in, n_out, layers, cos_in, nm))
        });
        lane.ray = if step.reflect {
            lane.weight *= r;
            Ray {
                point,
                direction: add(ray.direction, scale(normal, -2.0 * cos_in)),
            }
        } else {
            lane.weight *= 1.0 - r;
            Ray {
                point,
                direction: refract(ray.direction, normal, cos_in, step.mu)?,
            }
        };
        Some(())
    }

    /// A ray through every surface, on to the image plane.
    fn land(&self, lane: &Lane) -> Option<Arrival> {
        let ray = &lane.ray;
        let t = (self.image - ray.point[2]) / ray.direction[2];
        if !(lane.alive && t.is_finite() && t >= 0.0) || lane.weight <= 0.0 {
            return None;
        }
        Some(Arrival {
            at: add(ray.point, scale(ray.direction, t)),
            weight: lane.weight,
            margin: lane.margin,
            stop: lane.stop,
        })
    }
}

/// A ray on its way along a route: where it is, what it carries, and
/// what it met.
#[derive(Debug, Clone, Copy)]
struct Lane {
    ray: Ray,
    weight: f64,
    stop: Crossings,
    margin: f64,
    alive: bool,
}

impl Lane {
    fn new(ray: Ray) -> Lane {
        Lane {
            ray,
            weight: 1.0,
            stop: Crossings::default(),
            margin: f64::INFINITY,
            alive: true,
        }
    }
}

/// A surface's shape, in mm.
#[derive(Debug, Clone, Copy)]
enum Figure {
    /// Turned about the axis: 1/R, mm⁻¹ (0 a plane).
    Round(f64),
    /// A cylinder: 1/R across the axis that the mask keeps ([1, 0]: curved
    /// across x, [0, 1]: across y).
    Cylinder(f64, [f64; 2]),
    /// A torus: 1/R across x and across y.
    Torus(f64, f64),
}

impl Figure {
    /// `surface`'s, its lengths `mm` per unit.
    fn of(surface: &super::Surface, mm: f64) -> Figure {
        let (cx, cy) = surface.curvatures();
        match (cx / mm, cy / mm) {
            (c, _) if surface.is_round() => Figure::Round(c),
            (0.0, c) => Figure::Cylinder(c, [0.0, 1.0]),
            (c, 0.0) => Figure::Cylinder(c, [1.0, 0.0]),
            (cx, cy) => Figure::Torus(cx, cy),
        }
    }

    /// Where `ray` meets it, its vertex at `z`, within `semi` of the axis:
    /// the intersection nearer the vertex (a sphere's other side is
    /// another surface), or `None`.
    fn hit(&self, ray: &Ray, z: f64, semi: f64) -> Option<Vector> {
        // In the vertex's frame a quadric of these is c(x² + y² + z²) −
        // 2z = 0, a cylinder's without the other way's term; along p + t d
        // that is a t² − 2t(d_z − c p·d) + (c p·p − 2p_z) = 0, with a = c
        // for a sphere (d is a unit vector) and c(d_x² + d_z²) for a
        // cylinder curved across x.
        let p = [ray.point[0], ray.point[1], ray.point[2] - z];
        let d = ray.direction;
        let t = match *self {
            Figure::Round(c) => near_root(c, d[2] - c * dot(p, d), c * dot(p, p) - 2.0 * p[2])?,
            Figure::Cylinder(c, [mx, my]) => {
                let p = [p[0] * mx, p[1] * my, p[2]];
                let d = [d[0] * mx, d[1] * my, d[2]];
                near_root(
                    c * dot(d, d),
                    d[2] - c * dot(p, d),
                    c * dot(p, p) - 2.0 * p[2],
                )?
            }
            Figure::Torus(cx, cy) => newton(p, d, (cx, cy))?,
        };
        // Behind the ray: the surfaces overlap where it passes.
        if !(t.is_finite() && t >= -1e-9) {
            return None;
        }
        let at = add(ray.point, scale(d, t));
        (at[0] * at[0] + at[1] * at[1] <= semi * semi).then_some(at)
    }

    /// The unit normal at `point` (on it), its vertex at `z`, +z at the
    /// vertex; `None` beyond a torus's rim.
    fn normal(&self, point: Vector, z: f64) -> Option<Vector> {
        // (centre − point)/R across the curved ways: a unit vector with no
        // square root taken, since the point lies on the surface.
        let quadric = |c: f64, [mx, my]: [f64; 2]| {
            [
                -c * mx * point[0],
                -c * my * point[1],
                1.0 - c * (point[2] - z),
            ]
        };
        Some(match *self {
            Figure::Round(c) => quadric(c, [1.0, 1.0]),
            Figure::Cylinder(c, mask) => quadric(c, mask),
            Figure::Torus(cx, cy) => {
                let (_, hx, hy) = sag(point[0], point[1], (cx, cy))?;
                let norm = (hx * hx + hy * hy + 1.0).sqrt();
                [-hx / norm, -hy / norm, 1.0 / norm]
            }
        })
    }
}

/// The root of a t² − 2b t + c = 0 near the vertex (t = c / (b ± √(b² −
/// a c))), written without the difference of nearly equal terms (Spencer
/// and Murty); `None` where the line misses.
fn near_root(a: f64, b: f64, c: f64) -> Option<f64> {
    let discriminant = b * b - a * c;
    if discriminant < 0.0 {
        return None;
    }
    let root = b + b.signum() * discriminant.sqrt();
    (root != 0.0).then(|| c / root)
}

/// Where the line p + t d (in the vertex's frame) meets the torus of
/// curvatures (c_x, c_y): t, or `None`. A torus meets a line in up to four
/// points, so no closed form picks the one near the vertex: Newton's
/// method along the ray, from where it crosses the vertex's plane,
/// converges to it in a few steps wherever the surface is a lens's (its
/// slope well below 1).
fn newton(p: Vector, d: Vector, curvatures: (f64, f64)) -> Option<f64> {
    let mut t = -p[2] / d[2];
    for _ in 0..32 {
        if !t.is_finite() {
            return None;
        }
        let (h, hx, hy) = sag(p[0] + t * d[0], p[1] + t * d[1], curvatures)?;
        let gap = h - (p[2] + t * d[2]);
        let step = gap / (hx * d[0] + hy * d[1] - d[2]);
        t -= step;
        // Quadratic convergence: the step after one this small is at the
        // rounding of the coordinates.
        if step.abs() <= 1e-12 * (1.0 + t.abs()) {
            return Some(t);
        }
    }
    None
}

/// An anamorphic surface's sag at (x, y) from its vertex's plane, and its
/// slopes ∂/∂x and ∂/∂y; `None` beyond its rim. The y–z section's circle,
/// sag s_y(y), is turned about an axis parallel to y, 1/c_x behind the
/// vertex, so at height y the x–z section is a circle of curvature
/// c_x / (1 − c_x s_y): a cylinder where either curvature is 0.
fn sag(x: f64, y: f64, (cx, cy): (f64, f64)) -> Option<(f64, f64, f64)> {
    let ky = 1.0 - cy * cy * y * y;
    if ky < 0.0 {
        return None;
    }
    let ry = ky.sqrt();
    let sy = cy * y * y / (1.0 + ry);
    let c = cx / (1.0 - cx * sy);
    let kx = 1.0 - c * c * x * x;
    if !(kx > 0.0 && ry > 0.0 && c.is_finite()) {
        return None;
    }
    let rx = kx.sqrt();
    Some((sy + c * x * x / (1.0 + rx), c * x / rx, cy * y / ry / rx))
}

/// Snell's law in vector form: `d` refracted at a surface of unit normal
/// `normal` (along the ray, cos θ = `cos_in`) with index ratio `mu` =
/// n_in / n_out; `None` beyond the critical angle.
fn refract(d: Vector, normal: Vector, cos_in: f64, mu: f64) -> Option<Vector> {
    let k = 1.0 - mu * mu * (1.0 - cos_in * cos_in);
    if k < 0.0 {
        return None;
    }
    Some(add(scale(d, mu), scale(normal, k.sqrt() - mu * cos_in)))
}

pub(crate) fn dot(a: Vector, b: Vector) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn add(a: Vector, b: Vector) -> Vector {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

fn scale(a: Vector, k: f64) -> Vector {
    [a[0] * k, a[1] * k, a[2] * k]
}
