//! The pupil and its Fourier transform, in closed form (docs/physics.md §6).
//!
//! A pupil is a sum of transmitting and opaque polygons and discs, in mm.
//! Its transform Â(ν) = ∫ A(s) e^(−2πi ν·s) ds is exact at any spatial
//! frequency ν (cycles/mm): for a polygon, by the divergence theorem,
//! Â = (i/|q|²) Σ_edges L (q·n̂) e^(−iq·m) sinc(q·e/2) with q = 2πν; for a
//! disc of radius R, 2πR² J₁(qR)/(qR). No sampling grid, so no aliasing.

use std::f64::consts::{PI, TAU};

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

#[derive(Debug, Clone)]
enum Outline {
    Polygon {
        edges: Vec<Edge>,
        centroid: [f64; 2],
        reach: f64,
    },
    Disc {
        centre: [f64; 2],
        radius: f64,
    },
}

#[derive(Debug, Clone)]
struct Element {
    shape: Outline,
    /// +1 transmits, −1 blocks (subtracted from what lies beneath).
    sign: f64,
    area: f64,
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
                (p[0] * q[1] - p[1] * q[0]).atan2(p[0] * q[0] + p[1] * q[1])
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
        self.elements.push(Element {
            shape: Outline::Polygon {
                edges,
                centroid: [cx, cy],
                reach,
            },
            sign: if transmits { 1.0 } else { -1.0 },
            area,
        });
    }

    /// Adds a disc that transmits, or blocks with `transmits = false`.
    pub fn add_disc(&mut self, centre: [f64; 2], radius: f64, transmits: bool) {
        self.elements.push(Element {
            shape: Outline::Disc { centre, radius },
            sign: if transmits { 1.0 } else { -1.0 },
            area: PI * radius * radius,
        });
    }

    /// The transmitting area, mm² (opaque parts subtracted).
    pub fn area(&self) -> f64 {
        self.elements.iter().map(|e| e.sign * e.area).sum()
    }

    /// Â(ν) at spatial frequency ν (cycles/mm).
    pub fn amplitude(&self, nu: [f64; 2]) -> Amplitude {
        let q = [TAU * nu[0], TAU * nu[1]];
        let q2 = q[0] * q[0] + q[1] * q[1];
        let mut sum = [0.0, 0.0];
        for element in &self.elements {
            let a = match &element.shape {
                Outline::Disc { centre, radius } => disc(element.area, *centre, *radius, q, q2),
                Outline::Polygon {
                    edges,
                    centroid,
                    reach,
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
            sum[0] += element.sign * a[0];
            sum[1] += element.sign * a[1];
        }
        sum
    }

    /// What the far field is made of: every polygon edge as (length L mm,
    /// outward normal, unit direction along it), and every disc.
    /// Far from the centre the edges' and discs' patterns add incoherently.
    pub(crate) fn far_field_terms(&self) -> (Vec<EdgeTerm>, Vec<DiscTerm>) {
        let mut edges = Vec::new();
        let mut discs = Vec::new();
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
                            sign: element.sign,
                            fan: e.fan,
                        });
                    }
                }
                Outline::Disc { centre, radius } => discs.push(DiscTerm {
                    centre: *centre,
                    radius: *radius,
                    sign: element.sign,
                }),
            }
        }
        (edges, discs)
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
                dnu_x
                    .iter()
                    .zip(&dnu_y)
                    .map(|(&x, &y)| edge_phases(e, TAU * x, TAU * y))
                    .collect()
            })
            .collect();
        Offsets {
            x: dnu_x,
            y: dnu_y,
            weights,
            phases,
        }
    }

    fn polygon_edges(&self) -> impl Iterator<Item = &Edge> {
        self.elements
            .iter()
            .flat_map(|element| match &element.shape {
                Outline::Polygon { edges, .. } => edges.as_slice(),
                Outline::Disc { .. } => &[],
            })
    }

    /// Σ_k w_k |Â(ν_i + δ_k)|² for every point ν_i = (`nu_x`[i], `nu_y`) of a
    /// row and the `offsets` δ_k shared by all of them (the samples of a
    /// pixel), into `out`[i]. The same values as [`Pupil::intensity`], at a
    /// fraction of the cost for polygons: their edge phases e^(−iq·m) and
    /// e^(iq·e/2) factor into a part of the point and a part of the offset,
    /// so that the sines of the inner loop become complex products.
    pub fn intensity_sums(&self, nu_x: &[f64], nu_y: f64, offsets: &Offsets, out: &mut [f64]) {
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
        for element in &self.elements {
            let (edges, centroid, reach) = match &element.shape {
                Outline::Polygon {
                    edges,
                    centroid,
                    reach,
                } => (edges, *centroid, *reach),
                Outline::Disc { centre, radius } => {
                    for (at, t) in total.iter_mut().enumerate() {
                        let q = [qx[at], qy[at]];
                        let q2 = q[0] * q[0] + q[1] * q[1];
                        let a = disc(element.area, *centre, *radius, q, q2);
                        t[0] += element.sign * a[0];
                        t[1] += element.sign * a[1];
                    }
                    continue;
                }
            };
            sums_re.iter_mut().for_each(|s| *s = 0.0);
            sums_im.iter_mut().for_each(|s| *s = 0.0);
            for e in edges {
                let by_offset = &offsets.phases[edge_index];
                edge_index += 1;
                for (i, &x) in nu_x.iter().enumerate() {
                    let (phase_i, half_i) = edge_phases(e, TAU * x, TAU * nu_y);
                    let row = i * count..(i + 1) * count;
                    let terms = by_offset
                        .iter()
                        .zip(&qx[row.clone()])
                        .zip(&qy[row.clone()])
                        .zip(&mut sums_re[row.clone()])
                        .zip(&mut sums_im[row]);
                    for (((((phase_k, half_k), &q0), &q1), re), im) in terms {
                        let q = [q0, q1];
                        let z = 0.5 * (q[0] * e.delta[0] + q[1] * e.delta[1]);
                        let sin_z = half_i[0] * half_k[1] + half_i[1] * half_k[0];
                        let sinc = if z.abs() < 1e-8 {
                            1.0 - z * z / 6.0
                        } else {
                            sin_z / z
                        };
                        let weight = e.length * (q[0] * e.normal[0] + q[1] * e.normal[1]) * sinc;
                        *re += weight * (phase_i[0] * phase_k[0] - phase_i[1] * phase_k[1]);
                        *im += weight * (phase_i[0] * phase_k[1] + phase_i[1] * phase_k[0]);
                    }
                }
            }
            let sums = sums_re.iter().zip(&sums_im);
            for (at, (t, (s_re, s_im))) in total.iter_mut().zip(sums).enumerate() {
                let q = [qx[at], qy[at]];
                let q2 = q[0] * q[0] + q[1] * q[1];
                let a = polygon(element.area, centroid, reach, q, q2, || [*s_re, *s_im]);
                t[0] += element.sign * a[0];
                t[1] += element.sign * a[1];
            }
        }
        for (o, point) in out.iter_mut().zip(total.chunks(count)) {
            *o = point
                .iter()
                .zip(&offsets.weights)
                .map(|([re, im], w)| w * (re * re + im * im))
                .sum();
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
    /// Per polygon edge, per offset, [`edge_phases`].
    phases: Vec<Vec<EdgePhases>>,
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
}

/// e^(−iq·m) and e^(iq·e/2) of an edge (middle m, vector e) at q, as
/// (re, im) pairs.
type EdgePhases = ([f64; 2], [f64; 2]);

fn edge_phases(e: &Edge, qx: f64, qy: f64) -> EdgePhases {
    let (m, d) = (
        qx * e.middle[0] + qy * e.middle[1],
        0.5 * (qx * e.delta[0] + qy * e.delta[1]),
    );
    let ((sm, cm), (sd, cd)) = (libm::sincos(m), libm::sincos(d));
    ([cm, -sm], [cd, sd])
}

/// Â of a disc of `radius` at `centre` (its `area`), at q, |q|² = `q2`.
fn disc(area: f64, centre: [f64; 2], radius: f64, q: [f64; 2], q2: f64) -> Amplitude {
    let x = q2.sqrt() * radius;
    let magnitude = if x < 1e-6 {
        area
    } else {
        TAU * radius * radius * libm::j1(x) / x
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

/// magnitude · e^(−i q·c).
fn phase(magnitude: f64, q: [f64; 2], c: [f64; 2]) -> Amplitude {
    let (sin, cos) = libm::sincos(q[0] * c[0] + q[1] * c[1]);
    [magnitude * cos, -magnitude * sin]
}

#[cfg(test)]
mod tests {
    use super::*;

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
                    s[0] += p.cos() * h * h;
                    s[1] += p.sin() * h * h;
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
}
