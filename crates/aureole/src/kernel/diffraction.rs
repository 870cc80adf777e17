//! Rasterising a diffraction PSF: each pixel gets the mean over its area
//! of PSF_λ(x) = |Â(x/(λf))|² / ((λf)² · area), for each wavelength, weighted
//! by each channel's sensitivity; filter orders then convolve the pattern.

use rayon::prelude::*;

use super::Extent;
use crate::convolve::fft::convolve_same;
use crate::psf::aperture::Optics;

/// What light to integrate: (wavelength nm, weight per channel).
pub(crate) type Spectrum = Vec<(f64, Vec<f64>)>;

/// One plane per channel, each normalised to Σ = 1.
pub(crate) fn rasterise(
    optics: &Optics,
    spectrum: &Spectrum,
    extent: &Extent,
    pitch_mm: f64,
) -> Vec<Vec<f64>> {
    let channels = spectrum.first().map_or(1, |(_, w)| w.len());
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = (width / 2, height / 2);
    let f = optics.focal_mm;
    let area = optics.pupil.area();
    let shortest = spectrum
        .iter()
        .map(|(l, _)| *l)
        .fold(f64::INFINITY, f64::min)
        * 1e-6;
    // Fringes repeat every λf/D in the focal plane: two samples per fringe
    // at the shortest wavelength, shared out among the wavelengths, which
    // sample the pixel on offset grids.
    let per_pixel = (2.0 * pitch_mm * optics.diameter_mm / (shortest * f))
        .ceil()
        .clamp(1.0, 16.0);
    let grid = if spectrum.len() > 1 {
        (per_pixel / 3.0).ceil()
    } else {
        per_pixel
    } as usize;
    let weights_total: Vec<f64> = (0..channels)
        .map(|c| spectrum.iter().map(|(_, w)| w[c]).sum::<f64>())
        .collect();

    let mut planes = vec![vec![0.0; width * height]; channels];
    let mut rows: Vec<Vec<f64>> = vec![Vec::new(); height];
    rows.par_iter_mut().enumerate().for_each(|(j, row)| {
        *row = vec![0.0; width * channels];
        let y = (cy as f64 - j as f64) * pitch_mm;
        for i in 0..width {
            let x = (i as f64 - cx as f64) * pitch_mm;
            for (k, (lambda_nm, weights)) in spectrum.iter().enumerate() {
                let lambda = lambda_nm * 1e-6;
                let scale = 1.0 / (lambda * f);
                // Sample cells' centres, moved by a different fraction per
                // wavelength (golden-ratio steps), spread over the pixel.
                let (ox, oy) = (
                    frac(0.5 + 0.618_034 * k as f64),
                    frac(0.5 + 0.754_878 * k as f64),
                );
                let mut sum = 0.0;
                for a in 0..grid {
                    let sy = y + pitch_mm * ((a as f64 + oy) / grid as f64 - 0.5);
                    for b in 0..grid {
                        let sx = x + pitch_mm * ((b as f64 + ox) / grid as f64 - 0.5);
                        sum += optics.pupil.intensity([sx * scale, sy * scale]);
                    }
                }
                // Energy in the pixel: mean PSF × pixel area.
                let energy =
                    sum / (grid * grid) as f64 * scale * scale / area * pitch_mm * pitch_mm;
                for c in 0..channels {
                    row[i * channels + c] += weights[c] * energy;
                }
            }
        }
    });
    for (j, row) in rows.iter().enumerate() {
        for i in 0..width {
            for c in 0..channels {
                planes[c][j * width + i] = row[i * channels + c] / weights_total[c];
            }
        }
    }
    if optics.orders.len() > 1 {
        planes = planes
            .iter()
            .enumerate()
            .map(|(c, plane)| {
                let comb = order_comb(optics, spectrum, c, extent, pitch_mm, weights_total[c]);
                convolve_same(plane, &comb, width, height)
                    .into_iter()
                    .map(|v| v.max(0.0))
                    .collect()
            })
            .collect();
    }
    for plane in &mut planes {
        let total: f64 = plane.iter().sum();
        if total > 0.0 {
            plane.iter_mut().for_each(|v| *v /= total);
        }
    }
    planes
}

fn frac(v: f64) -> f64 {
    v - v.floor()
}

/// The filter's orders for channel `c`: each order m at x = ν_m λ f, with
/// its share |c_m|² of the light, spread bilinearly over the pixels, for
/// every wavelength of the channel (so orders disperse into spectra).
fn order_comb(
    optics: &Optics,
    spectrum: &Spectrum,
    c: usize,
    extent: &Extent,
    pitch_mm: f64,
    weights_total: f64,
) -> Vec<f64> {
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = ((width / 2) as f64, (height / 2) as f64);
    let mut comb = vec![0.0; width * height];
    for (lambda_nm, weights) in spectrum {
        let to_px = lambda_nm * 1e-6 * optics.focal_mm / pitch_mm;
        for (nu, share) in &optics.orders {
            let (px, py) = (cx + nu[0] * to_px, cy - nu[1] * to_px);
            let (x0, y0) = (px.floor(), py.floor());
            let (fx, fy) = (px - x0, py - y0);
            let weight = share * weights[c] / weights_total;
            for (dx, dy, w) in [
                (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
                (1.0, 0.0, fx * (1.0 - fy)),
                (0.0, 1.0, (1.0 - fx) * fy),
                (1.0, 1.0, fx * fy),
            ] {
                let (x, y) = (x0 + dx, y0 + dy);
                if x >= 0.0 && y >= 0.0 && (x as usize) < width && (y as usize) < height {
                    comb[y as usize * width + x as usize] += weight * w;
                }
            }
        }
    }
    comb
}
