//! The stop of an anamorphic lens as its image sees it (docs/physics.md
//! §6): a lens whose focal length across x is f/s forms the pattern
//! |Â(x/(λf/s), y/(λf))|², which is the pattern at f of the pupil
//! stretched s times along x, A(u/s, v). So the pupil is stretched and
//! everything after it is a round lens's.

use super::{Element, Outline, Pupil};

/// Straight pieces a disc's ellipse is sampled by: its area within 10⁻⁴
/// of the ellipse's, its far field treated as the curve they sample.
const ELLIPSE_PIECES: usize = 256;

impl Pupil {
    /// This pupil stretched `s` times along x. Polygons stay polygons and
    /// discs become ellipses (sampled polygons); spots of dirt move with
    /// the glass and keep their area, round: their own faint halos are
    /// not squeezed.
    pub fn stretched(&self, s: f64) -> Pupil {
        let mut out = Pupil::new();
        let at = |p: [f64; 2]| [p[0] * s, p[1]];
        for Element { shape, weight, .. } in &self.elements {
            let transmits = weight[0] > 0.0;
            match shape {
                Outline::Polygon {
                    made: (vertices, pieces),
                    ..
                } => {
                    let moved: Vec<[f64; 2]> = vertices.iter().map(|&p| at(p)).collect();
                    out.add_sampled_polygon(&moved, transmits, *pieces);
                }
                Outline::Disc { centre, radius } => {
                    let ellipse: Vec<[f64; 2]> = (0..ELLIPSE_PIECES)
                        .map(|k| {
                            let theta = std::f64::consts::TAU * k as f64 / ELLIPSE_PIECES as f64;
                            let (sin, cos) = libm::sincos(theta);
                            [centre[0] * s + radius * s * cos, centre[1] + radius * sin]
                        })
                        .collect();
                    out.add_sampled_polygon(&ellipse, transmits, ELLIPSE_PIECES);
                }
                Outline::Spot { centre, radius } => {
                    let amplitude = [weight[0] + 1.0, weight[1]];
                    out.add_spot(at(*centre), radius * s.sqrt(), amplitude);
                }
            }
        }
        out
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_stretched_pupil_transmits_where_the_pupil_did_and_its_transform_is_squeezed() {
        let s = 1.3;
        let mut pupil = Pupil::new();
        pupil.add_polygon(&[[-2.0, -1.0], [3.0, -1.5], [1.0, 2.5]], true);
        pupil.add_disc([0.5, 0.2], 0.4, false);
        let oval = pupil.stretched(s);
        assert!((oval.area() / (s * pupil.area()) - 1.0).abs() < 1e-3);
        for p in [
            [0.0, 0.0],
            [2.5, -1.2],
            [0.5, 0.2],
            [-1.5, -0.5],
            [0.0, 2.0],
        ] {
            let (before, after) = (pupil.transmission(p), oval.transmission([p[0] * s, p[1]]));
            assert_eq!(before, after, "{p:?}");
        }
        // Â'(ν) = s·Â(sν_x, ν_y), to the ellipse's sampling.
        for nu in [[0.0, 0.0], [0.2, -0.1], [0.05, 0.3], [-0.4, 0.25]] {
            let a = pupil.amplitude([s * nu[0], nu[1]]);
            let b = oval.amplitude(nu);
            let size = libm::hypot(a[0], a[1]).max(1e-3);
            assert!(
                (b[0] - s * a[0]).abs() < 2e-3 * s * size
                    && (b[1] - s * a[1]).abs() < 2e-3 * s * size,
                "{nu:?}: {b:?} against {a:?}"
            );
        }
    }
}
