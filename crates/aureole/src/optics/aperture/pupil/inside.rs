//! Where a pupil lets light through: the amplitude it transmits at a
//! point, and where a set of points lies against a convex opening, which
//! a lens's ghosts clip their bundles' cells with (lens/bundle.rs).

use super::{Amplitude, Edge, Outline, Pupil};

/// Where a set of points lies against a pupil's opening (where it
/// transmits half or more): [`Pupil::side`].
pub enum Side<'a> {
    /// All within it, and every mean of them with weights of 0 or more.
    Within,
    /// All beyond one line that bounds it, and every such mean.
    Beyond,
    /// Neither is sure: each mean is tested by [`Crossing::opens`].
    Across(Crossing<'a>),
}

/// How the means of a set of points that lies across a pupil's opening
/// are tested: for one transmitting polygon, against only the edges
/// whose lines pass between the points (one or two of a stop's blades),
/// the others passing them all by far more than a test's rounding.
pub struct Crossing<'a> {
    pupil: &'a Pupil,
    /// The polygon's centroid and reach, and the edges to test.
    polygon: Option<([f64; 2], f64, Vec<&'a Edge>)>,
}

impl Crossing<'_> {
    /// Whether the pupil opens at `point`, a mean with weights of 0 or
    /// more of the points this was made for: the answer of
    /// `transmission(point)[0] >= 0.5`.
    pub fn opens(&self, point: [f64; 2]) -> bool {
        match &self.polygon {
            Some((centroid, reach, edges)) => {
                let (dx, dy) = (point[0] - centroid[0], point[1] - centroid[1]);
                dx * dx + dy * dy <= reach * reach && edges.iter().all(|e| e.cross(point) >= 0.0)
            }
            None => self.pupil.transmission(point)[0] >= 0.5,
        }
    }
}

impl Pupil {
    /// Where `points` lie against the opening ([`Side`]). Only an opening
    /// that is one convex region, a single transmitting polygon (the
    /// points left of all its edges) or disc, is ever sure, and each
    /// point must lie by a margin far above the rounding of a test, so
    /// that every mean of them with weights of 0 or more lies there too.
    pub fn side(&self, points: &[[f64; 2]]) -> Side<'_> {
        let across = Side::Across(Crossing {
            pupil: self,
            polygon: None,
        });
        let [only] = self.elements.as_slice() else {
            return across;
        };
        if only.weight[0] < 0.5 {
            return across;
        }
        match &only.shape {
            Outline::Polygon {
                edges,
                centroid,
                reach,
                ..
            } => {
                let tolerance = 1e-9 * reach;
                // Each point's distance left of each edge's line.
                let left = |e: &Edge, p: &[f64; 2]| e.cross(*p) / e.length;
                let mut cut: Vec<&Edge> = Vec::new();
                for e in edges {
                    if points.iter().all(|p| left(e, p) <= -tolerance) {
                        return Side::Beyond;
                    }
                    if !points.iter().all(|p| left(e, p) >= tolerance) {
                        cut.push(e);
                    }
                }
                if cut.is_empty() {
                    Side::Within
                } else {
                    Side::Across(Crossing {
                        pupil: self,
                        polygon: Some((*centroid, *reach, cut)),
                    })
                }
            }
            Outline::Disc { centre, radius } | Outline::Spot { centre, radius } => {
                let within = radius * (1.0 - 1e-9);
                let all = points.iter().all(|p| {
                    let (dx, dy) = (p[0] - centre[0], p[1] - centre[1]);
                    dx * dx + dy * dy <= within * within
                });
                if all {
                    Side::Within
                } else {
                    across
                }
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
    /// them lies on the same side; across its edge, each mean is tested
    /// against the edges between them as against the whole pupil.
    #[test]
    fn every_point_between_corners_it_is_sure_of_lies_where_they_do() {
        let mut seen = [0usize; 3];
        for pupil in stops() {
            for centre in points(4_000) {
                let corners = [[0.0, 0.0], [0.07, 0.01], [0.08, 0.09], [-0.01, 0.06]]
                    .map(|d| [centre[0] + d[0], centre[1] + d[1]]);
                let side = pupil.side(&corners);
                seen[match side {
                    Side::Within => 0,
                    Side::Beyond => 1,
                    Side::Across(_) => 2,
                }] += 1;
                for k in 0..64 {
                    let (s, t) = ((k % 8) as f64 / 7.0, (k / 8) as f64 / 7.0);
                    let w = [(1.0 - s) * (1.0 - t), s * (1.0 - t), s * t, (1.0 - s) * t];
                    let p = [0, 1].map(|a| (0..4).map(|c| w[c] * corners[c][a]).sum::<f64>());
                    let opens = match &side {
                        Side::Within => true,
                        Side::Beyond => false,
                        Side::Across(crossing) => crossing.opens(p),
                    };
                    assert_eq!(pupil.transmission(p)[0] >= 0.5, opens, "{p:?} {corners:?}");
                }
            }
        }
        assert!(seen.iter().all(|&n| n > 100), "{seen:?}");
        // A pupil of more than one element is never sure.
        let mut obstructed = stop(0, 0.0, 0.0);
        obstructed.add_disc([0.0, 0.0], 0.3, false);
        assert!(matches!(obstructed.side(&[[0.9, 0.0]; 4]), Side::Across(_)));
    }
}
