//! The near field of a diffraction pattern: |Â(x/(λf))|² evaluated exactly
//! from the pupil's closed-form transform and integrated over each pixel by
//! Gauss–Legendre quadrature, for every wavelength (docs/physics.md §6).
//!
//! The pattern is band-limited: |Â|² holds spatial frequencies up to
//! D/(λf) = 1/(λN) in the focal plane, so over a pixel p wide it is an
//! entire function with at most p/(λN) cycles, which Gauss–Legendre
//! integrates with an error that falls exponentially once the points per
//! axis exceed about π/2 of the cycles. The count follows λN: two points
//! where the pixel is a small part of a fringe, more where it holds many.

use super::Spectrum;
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
}

impl<'a> NearField<'a> {
    pub fn new(optics: &'a Optics, spectrum: &'a Spectrum, pitch_mm: f64) -> NearField<'a> {
        NearField::with_points(optics, spectrum, pitch_mm, |c| {
            points_per_axis(c).min(MOST_POINTS)
        })
    }

    /// With `points`(p/(λN)) Gauss–Legendre points per axis (the core's
    /// never fewer than [`points_per_axis`]).
    fn with_points(
        optics: &'a Optics,
        spectrum: &'a Spectrum,
        pitch_mm: f64,
        points: fn(f64) -> usize,
    ) -> NearField<'a> {
        NearField {
            optics,
            spectrum,
            pitch_mm,
            offsets: quadrature(optics, spectrum, pitch_mm, points),
            core_offsets: quadrature(optics, spectrum, pitch_mm, |c| {
                points(c).max(points_per_axis(c))
            }),
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
        pitch_mm: f64,
    ) -> NearField<'a> {
        NearField::with_points(optics, spectrum, pitch_mm, |c| 2 * points_per_axis(c) + 8)
    }
}

/// The offsets and weights of `points`(p/(λN))² Gauss–Legendre points over
/// a pixel, per wavelength of `spectrum`.
fn quadrature(
    optics: &Optics,
    spectrum: &Spectrum,
    pitch_mm: f64,
    points: impl Fn(f64) -> usize,
) -> Vec<Offsets> {
    spectrum
        .iter()
        .map(|(lambda_nm, _)| {
            let lambda_n = lambda_nm * 1e-6 * optics.focal_mm / optics.diameter_mm;
            let scale = 1.0 / (lambda_nm * 1e-6 * optics.focal_mm);
            let (nodes, weights) = gauss_legendre(points(pitch_mm / lambda_n));
            let n = nodes.len();
            let (mut dx, mut dy, mut w) = (Vec::new(), Vec::new(), Vec::new());
            for a in 0..n {
                for b in 0..n {
                    dx.push(0.5 * pitch_mm * nodes[b] * scale);
                    dy.push(0.5 * pitch_mm * nodes[a] * scale);
                    // The weights on [−1, 1] sum to 2 per axis.
                    w.push(0.25 * weights[a] * weights[b]);
                }
            }
            optics.pupil.offsets(dx, dy, w)
        })
        .collect()
}

impl NearField<'_> {
    /// The energy of the pattern in pixels of one row, centred at
    /// (`xs`[i], y) mm, all in the core (the centre pixel and its
    /// neighbours) or none, added into `out`, their values side by side
    /// (`planes` each). The pixels share their sample offsets, which lets
    /// the pupil's transform factor them out ([`Pupil::intensity_sums`]).
    ///
    /// [`Pupil::intensity_sums`]: crate::optics::aperture::pupil::Pupil::intensity_sums
    pub fn add_many(&self, xs: &[f64], y: f64, core: bool, out: &mut [f64]) {
        let (f, pitch_mm) = (self.optics.focal_mm, self.pitch_mm);
        let area = self.optics.pupil.area();
        let planes = out.len() / xs.len().max(1);
        let mut sums = vec![0.0; xs.len()];
        let offsets = if core {
            &self.core_offsets
        } else {
            &self.offsets
        };
        for ((lambda_nm, weights), offsets) in self.spectrum.iter().zip(offsets) {
            let scale = 1.0 / (lambda_nm * 1e-6 * f);
            let nu_x: Vec<f64> = xs.iter().map(|x| x * scale).collect();
            self.optics
                .pupil
                .intensity_sums(&nu_x, y * scale, offsets, &mut sums);
            for (pixel, mean) in out.chunks_mut(planes).zip(&sums) {
                // Energy in the pixel: mean PSF × pixel area.
                let energy = mean * scale * scale / area * pitch_mm * pitch_mm;
                for (value, weight) in pixel.iter_mut().zip(weights) {
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

/// The `n` Gauss–Legendre nodes on [−1, 1] and their weights (Σ = 2):
/// Newton's method on P_n from the Chebyshev guesses, P_n by its
/// recurrence.
pub(super) fn gauss_legendre(n: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut nodes, mut weights) = (vec![0.0; n], vec![0.0; n]);
    for i in 0..n.div_ceil(2) {
        let mut x = (std::f64::consts::PI * (i as f64 + 0.75) / (n as f64 + 0.5)).cos();
        let mut derivative = 1.0;
        for _ in 0..100 {
            let (p, dp) = legendre(n, x);
            derivative = dp;
            let step = p / dp;
            x -= step;
            if step.abs() < 1e-15 {
                break;
            }
        }
        let w = 2.0 / ((1.0 - x * x) * derivative * derivative);
        nodes[i] = -x;
        nodes[n - 1 - i] = x;
        weights[i] = w;
        weights[n - 1 - i] = w;
    }
    (nodes, weights)
}

/// P_n(x) and P_n'(x).
fn legendre(n: usize, x: f64) -> (f64, f64) {
    let (mut p0, mut p1) = (1.0, x);
    for k in 2..=n {
        let k = k as f64;
        (p0, p1) = (p1, ((2.0 * k - 1.0) * x * p1 - (k - 1.0) * p0) / k);
    }
    if n == 0 {
        return (1.0, 0.0);
    }
    (p1, n as f64 * (x * p1 - p0) / (x * x - 1.0))
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
        for (blades, roundness) in [(7, 0.0), (8, 0.0), (0, 0.0), (6, 0.5)] {
            let optics = stop(blades, roundness, 4.0);
            for lambda_n_px in [0.3, 0.7, 1.0, 2.2, 5.0, 20.0] {
                let pitch = 550e-6 * 4.0 / lambda_n_px;
                let ours = rasterise(&NearField::new(&optics, &light, pitch), pitch, 12);
                let exact = rasterise(&NearField::exact(&optics, &light, pitch), pitch, 12);
                let mut worst = (0.0, 0);
                for (k, (a, b)) in ours.iter().zip(&exact).enumerate() {
                    let error = (a / b - 1.0).abs();
                    if *b > 1e-6 && error > worst.0 {
                        worst = (error, k);
                    }
                }
                assert!(
                    worst.0 < 0.005,
                    "{blades} blades, λN {lambda_n_px} px: pixel {} off by {:.4}",
                    worst.1,
                    worst.0
                );
            }
        }
    }

    #[test]
    fn gauss_legendre_integrates_polynomials_of_degree_2n_minus_1_exactly() {
        for n in [2, 3, 5, 8, 17, MOST_CORE_POINTS] {
            let (x, w) = gauss_legendre(n);
            assert!((w.iter().sum::<f64>() - 2.0).abs() < 1e-13, "n = {n}");
            for degree in 0..2 * n {
                let got: f64 = x
                    .iter()
                    .zip(&w)
                    .map(|(x, w)| w * x.powi(degree as i32))
                    .sum();
                let exact = if degree % 2 == 1 {
                    0.0
                } else {
                    2.0 / (degree as f64 + 1.0)
                };
                assert!(
                    (got - exact).abs() < 1e-12,
                    "n = {n}, x^{degree}: {got} vs {exact}"
                );
            }
        }
    }
}
