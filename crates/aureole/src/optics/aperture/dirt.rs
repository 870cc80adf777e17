//! Dirt on the lens, in the pupil the diffraction is computed from
//! (docs/physics.md §6): specks of dust (opaque discs), scratches (opaque
//! strips) and a smudge of grease (a disc that passes part of the light
//! and delays it), placed at random from the config's seed inside the
//! stop's inscribed circle, clear of the obstruction, the vanes and each
//! other, so that each lies on clear glass.
//!
//! For a star at infinity the beam fills the entrance pupil; on the front
//! element, near it, dirt lies in that beam at its own size, and the far
//! field is the transform of what the beam carries past it.

use std::f64::consts::PI;

use rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg64;

use super::pupil::Pupil;
use crate::check;
use crate::error::Result;

/// How many places are tried for one piece before the dirt is refused.
const TRIES: usize = 10_000;

/// The dirt of an aperture, sizes in mm.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct Dirt {
    pub dust: u32,
    /// Diameters, drawn uniformly in their logarithm.
    pub dust_diameters: [f64; 2],
    pub scratches: u32,
    pub scratch_length: f64,
    pub scratch_width: f64,
    /// Their mean direction and the spread about it, radians.
    pub scratch_angle: f64,
    pub scratch_spread: f64,
    /// The smudge's diameter as a fraction of the pupil's; 0 for none.
    pub grease: f64,
    /// The amplitude the smudge passes, a·e^(iφ).
    pub grease_amplitude: [f64; 2],
}

/// What the dirt must keep clear of: all within `inner` mm of the centre,
/// outside `obstruction` mm, and off the vanes (segments with a half
/// width).
pub(crate) struct Clearance {
    pub inner: f64,
    pub obstruction: f64,
    pub vanes: Vec<Strip>,
}

/// A straight strip: its axis from `start` to `end`, `half` its half
/// width.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Strip {
    pub start: [f64; 2],
    pub end: [f64; 2],
    pub half: f64,
}

impl Strip {
    /// Its four corners, in order around it.
    pub fn corners(&self) -> [[f64; 2]; 4] {
        let d = [self.end[0] - self.start[0], self.end[1] - self.start[1]];
        let length = libm::hypot(d[0], d[1]);
        let n = [-d[1] / length * self.half, d[0] / length * self.half];
        [
            [self.start[0] - n[0], self.start[1] - n[1]],
            [self.end[0] - n[0], self.end[1] - n[1]],
            [self.end[0] + n[0], self.end[1] + n[1]],
            [self.start[0] + n[0], self.start[1] + n[1]],
        ]
    }
}

/// A disc or a strip already placed.
enum Piece {
    Disc([f64; 2], f64),
    Strip(Strip),
}

impl Piece {
    /// Whether a disc at `c` of radius `r` keeps clear of it.
    fn clear_of_disc(&self, c: [f64; 2], r: f64) -> bool {
        match self {
            Piece::Disc(d, s) => distance(c, *d) > r + s,
            Piece::Strip(strip) => to_segment(c, strip.start, strip.end) > r + strip.half,
        }
    }

    fn clear_of_strip(&self, strip: &Strip) -> bool {
        match self {
            Piece::Disc(c, r) => to_segment(*c, strip.start, strip.end) > r + strip.half,
            Piece::Strip(other) => {
                segments_apart(strip.start, strip.end, other.start, other.end)
                    > strip.half + other.half
            }
        }
    }
}

/// A uniform deviate in [0, 1).
fn uniform(rng: &mut Pcg64) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Adds `dirt` to `pupil` (radius `radius` mm) clear of `clearance`, from
/// `seed`. Refuses dirt that does not fit, naming the piece. The places
/// are drawn with libm's functions, the same on every machine.
pub(crate) fn add(
    dirt: &Dirt,
    radius: f64,
    clearance: &Clearance,
    seed: u64,
    pupil: &mut Pupil,
) -> Result<()> {
    let mut rng = Pcg64::seed_from_u64(seed);
    // The obstruction is a disc at the centre (of radius 0 without one:
    // no piece covers the centre).
    let mut placed: Vec<Piece> = clearance.vanes.iter().map(|v| Piece::Strip(*v)).collect();
    placed.push(Piece::Disc([0.0, 0.0], clearance.obstruction));
    let inner = clearance.inner;
    let clear_disc = |placed: &[Piece], c: [f64; 2], r: f64| {
        libm::hypot(c[0], c[1]) + r < inner && placed.iter().all(|p| p.clear_of_disc(c, r))
    };
    // A point uniformly in the disc of radius `within`.
    let point = |rng: &mut Pcg64, within: f64| {
        let (u, v) = (uniform(rng), uniform(rng));
        let (rho, theta) = (within * libm::sqrt(u), 2.0 * PI * v);
        [rho * libm::cos(theta), rho * libm::sin(theta)]
    };
    if dirt.grease > 0.0 {
        let r = dirt.grease * radius;
        let found = (0..TRIES)
            .map(|_| point(&mut rng, (inner - r).max(0.0)))
            .find(|&c| clear_disc(&placed, c, r));
        let Some(centre) = found else {
            return check::count(NAME, "grease", dirt.grease, false, GREASE_FITS);
        };
        pupil.add_spot(centre, r, dirt.grease_amplitude);
        placed.push(Piece::Disc(centre, r));
    }
    let half = dirt.scratch_width / 2.0;
    for _ in 0..dirt.scratches {
        let strip = (0..TRIES).find_map(|_| {
            let centre = point(&mut rng, inner);
            let angle = dirt.scratch_angle + dirt.scratch_spread * (uniform(&mut rng) - 0.5);
            let direction = [libm::cos(angle), libm::sin(angle)];
            // A scratch longer than the beam is cut by its edge.
            let along = chord(centre, direction, inner - half)?;
            let reach = dirt.scratch_length / 2.0;
            let (a, b) = (along[0].max(-reach), along[1].min(reach));
            let at = |t: f64| [centre[0] + t * direction[0], centre[1] + t * direction[1]];
            let strip = Strip {
                start: at(a),
                end: at(b),
                half,
            };
            let clear = b - a > 2.0 * half && placed.iter().all(|p| p.clear_of_strip(&strip));
            clear.then_some(strip)
        });
        let Some(strip) = strip else {
            return check::count(NAME, "scratches", dirt.scratches, false, SCRATCHES_FIT);
        };
        pupil.add_polygon(&strip.corners(), false);
        placed.push(Piece::Strip(strip));
    }
    let [small, large] = dirt.dust_diameters;
    for _ in 0..dirt.dust {
        let r = small * libm::pow(large / small, uniform(&mut rng)) / 2.0;
        let found = (0..TRIES)
            .map(|_| point(&mut rng, inner - r))
            .find(|&c| clear_disc(&placed, c, r));
        let Some(centre) = found else {
            return check::count(NAME, "dust", dirt.dust, false, DUST_FITS);
        };
        pupil.add_spot(centre, r, [0.0, 0.0]);
        placed.push(Piece::Disc(centre, r));
    }
    Ok(())
}

const GREASE_FITS: &str =
    "a smudge that fits in the stop clear of the obstruction and the vanes: make it smaller";
const SCRATCHES_FIT: &str =
    "scratches that fit in the stop without crossing each other, the obstruction or the vanes: fewer or narrower";
const DUST_FITS: &str =
    "specks that fit in the stop without touching each other or the other dirt: fewer or smaller";

/// The effect whose dirt is refused.
const NAME: &str = "aperture";

/// The part of the line `centre` + t·`direction` inside the circle of
/// `radius` about the origin, as [t₀, t₁].
fn chord(centre: [f64; 2], direction: [f64; 2], radius: f64) -> Option<[f64; 2]> {
    let b = centre[0] * direction[0] + centre[1] * direction[1];
    let c = centre[0] * centre[0] + centre[1] * centre[1] - radius * radius;
    let discriminant = b * b - c;
    (discriminant > 0.0).then(|| {
        let root = libm::sqrt(discriminant);
        [-b - root, -b + root]
    })
}

fn distance(a: [f64; 2], b: [f64; 2]) -> f64 {
    libm::hypot(a[0] - b[0], a[1] - b[1])
}

/// The distance from `p` to the segment from `a` to `b`.
fn to_segment(p: [f64; 2], a: [f64; 2], b: [f64; 2]) -> f64 {
    let d = [b[0] - a[0], b[1] - a[1]];
    let length2 = d[0] * d[0] + d[1] * d[1];
    let t = if length2 > 0.0 {
        (((p[0] - a[0]) * d[0] + (p[1] - a[1]) * d[1]) / length2).clamp(0.0, 1.0)
    } else {
        0.0
    };
    distance(p, [a[0] + t * d[0], a[1] + t * d[1]])
}

/// The distance between two segments (0 where they cross).
fn segments_apart(a: [f64; 2], b: [f64; 2], c: [f64; 2], d: [f64; 2]) -> f64 {
    let side = |p: [f64; 2], q: [f64; 2], r: [f64; 2]| {
        (q[0] - p[0]) * (r[1] - p[1]) - (q[1] - p[1]) * (r[0] - p[0])
    };
    let crosses = side(a, b, c) * side(a, b, d) < 0.0 && side(c, d, a) * side(c, d, b) < 0.0;
    if crosses {
        0.0
    } else {
        to_segment(a, c, d)
            .min(to_segment(b, c, d))
            .min(to_segment(c, a, b))
            .min(to_segment(d, a, b))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn segments_apart_is_zero_when_they_cross_and_the_gap_otherwise() {
        assert_eq!(
            segments_apart([-1.0, 0.0], [1.0, 0.0], [0.0, -1.0], [0.0, 1.0]),
            0.0
        );
        let gap = segments_apart([-1.0, 0.0], [1.0, 0.0], [0.0, 0.5], [0.0, 2.0]);
        assert!((gap - 0.5).abs() < 1e-12);
        let ends = segments_apart([0.0, 0.0], [1.0, 0.0], [2.0, 0.0], [3.0, 0.0]);
        assert!((ends - 1.0).abs() < 1e-12);
    }

    #[test]
    fn a_chord_is_cut_by_the_circle() {
        let [a, b] = chord([0.0, 0.5], [1.0, 0.0], 1.0).unwrap_or_default();
        let half = (1.0f64 - 0.25).sqrt();
        assert!((a + half).abs() < 1e-12 && (b - half).abs() < 1e-12);
        assert!(chord([0.0, 2.0], [1.0, 0.0], 1.0).is_none());
    }
}
