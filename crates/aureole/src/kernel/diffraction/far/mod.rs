//! The far field of a diffraction pattern: beyond ~60 λN the cross terms
//! of edges whose rays differ fall below B·λN/r, and the pattern is the
//! sum of each edge's |F_k|² = L²(x·n)² sinc²(πu/λ) / (4π²|x|⁴·area), u
//! the offset across the edge's ray times L/f, averaged over the square
//! pixel exactly, with the cross terms of parallel edges, which share a
//! ray; each disc adds its ⟨J₁²⟩ term R λ f / (2π²|x|³·area) with its
//! fringes and their beats with concentric discs and with the edges that
//! end on its rim, and each piece of a curved side fans its light over the
//! turn of its normal, and each spot of dirt adds its whole pattern
//! (docs/physics.md §6).
//!
//! The edges and the pairs of parallel edges are summed here, the rims in
//! [`rims`], the curved sides in [`fans`], the spots in [`spots`].

mod fans;
mod means;
mod rims;
mod spots;

use fans::Fans;
use means::{Cumulative, Received};
use rims::{FringeRow, Fringes};
use spots::Spots;

use super::Spectrum;
use crate::kernel::Sending;
use crate::optics::aperture::pupil::{sinc, EdgeTerm};
use crate::optics::aperture::Optics;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};
use std::sync::Arc;

/// How far across its ray, in units of the longest wavelength's u, a pair
/// of parallel edges is summed line by line in spectral light: beyond it
/// the edge's own light is below 2·10⁻⁴ of its ray's and the cross term,
/// at most twice that, is left out.
const PAIR_REACH: f64 = 16.0;

/// How far across its ray, in wavelengths of u, a pair's cross term is
/// averaged over the square pixel exactly; beyond, the pixel's means of
/// the sinc² and of the cosine are multiplied, exact for rays along a
/// pixel axis, and the light there is below 1/(16π²) of the ray's.
const PAIR_CORE: f64 = 4.0;

/// The share of a kernel's light below which a pixel's disc fringes are
/// left out: beyond the radius where they could reach it they hold at
/// most 2π·10⁻¹⁰·r/p of the light in all, below the round-off of the f32
/// transforms that convolve with the kernel (docs/physics.md §6).
const FRINGE_FLOOR: f64 = 1e-10;

/// The far field: incoherent sums over edges, curved sides and discs, with
/// the cross terms of parallel edge pairs.
pub(super) struct FarField {
    edges: Vec<Edge>,
    /// Pieces of curved sides: the light they fan out, by direction.
    fans: Fans,
    /// Twice the discs' radii summed: each adds R λ f / (2π²|x|³·area).
    discs: f64,
    /// The discs' fringes about that mean.
    fringes: Fringes,
    /// Spots of dirt.
    spots: Spots,
    /// The planes' spectrum-averaged ∫₀ᵘ sinc²(πu'/λ) du' and its integral.
    table: Cumulative,
    /// Each wavelength of the light, for the pairs' cross terms, which are
    /// summed line by line near their ray.
    lines: Vec<Line>,
    /// Per plane: the sensitivity-weighted mean wavelength, mm.
    mean_lambda: Vec<f64>,
    /// The longest wavelength, mm.
    longest: f64,
    area: f64,
    focal: f64,
    /// What sends the light: a pixel's tent widens a ray across itself.
    sending: Sending,
}

/// One wavelength: λ in mm, its share of each plane's weight, and its own
/// ∫ sinc² (in monochromatic light, the plane's table).
struct Line {
    lambda: f64,
    shares: Vec<f64>,
    table: Option<Cumulative>,
}

impl Line {
    /// `amplitude` times the line's share of each plane.
    fn weights(&self, amplitude: f64) -> [f64; PLANES] {
        let mut weights = [0.0; PLANES];
        for (w, share) in weights.iter_mut().zip(&self.shares) {
            *w = amplitude * share;
        }
        weights
    }
}

/// A straight edge: L², its normal, its unit direction, L/f.
struct Edge {
    l2: f64,
    normal: [f64; 2],
    along: [f64; 2],
    l_over_f: f64,
    /// The pixel means of its light across its ray, tabulated (shared
    /// with the edges whose pixels project alike).
    received: Arc<Received>,
    /// Where its pairs are summed line by line: each line's own means
    /// near the ray, tabulated.
    line_means: Arc<Vec<Received>>,
    /// The equal, parallel edges after it, whose rays coincide with its
    /// own and interfere with it.
    pairs: Vec<Pair>,
}

/// The tables of means that edges whose pixels project alike share.
struct Tables {
    received: Arc<Received>,
    line_means: Arc<Vec<Received>>,
}

/// Two equal, parallel straight edges as the first of them sees it.
struct Pair {
    /// σ = s₁ s₂ (n̂₁·n̂₂): their fields along the common ray are F and
    /// σ F e^(iq·d), the signs those of the polygons they bound.
    sign: f64,
    /// The separation d of their midpoints over f: the phase at x is
    /// 2π x·d/(λf).
    d_over_f: [f64; 2],
    /// The other edge's length over this one's, r ≤ 1: their fields' sincs
    /// across the ray are sinc(πu/λ) and sinc(πur/λ).
    ratio: f64,
    /// Per line, the mean of e^(i2πx·d/(λf)) over a pixel centred at 0:
    /// the product of the sincs of its two sides.
    pixel: Vec<f64>,
    /// Per line, the quadrature of the cross term's exact pixel mean in
    /// the ray's core (see [`FarField::add_cross`]): (frequency across the
    /// ray, cycles/mm; weight) per node.
    nodes: Vec<Vec<(f64, f64)>>,
}

/// Scratch space for one row of far-field pixels.
#[derive(Default)]
pub(super) struct Row {
    /// Per pixel, the edges' tails without their plane's ⟨λ²⟩/(2π²).
    tails: Vec<f64>,
    /// Per pixel and plane, side by side, the rest.
    sums: Vec<f64>,
    /// Per pixel, a cosine along the row.
    cosines: Vec<f64>,
    /// Per pixel, a pair's cross term in one line, and one node's part.
    cross: Vec<f64>,
    waves: Vec<f64>,
    /// Per pixel within the edge's table, its first plane's mean, which a
    /// pair in one wavelength uses again.
    means: Vec<f64>,
    fringes: FringeRow,
}

/// The most planes a table holds.
const PLANES: usize = 3;

impl FarField {
    /// The far field of `optics` in `spectrum`, at `pitch` mm per pixel
    /// out to `reach` mm from the centre.
    pub fn new(
        optics: &Optics,
        spectrum: &Spectrum,
        weights_total: &[f64],
        (pitch, sending): (f64, Sending),
        reach: f64,
    ) -> FarField {
        let (edges, discs, spots) = optics.pupil.far_field_terms();
        let f = optics.focal_mm;
        let planes = weights_total.len();
        let light = |c: usize| -> Vec<(f64, f64)> {
            spectrum.iter().map(|(l, w)| (l * 1e-6, w[c])).collect()
        };
        let (curved, straight): (Vec<EdgeTerm>, Vec<EdgeTerm>) =
            edges.into_iter().partition(|e| e.fan.is_some());
        let found = parallel_pairs(&straight, optics.diameter_mm);
        // Each line's own table serves only the pairs in many wavelengths.
        let lined = spectrum.len() > 1 && !found.is_empty();
        let lines: Vec<Line> = spectrum
            .iter()
            .map(|(l, w)| Line {
                lambda: l * 1e-6,
                shares: w.iter().zip(weights_total).map(|(w, t)| w / t).collect(),
                table: lined.then(|| Cumulative::new(&[vec![(l * 1e-6, 1.0)]])),
            })
            .collect();
        let mut pairs: Vec<Vec<Pair>> = straight.iter().map(|_| Vec::new()).collect();
        for (first, d, sign, ratio) in found {
            let edge = &straight[first];
            pairs[first].push(Pair {
                sign,
                d_over_f: [d[0] / f, d[1] / f],
                ratio,
                pixel: lines
                    .iter()
                    .map(|line| {
                        pixel_mean(pitch, sending, [d[0], d[1]].map(|v| v / (line.lambda * f)))
                    })
                    .collect(),
                nodes: lines
                    .iter()
                    .map(|line| core_nodes(edge, d, ratio, line.lambda, f, (pitch, sending)))
                    .collect(),
            });
        }
        let area = optics.pupil.area();
        let fringes = Fringes::new(&discs, &straight, &lines, f, pitch, sending, area);
        let table = Cumulative::new(&(0..planes).map(light).collect::<Vec<_>>());
        let longest = lines.iter().map(|l| l.lambda).fold(0.0, f64::max);
        // Edges whose pixels project alike across their rays (parallel
        // edges, mirror images, a square's sides) have the same tables of
        // means: each is built once.
        let keys: Vec<[f64; 3]> = straight
            .iter()
            .map(|e| {
                let k = e.length / f;
                let (beta, gamma) = projections(e.along, k, pitch);
                [beta, gamma, reach * k]
            })
            .collect();
        let alike = |a: &[f64; 3], b: &[f64; 3]| {
            a.iter()
                .zip(b)
                .all(|(a, b)| (a - b).abs() <= 1e-12 * a.abs().max(b.abs()))
        };
        // Each edge's set of alike edges, numbered in order of first edge.
        let mut firsts: Vec<usize> = Vec::new();
        let set: Vec<usize> = (0..keys.len())
            .map(|i| {
                firsts
                    .iter()
                    .position(|&j| alike(&keys[j], &keys[i]))
                    .unwrap_or_else(|| {
                        firsts.push(i);
                        firsts.len() - 1
                    })
            })
            .collect();
        let near = PAIR_REACH * longest;
        let tables: Vec<Tables> = firsts
            .par_iter()
            .enumerate()
            .map(|(n, &i)| {
                let [beta, gamma, within] = keys[i];
                let received = Received::new(&table, (beta, gamma), sending, (table.end, within));
                // Each line's own means, where an edge of the set has pairs.
                let paired = (0..keys.len()).any(|j| set[j] == n && !pairs[j].is_empty());
                let line_means = if paired {
                    lines
                        .iter()
                        .filter_map(|line| line.table.as_ref())
                        .map(|own| Received::new(own, (beta, gamma), sending, (near, within)))
                        .collect()
                } else {
                    Vec::new()
                };
                Tables {
                    received: Arc::new(received),
                    line_means: Arc::new(line_means),
                }
            })
            .collect();
        let no_means = Arc::new(Vec::new());
        let edges = straight
            .into_iter()
            .zip(pairs)
            .zip(set)
            .map(|((e, pairs), n)| Edge {
                l2: e.length * e.length,
                normal: e.normal,
                along: e.along,
                l_over_f: e.length / f,
                received: Arc::clone(&tables[n].received),
                line_means: if pairs.is_empty() {
                    Arc::clone(&no_means)
                } else {
                    Arc::clone(&tables[n].line_means)
                },
                pairs,
            })
            .collect();
        FarField {
            edges,
            fans: Fans::new(curved.into_iter().filter_map(|e| {
                let [before, after] = e.fan?;
                (before + after > 0.0).then(|| {
                    (
                        e.length / (before + after),
                        libm::atan2(e.normal[1], e.normal[0]),
                        [before, after],
                    )
                })
            })),
            discs: 2.0 * discs.iter().map(|d| d.radius).sum::<f64>(),
            fringes,
            spots: Spots::new(&spots, &lines, planes, f, pitch, reach + pitch),
            table,
            longest,
            lines,
            mean_lambda: (0..planes)
                .map(|c| {
                    spectrum.iter().map(|(l, w)| l * 1e-6 * w[c]).sum::<f64>() / weights_total[c]
                })
                .collect(),
            area,
            focal: f,
            sending,
        }
    }

    /// The light of every plane in the pixels of a row centred at
    /// (`x0` + i·`pitch`, `y`) mm, each times its weight in `weights`, into
    /// `out`, their planes side by side: edge by edge along the row, so
    /// that the geometry is shared among the planes and the far side of
    /// each ray, where every plane's table is its tail, is a plain sum.
    pub fn row(
        &self,
        x0: f64,
        y: f64,
        pitch: f64,
        weights: &[f64],
        scratch: &mut Row,
        out: &mut [f64],
    ) {
        let planes = weights.len();
        let count = out.len() / planes;
        scratch.tails.clear();
        scratch.tails.resize(count, 0.0);
        scratch.sums.clear();
        scratch.sums.resize(count * planes, 0.0);
        scratch.cosines.resize(count, 0.0);
        for edge in &self.edges {
            self.add_edge(edge, x0, y, pitch, planes, scratch);
        }
        self.fringes
            .add_row(x0, y, pitch, planes, count, &mut scratch.fringes);
        let norm = pitch * pitch / (self.area * 4.0 * PI * PI);
        // Where the last pixel's angles fell among the fans' breakpoints:
        // the next pixel's lie beside them.
        let mut hints = [0, 0];
        for (i, pixel) in out.chunks_mut(planes).enumerate() {
            let x = x0 + i as f64 * pitch;
            let r2 = x * x + y * y;
            let r = r2.sqrt();
            // By stationary phase, the points of a curved side whose normal
            // is ±x/|x| send ρ λ f / (4π² |x|³) there (two such points on a
            // disc give its ⟨J₁²⟩ term), ρ the radius of curvature; each
            // piece covers its share of the normal's directions, averaged
            // over the angle the pixel spans.
            let mut curved = 0.0;
            if !self.fans.is_empty() {
                let phi = libm::atan2(y, x);
                let half = 0.5 * pitch * (x.abs() + y.abs()) / r2;
                curved += self.fans.between(phi - half, phi + half, &mut hints) / (2.0 * half);
            }
            curved += self.discs;
            let per_r3 = self.focal / (r2 * r);
            let mut spots = [0.0; PLANES];
            if !self.spots.is_empty() {
                self.spots.add(r, pitch, &mut spots);
            }
            for (c, value) in pixel.iter_mut().enumerate() {
                let straight = scratch.sums[i * planes + c] + self.table.tail[c] * scratch.tails[i];
                let curved = curved * self.mean_lambda[c] + Fringes::at(&scratch.fringes, i, c);
                *value = weights[c] * norm * (straight / (r2 * r2) + curved * per_r3)
                    + weights[c] * spots[c] * pitch * pitch / self.area;
            }
        }
    }

    /// One straight edge's L²(x·n̂)²⟨sinc²⟩ in the pixels of a row, the
    /// sinc² averaged across the ray over each square pixel exactly, and
    /// its cross terms with the parallel edges after it.
    fn add_edge(&self, edge: &Edge, x0: f64, y: f64, pitch: f64, planes: usize, row: &mut Row) {
        let count = row.tails.len();
        let [n0, n1] = edge.normal;
        let [a0, a1] = edge.along;
        let k = edge.l_over_f;
        let (beta, gamma) = projections(edge.along, k, pitch);
        let (across0, d_across) = (x0 * a0 + y * a1, pitch * a0);
        let (along0, d_along) = (x0 * n0 + y * n1, pitch * n0);
        let strip = |i: usize| {
            let across = across0 + i as f64 * d_across;
            let along = along0 + i as f64 * d_along;
            (edge.l2 * along * along, across * k)
        };
        let spread = spread(beta, gamma, self.sending);
        let table = band(across0, d_across, (self.table.end + spread) / k, count);
        // Beyond the table all four corners' u lie on one side, where
        // g = tail/u² and the trapezoid's mean is
        // −tail·ln(1 − x)/(x D), D = c² − (β − γ)², x = 4βγ/D ≤ 10⁻³: to
        // the second order 1/c²·(1 + 3m₂/c²), m₂ = (β² + γ²)/3 the
        // trapezoid's second moment, which the tent's doubles.
        let squeeze = (beta - gamma) * (beta - gamma);
        let corners = 2.0 * beta * gamma;
        let tented = 2.0 * (beta * beta + gamma * gamma);
        let sending = self.sending;
        let tail = |i: usize| {
            let (weight, c) = strip(i);
            match sending {
                Sending::Point => {
                    let d = 1.0 / (c * c - squeeze);
                    weight * d * (1.0 + corners * d)
                }
                Sending::Pixel => weight / (c * c - tented),
            }
        };
        for range in [0..table.start, table.end..count] {
            for (i, sum) in range.clone().zip(&mut row.tails[range]) {
                *sum += tail(i);
            }
        }
        row.means.resize(count, 0.0);
        for i in table.clone() {
            let (weight, c) = strip(i);
            let mean = edge
                .received
                .at(c)
                .unwrap_or_else(|| self.table.received(c, beta, gamma, self.sending));
            row.means[i] = mean[0];
            for (sum, m) in row.sums[i * planes..(i + 1) * planes].iter_mut().zip(mean) {
                *sum += weight * m;
            }
        }
        let at = Strip {
            line_means: &edge.line_means,
            x0,
            y,
            pitch,
            across0,
            d_across,
            k,
            beta,
            gamma,
        };
        for pair in &edge.pairs {
            if self.lines.len() == 1 {
                // In one wavelength everywhere: beyond the table the
                // pixel's means of the edge's light and of the cosine are
                // multiplied; within it, see add_cross.
                let lambda = self.lines[0].lambda;
                let (start, step) = pair.phase(x0, y, pitch, lambda);
                let twice = 2.0 * pair.sign * pair.pixel[0];
                for range in [0..table.start, table.end..count] {
                    cosines(start, step, range.clone(), &mut row.cosines);
                    for ((i, sum), cos) in range
                        .clone()
                        .zip(&mut row.tails[range.clone()])
                        .zip(&row.cosines[range])
                    {
                        *sum += tail(i) * twice * cos * pair.beat(strip(i).1, lambda);
                    }
                }
                self.add_cross(pair, &at, table.clone(), &strip, planes, row);
            } else {
                let reach = (PAIR_REACH * self.longest + spread) / k;
                let near = band(across0, d_across, reach, count);
                let start = near.start.max(table.start);
                let near = start..near.end.min(table.end).max(start);
                self.add_cross(pair, &at, near, &strip, planes, row);
            }
        }
    }

    /// A pair's cross term 2σ⟨|F|² cos q·d⟩ in the pixels `near` of a row,
    /// line by line, into each plane by the line's share. In the ray's core
    /// the pixel mean is exact: sinc²(πu/λ) = ∫ tri(z) e^(i2πzu/λ) dz over
    /// [−1, 1], so the mean over the square of sinc²·cos q·d is
    /// Σ_j w_j tri(z_j) P(z_j k â/λ + d/(λf)) cos 2π(x·d/(λf) + z_j k t/λ),
    /// P(ω) = sinc(πpω_x) sinc(πpω_y) the square's mean of e^(i2πω·δ), t
    /// the offset across the ray: Gauss–Legendre on each half of the
    /// triangle, whose weights do not depend on the pixel. Beyond the core
    /// the pixel's means of the sinc² and of the cosine are multiplied.
    fn add_cross(
        &self,
        pair: &Pair,
        at: &Strip,
        near: std::ops::Range<usize>,
        strip: &impl Fn(usize) -> (f64, f64),
        planes: usize,
        row: &mut Row,
    ) {
        let count = row.tails.len();
        row.cross.resize(count, 0.0);
        row.waves.resize(count, 0.0);
        let lines = self.lines.iter().zip(&pair.pixel).zip(&pair.nodes);
        for (l, ((line, pixel), nodes)) in lines.enumerate() {
            let (start, step) = pair.phase(at.x0, at.y, at.pitch, line.lambda);
            cosines(start, step, near.clone(), &mut row.cosines);
            let core = band(
                at.across0,
                at.d_across,
                PAIR_CORE * line.lambda / at.k,
                count,
            );
            let core = core.start.clamp(near.start, near.end)..core.end.clamp(near.start, near.end);
            row.cross[core.clone()].iter_mut().for_each(|v| *v = 0.0);
            for &(frequency, weight) in nodes {
                let (start, step) = (
                    start + TAU * frequency * at.across0,
                    step + TAU * frequency * at.d_across,
                );
                let Row { cross, waves, .. } = row;
                cosines(start, step, core.clone(), waves);
                for (sum, cos) in cross[core.clone()].iter_mut().zip(&waves[core.clone()]) {
                    *sum += weight * cos;
                }
            }
            for i in near.clone() {
                let (weight, c) = strip(i);
                let cross = if core.contains(&i) {
                    row.cross[i]
                } else {
                    // One wavelength's mean is the edge's own, found already.
                    let mean = match &line.table {
                        Some(table) => match at.line_means.get(l).and_then(|m| m.at(c)) {
                            Some(mean) => mean[0],
                            None => table.received(c, at.beta, at.gamma, self.sending)[0],
                        },
                        None => row.means[i],
                    };
                    mean * pixel * row.cosines[i] * pair.beat(c, line.lambda)
                };
                let term = 2.0 * pair.sign * weight * cross;
                for (sum, share) in row.sums[i * planes..(i + 1) * planes]
                    .iter_mut()
                    .zip(&line.shares)
                {
                    *sum += share * term;
                }
            }
        }
    }
}

impl Pair {
    /// Beyond the ray's core, sinc(πu/λ)·sinc(πur/λ) is sinc²(πu/λ) times
    /// cos(πu(1 − r)/λ) to within its fast fringes, which the pixel
    /// averages: the slow beat of unequal edges' sincs.
    fn beat(&self, u: f64, lambda: f64) -> f64 {
        if self.ratio < 1.0 {
            libm::cos(PI * u * (1.0 - self.ratio) / lambda)
        } else {
            1.0
        }
    }

    /// The phase 2π x·d/(λf) at the row's first pixel (`x0`, `y`) and its
    /// step from pixel to pixel, in `lambda` mm.
    fn phase(&self, x0: f64, y: f64, pitch: f64, lambda: f64) -> (f64, f64) {
        let [dx, dy] = self.d_over_f;
        (TAU * (x0 * dx + y * dy) / lambda, TAU * pitch * dx / lambda)
    }
}

/// Where a row's pixels lie about an edge's ray: the row's first pixel
/// at (`x0`, `y`), the offset across the ray of the first and its step,
/// u per offset (L/f), and the pixel's half projections in u.
struct Strip<'a> {
    /// The edge's means per line ([`Edge::line_means`]).
    line_means: &'a [Received],
    x0: f64,
    y: f64,
    pitch: f64,
    across0: f64,
    d_across: f64,
    k: f64,
    beta: f64,
    gamma: f64,
}

/// The nodes of a pair's exact cross term in one wavelength (see
/// [`FarField::add_cross`]): sinc(πu/λ)·sinc(πur/λ) is the transform of
/// the trapezoid T(z) = (1/r)·|[z − r/2, z + r/2] ∩ [−½, ½]| (for r = 1 the
/// triangle 1 − |z|), integrated by Gauss–Legendre on its flat top and on
/// each slope, on either side, with enough points for the PAIR_CORE turns
/// of the phase across the core and the turns of the square's mean P. The
/// weights hold r, so that a pair's term is its longer edge's L² times
/// them.
fn core_nodes(
    edge: &EdgeTerm,
    d: [f64; 2],
    ratio: f64,
    lambda: f64,
    f: f64,
    (pitch, sending): (f64, Sending),
) -> Vec<(f64, f64)> {
    let (k, a) = (edge.length / f, edge.along);
    let per_z = k / lambda;
    let turns = PAIR_CORE + pitch * per_z * (a[0].abs() + a[1].abs());
    let (points, weights) =
        crate::math::gauss_legendre(((2.2 * turns + 2.0).ceil() as usize).min(32));
    let (top, foot) = (0.5 * (1.0 - ratio), 0.5 * (1.0 + ratio));
    let trapezoid =
        |z: f64| ((0.5f64).min(z + 0.5 * ratio) - (-0.5f64).max(z - 0.5 * ratio)).max(0.0);
    let mut nodes = Vec::with_capacity(4 * points.len());
    for side in [-1.0, 1.0] {
        for (from, to) in [(0.0, top), (top, foot)] {
            if to <= from {
                continue;
            }
            for (x, w) in points.iter().zip(&weights) {
                let z = side * (from + 0.5 * (to - from) * (1.0 + x));
                let omega = [
                    z * per_z * a[0] + d[0] / (lambda * f),
                    z * per_z * a[1] + d[1] / (lambda * f),
                ];
                let pixel = pixel_mean(pitch, sending, omega);
                nodes.push((z * per_z, 0.5 * (to - from) * w * trapezoid(z) * pixel));
            }
        }
    }
    nodes
}

/// The mean of e^(i2πω·δ) over where a pixel `pitch` wide centred at 0
/// takes its light from: its square for light sent by a point, the
/// product of the sincs of its two sides; its tent for light sent by a
/// pixel, the square's own convolved with itself, whose transform is that
/// product squared.
pub(super) fn pixel_mean(pitch: f64, sending: Sending, omega: [f64; 2]) -> f64 {
    let square = sinc(PI * pitch * omega[0]) * sinc(PI * pitch * omega[1]);
    match sending {
        Sending::Point => square,
        Sending::Pixel => square * square,
    }
}

/// Half the projections of a square pixel's sides on the normal of a ray
/// along `along`, in u (`k` = L/f per mm), the larger first.
fn projections(along: [f64; 2], k: f64, pitch: f64) -> (f64, f64) {
    let (sx, sy) = (
        0.5 * pitch * along[0].abs() * k,
        0.5 * pitch * along[1].abs() * k,
    );
    (sx.max(sy), sx.min(sy))
}

/// How far in u a pixel takes its light from across a ray: its square's
/// projection, and a sending pixel's tent as far again.
fn spread(beta: f64, gamma: f64, sending: Sending) -> f64 {
    match sending {
        Sending::Point => beta + gamma,
        Sending::Pixel => 2.0 * (beta + gamma),
    }
}

/// The pixels i of 0..`count` where |`c0` + i·`c1`| < `reach`, and one
/// more on either side.
fn band(c0: f64, c1: f64, reach: f64, count: usize) -> std::ops::Range<usize> {
    let n = count as f64;
    let (lo, hi) = if c1 == 0.0 {
        if c0.abs() < reach {
            (0.0, n)
        } else {
            (0.0, 0.0)
        }
    } else {
        let (t1, t2) = ((-reach - c0) / c1, (reach - c0) / c1);
        (
            (t1.min(t2).floor() - 1.0).clamp(0.0, n),
            (t1.max(t2).ceil() + 1.0).clamp(0.0, n),
        )
    };
    if hi > lo {
        lo as usize..hi as usize
    } else {
        0..0
    }
}

/// cos(`start` + i·`step`) into `out[i]` for i in `range`: a rotation from
/// pixel to pixel, started afresh every 32 so that round-off cannot grow.
fn cosines(start: f64, step: f64, range: std::ops::Range<usize>, out: &mut [f64]) {
    let (sin_step, cos_step) = crate::math::sin_cos_wide(step);
    let mut i = range.start;
    while i < range.end {
        let (mut s, mut c) = crate::math::sin_cos_wide(start + i as f64 * step);
        for value in &mut out[i..range.end.min(i + 32)] {
            *value = c;
            (c, s) = (c * cos_step - s * sin_step, s * cos_step + c * sin_step);
        }
        i += 32;
    }
}

/// Pairs of parallel straight edges (opposite blades of an even stop, the
/// sides of a vane, the sides of opposite vanes, a vane's side and the
/// blade beside it), each edge at least 5 % of the pupil's `diameter` long
/// (shorter ones, such as a vane's ends, hold (L/D)² of a blade's light):
/// the longer one's index, the separation of their midpoints from the
/// shorter one's, mm, σ = s₁ s₂ (n̂₁·n̂₂), and the shorter's length over
/// the longer's.
fn parallel_pairs(edges: &[EdgeTerm], diameter: f64) -> Vec<(usize, [f64; 2], f64, f64)> {
    let long = 0.05 * diameter;
    let mut pairs = Vec::new();
    for (j, a) in edges.iter().enumerate() {
        for (k, b) in edges.iter().enumerate().skip(j + 1) {
            let cosine = a.normal[0] * b.normal[0] + a.normal[1] * b.normal[1];
            if cosine.abs() > 1.0 - 1e-9 && a.length >= long && b.length >= long {
                // Equal edges within round-off pair from the first, and
                // share one sinc.
                let (first, this, other) = if b.length > a.length * (1.0 + 1e-9) {
                    (k, b, a)
                } else {
                    (j, a, b)
                };
                let d = [
                    this.middle[0] - other.middle[0],
                    this.middle[1] - other.middle[1],
                ];
                let ratio = other.length / this.length;
                let ratio = if ratio > 1.0 - 1e-9 { 1.0 } else { ratio };
                pairs.push((first, d, a.sign * b.sign * cosine.signum(), ratio));
            }
        }
    }
    pairs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::Aperture;
    use means::MOST_FOOTPRINT;

    #[test]
    fn cosines_are_the_cosines_of_their_phases_and_touch_nothing_else() {
        for (start, step, range) in [
            (0.3, 0.01, 0..100),
            (2.0e4, -1.7, 5..6),
            (-7.5, 0.9, 3..38),
            (123.4, 2.6, 31..97),
            (1.0, 0.5, 7..7),
        ] {
            let mut out = vec![f64::NAN; 100];
            cosines(start, step, range.clone(), &mut out);
            for (i, v) in out.iter().enumerate() {
                if range.contains(&i) {
                    let exact = libm::cos(start + i as f64 * step);
                    assert!((v - exact).abs() < 1e-13, "{start} {step} {i}: {v} {exact}");
                } else {
                    assert!(v.is_nan(), "{i} written outside {range:?}");
                }
            }
        }
    }

    fn optics(blades: u32, vanes: u32) -> Optics {
        let aperture = Aperture {
            blades,
            rotation_deg: 0.0,
            roundness: 0.0,
            spectral: false,
            wavelength_nm: 550.0,
            obstruction: 0.0,
            vanes,
            vane_width: 0.02,
            ..Aperture::new(7)
        };
        let camera = crate::CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: Some(8.0),
            ..Default::default()
        };
        aperture.optics(&camera, 1.0, 0).unwrap()
    }

    /// The mean of g = Σ w sinc²(πu/λ) / Σ w over a pixel's footprint
    /// about `u`: its square's projection is the sum of two uniform
    /// offsets, ±β and ±γ, and a sending pixel's tent adds two more.
    fn footprint_mean(
        light: &[(f64, f64)],
        u: f64,
        (beta, gamma): (f64, f64),
        sending: Sending,
    ) -> f64 {
        let total: f64 = light.iter().map(|(_, w)| w).sum();
        let g = |u: f64| {
            light
                .iter()
                .map(|(l, w)| w * sinc(PI * u / l).powi(2))
                .sum::<f64>()
                / total
        };
        let (points, weights) = crate::math::gauss_legendre(12);
        let halves = match sending {
            Sending::Point => vec![beta, gamma],
            Sending::Pixel => vec![beta, gamma, beta, gamma],
        };
        let mut sum = 0.0;
        let n = points.len();
        for index in 0..n.pow(halves.len() as u32) {
            let (mut offset, mut weight, mut rest) = (0.0, 1.0, index);
            for half in &halves {
                offset += half * points[rest % n];
                weight *= weights[rest % n] / 2.0;
                rest /= n;
            }
            sum += weight * g(u + offset);
        }
        sum
    }

    #[test]
    fn a_thumbnails_pixel_keeps_its_table_small_and_is_computed_beyond_it() {
        // A pixel spanning 10⁵ wavelengths across the ray (a 3 px wide
        // image): its footprint would take millions of nodes.
        let table = Cumulative::new(&[vec![(550e-6, 1.0)]]);
        let (beta, gamma) = (30.0, 12.0);
        for sending in [Sending::Point, Sending::Pixel] {
            let received =
                Received::new(&table, (beta, gamma), sending, (table.end, f64::INFINITY));
            let step = 1.0 / received.inverse_step;
            let nodes = received.values.len() / received.planes;
            assert!(
                nodes as f64 <= table.end / step + MOST_FOOTPRINT + 5.0,
                "{nodes} nodes"
            );
            let last = (nodes - 4) as f64 * step;
            assert!(received.at(last + 4.0 * step).is_none());
            for u in [0.0, 0.37 * last, last] {
                let (ours, direct) = (
                    received.at(u).unwrap()[0],
                    table.received(u, beta, gamma, sending)[0],
                );
                assert!(
                    (ours - direct).abs() <= 1e-9 * direct.abs(),
                    "u {u}: {ours} against {direct}"
                );
            }
        }
    }

    #[test]
    fn an_edges_tabulated_means_are_as_close_to_the_pixels_as_its_tables() {
        // Seventeen lines (the table to 32 λ) and one (to 256 λ); the
        // projections of a blade's pixel and of a scratch's end (far
        // narrower than the table's nodes); light from a point and from a
        // pixel. Against the footprint's exact mean, the interpolated
        // means err no more than the table they come from, to 10⁻⁶ of
        // the fringes' envelope: at every u where the footprint spans a
        // node of the table, and at worst where it does not.
        let spectral: Vec<(f64, f64)> = (0..17)
            .map(|k| ((380.0 + 20.0 * k as f64) * 1e-6, 1.0 + (k % 5) as f64))
            .collect();
        for light in [spectral, vec![(550e-6, 1.0)]] {
            let table = Cumulative::new(std::slice::from_ref(&light));
            for (beta, gamma) in [(2.5e-4, 1.1e-4), (2.8e-6, 1.9e-6)] {
                for sending in [Sending::Point, Sending::Pixel] {
                    let reach = table.end + spread(beta, gamma, sending);
                    let received =
                        Received::new(&table, (beta, gamma), sending, (table.end, reach));
                    let step = 1.0 / received.inverse_step;
                    let mut worst = [0.0f64; 2];
                    for k in (0..(reach / step) as usize).step_by(97) {
                        let u = (k as f64 + 0.5) * step * if k % 2 == 0 { 1.0 } else { -1.0 };
                        let exact = footprint_mean(&light, u, (beta, gamma), sending);
                        let tabled = table.received(u, beta, gamma, sending)[0];
                        let interpolated = received.at(u).unwrap()[0];
                        let envelope = (table.tail[0] / (u * u)).min(1.0);
                        let (ours, its) = ((interpolated - exact).abs(), (tabled - exact).abs());
                        if beta + gamma >= table.step {
                            assert!(
                                ours <= its + 1e-6 * envelope,
                                "u {u}: {interpolated} and {tabled} against {exact}"
                            );
                        }
                        worst = [worst[0].max(ours / envelope), worst[1].max(its / envelope)];
                    }
                    assert!(worst[0] <= worst[1] + 1e-6, "{worst:?}");
                    assert!(received.at(reach + 4.0 * step).is_none());
                }
            }
        }
    }

    #[test]
    fn parallel_edges_pair_with_the_sign_of_their_fields() {
        // An even stop's opposite blades: fields F and −F·e^(iq·d).
        let o = optics(8, 0);
        let (edges, _, _) = o.pupil.far_field_terms();
        let pairs = parallel_pairs(&edges, o.diameter_mm);
        assert_eq!(pairs.len(), 4);
        assert!(pairs
            .iter()
            .all(|&(_, _, sign, ratio)| sign == -1.0 && ratio == 1.0));
        // Four opaque vanes on a round stop: each vane's sides (−1), and
        // with the opposite vane's sides, one collinear (+1: same normal,
        // both opaque) and one facing (−1); the vanes' ends, 2 % of D, are
        // left out, and perpendicular vanes do not pair.
        let o = optics(0, 4);
        let (edges, _, _) = o.pupil.far_field_terms();
        let pairs = parallel_pairs(&edges, o.diameter_mm);
        let count = |s: f64| pairs.iter().filter(|p| p.2 == s).count();
        assert_eq!((pairs.len(), count(1.0), count(-1.0)), (12, 4, 8));
        // Three vanes in a hexagon run to its corners: each vane's sides
        // lie parallel to the two blades across the vane, longer than them.
        let o = optics(6, 3);
        let (edges, _, _) = o.pupil.far_field_terms();
        let pairs = parallel_pairs(&edges, o.diameter_mm);
        let unequal: Vec<_> = pairs.iter().filter(|p| p.3 < 1.0).collect();
        assert_eq!((pairs.len(), unequal.len()), (18, 12));
        for &&(first, _, _, ratio) in &unequal {
            assert!((edges[first].length - o.diameter_mm / 2.0).abs() < 1e-9);
            assert!(ratio > 0.7 && ratio < 0.9, "{ratio}");
        }
        // Odd stops have none.
        let o = optics(7, 0);
        assert!(parallel_pairs(&o.pupil.far_field_terms().0, o.diameter_mm).is_empty());
    }
}
