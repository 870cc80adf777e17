//! The pupil and its Fourier transform, in closed form (docs/physics.md §6).
//!
//! A pupil is a sum of transmitting and opaque polygons and discs, in mm,
//! and of spots (dust, grease) that change what the glass under them
//! transmits, amplitude and phase. Its transform
//! Â(ν) = ∫ A(s) e^(−2πi ν·s) ds is exact at any spatial
//! frequency ν (cycles/mm): for a polygon, by the divergence theorem,
//! Â = (i/|q|²) Σ_edges L (q·n̂) e^(−iq·m) sinc(q·e/2) with q = 2πν; for a
//! disc of radius R, 2πR² J₁(qR)/(qR). No sampling grid, so no aliasing.

use super::jinc;
use std::f64::consts::{PI, TAU};

mod inside;
mod oval;

pub use inside::{Crossing, Side};

/// A complex amplitude (re, im).
pub type Amplitude = [f64; 2];

/// A polygon edge for the far field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct EdgeTerm {
    /// Length, mm.
    pub length: f64,
    /// Outward unit normal.
    pub normal: [f64; 2],
    /// Unit direction along the edge.
    pub along: [f64; 2],
    /// Its midpoint, mm.
    pub middle: [f64; 2],
    /// Which polygon of the pupil it bounds (edges of one polygon share its
    /// sign: both transmit, or both block).
    pub polygon: usize,
    /// +1 for an edge of a polygon that transmits, −1 for one that blocks.
    pub sign: f64,
    /// For a piece of a curved side: the angles (rad) by which the curve's
    /// normal turns before and after this piece, counter-clockwise, half of
    /// each turn to its neighbours. Its light fans over that range of
    /// directions instead of forming a straight edge's ray.
    pub fan: Option<[f64; 2]>,
}

/// A spot for the far field: its pattern, |w|²|Â_disc|², is added whole
/// and incoherently, its centre and phase averaging out over a pixel.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct SpotTerm {
    /// mm.
    pub radius: f64,
    /// |w|², w the change of the amplitude it transmits.
    pub power: f64,
}

/// A disc for the far field.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct DiscTerm {
    pub centre: [f64; 2],
    /// mm.
    pub radius: f64,
    /// +1 transmits, −1 blocks.
    pub sign: f64,
}

#[derive(Debug, Clone)]
struct Edge {
    length: f64,
    normal: [f64; 2],
    middle: [f64; 2],
    delta: [f64; 2],
    fan: Option<[f64; 2]>,
}

impl Edge {
    /// The cross product of the edge's direction (start to end) and the
    /// way from its start to `p`: positive left of its line, where a
    /// counter-clockwise polygon's inside lies; |delta| times the distance.
    fn cross(&self, p: [f64; 2]) -> f64 {
        let start = [
            self.middle[0] - self.delta[0] / 2.0,
            self.middle[1] - self.delta[1] / 2.0,
        ];
        self.delta[0] * (p[1] - start[1]) - self.delta[1] * (p[0] - start[0])
    }
}

#[derive(Debug, Clone)]
enum Outline {
    Polygon {
        edges: Vec<Edge>,
        centroid: [f64; 2],
        reach: f64,
        /// The radius of the circle about the centroid within every
        /// edge's line (0 where the centroid is not inside them all): a
        /// point within it is inside without its edges tested.
        inner: f64,
        /// The vertices and pieces per side it was made from.
        made: (Vec<[f64; 2]>, usize),
    },
    Disc {
        centre: [f64; 2],
        radius: f64,
    },
    Spot {
        centre: [f64; 2],
        radius: f64,
    },
}

#[derive(Debug, Clone)]
struct Element {
    shape: Outline,
    /// What it adds to the amplitude beneath it: +1 transmits, −1 blocks,
    /// a spot's t − 1.
    weight: Amplitude,
    /// Its geometric area, mm².
    area: f64,
    /// What it adds to ∫|A|², mm².
    power: f64,
}

impl Element {
    /// Whether this element is `other` with its coordinates multiplied by
    /// `mirror` (one of them −1), to `tolerance` mm.
    fn is_mirror_of(&self, other: &Element, mirror: [f64; 2], tolerance: f64) -> bool {
        let near = |a: f64, b: f64| (a - b).abs() <= tolerance;
        let mirrored =
            |p: [f64; 2], q: [f64; 2]| near(p[0], q[0] * mirror[0]) && near(p[1], q[1] * mirror[1]);
        if self.weight != other.weight {
            return false;
        }
        match (&self.shape, &other.shape) {
            (Outline::Polygon { edges, .. }, Outline::Polygon { edges: theirs, .. }) => {
                // A mirror reverses the turn from edge to edge: a curved
                // piece's fan swaps its two sides.
                let same_fan = |a: Option<[f64; 2]>, b: Option<[f64; 2]>| match (a, b) {
                    (None, None) => true,
                    (Some(a), Some(b)) => near(a[0], b[1]) && near(a[1], b[0]),
                    _ => false,
                };
                edges.len() == theirs.len()
                    && theirs.iter().all(|t| {
                        edges.iter().any(|e| {
                            near(e.length, t.length)
                                && mirrored(e.middle, t.middle)
                                && (e.normal[0] - t.normal[0] * mirror[0]).abs() <= 1e-9
                                && (e.normal[1] - t.normal[1] * mirror[1]).abs() <= 1e-9
                                && same_fan(e.fan, t.fan)
                        })
                    })
            }
            (
                Outline::Disc { centre, radius },
                Outline::Disc {
                    centre: c,
                    radius: r,
                },
            )
            | (
                Outline::Spot { centre, radius },
                Outline::Spot {
                    centre: c,
                    radius: r,
                },
            ) => mirrored(*centre, *c) && near(*radius, *r),
            _ => false,
        }
    }
}

/// A pupil made of polygons and discs, lengths in mm.
#[derive(Debug, Clone, Default)]
pub struct Pupil {
    elements: Vec<Element>,
}

/// sin z / z, its series near 0.
pub(crate) fn sinc(z: f64) -> f64 {
    if z.abs() < 1e-8 {
        1.0 - z * z / 6.0
    } else {
        libm::sin(z) / z
    }
}

impl Pupil {
    /// An empty pupil (blocks everything).
    pub fn new() -> Pupil {
        Pupil::default()
    }

    /// Adds a polygon (vertices in mm, either orientation) that transmits,
    /// or, with `transmits = false`, blocks what lies beneath it.
    pub fn add_polygon(&mut self, vertices: &[[f64; 2]], transmits: bool) {
        self.add_sampled_polygon(vertices, transmits, 1);
    }

    /// Adds a polygon whose sides are smooth curves sampled by
    /// `pieces_per_side` straight pieces each: vertex 0 and every
    /// `pieces_per_side`-th one after it are corners, the others lie on a
    /// curve. The transform is the polygon's, exact; the far field treats
    /// the pieces as the curve they sample (see [`EdgeTerm::fan`]).
    pub fn add_sampled_polygon(
        &mut self,
        vertices: &[[f64; 2]],
        transmits: bool,
        pieces_per_side: usize,
    ) {
        let n = vertices.len();
        if n < 3 {
            return;
        }
        let mut corner: Vec<bool> = (0..n)
            .map(|k| pieces_per_side <= 1 || k % pieces_per_side == 0)
            .collect();
        let signed: f64 = (0..n)
            .map(|k| {
                let (a, b) = (vertices[k], vertices[(k + 1) % n]);
                a[0] * b[1] - b[0] * a[1]
            })
            .sum::<f64>()
            / 2.0;
        let made = (vertices.to_vec(), pieces_per_side);
        let mut points = vertices.to_vec();
        if signed < 0.0 {
            points.reverse();
            corner.reverse();
        }
        let area = signed.abs();
        let (mut cx, mut cy) = (0.0, 0.0);
        for p in &points {
            cx += p[0] / n as f64;
            cy += p[1] / n as f64;
        }
        let reach = points
            .iter()
            .map(|p| ((p[0] - cx).powi(2) + (p[1] - cy).powi(2)).sqrt())
            .fold(0.0, f64::max);
        let mut edges: Vec<Edge> = (0..n)
            .map(|k| {
                let (a, b) = (points[k], points[(k + 1) % n]);
                let delta = [b[0] - a[0], b[1] - a[1]];
                let length = (delta[0] * delta[0] + delta[1] * delta[1]).sqrt();
                Edge {
                    length,
                    // Counter-clockwise vertices: the outward normal is the
                    // edge direction turned clockwise.
                    normal: [delta[1] / length, -delta[0] / length],
                    middle: [(a[0] + b[0]) / 2.0, (a[1] + b[1]) / 2.0],
                    delta,
                    fan: None,
                }
            })
            .collect();
        if pieces_per_side > 1 {
            // The normal's turn at vertex k, from edge k − 1 to edge k.
            let turn = |k: usize| {
                let (p, q) = (edges[(k + n - 1) % n].normal, edges[k].normal);
                libm::atan2(p[0] * q[1] - p[1] * q[0], p[0] * q[0] + p[1] * q[1])
            };
            let fans: Vec<Option<[f64; 2]>> = (0..n)
                .map(|k| {
                    let end = (k + 1) % n;
                    // At a corner the curve stops: the piece next to it
                    // fans as far on that side as on its other one.
                    match (corner[k], corner[end]) {
                        (true, true) => None,
                        (false, false) => Some([turn(k) / 2.0, turn(end) / 2.0]),
                        (true, false) => Some([turn(end) / 2.0, turn(end) / 2.0]),
                        (false, true) => Some([turn(k) / 2.0, turn(k) / 2.0]),
                    }
                })
                .collect();
            for (edge, fan) in edges.iter_mut().zip(fans) {
                // A degenerate neighbour has no direction to turn from.
                edge.fan = fan.filter(|f| f.iter().all(|v| v.is_finite()));
            }
        }
        edges.retain(|e| e.length > 0.0);
        // The centroid's distance left of each edge's line.
        let inner = edges
            .iter()
            .map(|e| e.cross([cx, cy]) / e.length)
            .fold(f64::INFINITY, f64::min)
            .max(0.0);
        let sign = if transmits { 1.0 } else { -1.0 };
        self.elements.push(Element {
            shape: Outline::Polygon {
                edges,
                centroid: [cx, cy],
                reach,
                inner,
                made,
            },
            weight: [sign, 0.0],
            area,
            power: sign * area,
        });
    }

    /// Adds a disc that transmits, or blocks with `transmits = false`.
    pub fn add_disc(&mut self, centre: [f64; 2], radius: f64, transmits: bool) {
        let sign = if transmits { 1.0 } else { -1.0 };
        let area = PI * radius * radius;
        self.elements.push(Element {
            shape: Outline::Disc { centre, radius },
            weight: [sign, 0.0],
            area,
            power: sign * area,
        });
    }

    /// Adds a spot of dirt on clear glass (where the pupil transmits 1 and
    /// nothing else lies): a disc that transmits the complex amplitude
    /// `transmits` instead, 0 for dust, a·e^(iφ) for grease. Its whole
    /// pattern is added in the far field, where a small disc's is not yet
    /// the asymptotic one of a stop's rim.
    pub fn add_spot(&mut self, centre: [f64; 2], radius: f64, transmits: Amplitude) {
        let area = PI * radius * radius;
        let [re, im] = transmits;
        self.elements.push(Element {
            shape: Outline::Spot { centre, radius },
            weight: [re - 1.0, im],
            area,
            power: (re * re + im * im - 1.0) * area,
        });
    }

    /// ∫|A|² over the pupil, mm²: the transmitting area, opaque parts
    /// subtracted and spots counted by the power they pass.
    pub fn area(&self) -> f64 {
        self.elements.iter().map(|e| e.power).sum()
    }

    /// Whether it transmits real amplitudes only: then its pattern is
    /// centrosymmetric, |Â(−ν)| = |Â(ν)|.
    pub fn is_real(&self) -> bool {
        self.elements.iter().all(|e| e.weight[1] == 0.0)
    }

    /// Whether it is round: discs about the axis, transmitting real
    /// amplitudes. Then its pattern has the square's symmetries, mirrors
    /// across both axes and the diagonals.
    pub fn is_round(&self) -> bool {
        self.is_real()
            && self
                .elements
                .iter()
                .all(|e| matches!(e.shape, Outline::Disc { centre, .. } if centre == [0.0, 0.0]))
    }

    /// Whether it is its own mirror image across the x axis or across the
    /// y axis (a stop whose blade tip or blade side lies on an axis, vanes
    /// in pairs about it, spots mirrored). A real pupil's pattern is then
    /// mirrored across both axes: across the pupil's axis by the mirror,
    /// across the other by the mirror and the centrosymmetry together.
    /// Geometry that agrees to 10⁻⁹ of the pupil's reach counts as the same.
    pub fn is_mirror_symmetric(&self) -> bool {
        let reach = self
            .elements
            .iter()
            .map(|e| match &e.shape {
                Outline::Polygon {
                    centroid, reach, ..
                } => libm::hypot(centroid[0], centroid[1]) + reach,
                Outline::Disc { centre, radius } | Outline::Spot { centre, radius } => {
                    libm::hypot(centre[0], centre[1]) + radius
                }
            })
            .fold(0.0, f64::max);
        let tolerance = 1e-9 * reach.max(f64::MIN_POSITIVE);
        [[1.0, -1.0], [-1.0, 1.0]].into_iter().any(|mirror| {
            self.elements.iter().all(|e| {
                self.elements
                    .iter()
                    .any(|f| f.is_mirror_of(e, mirror, tolerance))
            })
        })
    }

    /// Â(ν) at spatial frequency ν (cycles/mm).
    pub fn amplitude(&self, nu: [f64; 2]) -> Amplitude {
        let q = [TAU * nu[0], TAU * nu[1]];
        let q2 = q[0] * q[0] + q[1] * q[1];
        let mut sum = [0.0, 0.0];
        for element in &self.elements {
            let a = match &element.shape {
                Outline::Disc { centre, radius } | Outline::Spot { centre, radius } => {
                    disc(element.area, *centre, *radius, q, q2)
                }
                Outline::Polygon {
                    edges,
                    centroid,
                    reach,
                    ..
                } => polygon(element.area, *centroid, *reach, q, q2, || {
                    let mut s = [0.0, 0.0];
                    for e in edges {
                        let weight = e.length
                            * (q[0] * e.normal[0] + q[1] * e.normal[1])
                            * sinc(0.5 * (q[0] * e.delta[0] + q[1] * e.delta[1]));
                        let (sin, cos) = libm::sincos(q[0] * e.middle[0] + q[1] * e.middle[1]);
                        s[0] += weight * cos;
                        s[1] -= weight * sin;
                    }
                    s
                }),
            };
            add_product(&mut sum, element.weight, a);
        }
        sum
    }

    /// What the far field is made of: every polygon edge as (length L mm,
    /// outward normal, unit direction along it), every disc and every
    /// spot. Far from the centre their patterns add incoherently.
    pub(crate) fn far_field_terms(&self) -> (Vec<EdgeTerm>, Vec<DiscTerm>, Vec<SpotTerm>) {
        let mut edges = Vec::new();
        let mut discs = Vec::new();
        let mut spots = Vec::new();
        for (polygon, element) in self.elements.iter().enumerate() {
            match &element.shape {
                Outline::Polygon { edges: list, .. } => {
                    for e in list {
                        edges.push(EdgeTerm {
                            length: e.length,
                            normal: e.normal,
                            along: [e.delta[0] / e.length, e.delta[1] / e.length],
                            middle: e.middle,
                            polygon,
                            sign: element.weight[0],
                            fan: e.fan,
                        });
                    }
                }
                Outline::Disc { centre, radius } => discs.push(DiscTerm {
                    centre: *centre,
                    radius: *radius,
                    sign: element.weight[0],
                }),
                Outline::Spot { radius, .. } => {
                    let [re, im] = element.weight;
                    spots.push(SpotTerm {
                        radius: *radius,
                        power: re * re + im * im,
                    });
                }
            }
        }
        (edges, discs, spots)
    }

    /// |Â(ν)|².
    pub fn intensity(&self, nu: [f64; 2]) -> f64 {
        let [re, im] = self.amplitude(nu);
        re * re + im * im
    }

    /// The offsets δ_k = (`dnu_x`[k], `dnu_y`[k]) (cycles/mm) of the
    /// samples of a pixel and their quadrature `weights`, with their share
    /// of every polygon edge's phases, for [`Pupil::intensity_sums`]:
    /// computed once, used for every pixel.
    pub fn offsets(&self, dnu_x: Vec<f64>, dnu_y: Vec<f64>, weights: Vec<f64>) -> Offsets {
        let phases = self
            .polygon_edges()
            .map(|e| {
                let mut parts: [Vec<f64>; 4] =
                    std::array::from_fn(|_| Vec::with_capacity(dnu_x.len()));
                for (&x, &y) in dnu_x.iter().zip(&dnu_y) {
                    let (phase, half) = edge_phases(e, TAU * x, TAU * y);
                    for (part, value) in
                        parts.iter_mut().zip([phase[0], phase[1], half[0], half[1]])
                    {
                        part.push(value);
                    }
                }
                parts
            })
            .collect();
        let reach = dnu_x
            .iter()
            .zip(&dnu_y)
            .map(|(x, y)| TAU * (x * x + y * y).sqrt())
            .fold(0.0, f64::max);
        let spots = self.spots(reach);
        // The small spots first, then the large ones ([`Pupil::add_spots`]).
        let spot_phases = spots
            .iter()
            .flatten()
            .map(|s| {
                dnu_x
                    .iter()
                    .zip(&dnu_y)
                    .map(|(&x, &y)| {
                        let [re, im] = phase(1.0, [TAU * x, TAU * y], s.centre);
                        (re, im)
                    })
                    .unzip()
            })
            .map(|(re, im): (Vec<f64>, Vec<f64>)| [re, im])
            .collect();
        Offsets {
            x: dnu_x,
            y: dnu_y,
            weights,
            phases,
            spot_phases,
            spots,
        }
    }

    /// The spots: those small enough for [`Pupil::add_spots`]'s Taylor
    /// series over offsets reaching `reach` (rad/mm), and the others.
    fn spots(&self, reach: f64) -> [Vec<SpotSum>; 2] {
        let (small, large) = self
            .elements
            .iter()
            .filter_map(|e| match e.shape {
                Outline::Spot { centre, radius } => Some(SpotSum {
                    weight: e.weight.map(|w| w * e.area),
                    centre,
                    radius,
                }),
                _ => None,
            })
            .partition(|s| s.radius * reach < jinc::TAYLOR_REACH);
        [small, large]
    }

    fn polygon_edges(&self) -> impl Iterator<Item = &Edge> {
        self.elements
            .iter()
            .flat_map(|element| match &element.shape {
                Outline::Polygon { edges, .. } => edges.as_slice(),
                Outline::Disc { .. } | Outline::Spot { .. } => &[],
            })
    }

    /// Σ_k w_k |Â(ν_i + δ_k)|² for every point ν_i = (`nu_x`[i], `nu_y`) of a
    /// row and the `offsets` δ_k shared by all of them (the samples of a
    /// pixel), into `out`[i]. The same values as [`Pupil::intensity`], at a
    /// fraction of the cost for polygons: their edge phases e^(−iq·m) and
    /// e^(iq·e/2) factor into a part of the point and a part of the offset,
    /// so that the sines of the inner loop become complex products.
    pub fn intensity_sums(&self, nu_x: &[f64], nu_y: f64, offsets: &Offsets, out: &mut [f64]) {
        self.intensity_moments(nu_x, nu_y, offsets, &[&offsets.weights], out);
    }

    /// Σ_k w_k |Â(ν_i + δ_k)|² for each set of weights w in `sets`, as
    /// [`Pupil::intensity_sums`]: `out`[i·S + s] for the point i and the
    /// set s of S. The transform is evaluated once for all the sets.
    pub fn intensity_moments(
        &self,
        nu_x: &[f64],
        nu_y: f64,
        offsets: &Offsets,
        sets: &[&[f64]],
        out: &mut [f64],
    ) {
        let (dnu_x, dnu_y) = (&offsets.x, &offsets.y);
        let (points, count) = (nu_x.len(), dnu_x.len());
        let mut total = vec![[0.0f64; 2]; points * count];
        // Every sample's q, point by point, for the discs, the edges' inner
        // loop and the polygons' sums.
        let (qx, qy): (Vec<f64>, Vec<f64>) = (0..points * count)
            .map(|at| {
                let (i, k) = (at / count, at % count);
                (TAU * (nu_x[i] + dnu_x[k]), TAU * (nu_y + dnu_y[k]))
            })
            .unzip();
        // The edge sums, real and imaginary parts apart so that the inner
        // loop runs in vector registers.
        let (mut sums_re, mut sums_im) = (vec![0.0; points * count], vec![0.0; points * count]);
        let mut edge_index = 0;
        self.add_spots(nu_x, nu_y, offsets, &qx, &qy, &mut total);
        for element in &self.elements {
            let (edges, centroid, reach) = match &element.shape {
                Outline::Polygon {
                    edges,
                    centroid,
                    reach,
                    ..
                } => (edges, *centroid, *reach),
                Outline::Spot { .. } => continue,
                Outline::Disc { centre, radius } => {
                    for (at, t) in total.iter_mut().enumerate() {
                        let q = [qx[at], qy[at]];
                        let q2 = q[0] * q[0] + q[1] * q[1];
                        let a = disc(element.area, *centre, *radius, q, q2);
                        add_product(t, element.weight, a);
                    }
                    continue;
                }
            };
            sums_re.iter_mut().for_each(|s| *s = 0.0);
            sums_im.iter_mut().for_each(|s| *s = 0.0);
            for e in edges {
                let by_offset = &offsets.phases[edge_index];
                edge_index += 1;
                crate::convolve::widest_sums(
                    #[inline(always)]
                    || {
                        add_edge(
                            e,
                            (nu_x, nu_y),
                            by_offset,
                            (&qx, &qy),
                            (&mut sums_re, &mut sums_im),
                        )
                    },
                );
            }
            let sums = sums_re.iter().zip(&sums_im);
            for (at, (t, (s_re, s_im))) in total.iter_mut().zip(sums).enumerate() {
                let q = [qx[at], qy[at]];
                let q2 = q[0] * q[0] + q[1] * q[1];
                let a = polygon(element.area, centroid, reach, q, q2, || [*s_re, *s_im]);
                add_product(t, element.weight, a);
            }
        }
        for (o, point) in out.chunks_mut(sets.len()).zip(total.chunks(count)) {
            for (o, weights) in o.iter_mut().zip(sets) {
                *o = point
                    .iter()
                    .zip(weights.iter())
                    .map(|([re, im], w)| w * (re * re + im * im))
                    .sum();
            }
        }
    }
}

impl Pupil {
    /// The spots' part of [`Pupil::intensity_sums`]'s amplitudes, added
    /// into `total`. Spots may be many: each sample sums them all at once,
    /// their phases factored like the edges'. A small spot's jinc(|q|R)
    /// turns little across a pixel: it is taken to second order in |q|
    /// about the pixel's centre, so that the inner loop is products and
    /// sums only; a larger one's is looked up at every sample.
    fn add_spots(
        &self,
        nu_x: &[f64],
        nu_y: f64,
        offsets: &Offsets,
        qx: &[f64],
        qy: &[f64],
        total: &mut [Amplitude],
    ) {
        let [small, large] = &offsets.spots;
        if small.is_empty() && large.is_empty() {
            return;
        }
        let table = jinc::table();
        let count = offsets.len();
        // Per small spot at the pixel's centre: its amplitude (re, im)
        // times jinc, times its first and times its second Taylor term.
        let mut terms = vec![[0.0; 6]; small.len()];
        let mut points = vec![[0.0; 2]; large.len()];
        let mut sample_q = vec![0.0; count];
        let mut sums = [vec![0.0; count], vec![0.0; count]];
        let mut magnitudes = vec![0.0; count];
        for (i, &x) in nu_x.iter().enumerate() {
            let nu = [TAU * x, TAU * nu_y];
            let centre_q = (nu[0] * nu[0] + nu[1] * nu[1]).sqrt();
            let row = i * count..(i + 1) * count;
            for ((q, &a), &b) in sample_q
                .iter_mut()
                .zip(&qx[row.clone()])
                .zip(&qy[row.clone()])
            {
                *q = (a * a + b * b).sqrt();
            }
            for (term, spot) in terms.iter_mut().zip(small) {
                let p = product(spot.weight, phase(1.0, nu, spot.centre));
                let r = spot.radius;
                let [value, first, second] = table.taylor(centre_q * r);
                let (d1, d2) = (first * r, 0.5 * second * r * r);
                *term = [
                    p[0] * value,
                    p[1] * value,
                    p[0] * d1,
                    p[1] * d1,
                    p[0] * d2,
                    p[1] * d2,
                ];
            }
            for (p, spot) in points.iter_mut().zip(large) {
                *p = product(spot.weight, phase(1.0, nu, spot.centre));
            }
            let (by_small, by_large) = offsets.spot_phases.split_at(small.len());
            crate::convolve::widest_sums(
                #[inline(always)]
                || add_small_spots(&terms, by_small, &sample_q, centre_q, &mut sums),
            );
            let [sums_re, sums_im] = &mut sums;
            for ((p, spot), [b_re, b_im]) in points.iter().zip(large).zip(by_large) {
                table.values(&sample_q, spot.radius, &mut magnitudes);
                for (k, magnitude) in magnitudes.iter().enumerate() {
                    sums_re[k] += magnitude * (p[0] * b_re[k] - p[1] * b_im[k]);
                    sums_im[k] += magnitude * (p[0] * b_im[k] + p[1] * b_re[k]);
                }
            }
            for ((t, re), im) in total[row].iter_mut().zip(&*sums_re).zip(&*sums_im) {
                t[0] += re;
                t[1] += im;
            }
        }
    }
}

/// The small spots' sums at every sample of a pixel (|q| = `sample_q`[k]),
/// from their Taylor `terms` about the pixel's centre (|q| = `centre_q`)
/// and their phases by offset, into `sums` (real and imaginary parts),
/// spot after spot: the inner loop of [`Pupil::add_spots`], four samples
/// at once with AVX2, the same bits.
#[inline(always)]
fn add_small_spots(
    terms: &[[f64; 6]],
    phases: &[[Vec<f64>; 2]],
    sample_q: &[f64],
    centre_q: f64,
    [sums_re, sums_im]: &mut [Vec<f64>; 2],
) {
    let n = sample_q.len();
    let (sums_re, sums_im) = (&mut sums_re[..n], &mut sums_im[..n]);
    sums_re.fill(0.0);
    sums_im.fill(0.0);
    for (term, [b_re, b_im]) in terms.iter().zip(phases) {
        let (b_re, b_im) = (&b_re[..n], &b_im[..n]);
        for k in 0..n {
            let dq = sample_q[k] - centre_q;
            let re = term[0] + dq * (term[2] + dq * term[4]);
            let im = term[1] + dq * (term[3] + dq * term[5]);
            sums_re[k] += re * b_re[k] - im * b_im[k];
            sums_im[k] += re * b_im[k] + im * b_re[k];
        }
    }
}

/// The sample offsets of a pixel and their share of each polygon edge's
/// phases ([`Pupil::offsets`]).
#[derive(Debug, Clone)]
pub struct Offsets {
    x: Vec<f64>,
    y: Vec<f64>,
    /// The quadrature weight of each offset.
    weights: Vec<f64>,
    /// Per polygon edge, [`edge_phases`] by part (the phase's real and
    /// imaginary parts, the half phase's), per offset: apart, so that
    /// the inner loop loads each in vectors.
    phases: Vec<[Vec<f64>; 4]>,
    /// Per spot, e^(−iδ·c) (c its centre) at every offset, its real and
    /// imaginary parts apart, so that the sums over a pixel's samples run
    /// in vectors.
    spot_phases: Vec<[Vec<f64>; 2]>,
    /// The spots, small and large ([`Pupil::spots`]), in the order of
    /// `spot_phases`.
    spots: [Vec<SpotSum>; 2],
}

/// A spot as the near field sums it.
#[derive(Debug, Clone)]
struct SpotSum {
    /// Its weight times its area: its amplitude at q = 0.
    weight: Amplitude,
    centre: [f64; 2],
    radius: f64,
}

impl Offsets {
    /// How many offsets.
    pub fn len(&self) -> usize {
        self.x.len()
    }

    /// Whether there are none.
    pub fn is_empty(&self) -> bool {
        self.x.is_empty()
    }

    /// The quadrature weight of each offset.
    pub fn weights(&self) -> &[f64] {
        &self.weights
    }
}

/// e^(−iq·m) and e^(iq·e/2) of an edge (middle m, vector e) at q, as
/// (re, im) pairs.
type EdgePhases = ([f64; 2], [f64; 2]);

/// Adds edge `e`'s terms to the sums of every point (`nu_x`[i], `nu_y`)
/// and its samples, whose q are (`qx`, `qy`), the points' side by side:
/// the inner loop of [`Pupil::intensity_moments`], inlined where the CPU's
/// widest vectors take it (four samples at once with AVX2, the same bits).
#[inline(always)]
fn add_edge(
    e: &Edge,
    (nu_x, nu_y): (&[f64], f64),
    [phase_re, phase_im, half_cos, half_sin]: &[Vec<f64>; 4],
    (qx, qy): (&[f64], &[f64]),
    (sums_re, sums_im): (&mut [f64], &mut [f64]),
) {
    let n = phase_re.len();
    if n == 0 {
        return;
    }
    let (phase_im, half_cos, half_sin) = (&phase_im[..n], &half_cos[..n], &half_sin[..n]);
    let points = qx
        .chunks_exact(n)
        .zip(qy.chunks_exact(n))
        .zip(sums_re.chunks_exact_mut(n).zip(sums_im.chunks_exact_mut(n)));
    for (&x, ((qx, qy), (sums_re, sums_im))) in nu_x.iter().zip(points) {
        let (phase_i, half_i) = edge_phases(e, TAU * x, TAU * nu_y);
        for k in 0..n {
            let q = [qx[k], qy[k]];
            let z = 0.5 * (q[0] * e.delta[0] + q[1] * e.delta[1]);
            let sin_z = half_i[0] * half_sin[k] + half_i[1] * half_cos[k];
            // Both sides computed and one chosen, without a branch, so
            // that the loop takes vectors.
            let small = z.abs() < 1e-8;
            let ratio = sin_z / if small { 1.0 } else { z };
            let sinc = if small { 1.0 - z * z / 6.0 } else { ratio };
            let weight = e.length * (q[0] * e.normal[0] + q[1] * e.normal[1]) * sinc;
            sums_re[k] += weight * (phase_i[0] * phase_re[k] - phase_i[1] * phase_im[k]);
            sums_im[k] += weight * (phase_i[0] * phase_im[k] + phase_i[1] * phase_re[k]);
        }
    }
}

fn edge_phases(e: &Edge, qx: f64, qy: f64) -> EdgePhases {
    let (m, d) = (
        qx * e.middle[0] + qy * e.middle[1],
        0.5 * (qx * e.delta[0] + qy * e.delta[1]),
    );
    let ((sm, cm), (sd, cd)) = (crate::math::sin_cos_wide(m), crate::math::sin_cos_wide(d));
    ([cm, -sm], [cd, sd])
}

/// Â of a disc of `radius` at `centre` (its `area`), at q, |q|² = `q2`.
fn disc(area: f64, centre: [f64; 2], radius: f64, q: [f64; 2], q2: f64) -> Amplitude {
    let x = q2.sqrt() * radius;
    let magnitude = if x < 1e-6 {
        area
    } else {
        TAU * radius * radius * crate::math::j1(x) / x
    };
    phase(magnitude, q, centre)
}

/// Â of a polygon (its `area`, `centroid`, `reach`) at q, |q|² = `q2`,
/// from its edge sum s = Σ L (q·n̂) e^(−iq·m) sinc(q·e/2): i·s/|q|², or
/// near q = 0, where the edge sum cancels to round-off, the area at the
/// centroid.
fn polygon(
    area: f64,
    centroid: [f64; 2],
    reach: f64,
    q: [f64; 2],
    q2: f64,
    edge_sum: impl FnOnce() -> [f64; 2],
) -> Amplitude {
    if q2.sqrt() * reach < 1e-4 {
        phase(area, q, centroid)
    } else {
        let s = edge_sum();
        [-s[1] / q2, s[0] / q2]
    }
}

/// w·a, complex.
fn product(w: Amplitude, a: Amplitude) -> Amplitude {
    [w[0] * a[0] - w[1] * a[1], w[0] * a[1] + w[1] * a[0]]
}

/// sum += w·a, complex.
fn add_product(sum: &mut Amplitude, w: Amplitude, a: Amplitude) {
    let [re, im] = product(w, a);
    sum[0] += re;
    sum[1] += im;
}

/// magnitude · e^(−i q·c).
fn phase(magnitude: f64, q: [f64; 2], c: [f64; 2]) -> Amplitude {
    let (sin, cos) = libm::sincos(q[0] * c[0] + q[1] * c[1]);
    [magnitude * cos, -magnitude * sin]
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A regular polygon of `n` vertices on a circle of 3 mm, the first at
    /// `start` rad.
    fn regular(n: usize, start: f64) -> Vec<[f64; 2]> {
        (0..n)
            .map(|k| {
                let a = start + TAU * k as f64 / n as f64;
                [3.0 * libm::cos(a), 3.0 * libm::sin(a)]
            })
            .collect()
    }

    #[test]
    fn a_pupil_is_mirror_symmetric_when_every_element_has_its_mirror_image() {
        let with = |build: &dyn Fn(&mut Pupil)| {
            let mut pupil = Pupil::new();
            build(&mut pupil);
            pupil.is_mirror_symmetric()
        };
        // A tip on +x (across the x axis), a tip on +y (across the y axis).
        assert!(with(&|p| p.add_polygon(&regular(7, 0.0), true)));
        assert!(with(&|p| p.add_polygon(&regular(6, PI / 6.0), true)));
        assert!(with(&|p| p.add_sampled_polygon(&regular(28, 0.0), true, 4)));
        assert!(!with(&|p| p.add_polygon(&regular(7, 0.1), true)));
        assert!(!with(&|p| p.add_polygon(&regular(7, 1e-8), true)));
        // A spot off the axes breaks the symmetry; its mirror image restores it.
        let spot = |p: &mut Pupil| {
            p.add_disc([0.0, 0.0], 3.0, true);
            p.add_spot([1.0, 0.5], 0.1, [0.0, 0.0]);
        };
        assert!(!with(&spot));
        assert!(with(&|p| {
            spot(p);
            p.add_spot([1.0, -0.5], 0.1, [0.0, 0.0]);
        }));
        // A vane on one side only, and a pair about the x axis.
        let vane = |y: f64| vec![[0.5, y], [3.0, y], [3.0, y + 0.1], [0.5, y + 0.1]];
        assert!(!with(&|p| {
            p.add_disc([0.0, 0.0], 3.0, true);
            p.add_polygon(&vane(0.3), false);
        }));
        assert!(with(&|p| {
            p.add_disc([0.0, 0.0], 3.0, true);
            p.add_polygon(&vane(0.3), false);
            p.add_polygon(&vane(-0.4), false);
        }));
    }

    /// Â by brute-force summation over a fine grid, for comparison.
    fn numeric(pupil_inside: impl Fn(f64, f64) -> bool, half: f64, nu: [f64; 2]) -> Amplitude {
        let n = 800;
        let h = 2.0 * half / n as f64;
        let mut s = [0.0, 0.0];
        for i in 0..n {
            for j in 0..n {
                let (x, y) = (-half + (i as f64 + 0.5) * h, -half + (j as f64 + 0.5) * h);
                if pupil_inside(x, y) {
                    let p = -TAU * (nu[0] * x + nu[1] * y);
                    s[0] += libm::cos(p) * h * h;
                    s[1] += libm::sin(p) * h * h;
                }
            }
        }
        s
    }

    #[test]
    fn polygon_transform_matches_direct_integration() {
        // A triangle off the origin, both orientations.
        let triangle = [[0.1, -0.2], [0.8, 0.1], [-0.3, 0.6]];
        let inside = |x: f64, y: f64| {
            let sign =
                |a: [f64; 2], b: [f64; 2]| (b[0] - a[0]) * (y - a[1]) - (b[1] - a[1]) * (x - a[0]);
            let (d1, d2, d3) = (
                sign(triangle[0], triangle[1]),
                sign(triangle[1], triangle[2]),
                sign(triangle[2], triangle[0]),
            );
            (d1 >= 0.0 && d2 >= 0.0 && d3 >= 0.0) || (d1 <= 0.0 && d2 <= 0.0 && d3 <= 0.0)
        };
        for reversed in [false, true] {
            let mut pupil = Pupil::new();
            let mut v = triangle.to_vec();
            if reversed {
                v.reverse();
            }
            pupil.add_polygon(&v, true);
            for nu in [[0.0, 0.0], [0.3, -0.7], [1.9, 0.4], [-2.5, -1.1]] {
                let (a, b) = (pupil.amplitude(nu), numeric(inside, 1.0, nu));
                assert!(
                    (a[0] - b[0]).abs() < 2e-3 && (a[1] - b[1]).abs() < 2e-3,
                    "{nu:?}: {a:?} vs {b:?}"
                );
            }
        }
    }

    #[test]
    fn disc_transform_matches_direct_integration_and_opaque_parts_subtract() {
        let mut pupil = Pupil::new();
        pupil.add_disc([0.1, 0.0], 0.6, true);
        pupil.add_disc([0.1, 0.0], 0.2, false);
        let inside = |x: f64, y: f64| {
            let r2 = (x - 0.1).powi(2) + y * y;
            r2 <= 0.36 && r2 > 0.04
        };
        assert!((pupil.area() - PI * (0.36 - 0.04)).abs() < 1e-12);
        for nu in [[0.0, 0.0], [0.5, 0.2], [-1.3, 2.0]] {
            let (a, b) = (pupil.amplitude(nu), numeric(inside, 1.0, nu));
            assert!(
                (a[0] - b[0]).abs() < 3e-3 && (a[1] - b[1]).abs() < 3e-3,
                "{nu:?}: {a:?} vs {b:?}"
            );
        }
    }

    #[test]
    fn a_spot_transmits_its_amplitude_and_adds_its_disc_times_t_minus_one() {
        let mut pupil = Pupil::new();
        pupil.add_disc([0.0, 0.0], 1.0, true);
        let t = [0.6, 0.5];
        pupil.add_spot([0.3, -0.2], 0.25, t);
        let inside = pupil.transmission([0.3, -0.1]);
        assert!((inside[0] - t[0]).abs() < 1e-15 && (inside[1] - t[1]).abs() < 1e-15);
        assert_eq!(pupil.transmission([-0.5, 0.0]), [1.0, 0.0]);
        assert_eq!(pupil.transmission([1.5, 0.0]), [0.0, 0.0]);
        // ∫|A|²: the clear glass and the spot's |t|² of its area.
        let spot = PI * 0.25 * 0.25;
        let power = PI - spot + (t[0] * t[0] + t[1] * t[1]) * spot;
        assert!((pupil.area() - power).abs() < 1e-12);
        // Â by direct summation over a grid, with the spot's amplitude.
        for nu in [[0.0, 0.0], [0.4, -0.9], [1.7, 0.6]] {
            let n = 800;
            let h = 2.4 / n as f64;
            let mut sum = [0.0, 0.0];
            for i in 0..n {
                for j in 0..n {
                    let (x, y) = (-1.2 + (i as f64 + 0.5) * h, -1.2 + (j as f64 + 0.5) * h);
                    let a = pupil.transmission([x, y]);
                    let (sin, cos) = libm::sincos(-TAU * (nu[0] * x + nu[1] * y));
                    sum[0] += (a[0] * cos - a[1] * sin) * h * h;
                    sum[1] += (a[0] * sin + a[1] * cos) * h * h;
                }
            }
            let a = pupil.amplitude(nu);
            assert!(
                (a[0] - sum[0]).abs() < 3e-3 && (a[1] - sum[1]).abs() < 3e-3,
                "{nu:?}: {a:?} vs {sum:?}"
            );
        }
    }

    #[test]
    fn the_sums_over_a_pixel_are_those_of_the_exact_transform_with_many_spots() {
        // A stop of 3 mm radius with specks from 10 to 150 µm and a smudge:
        // the specks take the Taylor series, the smudge the table.
        let mut pupil = Pupil::new();
        let stop: Vec<[f64; 2]> = (0..7)
            .map(|k| {
                let a = TAU * k as f64 / 7.0;
                [3.0 * libm::cos(a), 3.0 * libm::sin(a)]
            })
            .collect();
        pupil.add_polygon(&stop, true);
        pupil.add_spot([0.8, 0.9], 0.9, [0.7, 0.4]);
        for k in 0..40 {
            let (a, r) = (k as f64 * 2.4, 0.3 + 0.05 * k as f64);
            let radius = 0.005 + 0.07 * ((k * 7) % 40) as f64 / 40.0;
            pupil.add_spot(
                [r * libm::cos(a) - 0.5, r * libm::sin(a) - 0.5],
                radius,
                [0.0, 0.0],
            );
        }
        // A 10 µm pixel at λf = 0.0275 mm: 7×7 Gauss-like offsets.
        let scale = 1.0 / 0.0275;
        let nodes: Vec<f64> = (0..7)
            .map(|i| (i as f64 - 3.0) / 3.0 * 0.005 * scale)
            .collect();
        let (mut dx, mut dy, mut w) = (Vec::new(), Vec::new(), Vec::new());
        for &a in &nodes {
            for &b in &nodes {
                dx.push(b);
                dy.push(a);
                w.push(1.0 / 49.0);
            }
        }
        let offsets = pupil.offsets(dx.clone(), dy.clone(), w.clone());
        let [small, large] = &offsets.spots;
        assert_eq!((small.len(), large.len()), (40, 1));
        let nu_x: Vec<f64> = (0..24).map(|i| (i as f64 * 0.013 - 0.1) * scale).collect();
        for nu_y in [0.0, 0.031 * scale, 0.2 * scale] {
            let mut fast = vec![0.0; nu_x.len()];
            pupil.intensity_sums(&nu_x, nu_y, &offsets, &mut fast);
            for (x, fast) in nu_x.iter().zip(fast) {
                let exact: f64 = (0..w.len())
                    .map(|k| w[k] * pupil.intensity([x + dx[k], nu_y + dy[k]]))
                    .sum();
                assert!(
                    (fast - exact).abs() <= 1e-5 * exact + 1e-9 * pupil.area().powi(2),
                    "({x}, {nu_y}): {fast} vs {exact}"
                );
            }
        }
    }
}
