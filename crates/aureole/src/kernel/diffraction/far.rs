//! The far field of a diffraction pattern: beyond ~60 λN the interference
//! between different edges oscillates faster than a pixel, and the pattern
//! is the incoherent sum of each edge's |F_k|² = L²(x·n)² sinc²(πu/λ) /
//! (4π²|x|⁴·area), u the offset across the edge's ray times L/f, averaged
//! over the pixel analytically; each disc adds its ⟨J₁²⟩ term
//! R λ f / (2π²|x|³·area), and each piece of a curved side fans its light
//! over the turn of its normal (docs/physics.md §6).

use super::Spectrum;
use crate::optics::aperture::pupil::EdgeTerm;
use crate::optics::aperture::Optics;

/// The far field: incoherent sums over edges, curved sides and discs.
/// Two equal, opposite edges sharing a ray, as the first of them sees it.
struct Pair {
    /// The separation d of their midpoints over λf, cycles/mm.
    wave: [f64; 2],
    /// The mean of e^(i2πx·d/(λf)) over a pixel centred at 0: the product
    /// of the sincs of its two sides.
    pixel: f64,
}

pub(super) struct FarField {
    /// (L², normal, unit direction along, L/f) per straight edge.
    edges: Vec<(f64, [f64; 2], [f64; 2], f64)>,
    /// In monochromatic light, for each straight edge that is the first of
    /// a pair of equal, opposite edges of one polygon (whose rays coincide
    /// and interfere), the pair.
    pairs: Vec<Option<Pair>>,
    /// Pieces of curved sides: the light they fan out, by direction.
    fans: Fans,
    discs: Vec<f64>,
    /// Per plane: the spectrum-averaged ∫₀ᵘ sinc²(πu'/λ) du'.
    tables: Vec<Cumulative>,
    /// Per plane: the sensitivity-weighted mean wavelength, mm.
    mean_lambda: Vec<f64>,
    area: f64,
    focal: f64,
}

/// G(u) = ∫₀ᵘ g, g(u) = Σ w sinc²(πu/λ) / Σ w, tabulated finely, with the
/// tail g ≈ ⟨λ²⟩/(2π²u²) beyond.
struct Cumulative {
    step: f64,
    values: Vec<f64>,
    tail: f64,
    /// Where the table ends, and 1 over it.
    end: f64,
    inverse_end: f64,
}

impl Cumulative {
    fn new(light: &[(f64, f64)]) -> Cumulative {
        let total: f64 = light.iter().map(|(_, w)| w).sum();
        let shortest = light.iter().map(|(l, _)| *l).fold(f64::INFINITY, f64::min);
        let longest = light.iter().map(|(l, _)| *l).fold(0.0, f64::max);
        let step = shortest / 32.0;
        let count = (256.0 * longest / step).ceil() as usize;
        let g = |u: f64| {
            light
                .iter()
                .map(|(l, w)| {
                    let z = std::f64::consts::PI * u / l;
                    let s = if z.abs() < 1e-9 { 1.0 } else { z.sin() / z };
                    w * s * s
                })
                .sum::<f64>()
                / total
        };
        let mut values = Vec::with_capacity(count + 1);
        let mut sum = 0.0;
        let mut last = g(0.0);
        values.push(0.0);
        for k in 1..=count {
            let next = g(k as f64 * step);
            sum += 0.5 * (last + next) * step;
            values.push(sum);
            last = next;
        }
        let mean_square = light.iter().map(|(l, w)| w * l * l).sum::<f64>() / total;
        let end = (values.len() - 1) as f64 * step;
        Cumulative {
            step,
            values,
            tail: mean_square / (2.0 * std::f64::consts::PI.powi(2)),
            end,
            inverse_end: 1.0 / end,
        }
    }

    /// G(u), odd in u, given a = |u| and 1/a, which a caller with several
    /// tables divides once for all of them.
    #[inline]
    fn at(&self, u: f64, a: f64, inverse: f64) -> f64 {
        let g = if a >= self.end {
            self.values[self.values.len() - 1] + self.tail * (self.inverse_end - inverse)
        } else {
            let position = a / self.step;
            let k = position as usize;
            let t = position - k as f64;
            self.values[k] * (1.0 - t) + self.values[k + 1] * t
        };
        g.copysign(u)
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
        // In one wavelength a pair's fringes along its ray are the
        // pattern; over a spectrum their phases drift apart with distance
        // (docs/physics.md §6), and the pairs are left out.
        let mut pairs: Vec<Option<Pair>> = straight.iter().map(|_| None).collect();
        if let [(lambda_nm, _)] = spectrum.as_slice() {
            let lf = lambda_nm * 1e-6 * f;
            let sinc = |z: f64| if z.abs() < 1e-12 { 1.0 } else { z.sin() / z };
            let pi = std::f64::consts::PI;
            for (first, d) in parallel_pairs(&straight) {
                let wave = [d[0] / lf, d[1] / lf];
                pairs[first] = Some(Pair {
                    wave,
                    pixel: sinc(pi * pitch * wave[0]) * sinc(pi * pitch * wave[1]),
                });
            }
        }
        FarField {
            pairs,

            edges: straight
                .into_iter()
                .map(|e| (e.length * e.length, e.normal, e.along, e.length / f))
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
            discs,
            tables: (0..planes).map(|c| Cumulative::new(&light(c))).collect(),
            mean_lambda: (0..planes)
                .map(|c| {
                    spectrum.iter().map(|(l, w)| l * 1e-6 * w[c]).sum::<f64>() / weights_total[c]
                })
                .collect(),
            area: optics.pupil.area(),
            focal: f,
        }
    }

    /// The light of every plane in the pixel at (x, y) mm, each times its
    /// weight in `weights`, into `out`: the geometry is shared among the
    /// planes, only the spectrum's tables differ.
    pub fn energies(&self, x: f64, y: f64, pitch: f64, weights: &[f64], out: &mut [f64]) {
        const PLANES: usize = 3;
        let planes = out.len().min(PLANES);
        let r2 = x * x + y * y;
        let mut sums = [0.0; PLANES];
        for (edge, pair) in self.edges.iter().zip(&self.pairs) {
            let term = self.edge_term(edge, x, y, pitch, planes);
            // A pair's fields F and −F·e^(iq·d) share a ray: |F|² + |F|²
            // becomes 2|F|²(1 − cos q·d), the cosine averaged over the
            // square pixel exactly (a product of two sincs).
            let interference = pair.as_ref().map_or(0.0, |pair| {
                let phase = std::f64::consts::TAU * (x * pair.wave[0] + y * pair.wave[1]);
                2.0 * phase.cos() * pair.pixel
            });
            for (sum, t) in sums.iter_mut().zip(term) {
                *sum += t * (1.0 - interference);
            }
        }
        let r = r2.sqrt();
        let r3 = r2 * r;
        // By stationary phase, the points of a curved side whose normal is
        // ±x/|x| send ρ λ f / (4π² |x|³) there (two such points on a disc
        // give its ⟨J₁²⟩ term), ρ the radius of curvature; each piece
        // covers its share of the normal's directions, averaged over the
        // angle the pixel spans.
        let fanned = (!self.fans.is_empty()).then(|| {
            let phi = y.atan2(x);
            let half = 0.5 * pitch * (x.abs() + y.abs()) / r2;
            self.fans.between(phi - half, phi + half) / (2.0 * half)
        });
        for (c, (value_out, sum)) in out.iter_mut().zip(sums).enumerate() {
            let mut value = sum / (4.0 * std::f64::consts::PI.powi(2) * r2 * r2);
            if let Some(fanned) = fanned {
                value += fanned * self.mean_lambda[c] * self.focal
                    / (4.0 * std::f64::consts::PI.powi(2) * r3);
            }
            for radius in &self.discs {
                value += radius * self.mean_lambda[c] * self.focal
                    / (2.0 * std::f64::consts::PI.powi(2) * r3);
            }
            *value_out = weights[c] * (value / self.area * pitch * pitch);
        }
    }
}

impl FarField {
    /// One straight edge's L²(x·n̂)²⟨sinc²⟩ per plane in the pixel at
    /// (x, y): the sinc² averaged across the ray over the strip the pixel
    /// covers (as wide as the square's projection).
    fn edge_term(
        &self,
        &(l2, n, a, l_over_f): &(f64, [f64; 2], [f64; 2], f64),
        x: f64,
        y: f64,
        pitch: f64,
        planes: usize,
    ) -> [f64; 3] {
        let along = x * n[0] + y * n[1];
        let across = x * a[0] + y * a[1];
        let half = 0.5 * pitch * (a[0].abs() + a[1].abs());
        let (u1, u2) = ((across - half) * l_over_f, (across + half) * l_over_f);
        let (a1, a2) = (u1.abs(), u2.abs());
        let (i1, i2) = (1.0 / a1, 1.0 / a2);
        let mut term = [0.0; 3];
        for (t, table) in term.iter_mut().zip(&self.tables[..planes]) {
            let mean = (table.at(u2, a2, i2) - table.at(u1, a1, i1)) / (u2 - u1);
            *t = l2 * along * along * mean;
        }
        term
    }
}

/// Pairs of straight edges of one polygon with equal lengths and opposite
/// normals: the first's index and the separation of their midpoints, mm.
fn parallel_pairs(edges: &[EdgeTerm]) -> Vec<(usize, [f64; 2])> {
    let mut pairs = Vec::new();
    for (k, a) in edges.iter().enumerate() {
        for b in &edges[k + 1..] {
            let opposite = a.normal[0] * b.normal[0] + a.normal[1] * b.normal[1] < -1.0 + 1e-9;
            let equal = (a.length - b.length).abs() <= 1e-9 * a.length;
            if a.polygon == b.polygon && opposite && equal {
                pairs.push((k, [a.middle[0] - b.middle[0], a.middle[1] - b.middle[1]]));
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
    /// leaves of a range no piece covers is round-off, and 0.
    fn between(&self, from: f64, to: f64) -> f64 {
        let covered = self.integral(to) - self.integral(from);
        if covered > 1e-12 * self.turn {
            covered
        } else {
            0.0
        }
    }

    /// ∫ of the density from −π to `angle` (any angle, whole turns
    /// counted).
    fn integral(&self, angle: f64) -> f64 {
        use std::f64::consts::{PI, TAU};
        let turns = ((angle + PI) / TAU).floor();
        let a = angle - turns * TAU;
        let k = self.points.partition_point(|p| p.0 <= a).max(1) - 1;
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
