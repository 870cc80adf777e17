//! The far field of a diffraction pattern: beyond ~60 λN the cross terms
//! of edges whose rays differ fall below B·λN/r, and the pattern is the
//! sum of each edge's |F_k|² = L²(x·n)² sinc²(πu/λ) / (4π²|x|⁴·area), u
//! the offset across the edge's ray times L/f, averaged over the square
//! pixel exactly, with the cross terms of parallel edges, which share a
//! ray; each disc adds its ⟨J₁²⟩ term R λ f / (2π²|x|³·area) with its
//! fringes and their beats with concentric discs and with the edges that
//! end on its rim, and each piece of a curved side fans its light over the
//! turn of its normal (docs/physics.md §6).

use super::Spectrum;
use crate::optics::aperture::pupil::{sinc, DiscTerm, EdgeTerm};
use crate::optics::aperture::Optics;
use std::f64::consts::{FRAC_1_SQRT_2, PI, TAU};

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
    /// The equal, parallel edges after it, whose rays coincide with its
    /// own and interfere with it.
    pairs: Vec<Pair>,
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

/// G(u) = ∫₀ᵘ g and H(u) = ∫₀ᵘ G, g(u) = Σ w sinc²(πu/λ) / Σ w, for each
/// plane's weights on one grid, tabulated finely, with the tail
/// g ≈ ⟨λ²⟩/(2π²u²) beyond.
struct Cumulative {
    planes: usize,
    step: f64,
    /// G at the nodes, the planes side by side.
    values: Vec<f64>,
    /// H at the nodes, likewise.
    seconds: Vec<f64>,
    /// Per plane, ⟨λ²⟩/(2π²).
    tail: [f64; PLANES],
    /// Where the table ends, and 1 over it.
    end: f64,
    inverse_end: f64,
}

impl Cumulative {
    /// The table of each plane's `light` (λ mm, weight), out to 32 times
    /// the longest wavelength for many lines (their ⟨sinc²⟩ has lost its
    /// fringes well before) and 256 times for one.
    fn new(light: &[Vec<(f64, f64)>]) -> Cumulative {
        let planes = light.len().min(PLANES);
        let all = || light.iter().flatten().map(|(l, _)| *l);
        let shortest = all().fold(f64::INFINITY, f64::min);
        let longest = all().fold(0.0, f64::max);
        let step = shortest / 32.0;
        let reach = if light.iter().all(|l| l.len() == 1) {
            256.0
        } else {
            32.0
        };
        let count = (reach * longest / step).ceil() as usize;
        let g = |plane: &[(f64, f64)], u: f64| {
            let total: f64 = plane.iter().map(|(_, w)| w).sum();
            plane
                .iter()
                .map(|(l, w)| w * sinc(PI * u / l).powi(2))
                .sum::<f64>()
                / total
        };
        let mut values = vec![0.0; (count + 1) * planes];
        let mut seconds = vec![0.0; (count + 1) * planes];
        for (c, plane) in light[..planes].iter().enumerate() {
            let (mut first, mut second) = (0.0, 0.0);
            let mut last = g(plane, 0.0);
            for k in 1..=count {
                let next = g(plane, k as f64 * step);
                // The trapezoid rule with its end correction, exact to the
                // fourth order, for both integrals.
                let before = first;
                first += 0.5 * (last + next) * step;
                second += 0.5 * (before + first) * step + step * step * (last - next) / 12.0;
                values[k * planes + c] = first;
                seconds[k * planes + c] = second;
                last = next;
            }
        }
        let mut tail = [0.0; PLANES];
        for (t, plane) in tail.iter_mut().zip(light) {
            let total: f64 = plane.iter().map(|(_, w)| w).sum();
            *t = plane.iter().map(|(l, w)| w * l * l).sum::<f64>() / total / (2.0 * PI * PI);
        }
        let end = count as f64 * step;
        Cumulative {
            planes,
            step,
            values,
            seconds,
            tail,
            end,
            inverse_end: 1.0 / end,
        }
    }

    /// G(u) of every plane, odd in u.
    #[inline]
    fn first(&self, u: f64) -> [f64; PLANES] {
        let (a, p) = (u.abs(), self.planes);
        let mut out = [0.0; PLANES];
        if a >= self.end {
            let last = self.values.len() - p;
            let beyond = self.inverse_end - 1.0 / a;
            for (c, o) in out[..p].iter_mut().enumerate() {
                *o = (self.values[last + c] + self.tail[c] * beyond).copysign(u);
            }
        } else {
            let position = a / self.step;
            let k = position as usize;
            let t = position - k as f64;
            let (here, next) = (&self.values[k * p..][..p], &self.values[(k + 1) * p..][..p]);
            for (c, o) in out[..p].iter_mut().enumerate() {
                *o = (here[c] * (1.0 - t) + next[c] * t).copysign(u);
            }
        }
        out
    }

    /// H(u) of every plane, even in u: cubic Hermite between the nodes, G
    /// being its slope.
    #[inline]
    fn second(&self, u: f64) -> [f64; PLANES] {
        let (a, p) = (u.abs(), self.planes);
        let mut out = [0.0; PLANES];
        if a >= self.end {
            let last = self.values.len() - p;
            let log = (a / self.end).ln();
            for (c, o) in out[..p].iter_mut().enumerate() {
                let slope = self.values[last + c] + self.tail[c] * self.inverse_end;
                *o = self.seconds[last + c] + slope * (a - self.end) - self.tail[c] * log;
            }
            return out;
        }
        let position = a / self.step;
        let k = position as usize;
        let t = position - k as f64;
        let (t2, t3) = (t * t, t * t * t);
        let (h00, h01) = (2.0 * t3 - 3.0 * t2 + 1.0, 3.0 * t2 - 2.0 * t3);
        let (h10, h11) = ((t3 - 2.0 * t2 + t) * self.step, (t3 - t2) * self.step);
        let (s0, s1) = (
            &self.seconds[k * p..][..p],
            &self.seconds[(k + 1) * p..][..p],
        );
        let (v0, v1) = (&self.values[k * p..][..p], &self.values[(k + 1) * p..][..p]);
        for (c, o) in out[..p].iter_mut().enumerate() {
            *o = h00 * s0[c] + h10 * v0[c] + h01 * s1[c] + h11 * v1[c];
        }
        out
    }

    /// The mean of every plane's g over a square pixel whose sides project
    /// onto the u axis as 2β and 2γ (β ≥ γ) about `c`: g weighted by the
    /// trapezoid that is the square's width along u, the second difference
    /// of H over 4βγ. Where γ is a hundredth of β or less the square is a
    /// strip 2β wide to within 10⁻⁴, and G's first difference, free of the
    /// second's cancellation, is used.
    #[inline]
    fn mean(&self, c: f64, beta: f64, gamma: f64) -> [f64; PLANES] {
        let mut out = [0.0; PLANES];
        if gamma <= 0.01 * beta {
            let (a, b) = (self.first(c + beta), self.first(c - beta));
            for k in 0..self.planes {
                out[k] = (a[k] - b[k]) / (2.0 * beta);
            }
        } else {
            let h = [
                self.second(c + beta + gamma),
                self.second(c - beta + gamma),
                self.second(c + beta - gamma),
                self.second(c - beta - gamma),
            ];
            for k in 0..self.planes {
                out[k] = (h[0][k] - h[1][k] - h[2][k] + h[3][k]) / (4.0 * beta * gamma);
            }
        }
        out
    }
}

impl FarField {
    pub fn new(
        optics: &Optics,
        spectrum: &Spectrum,
        weights_total: &[f64],
        pitch: f64,
    ) -> FarField {
        let (edges, discs) = optics.pupil.far_field_terms();
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
                    .map(|line| square_mean(pitch, [d[0], d[1]].map(|v| v / (line.lambda * f))))
                    .collect(),
                nodes: lines
                    .iter()
                    .map(|line| core_nodes(edge, d, ratio, line.lambda, f, pitch))
                    .collect(),
            });
        }
        let fringes = Fringes::new(&discs, &straight, &lines, f, pitch, optics.pupil.area());
        FarField {
            edges: straight
                .into_iter()
                .zip(pairs)
                .map(|(e, pairs)| Edge {
                    l2: e.length * e.length,
                    normal: e.normal,
                    along: e.along,
                    l_over_f: e.length / f,
                    pairs,
                })
                .collect(),
            fans: Fans::new(curved.into_iter().filter_map(|e| {
                let [before, after] = e.fan?;
                (before + after > 0.0).then(|| {
                    (
                        e.length / (before + after),
                        e.normal[1].atan2(e.normal[0]),
                        [before, after],
                    )
                })
            })),
            discs: 2.0 * discs.iter().map(|d| d.radius).sum::<f64>(),
            fringes,
            table: Cumulative::new(&(0..planes).map(light).collect::<Vec<_>>()),
            longest: lines.iter().map(|l| l.lambda).fold(0.0, f64::max),
            lines,
            mean_lambda: (0..planes)
                .map(|c| {
                    spectrum.iter().map(|(l, w)| l * 1e-6 * w[c]).sum::<f64>() / weights_total[c]
                })
                .collect(),
            area: optics.pupil.area(),
            focal: f,
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
                let phi = y.atan2(x);
                let half = 0.5 * pitch * (x.abs() + y.abs()) / r2;
                curved += self.fans.between(phi - half, phi + half, &mut hints) / (2.0 * half);
            }
            curved += self.discs;
            let per_r3 = self.focal / (r2 * r);
            for (c, value) in pixel.iter_mut().enumerate() {
                let straight = scratch.sums[i * planes + c] + self.table.tail[c] * scratch.tails[i];
                let curved = curved * self.mean_lambda[c] + Fringes::at(&scratch.fringes, i, c);
                *value = weights[c] * norm * (straight / (r2 * r2) + curved * per_r3);
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
        // Half the projections of the pixel's sides on the ray's normal,
        // in u, the larger first.
        let (sx, sy) = (0.5 * pitch * a0.abs() * k, 0.5 * pitch * a1.abs() * k);
        let (beta, gamma) = (sx.max(sy), sx.min(sy));
        let (across0, d_across) = (x0 * a0 + y * a1, pitch * a0);
        let (along0, d_along) = (x0 * n0 + y * n1, pitch * n0);
        let strip = |i: usize| {
            let across = across0 + i as f64 * d_across;
            let along = along0 + i as f64 * d_along;
            (edge.l2 * along * along, across * k)
        };
        let table = band(
            across0,
            d_across,
            (self.table.end + beta + gamma) / k,
            count,
        );
        // Beyond the table all four corners' u lie on one side, where
        // g = tail/u² and the trapezoid's mean is
        // −tail·ln(1 − x)/(x D), D = c² − (β − γ)², x = 4βγ/D ≤ 10⁻³.
        let squeeze = (beta - gamma) * (beta - gamma);
        let corners = 2.0 * beta * gamma;
        let tail = |i: usize| {
            let (weight, c) = strip(i);
            let d = 1.0 / (c * c - squeeze);
            weight * d * (1.0 + corners * d)
        };
        for range in [0..table.start, table.end..count] {
            for (i, sum) in range.clone().zip(&mut row.tails[range]) {
                *sum += tail(i);
            }
        }
        row.means.resize(count, 0.0);
        for i in table.clone() {
            let (weight, c) = strip(i);
            let mean = self.table.mean(c, beta, gamma);
            row.means[i] = mean[0];
            for (sum, m) in row.sums[i * planes..(i + 1) * planes].iter_mut().zip(mean) {
                *sum += weight * m;
            }
        }
        let at = Strip {
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
                let reach = (PAIR_REACH * self.longest + beta + gamma) / k;
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
        for ((line, pixel), nodes) in self.lines.iter().zip(&pair.pixel).zip(&pair.nodes) {
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
                        Some(table) => table.mean(c, at.beta, at.gamma)[0],
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

/// The discs' fringes. Far out a disc's amplitude is, by stationary
/// phase, s√R cos(z − 3π/4)/(πρ^{3/2}), z = 2πρR, ρ = r/(λf), so that
/// concentric discs add to their means R/(2π²ρ³) the waves −R sin 2z of
/// each and 2s₁s₂√(R₁R₂)(cos(z₁ − z₂) − sin(z₁ + z₂)) of each pair: waves
/// along the radius, each averaged over the square pixel as e^(iK n̂·δ),
/// K its wavenumber, n̂ = x/r. (Across a pixel the circle bends from its
/// tangent by p²/(8r): below 0.03 rad of phase beyond r_far.) Discs with
/// different centres are left incoherent: no stop has them.
struct Fringes {
    /// Per disc, 2πR/f: z = that·r/λ.
    radii: Vec<f64>,
    /// Per line, its waves.
    lines: Vec<Vec<Wave>>,
    /// Per line, 1/λ.
    inverse_lambda: Vec<f64>,
    /// The step in u = min(|n̂_x|, |n̂_y|) of the waves' pixel means.
    step: f64,
    /// The edges that end on a disc's rim.
    rims: Vec<Rim>,
    focal: f64,
    /// How far out, mm, the fringes and the rims' beats can hold
    /// FRINGE_FLOOR of the light in a pixel.
    reach: f64,
}

/// A straight edge whose midpoint m lies on a disc's rim with its normal
/// along the radius: a vane's end on the stop or on the obstruction. About
/// the edge's ray, x ∥ ±(m − c), the disc's stationary point ±R x/|x| is
/// the edge itself, so that their fields' cross term does not oscillate:
/// with the edge's field s_k(i/|q|²)L(q·n̂)sinc(q·e/2)e^(−iq·m) and the
/// disc's as above, 2 Re(F_k Â_j*) = A (P₁ sin Φ₁ − P₂ sin Φ₂),
/// A = s_k s_j L(q·n̂) sinc(q·e/2) √R/(π|q|²ρ^{3/2}),
/// Φ_{1,2} = z ± q·d − 3π/4, d = m − c: each slow on its side of the
/// centre, and averaged over the square pixel by its phase's gradient,
/// P = the pixel's mean of e^(i2π(Rn̂ ± d)·δ/(λf)).
struct Rim {
    disc: usize,
    /// d, mm.
    offset: [f64; 2],
    normal: [f64; 2],
    along: [f64; 2],
    length: f64,
    /// Per line and plane: 2 s_k s_j L √R √(λ/f), in the units of
    /// [`FarField::discs`], times the line's share of the plane.
    weights: Vec<[f64; PLANES]>,
    /// Per line, P₁ at the angles θ = −π + i·step of n̂ up to 2π (P₂ is
    /// P₁ at θ + π, `half_turn` steps on).
    pixel: Vec<Vec<f64>>,
    step: f64,
    half_turn: usize,
    /// The beat can reach FRINGE_FLOOR in a pixel at r only within
    /// band/r^{5/2} of the edge's ray (mm), and r only within `reach`.
    band: f64,
    reach: f64,
}

impl Rim {
    /// The edges of `edges` that end on a disc of `discs`, in a pupil of
    /// `area` mm².
    fn find(
        edges: &[EdgeTerm],
        discs: &[DiscTerm],
        lines: &[Line],
        f: f64,
        pitch: f64,
        area: f64,
    ) -> Vec<Rim> {
        let shortest = lines.iter().map(|l| l.lambda).fold(f64::INFINITY, f64::min);
        let longest = lines.iter().map(|l| l.lambda).fold(0.0, f64::max);
        let mut rims = Vec::new();
        for edge in edges {
            // An edge on a rim beats with it along its whole ray; a short
            // one elsewhere (a vane's end on another disc) with a phase
            // that turns along the ray, which the pixel's mean follows as
            // long as the edge's sinc is smooth across the pixel: its ray
            // two pixels wide or more.
            let short = edge.length <= shortest * f / (2.0 * pitch);
            for (j, disc) in discs.iter().enumerate() {
                let d = [
                    edge.middle[0] - disc.centre[0],
                    edge.middle[1] - disc.centre[1],
                ];
                let distance = d[0].hypot(d[1]);
                let radial = (d[0] * edge.normal[1] - d[1] * edge.normal[0]).abs();
                let on_rim = (distance - disc.radius).abs() <= 1e-6 * disc.radius;
                if !(on_rim || short) || radial > 1e-9 * distance {
                    continue;
                }
                // P turns by at most 0.02 rad per step.
                let turn = PI * pitch * (disc.radius + distance) / (shortest * f);
                let half_turn = ((PI * turn / 0.02).ceil() as usize).clamp(32, 1 << 15);
                let step = PI / half_turn as f64;
                let amplitude = 2.0 * edge.sign * disc.sign * edge.length * disc.radius.sqrt();
                // The beat is at most L√R (λf)^{1/2} p²/(π² r^{5/2}·area) of
                // the light in a pixel, and 2/(κL|x·ê|) of that beside the
                // edge's ray, κ = 2π/(λf).
                let beat = edge.length * (disc.radius * longest * f).sqrt() * pitch * pitch
                    / (PI * PI * area * FRINGE_FLOOR);
                rims.push(Rim {
                    disc: j,
                    offset: d,
                    normal: edge.normal,
                    along: edge.along,
                    length: edge.length,
                    weights: lines
                        .iter()
                        .map(|line| line.weights(amplitude * (line.lambda / f).sqrt()))
                        .collect(),
                    pixel: lines
                        .iter()
                        .map(|line| {
                            (0..3 * half_turn + 2)
                                .map(|i| {
                                    let (sin, cos) = (-PI + i as f64 * step).sin_cos();
                                    let g = [disc.radius * cos + d[0], disc.radius * sin + d[1]];
                                    square_mean(pitch, g.map(|g| g / (line.lambda * f)))
                                })
                                .collect()
                        })
                        .collect(),
                    step,
                    half_turn,
                    band: beat * 2.0 * longest * f / (TAU * edge.length),
                    reach: beat.powf(0.4),
                });
            }
        }
        rims
    }
}

/// The discs a wave is made of.
#[derive(Clone, Copy)]
enum Waveform {
    /// −sin 2z_j.
    Own(usize),
    /// −sin(z_j + z_k).
    Sum(usize, usize),
    /// cos(z_j − z_k).
    Difference(usize, usize),
}

/// One wave in one wavelength.
struct Wave {
    form: Waveform,
    /// Per plane: its amplitude, in the units of [`FarField::discs`],
    /// times the line's λ and its share of the plane.
    weights: [f64; PLANES],
    /// The mean of e^(iK n̂·δ) over the pixel at u = i·step.
    pixel: Vec<f64>,
}

/// Scratch space for one row's fringes.
#[derive(Default)]
pub(super) struct FringeRow {
    x: Vec<f64>,
    radius: Vec<f64>,
    /// Per pixel, √r.
    root: Vec<f64>,
    /// Per pixel, a rim's second wave.
    second: Vec<f64>,
    /// Per pixel, the angle of x, for the rims.
    angle: Vec<f64>,
    node: Vec<usize>,
    fraction: Vec<f64>,
    /// Per disc, sin z and cos z along the row.
    sines: Vec<Vec<f64>>,
    cosines: Vec<Vec<f64>>,
    wave: Vec<f64>,
    /// The first pixel within the fringes' reach.
    start: usize,
    /// Per plane, the fringes' sum in the pixels from `start` on.
    sums: Vec<Vec<f64>>,
}

impl Fringes {
    fn new(
        discs: &[DiscTerm],
        edges: &[EdgeTerm],
        lines: &[Line],
        f: f64,
        pitch: f64,
        area: f64,
    ) -> Fringes {
        // Each wave's form, amplitude and R₁ ± R₂ (or 2R), the same in
        // every line.
        let mut forms = Vec::new();
        for (j, a) in discs.iter().enumerate() {
            forms.push((Waveform::Own(j), 2.0 * a.radius, 2.0 * a.radius));
            for (k, b) in discs.iter().enumerate().skip(j + 1) {
                if a.centre != b.centre {
                    continue;
                }
                let amplitude = 4.0 * a.sign * b.sign * (a.radius * b.radius).sqrt();
                forms.push((Waveform::Sum(j, k), amplitude, a.radius + b.radius));
                forms.push((
                    Waveform::Difference(j, k),
                    amplitude,
                    (a.radius - b.radius).abs(),
                ));
            }
        }
        let shortest = lines.iter().map(|l| l.lambda).fold(f64::INFINITY, f64::min);
        let widest = forms.iter().map(|s| s.2).fold(0.0, f64::max) * TAU / (shortest * f);
        // The means turn by at most 0.02 rad per step: linear
        // interpolation is then within 5·10⁻⁵ of them.
        let step = (0.02 / (0.5 * widest * pitch)).min(0.01);
        let nodes = (FRAC_1_SQRT_2 / step).ceil() as usize + 2;
        let waves = lines
            .iter()
            .map(|line| {
                forms
                    .iter()
                    .map(|&(form, amplitude, radii)| {
                        let k = TAU * radii / (line.lambda * f);
                        let pixel = (0..nodes)
                            .map(|i| {
                                let u = (i as f64 * step).min(FRAC_1_SQRT_2);
                                let v = (1.0 - u * u).sqrt();
                                square_mean(pitch, [k * u / TAU, k * v / TAU])
                            })
                            .collect();
                        Wave {
                            form,
                            weights: line.weights(amplitude * line.lambda),
                            pixel,
                        }
                    })
                    .collect()
            })
            .collect();
        // The waves' amplitudes sum to at most 4(Σ√R)² in the units of
        // `discs`, λ f p²/(4π² r³·area) of the light in a pixel.
        let roots: f64 = discs.iter().map(|d| d.radius.sqrt()).sum();
        let longest = lines.iter().map(|l| l.lambda).fold(0.0, f64::max);
        let rims = Rim::find(edges, discs, lines, f, pitch, area);
        let reach = rims.iter().map(|rim| rim.reach).fold(
            (roots * roots * longest * f * pitch * pitch / (PI * PI * area * FRINGE_FLOOR)).cbrt(),
            f64::max,
        );
        Fringes {
            reach,
            rims,
            focal: f,
            radii: discs.iter().map(|d| TAU * d.radius / f).collect(),
            lines: waves,
            inverse_lambda: lines.iter().map(|l| 1.0 / l.lambda).collect(),
            step,
        }
    }

    /// Every wave's pixel mean in the pixels of a row centred at
    /// (`x0` + i·`pitch`, `y`) within `reach` of the centre, into each
    /// plane of `row.sums`, those pixels from `row.start` on.
    fn add_row(
        &self,
        x0: f64,
        y: f64,
        pitch: f64,
        planes: usize,
        count: usize,
        row: &mut FringeRow,
    ) {
        let half = (self.reach * self.reach - y * y).max(0.0).sqrt();
        let first = (((-half - x0) / pitch).ceil().max(0.0) as usize).min(count);
        let end = ((((half - x0) / pitch).floor() + 1.0).max(0.0) as usize).clamp(first, count);
        let n = if self.radii.is_empty() {
            0
        } else {
            end - first
        };
        row.start = first;
        row.sums.resize_with(planes, Vec::new);
        for sums in &mut row.sums {
            sums.clear();
            sums.resize(n, 0.0);
        }
        if n == 0 {
            return;
        }
        row.x.clear();
        row.radius.clear();
        row.root.clear();
        row.node.clear();
        row.fraction.clear();
        row.angle.clear();
        for i in first..end {
            let x = x0 + i as f64 * pitch;
            let r = x.hypot(y);
            let t = x.abs().min(y.abs()) / (r * self.step);
            row.radius.push(r);
            row.node.push(t as usize);
            row.fraction.push(t.fract());
            if !self.rims.is_empty() {
                row.x.push(x);
                row.root.push(r.sqrt());
                row.angle.push(libm::atan2(y, x));
            }
        }
        let discs = self.radii.len();
        row.sines.resize_with(discs, Vec::new);
        row.cosines.resize_with(discs, Vec::new);
        row.wave.resize(n, 0.0);
        for (line, (waves, inverse)) in self.lines.iter().zip(&self.inverse_lambda).enumerate() {
            for (j, radius) in self.radii.iter().enumerate() {
                let k = radius * inverse;
                let (sines, cosines) = (&mut row.sines[j], &mut row.cosines[j]);
                sines.resize(n, 0.0);
                cosines.resize(n, 0.0);
                for ((r, s), c) in row
                    .radius
                    .iter()
                    .zip(sines.iter_mut())
                    .zip(cosines.iter_mut())
                {
                    (*s, *c) = sin_cos(k * r);
                }
            }
            for wave in waves {
                let (s, c) = (&row.sines, &row.cosines);
                match wave.form {
                    Waveform::Own(j) => {
                        for ((w, s), c) in row.wave.iter_mut().zip(&s[j]).zip(&c[j]) {
                            *w = -2.0 * s * c;
                        }
                    }
                    Waveform::Sum(j, k) => {
                        let pairs = s[j].iter().zip(&c[j]).zip(s[k].iter().zip(&c[k]));
                        for (w, ((sj, cj), (sk, ck))) in row.wave.iter_mut().zip(pairs) {
                            *w = -(sj * ck + cj * sk);
                        }
                    }
                    Waveform::Difference(j, k) => {
                        let pairs = s[j].iter().zip(&c[j]).zip(s[k].iter().zip(&c[k]));
                        for (w, ((sj, cj), (sk, ck))) in row.wave.iter_mut().zip(pairs) {
                            *w = cj * ck + sj * sk;
                        }
                    }
                }
                for ((value, &node), t) in row.wave.iter_mut().zip(&row.node).zip(&row.fraction) {
                    let (a, b) = (wave.pixel[node], wave.pixel[node + 1]);
                    *value *= a + t * (b - a);
                }
                for (sums, w) in row.sums.iter_mut().zip(&wave.weights) {
                    for (sum, value) in sums.iter_mut().zip(&row.wave) {
                        *sum += w * value;
                    }
                }
            }
            for rim in &self.rims {
                self.add_rim(rim, line, *inverse, y, row);
            }
        }
    }

    /// One rim's beat in one line along the row's pixels within reach:
    /// the waves first, in plain arithmetic that vectorises, then their
    /// pixel means, looked up by angle.
    fn add_rim(&self, rim: &Rim, line: usize, inverse: f64, y: f64, row: &mut FringeRow) {
        let kappa = TAU * inverse / self.focal;
        let [d0, d1] = rim.offset;
        let [n0, n1] = rim.normal;
        let [a0, a1] = rim.along;
        // Across the edge's ray |sinc| ≤ 1/|h|: only the band where the
        // beat can reach the floor, for the nearest pixel of the row.
        let nearest = row.radius.iter().copied().fold(f64::INFINITY, f64::min);
        let width = rim.band / (nearest * nearest * nearest.sqrt());
        let n = row.wave.len();
        let band = match row.x.first() {
            Some(&x0) if n > 1 => band(x0 * a0 + y * a1, (row.x[1] - x0) * a0, width, n),
            _ => 0..n,
        };
        let half = 0.5 * kappa * rim.length;
        row.second.resize(n, 0.0);
        let (sines, cosines) = (
            &row.sines[rim.disc][band.clone()],
            &row.cosines[rim.disc][band.clone()],
        );
        let pixels = row.x[band.clone()]
            .iter()
            .zip(&row.root[band.clone()])
            .zip(sines.iter().zip(cosines));
        let waves = row.wave[band.clone()]
            .iter_mut()
            .zip(row.second[band.clone()].iter_mut());
        for ((first, second), ((x, root), (sz, cz))) in waves.zip(pixels) {
            let (sd, cd) = sin_cos(kappa * (x * d0 + y * d1));
            let h = half * (x * a0 + y * a1);
            let sinc = if h.abs() < 1e-8 {
                1.0
            } else {
                sin_cos(h).0 / h
            };
            let amplitude = sinc * (x * n0 + y * n1) / root;
            // sin and cos of z − 3π/4.
            let (sa, ca) = (-(sz + cz) * FRAC_1_SQRT_2, (sz - cz) * FRAC_1_SQRT_2);
            *first = amplitude * (sa * cd + ca * sd);
            *second = amplitude * (sa * cd - ca * sd);
        }
        let pixel = &rim.pixel[line];
        let waves = row.wave[band.clone()]
            .iter_mut()
            .zip(&row.second[band.clone()]);
        for ((first, second), theta) in waves.zip(&row.angle[band.clone()]) {
            let t = (theta + PI) / rim.step;
            let (node, frac) = (t as usize, t.fract());
            let p1 = pixel[node] + frac * (pixel[node + 1] - pixel[node]);
            let node = node + rim.half_turn;
            let p2 = pixel[node] + frac * (pixel[node + 1] - pixel[node]);
            *first = p1 * *first - p2 * second;
        }
        for (sums, w) in row.sums.iter_mut().zip(&rim.weights[line]) {
            for (sum, value) in sums[band.clone()].iter_mut().zip(&row.wave[band.clone()]) {
                *sum += w * value;
            }
        }
    }

    /// A row's fringes in pixel `i` and `plane`.
    fn at(row: &FringeRow, i: usize, plane: usize) -> f64 {
        i.checked_sub(row.start)
            .and_then(|k| row.sums[plane].get(k))
            .copied()
            .unwrap_or(0.0)
    }
}

/// (sin x, cos x) to within 4·10⁻¹⁶ for |x| < 10⁵ in plain arithmetic,
/// so that rows of them vectorise and give the same bytes everywhere:
/// x less the nearest multiple n of π/2, in two parts, then the Taylor
/// series on [−π/4, π/4], turned by n quarter turns.
fn sin_cos(x: f64) -> (f64, f64) {
    const ROUND: f64 = 6_755_399_441_055_744.0;
    const HIGH: f64 = 1.570_796_326_734_125_6;
    const LOW: f64 = 6.077_100_506_506_192e-11;
    let shifted = x * std::f64::consts::FRAC_2_PI + ROUND;
    let quarter = shifted.to_bits();
    let n = shifted - ROUND;
    let y = (x - n * HIGH) - n * LOW;
    let y2 = y * y;
    let sin = y
        * (1.0
            + y2 * (-1.0 / 6.0
                + y2 * (1.0 / 120.0
                    + y2 * (-1.0 / 5040.0
                        + y2 * (1.0 / 362_880.0
                            + y2 * (-1.0 / 39_916_800.0
                                + y2 * (1.0 / 6_227_020_800.0
                                    + y2 * (-1.0 / 1_307_674_368_000.0))))))));
    let cos = 1.0
        + y2 * (-0.5
            + y2 * (1.0 / 24.0
                + y2 * (-1.0 / 720.0
                    + y2 * (1.0 / 40_320.0
                        + y2 * (-1.0 / 3_628_800.0
                            + y2 * (1.0 / 479_001_600.0
                                + y2 * (-1.0 / 87_178_291_200.0
                                    + y2 * (1.0 / 20_922_789_888_000.0))))))));
    // The quarter turns by masks, not branches, which would be taken at
    // random.
    const SIGN: u64 = 1 << 63;
    let odd = 0u64.wrapping_sub(quarter & 1);
    let half = (quarter & 2) << 62;
    let (sin, cos) = (sin.to_bits(), cos.to_bits());
    let s = (sin & !odd) | (cos & odd);
    let c = (cos & !odd) | ((sin ^ SIGN) & odd);
    (f64::from_bits(s ^ half), f64::from_bits(c ^ half))
}

/// Where a row's pixels lie about an edge's ray: the row's first pixel
/// at (`x0`, `y`), the offset across the ray of the first and its step,
/// u per offset (L/f), and the pixel's half projections in u.
struct Strip {
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
    pitch: f64,
) -> Vec<(f64, f64)> {
    let (k, a) = (edge.length / f, edge.along);
    let per_z = k / lambda;
    let turns = PAIR_CORE + pitch * per_z * (a[0].abs() + a[1].abs());
    let (points, weights) =
        super::near::gauss_legendre(((2.2 * turns + 2.0).ceil() as usize).min(32));
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
                let box_mean = square_mean(pitch, omega);
                nodes.push((z * per_z, 0.5 * (to - from) * w * trapezoid(z) * box_mean));
            }
        }
    }
    nodes
}

/// The mean of e^(i2πω·δ) over a square pixel `pitch` wide centred at 0:
/// the product of the sincs of its two sides.
fn square_mean(pitch: f64, omega: [f64; 2]) -> f64 {
    sinc(PI * pitch * omega[0]) * sinc(PI * pitch * omega[1])
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
    let (sin_step, cos_step) = step.sin_cos();
    let mut i = range.start;
    while i < range.end {
        let (mut s, mut c) = (start + i as f64 * step).sin_cos();
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

/// The light the pieces of curved sides fan out, as a density over the
/// direction θ of the normal: each piece (ρ its radius of curvature, its
/// normal's angle, the turn [before, after] it covers) adds ρ over its
/// range of directions, and again half a turn on (a side sends light both
/// ways). A pixel's share is the integral over the angle it spans, which
/// the cumulative integral gives with two lookups whatever the number of
/// pieces.
struct Fans {
    /// Breakpoints in [−π, π), ascending, with the integral from −π up to
    /// each and the density after it.
    points: Vec<(f64, f64, f64)>,
    /// The integral over a whole turn.
    turn: f64,
}

impl Fans {
    fn new(pieces: impl Iterator<Item = (f64, f64, [f64; 2])>) -> Fans {
        use std::f64::consts::{PI, TAU};
        // Density steps (angle, change), each range split where it wraps.
        let mut steps: Vec<(f64, f64)> = Vec::new();
        for (rho, normal, [before, after]) in pieces {
            for side in [0.0, PI] {
                let start = wrap(normal + side - before);
                let end = start + before + after;
                if end <= PI {
                    steps.extend([(start, rho), (end, -rho)]);
                } else {
                    steps.extend([(start, rho), (PI, -rho), (-PI, rho), (end - TAU, -rho)]);
                }
            }
        }
        steps.sort_by(|a, b| a.0.total_cmp(&b.0));
        let mut points = Vec::with_capacity(steps.len() + 1);
        let (mut at, mut integral, mut density) = (-PI, 0.0, 0.0);
        points.push((at, integral, density));
        for (angle, change) in steps {
            integral += density * (angle - at);
            density += change;
            at = angle;
            points.push((at, integral, density));
        }
        let turn = integral + density * (PI - at);
        Fans { points, turn }
    }

    fn is_empty(&self) -> bool {
        self.turn == 0.0
    }

    /// ∫ of the density from `from` to `to`: what the cumulative integral
    /// leaves of a range no piece covers is round-off, and 0. `hints` are
    /// where the search for each end starts, and where it ended.
    fn between(&self, from: f64, to: f64, hints: &mut [usize; 2]) -> f64 {
        let [low, high] = hints;
        let covered = self.integral(to, high) - self.integral(from, low);
        if covered > 1e-12 * self.turn {
            covered
        } else {
            0.0
        }
    }

    /// ∫ of the density from −π to `angle` (any angle, whole turns
    /// counted). The breakpoint below it is sought from `hint` outwards,
    /// a step or two along a row, and left there.
    fn integral(&self, angle: f64, hint: &mut usize) -> f64 {
        use std::f64::consts::{PI, TAU};
        let turns = ((angle + PI) / TAU).floor();
        let a = angle - turns * TAU;
        // The last breakpoint at or below a (the first is −π ≤ a).
        let mut k = (*hint).min(self.points.len() - 1);
        while k + 1 < self.points.len() && self.points[k + 1].0 <= a {
            k += 1;
        }
        while k > 0 && self.points[k].0 > a {
            k -= 1;
        }
        *hint = k;
        let (start, integral, density) = self.points[k];
        turns * self.turn + integral + density * (a - start)
    }
}

/// An angle brought into (−π, π]; the angles here lie within a few turns,
/// and steps of 2π are far cheaper than a rounding division.
fn wrap(mut angle: f64) -> f64 {
    use std::f64::consts::{PI, TAU};
    while angle > PI {
        angle -= TAU;
    }
    while angle <= -PI {
        angle += TAU;
    }
    angle
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::Aperture;

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
            filters: Vec::new(),
        };
        let camera = crate::Camera {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: Some(8.0),
        };
        aperture.optics(&camera, 1.0).unwrap()
    }

    #[test]
    fn the_rows_sines_and_cosines_are_those_of_libm() {
        // Across the quarter turns' boundaries and out to the phases of
        // the farthest fringes (K r ≲ 10⁵ rad).
        let mut x = -20.0;
        while x < 1e5 {
            let (s, c) = sin_cos(x);
            let tolerance = 4e-16;
            assert!((s - libm::sin(x)).abs() <= tolerance, "sin {x}: {s}");
            assert!((c - libm::cos(x)).abs() <= tolerance, "cos {x}: {c}");
            x = if x < 1.0 { x + 0.0123 } else { x * 1.001 };
        }
        for k in -8..=8 {
            let x = f64::from(k) * std::f64::consts::FRAC_PI_4;
            let (s, c) = sin_cos(x);
            assert!(
                (s - x.sin()).abs() < 1e-15 && (c - x.cos()).abs() < 1e-15,
                "{x}"
            );
        }
    }

    #[test]
    fn parallel_edges_pair_with_the_sign_of_their_fields() {
        // An even stop's opposite blades: fields F and −F·e^(iq·d).
        let o = optics(8, 0);
        let (edges, _) = o.pupil.far_field_terms();
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
        let (edges, _) = o.pupil.far_field_terms();
        let pairs = parallel_pairs(&edges, o.diameter_mm);
        let count = |s: f64| pairs.iter().filter(|p| p.2 == s).count();
        assert_eq!((pairs.len(), count(1.0), count(-1.0)), (12, 4, 8));
        // Three vanes in a hexagon run to its corners: each vane's sides
        // lie parallel to the two blades across the vane, longer than them.
        let o = optics(6, 3);
        let (edges, _) = o.pupil.far_field_terms();
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
