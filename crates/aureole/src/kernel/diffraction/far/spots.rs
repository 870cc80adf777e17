//! Spots of dirt in the far field (docs/physics.md §6): each adds its
//! whole pattern |w|²(πR²)² jinc²(2πrR/(λf)) / ((λf)²·area), jinc(z) =
//! 2J₁(z)/z, incoherently. A speck of dust is a few wavelengths of the
//! far field's start across, where a stop's rim is already in its
//! asymptotic ⟨J₁²⟩ regime and a speck is not; and the cross terms of
//! spots at random places with each other and with the stop turn within a
//! pixel and average out.
//!
//! The patterns are radial: they are summed per plane on a fine radius
//! grid, integrated along the radius, and each pixel takes the mean over
//! its width across the radius. Spots are grouped by size in octaves,
//! each group on a grid fine enough for its largest spot's fringes.

use std::collections::BTreeMap;

use super::{Line, PLANES};
use crate::optics::aperture::jinc::jinc;
use crate::optics::aperture::pupil::SpotTerm;
use rayon::prelude::*;
use std::f64::consts::{PI, TAU};

/// Grid steps per fringe of the largest spot of a group at the shortest
/// wavelength.
const STEPS_PER_FRINGE: f64 = 16.0;

/// One octave of spot sizes, its patterns integrated along the radius.
struct Group {
    /// 1 over the grid's step.
    inverse_step: f64,
    /// ∫₀^r of the planes' sum, at r = k·step, the planes side by side.
    integral: Vec<f64>,
}

pub(super) struct Spots {
    groups: Vec<Group>,
    planes: usize,
}

impl Spots {
    /// The patterns of `spots` in every `line`'s light, out to `reach` mm,
    /// at `pitch` mm per pixel; per plane, the sum over the lines of each
    /// one's share.
    pub(super) fn new(
        spots: &[SpotTerm],
        lines: &[Line],
        planes: usize,
        f: f64,
        pitch: f64,
        reach: f64,
    ) -> Spots {
        let shortest = lines.iter().map(|l| l.lambda).fold(f64::INFINITY, f64::min);
        // By octave, in order: the same groups on every run.
        let mut octaves: BTreeMap<i32, Vec<SpotTerm>> = BTreeMap::new();
        for spot in spots.iter().filter(|s| s.radius > 0.0 && s.power > 0.0) {
            // libm's, so that the groups are the same on every machine.
            let octave = libm::log2(spot.radius).floor() as i32;
            octaves.entry(octave).or_default().push(*spot);
        }
        let groups = octaves
            .into_values()
            .map(|group| {
                let largest = group.iter().map(|s| s.radius).fold(0.0, f64::max);
                let fringe = shortest * f / (2.0 * largest);
                let step = (pitch / 4.0).min(fringe / STEPS_PER_FRINGE);
                let count = (reach / step).ceil() as usize + 2;
                let values: Vec<f64> = (0..count)
                    .into_par_iter()
                    .flat_map_iter(|k| {
                        let r = k as f64 * step;
                        let mut sum = [0.0; PLANES];
                        for line in lines {
                            let lf = line.lambda * f;
                            let light: f64 = group
                                .iter()
                                .map(|s| {
                                    let z = TAU * r * s.radius / lf;
                                    let area = PI * s.radius * s.radius;
                                    s.power * (area * jinc(z)).powi(2)
                                })
                                .sum::<f64>()
                                / (lf * lf);
                            for (c, value) in sum.iter_mut().take(planes).enumerate() {
                                *value += line.shares[c] * light;
                            }
                        }
                        sum.into_iter().take(planes)
                    })
                    .collect();
                // Trapezoids along the radius, in order.
                let mut integral = vec![0.0; values.len()];
                for k in 1..count {
                    for c in 0..planes {
                        let (a, b) = (values[(k - 1) * planes + c], values[k * planes + c]);
                        integral[k * planes + c] =
                            integral[(k - 1) * planes + c] + 0.5 * step * (a + b);
                    }
                }
                Group {
                    inverse_step: 1.0 / step,
                    integral,
                }
            })
            .collect();
        Spots { groups, planes }
    }

    pub(super) fn is_empty(&self) -> bool {
        self.groups.is_empty()
    }

    /// Each plane's pattern at `r` mm, the mean over `width` mm across
    /// the radius, added into `out`.
    pub(super) fn add(&self, r: f64, width: f64, out: &mut [f64; PLANES]) {
        let p = self.planes;
        // Multiplications, not the divisions a pixel would wait on.
        let per_width = 1.0 / width;
        for group in &self.groups {
            let nodes = group.integral.len() / p;
            // The two nodes about `r` and where it lies between them, for
            // every plane at once (r ≥ 0: truncation is the floor).
            let place = |r: f64| {
                let position = (r.max(0.0) * group.inverse_step).min((nodes - 1) as f64);
                let k = (position as usize).min(nodes - 2);
                (&group.integral[k * p..(k + 2) * p], position - k as f64)
            };
            let ((outer, t_outer), (inner, t_inner)) =
                (place(r + width / 2.0), place(r - width / 2.0));
            for (c, value) in out.iter_mut().take(p).enumerate() {
                let at = |pair: &[f64], t: f64| pair[c] + t * (pair[p + c] - pair[c]);
                *value += (at(outer, t_outer) - at(inner, t_inner)) * per_width;
            }
        }
    }
}
