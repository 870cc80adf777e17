//! An edge's light averaged over a pixel: the cumulative tables of its
//! sinc² (G and H, [`Cumulative`]) and, per edge, the means over the
//! pixels' footprint as a function of the offset across its ray
//! ([`Received`]).

use std::f64::consts::PI;

use super::{spread, PLANES};
use crate::kernel::Sending;
use crate::optics::aperture::pupil::sinc;

/// G(u) = ∫₀ᵘ g and H(u) = ∫₀ᵘ G, g(u) = Σ w sinc²(πu/λ) / Σ w, for each
/// plane's weights on one grid, tabulated finely, with the tail
/// g ≈ ⟨λ²⟩/(2π²u²) beyond.
pub(super) struct Cumulative {
    pub(super) planes: usize,
    pub(super) step: f64,
    /// G at the nodes, the planes side by side.
    pub(super) values: Vec<f64>,
    /// H at the nodes, likewise.
    pub(super) seconds: Vec<f64>,
    /// Per plane, ⟨λ²⟩/(2π²).
    pub(super) tail: [f64; PLANES],
    /// Where the table ends, and 1 over it.
    pub(super) end: f64,
    pub(super) inverse_end: f64,
}

impl Cumulative {
    /// The table of each plane's `light` (λ mm, weight), out to 32 times
    /// the longest wavelength for many lines (their ⟨sinc²⟩ has lost its
    /// fringes well before) and 256 times for one.
    pub(super) fn new(light: &[Vec<(f64, f64)>]) -> Cumulative {
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
    pub(super) fn first(&self, u: f64) -> [f64; PLANES] {
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
    pub(super) fn second(&self, u: f64) -> [f64; PLANES] {
        let (a, p) = (u.abs(), self.planes);
        let mut out = [0.0; PLANES];
        if a >= self.end {
            let last = self.values.len() - p;
            let log = libm::log(a / self.end);
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

    /// The mean of every plane's g that a pixel receives, as `sending`
    /// sends it: from a point, over the pixel's square ([`Cumulative::mean`]);
    /// from a pixel, under its tent, whose width along u is the square's
    /// trapezoid T convolved with itself: the square's mean at the
    /// sending pixel's offsets s along u, T's distribution, by the
    /// symmetric three-point rule that holds T's moments to the fifth
    /// (nodes 0 and ±√(m₄/m₂), m₂ = (β² + γ²)/3 and
    /// m₄ = (β⁴ + γ⁴)/5 + 2β²γ²/3 its second and fourth moments; for
    /// γ = 0, Gauss–Legendre's three points).
    #[inline]
    pub(super) fn received(
        &self,
        c: f64,
        beta: f64,
        gamma: f64,
        sending: Sending,
    ) -> [f64; PLANES] {
        if sending == Sending::Point {
            return self.mean(c, beta, gamma);
        }
        let (b2, g2) = (beta * beta, gamma * gamma);
        let m2 = (b2 + g2) / 3.0;
        let m4 = (b2 * b2 + g2 * g2) / 5.0 + 2.0 * b2 * g2 / 3.0;
        let (d, side) = ((m4 / m2).sqrt(), m2 * m2 / (2.0 * m4));
        let (middle, before, after) = (
            self.mean(c, beta, gamma),
            self.mean(c - d, beta, gamma),
            self.mean(c + d, beta, gamma),
        );
        let mut out = [0.0; PLANES];
        for k in 0..self.planes {
            out[k] = (1.0 - 2.0 * side) * middle[k] + side * (before[k] + after[k]);
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
    pub(super) fn mean(&self, c: f64, beta: f64, gamma: f64) -> [f64; PLANES] {
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

/// Nodes of [`Received`] per shortest wavelength in u.
const RECEIVED_NODES: f64 = 256.0;

/// The most nodes of a [`Received`] that follow the pixel's footprint:
/// about 900 for a 4K kernel's blades at f/11, 11 000 for a 320 px wide
/// image's (which keep every node). The footprint grows with the pixel,
/// and a thumbnail's pixel spans thousands of wavelengths (a 3 px wide
/// image through a 6-blade stop held 280 MB of tables for 15 pixels);
/// beyond the table a pixel's mean is computed from
/// [`Cumulative::received`] itself, which the table only interpolates.
pub(super) const MOST_FOOTPRINT: f64 = 16384.0;

/// One edge's [`Cumulative::received`] as a function of the offset u
/// across its ray alone: every pixel projects onto u with the same β and
/// γ, so the mean is tabulated once per edge, every λ/256 of the shortest
/// wavelength, and interpolated by four points. The mean is g averaged
/// over a footprint, and g, a sum of sinc²(πu/λ), holds no frequency above
/// 1/λ in u: its fourth derivative is at most (2π/λ)⁴ times its size
/// about there, so where the footprint spans a node of the table (every
/// blade's pixels) the interpolation adds less than (2π/256)⁴·3/128 ≈
/// 10⁻⁸ to the table's own error. A narrower footprint (the ends of a
/// scratch) takes its mean from the slope of G between two nodes, a step
/// from node to node, which the interpolation smooths: it errs no more
/// than the table does. A pixel costs four loads per plane instead of the
/// twelve Hermite evaluations of the table a tent's three squares take.
pub(super) struct Received {
    pub(super) planes: usize,
    pub(super) inverse_step: f64,
    /// The mean at u = k·step for k = −1, 0, 1, … (even in u), the planes
    /// side by side.
    pub(super) values: Vec<f64>,
}

impl Received {
    /// The means of `table` for an edge whose pixels project as `beta`
    /// and `gamma`, sent as `sending`, out to `pattern` in u and the
    /// pixel's footprint beyond (at most [`MOST_FOOTPRINT`] nodes of it),
    /// and no further than `limit`: every pixel whose mean the pattern
    /// within `pattern` reaches lies within it and a pixel's step beyond.
    pub(super) fn new(
        table: &Cumulative,
        (beta, gamma): (f64, f64),
        sending: Sending,
        (pattern, limit): (f64, f64),
    ) -> Received {
        let step = table.step * 32.0 / RECEIVED_NODES;
        let planes = table.planes;
        let footprint =
            (spread(beta, gamma, sending) + 2.0 * (beta + gamma)).min(MOST_FOOTPRINT * step);
        let nodes = ((pattern + footprint).min(limit) / step).ceil() as usize + 3;
        let mut values = Vec::with_capacity((nodes + 1) * planes);
        for k in 0..=nodes {
            let u = (k as f64 - 1.0) * step;
            values.extend_from_slice(&table.received(u, beta, gamma, sending)[..planes]);
        }
        Received {
            planes,
            inverse_step: 1.0 / step,
            values,
        }
    }

    /// The mean at `u`, or `None` beyond the table.
    #[inline]
    pub(super) fn at(&self, u: f64) -> Option<[f64; PLANES]> {
        let position = u.abs() * self.inverse_step;
        let k = position as usize;
        let p = self.planes;
        let nodes = self.values.get(k * p..(k + 4) * p)?;
        let t = position - k as f64;
        let (before, after) = (t + 1.0, t - 1.0);
        const SIXTH: f64 = 1.0 / 6.0;
        let weights = [
            -t * after * (t - 2.0) * SIXTH,
            before * after * (t - 2.0) * 0.5,
            -before * t * (t - 2.0) * 0.5,
            before * t * after * SIXTH,
        ];
        let mut out = [0.0; PLANES];
        for (c, o) in out[..p].iter_mut().enumerate() {
            *o = weights[0] * nodes[c]
                + weights[1] * nodes[p + c]
                + weights[2] * nodes[2 * p + c]
                + weights[3] * nodes[3 * p + c];
        }
        Some(out)
    }
}
