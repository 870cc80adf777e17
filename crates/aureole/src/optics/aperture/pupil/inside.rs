//! Where a pupil lets light through: the amplitude it transmits at a
//! point, and where a set of points lies against a convex opening, which
//! a lens's ghosts clip their bundles' cells with (lens/bundle.rs).

use super::{Amplitude, Edge, Outline, Pupil};

impl Pupil {
    /// Where `points` lie, for a pupil whose opening (where it transmits
    /// half or more) is one convex region, a single transmitting polygon
    /// (the points left of all its edges) or disc: all
    /// within its opening (`Some(true)`), all beyond one line that bounds
    /// it (`Some(false)`), each by a margin far above the rounding of a
    /// test, so that every mean of them with weights of 0 or more lies
    /// there too; `None` where neither holds, or for another pupil.
    pub fn convex_side(&self, points: &[[f64; 2]]) -> Option<bool> {
        let [only] = self.elements.as_slice() else {
            return None;
        };
        if only.weight[0] < 0.5 {
            return None;
        }
        match &only.shape {
            Outline::Polygon { edges, reach, .. } => {
                let tolerance = 1e-9 * reach;
                // Each point's distance left of each edge's line.
                let left = |e: &Edge, p: &[f64; 2]| e.cross(*p) / e.length;
                if edges
                    .iter()
                    .any(|e| points.iter().all(|p| left(e, p) <= -tolerance))
                {
                    Some(false)
                } else if edges
                    .iter()
                    .all(|e| points.iter().all(|p| left(e, p) >= tolerance))
                {
                    Some(true)
                } else {
                    None
                }
            }
            Outline::Disc { centre, radius } | Outline::Spot { centre, radius } => {
                let within = radius * (1.0 - 1e-9);
                points
                    .iter()
                    .all(|p| {
                        let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
                        dx * dx + dy * dy <= within * within
                    })
                    .then_some(true)
            }
        }
    }

    /// The amplitude the pupil transmits at `point` (mm).
    pub fn transmission(&self, point: [f64; 2]) -> Amplitude {
        let mut sum = [0.0, 0.0];
        for element in &self.elements {
            let squared = |centre: &[f64; 2]| {
                let (dx, dy) = (point[0] - centre[0], point[1] - centre[1]);
                dx * dx + dy * dy
            };
            let inside = match &element.shape {
                Outline::Disc { centre, radius } | Outline::Spot { centre, radius } => {
                    squared(centre) <= radius * radius
                }
                // Counter-clockwise edges: inside lies left of every one.
                // Well within the inscribed circle (by far more than the
                // edge tests' rounding), a point is.
                Outline::Polygon {
                    edges,
                    centroid,
                    reach,
                    inner,
                    ..
                } => {
                    let d2 = squared(centroid);
                    d2 <= reach * reach
                        && (d2 < inner * inner * (1.0 - 1e-9)
                            || edges.iter().all(|e| e.cross(point) >= 0.0))
                }
            };
            if inside {
                sum[0] += element.weight[0];
                sum[1] += element.weight[1];
            }
        }
        sum
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::optics::aperture::Aperture;

    /// The opening of `blades` blades (0: round) in a circle of 1 mm.
    fn stop(blades: u32, rotation_deg: f64, roundness: f64) -> Pupil {
        let mut aperture = Aperture::new(blades);
        aperture.rotation_deg = rotation_deg;
        aperture.roundness = roundness;
        aperture.stop(1.0)
    }

    /// Whether `p` is left of every edge of the pupil's polygon (within
    /// its disc), tested edge by edge.
    fn inside_by_edges(pupil: &Pupil, p: [f64; 2]) -> bool {
        pupil.elements.iter().all(|element| match &element.shape {
            Outline::Polygon { edges, .. } => edges.iter().all(|e| e.cross(p) >= 0.0),
            Outline::Disc { centre, radius } | Outline::Spot { centre, radius } => {
                (p[0] - centre[0]).powi(2) + (p[1] - centre[1]).powi(2) <= radius * radius
            }
        })
    }

    /// Points spread over [−1.2, 1.2]², the same every run.
    fn points(count: usize) -> impl Iterator<Item = [f64; 2]> {
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = move || {
            state = state
                .wrapping_mul(6_364_136_223_846_793_005)
                .wrapping_add(1_442_695_040_888_963_407);
            (state >> 11) as f64 / (1u64 << 53) as f64 * 2.4 - 1.2
        };
        (0..count).map(move |_| [next(), next()])
    }

    fn stops() -> Vec<Pupil> {
        vec![
            stop(7, 0.0, 0.0),
            stop(5, 17.0, 0.0),
            stop(6, 0.0, 0.6),
            stop(3, 40.0, 0.0),
            stop(0, 0.0, 0.0),
        ]
    }

    #[test]
    fn within_the_inscribed_circle_the_opening_passes_what_its_edges_do() {
        for pupil in stops() {
            for p in points(20_000) {
                assert_eq!(
                    pupil.transmission(p)[0] >= 0.5,
                    inside_by_edges(&pupil, p),
                    "{p:?}"
                );
            }
        }
    }

    /// Where the opening is sure of a cell's four corners, every mean of
    /// them lies on the same side; cells across its edge are left to be
    /// tested point by point.
    #[test]
    fn every_point_between_corners_it_is_sure_of_lies_where_they_do() {
        let mut seen = [0usize; 3];
        for pupil in stops() {
            for centre in points(4_000) {
                let corners = [[0.0, 0.0], [0.07, 0.01], [0.08, 0.09], [-0.01, 0.06]]
                    .map(|d| [centre[0] + d[0], centre[1] + d[1]]);
                let sure = pupil.convex_side(&corners);
                seen[match sure {
                    Some(true) => 0,
                    Some(false) => 1,
                    None => 2,
                }] += 1;
                let Some(side) = sure else { continue };
                for k in 0..64 {
                    let (s, t) = ((k % 8) as f64 / 7.0, (k / 8) as f64 / 7.0);
                    let w = [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t];
                    let p = [0, 1].map(|a| (0..4).map(|c| w[c] * corners[c][a]).sum::<f64>());
                    assert_eq!(pupil.transmission(p)[0] >= 0.5, side, "{p:?} {corners:?}");
                }
            }
        }
        assert!(seen.iter().all(|&n| n > 100), "{seen:?}");
        // A pupil of more than one element is never sure.
        let mut obstructed = stop(0, 0.0, 0.0);
        obstructed.add_disc([0.0, 0.0], 0.3, false);
        assert_eq!(obstructed.convex_side(&[[0.9, 0.0]; 4]), None);
    }
}
