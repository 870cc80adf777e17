//! Curved sides: each piece of a rounded blade fans its light over the
//! turn of its normal (stationary phase), a wedge-shaped ray.

/// The light the pieces of curved sides fan out, as a density over the
/// direction θ of the normal: each piece (ρ its radius of curvature, its
/// normal's angle, the turn [before, after] it covers) adds ρ over its
/// range of directions, and again half a turn on (a side sends light both
/// ways). A pixel's share is the integral over the angle it spans, which
/// the cumulative integral gives with two lookups whatever the number of
/// pieces.
pub(super) struct Fans {
    /// Breakpoints in [−π, π), ascending, with the integral from −π up to
    /// each and the density after it.
    points: Vec<(f64, f64, f64)>,
    /// The integral over a whole turn.
    turn: f64,
}

impl Fans {
    pub(super) fn new(pieces: impl Iterator<Item = (f64, f64, [f64; 2])>) -> Fans {
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

    pub(super) fn is_empty(&self) -> bool {
        self.turn == 0.0
    }

    /// ∫ of the density from `from` to `to`: what the cumulative integral
    /// leaves of a range no piece covers is round-off, and 0. `hints` are
    /// where the search for each end starts, and where it ended.
    pub(super) fn between(&self, from: f64, to: f64, hints: &mut [usize; 2]) -> f64 {
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
