//! The near field of a diffraction pattern: |Â(x/(λf))|² evaluated exactly
//! from the pupil's closed-form transform and integrated over each pixel
//! (and, for a kernel of an image, under its tent: the sending pixel's area
//! too, docs/physics.md §2) by Gauss–Legendre quadrature, for every
//! wavelength (§6).
//!
//! The pattern is band-limited: |Â|² holds spatial frequencies up to
//! D/(λf) = 1/(λN) in the focal plane, so over a pixel p wide it is an
//! entire function with at most p/(λN) cycles, which Gauss–Legendre
//! integrates with an error that falls exponentially once the points per
//! axis exceed about π/2 of the cycles. The count follows λN: two points
//! where the pixel is a small part of a fringe, more where it holds many.

use super::Spectrum;
use crate::kernel::Sending;
use crate::optics::aperture::pupil::Offsets;
use crate::optics::aperture::Optics;

/// The most Gauss–Legendre points per axis: enough down to λN = 0.3 px.
/// Below, pixels span more fringes than points; the rings there average
/// out within a pixel and the pixel's share, not its fringes, is what
/// shows, while the cost grows as the square (a 720p kernel on a 35 mm
/// lens would take three times as long with the count uncapped).
const MOST_POINTS: usize = 10;

/// The most points per axis in the centre pixel and its neighbours, which
/// hold most of the light: there the count is never capped at
/// [`MOST_POINTS`] (48 points resolve λN down to 0.05 px).
const MOST_CORE_POINTS: usize = 48;

/// How a pixel of the near field is sampled, for one pupil and light.
pub(super) struct NearField<'a> {
    optics: &'a Optics,
    spectrum: &'a Spectrum,
    pitch_mm: f64,
    /// The quadrature offsets and weights of a pixel, per wavelength.
    offsets: Vec<Offsets>,
    /// Those of the centre pixel and its eight neighbours.
    core_offsets: Vec<Offsets>,
    /// For light sent by a pixel: the unit squares between four pixel
    /// centres, per wavelength ([`NearField::add_squares`]).
    squares: Vec<Squares>,
    /// Those of the sixteen squares within 2 px of the centre.
    core_squares: Vec<Squares>,
}

/// A unit square between four pixel centres, sampled once for the four
/// pixels whose tents cover it: a pixel's Gauss–Legendre points, and per
/// corner pixel (top left, top right, bottom left, bottom right) the
/// weights that carry its tent over the square.
struct Squares {
    offsets: Offsets,
    corners: [Vec<f64>; 4],
}

/// The corners of a square in [`Squares::corners`] order.
pub(super) const CORNERS: usize = 4;

impl<'a> NearField<'a> {
    pub fn new(
        optics: &'a Optics,
        spectrum: &'a Spectrum,
        (pitch_mm, sending): (f64, Sending),
    ) -> NearField<'a> {
        NearField::with_points(optics, spectrum, pitch_mm, sending, |c| {
            points_per_axis(c).min(MOST_POINTS)
        })
    }

    /// With `points`(p/(λN)) Gauss–Legendre points per axis (the core's
    /// never fewer than [`points_per_axis`]).
    fn with_points(
        optics: &'a Optics,
        spectrum: &'a Spectrum,
        pitch_mm: f64,
        sending: Sending,
        points: fn(f64) -> usize,
    ) -> NearField<'a> {
        let core_points = |c| points(c).max(points_per_axis(c));
        let (squares, core_squares) = match sending {
            Sending::Pixel => (
                squares(optics, spectrum, pitch_mm, points),
                squares(optics, spectrum, pitch_mm, core_points),
            ),
            Sending::Point => (Vec::new(), Vec::new()),
        };
        NearField {
            optics,
            spectrum,
            pitch_mm,
            offsets: quadrature(optics, spectrum, pitch_mm, sending, points),
            core_offsets: quadrature(optics, spectrum, pitch_mm, sending, core_points),
            squares,
            core_squares,
        }
    }
}

#[cfg(test)]
impl<'a> NearField<'a> {
    /// With twice the points and more: exact to 10⁻⁶ (the tests below), a
    /// reference for the patterns built from the near field.
    pub(super) fn exact(
        optics: &'a Optics,
        spectrum: &'a Spectrum,
        (pitch_mm, sending): (f64, Sending),
    ) -> NearField<'a> {
        NearField::with_points(optics, spectrum, pitch_mm, sending, |c| {
            2 * points_per_axis(c) + 8
        })
    }
}

/// The offsets and weights of a pixel's `points`(p/(λN))² points, or its
/// tent's (2 `points`)² for light sent by a pixel, per wavelength of
/// `spectrum`.
fn quadrature(
    optics: &Optics,
    spectrum: &Spectrum,
    pitch_mm: f64,
    sending: Sending,
    points: impl Fn(f64) -> usize,
) -> Vec<Offsets> {
    per_line(optics, spectrum, pitch_mm, points, |n| {
        let (nodes, weights) = match sending {
            Sending::Pixel => tent(n),
            Sending::Point => square(n),
        };
        tensor(&nodes, &weights)
    })
    .into_iter()
    .map(|(grid, scale)| {
        let (dx, dy) = grid
            .iter()
            .map(|&(s, t, _)| (pitch_mm * s * scale, pitch_mm * t * scale))
            .unzip();
        optics
            .pupil
            .offsets(dx, dy, grid.iter().map(|&(_, _, w)| w).collect())
    })
    .collect()
}

/// The [`Squares`] of `points`(p/(λN))² points, per wavelength.
fn squares(
    optics: &Optics,
    spectrum: &Spectrum,
    pitch_mm: f64,
    points: impl Fn(f64) -> usize,
) -> Vec<Squares> {
    per_line(optics, spectrum, pitch_mm, points, |n| {
        let (nodes, weights) = square(n);
        tensor(&nodes, &weights)
    })
    .into_iter()
    .map(|(grid, scale)| {
        let mut corners: [Vec<f64>; 4] = Default::default();
        for &(s, t, w) in &grid {
            // A corner pixel's tent is 1 at its centre and 0 at the far
            // side: s, t in [−½, ½], y up.
            let (left, right, top, bottom) = (0.5 - s, 0.5 + s, 0.5 + t, 0.5 - t);
            let shares = [left * top, right * top, left * bottom, right * bottom];
            for (corner, share) in corners.iter_mut().zip(shares) {
                corner.push(w * share);
            }
        }
        let (dx, dy) = grid
            .iter()
            .map(|&(s, t, _)| (pitch_mm * s * scale, pitch_mm * t * scale))
            .unzip();
        let w = grid.iter().map(|&(_, _, w)| w).collect();
        Squares {
            offsets: optics.pupil.offsets(dx, dy, w),
            corners,
        }
    })
    .collect()
}

/// Per wavelength of `spectrum`, `build`(`points`(p/(λN))) and the scale
/// 1/(λf) from mm on the sensor to the pupil's frequencies.
fn per_line<T>(
    optics: &Optics,
    spectrum: &Spectrum,
    pitch_mm: f64,
    points: impl Fn(f64) -> usize,
    build: impl Fn(usize) -> T,
) -> Vec<(T, f64)> {
    spectrum
        .iter()
        .map(|(lambda_nm, _)| {
            let lambda_n = lambda_nm * 1e-6 * optics.focal_mm / optics.diameter_mm;
            let scale = 1.0 / (lambda_nm * 1e-6 * optics.focal_mm);
            (build(points(pitch_mm / lambda_n)), scale)
        })
        .collect()
}

/// The tensor grid of `nodes` along both axes: (s, t, weight) with t, the
/// offset up, the slower.
fn tensor(nodes: &[f64], weights: &[f64]) -> Vec<(f64, f64, f64)> {
    nodes
        .iter()
        .zip(weights)
        .flat_map(|(&t, &wt)| {
            nodes
                .iter()
                .zip(weights)
                .map(move |(&s, &ws)| (s, t, ws * wt))
        })
        .collect()
}

impl NearField<'_> {
    /// For light sent by a pixel: the energy of the pattern in unit
    /// squares of one row, centred at (`xs`[i], y) mm, all within 2 px of
    /// the centre or none, weighed by each corner pixel's tent, added into
    /// `out`: per square its [`CORNERS`] corners, per corner `planes`
    /// values. A pixel's light is the sum over the four squares about it,
    /// so every point of the pattern is evaluated once for four pixels.
    pub fn add_squares(&self, xs: &[f64], y: f64, core: bool, out: &mut [f64]) {
        let squares = if core {
            &self.core_squares
        } else {
            &self.squares
        };
        let grids = squares.iter().map(|squares| {
            let sets = squares.corners.iter().map(Vec::as_slice).collect();
            (&squares.offsets, sets)
        });
        self.add_weighed(xs, y, grids, out);
    }

    /// The energy of the pattern in pixels of one row, centred at
    /// (`xs`[i], y) mm, all in the core (the centre pixel and its
    /// neighbours) or none, added into `out`, their values side by side
    /// (`planes` each). The pixels share their sample offsets, which lets
    /// the pupil's transform factor them out ([`Pupil::intensity_sums`]).
    ///
    /// [`Pupil::intensity_sums`]: crate::optics::aperture::pupil::Pupil::intensity_sums
    pub fn add_many(&self, xs: &[f64], y: f64, core: bool, out: &mut [f64]) {
        let offsets = if core {
            &self.core_offsets
        } else {
            &self.offsets
        };
        let grids = offsets
            .iter()
            .map(|offsets| (offsets, vec![offsets.weights()]));
        self.add_weighed(xs, y, grids, out);
    }

    /// The energy of the pattern at the points (`xs`[i], y) mm under each
    /// set of weights of each wavelength's grid in `grids` (offsets and
    /// sets), added into `out`: per point its sets, per set `planes`
    /// values.
    fn add_weighed<'g>(
        &self,
        xs: &[f64],
        y: f64,
        grids: impl Iterator<Item = (&'g Offsets, Vec<&'g [f64]>)>,
        out: &mut [f64],
    ) {
        let (f, pitch_mm) = (self.optics.focal_mm, self.pitch_mm);
        let area = self.optics.pupil.area();
        let mut sums = Vec::new();
        for ((lambda_nm, weights), (offsets, sets)) in self.spectrum.iter().zip(grids) {
            let scale = 1.0 / (lambda_nm * 1e-6 * f);
            let nu_x: Vec<f64> = xs.iter().map(|x| x * scale).collect();
            sums.resize(xs.len() * sets.len(), 0.0);
            self.optics
                .pupil
                .intensity_moments(&nu_x, y * scale, offsets, &sets, &mut sums);
            let planes = out.len() / sums.len().max(1);
            for (value_set, mean) in out.chunks_mut(planes).zip(&sums) {
                // Energy in the pixel: mean PSF × pixel area.
                let energy = mean * scale * scale / area * pitch_mm * pitch_mm;
                for (value, weight) in value_set.iter_mut().zip(weights) {
                    *value += weight * energy;
                }
            }
        }
    }
}

/// Gauss–Legendre points per axis for a pixel holding `cycles` = p/(λN)
/// of the pattern's highest frequency: enough that every pixel's integral
/// is within 0.5 % of its exact value (the tests check it from λN = 0.3 to
/// 20 px).
fn points_per_axis(cycles: f64) -> usize {
    ((2.2 * cycles + 2.0).ceil() as usize).clamp(2, MOST_CORE_POINTS)
}

/// Nodes in pixels and weights (Σ = 1) for the mean over a pixel: `n`
/// Gauss–Legendre points.
fn square(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (nodes, weights) = crate::math::gauss_legendre(n);
    (
        nodes.iter().map(|t| 0.5 * t).collect(),
        weights.iter().map(|w| 0.5 * w).collect(),
    )
}

/// Nodes in pixels and weights (Σ = 1) for the mean under the tent
/// 1 − |s| on [−1, 1], the light a pixel receives from a pixel beside it
/// (docs/physics.md §2): `n` Gauss–Legendre points on each half, whose
/// weights take the tent's linear factor, so that a pixel's worth of the
/// pattern still meets `n` points.
fn tent(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (nodes, weights) = crate::math::gauss_legendre(n);
    let half = nodes.iter().zip(&weights).map(|(t, w)| {
        let s = 0.5 * (1.0 + t);
        (s, 0.5 * w * (1.0 - s))
    });
    half.clone().map(|(s, w)| (-s, w)).chain(half).unzip()
}

#[cfg(test)]
mod tests {
    use super::super::tests::stop;
    use super::*;
    use crate::optics::aperture::spectrum::Light;

    /// The pixels within `reach` px of the centre, row by row.
    fn rasterise(near: &NearField<'_>, pitch: f64, reach: i32) -> Vec<f64> {
        let xs: Vec<f64> = (-reach..=reach).map(|i| f64::from(i) * pitch).collect();
        let mut out = Vec::new();
        for j in -reach..=reach {
            let mut row = vec![0.0; xs.len()];
            near.add_many(&xs, f64::from(j) * pitch, false, &mut row);
            out.extend(row);
        }
        out
    }

    #[test]
    fn every_pixel_is_integrated_to_half_a_percent_at_any_lambda_n() {
        // 550 nm at f/4 is λN = 2.2 µm: pitches from 0.11 to 7.3 µm give
        // λN from 20 to 0.3 px. The reference has more than twice the
        // points, enough that it is exact to 1e-6.
        let light = Light::Monochrome(550.0).wavelengths();
        let cases = [(7, 0.0), (8, 0.0), (0, 0.0), (6, 0.5)];
        for ((blades, roundness), sending) in cases
            .into_iter()
            .flat_map(|case| [(case, Sending::Point), (case, Sending::Pixel)])
        {
            let optics = stop(blades, roundness, 4.0);
            for lambda_n_px in [0.3, 0.7, 1.0, 2.2, 5.0, 20.0] {
                let pitch = 550e-6 * 4.0 / lambda_n_px;
                let near = NearField::new(&optics, &light, (pitch, sending));
                let exact = NearField::exact(&optics, &light, (pitch, sending));
                let (ours, exact) = (rasterise(&near, pitch, 12), rasterise(&exact, pitch, 12));
                let mut worst = (0.0, 0);
                for (k, (a, b)) in ours.iter().zip(&exact).enumerate() {
                    let error = (a / b - 1.0).abs();
                    if *b > 1e-6 && error > worst.0 {
                        worst = (error, k);
                    }
                }
                assert!(
                    worst.0 < 0.005,
                    "{blades} blades, {sending:?}, λN {lambda_n_px} px: pixel {} off by {:.4}",
                    worst.1,
                    worst.0
                );
            }
        }
    }
}
