//! Star filters and gratings: their diffraction orders. A family of lines
//! shifts copies of the stop's pattern to the orders m·λf/d, each with its
//! share |c_m|² of the light; every wavelength lands elsewhere, so the
//! orders disperse into spectra (docs/physics.md §6).

use super::Spectrum;
use crate::control::{for_each_row, Control};
use crate::convolve::single::Convolver;
use crate::convolve::Centre;
use crate::error::Result;
use crate::kernel::{Extent, Kernel};
use crate::optics::aperture::Optics;

/// The pattern of a stop seen through the filter: the zero order keeps the
/// whole pattern, scaled by its share. Every other order holds
/// |c_m|² ≲ (e/d)² of the light: it carries the window of the pattern that
/// holds 98 % of its light (the Airy core and its first rings),
/// renormalised, so what an order loses is its faint halo.
pub(super) fn through_filter(
    optics: &Optics,
    spectrum: &Spectrum,
    planes: Vec<Vec<f64>>,
    extent: &Extent,
    pitch_mm: f64,
    weights_total: &[f64],
    control: &mut Control,
) -> Result<Vec<Vec<f64>>> {
    let zero: f64 = optics
        .orders
        .iter()
        .filter(|(nu, _)| nu[0] == 0.0 && nu[1] == 0.0)
        .map(|(_, w)| w)
        .sum();
    let share = 1.0 / planes.len().max(1) as f64;
    let mut filtered = Vec::with_capacity(planes.len());
    for (c, plane) in planes.iter().enumerate() {
        let comb = order_comb(optics, spectrum, c, extent, pitch_mm, weights_total[c]);
        let window = core_window(plane, extent, ORDER_CORE, ORDER_REACH);
        let mut part = control.part(c as f64 * share, (c + 1) as f64 * share);
        let moved = spread_orders(&comb, &window, extent, &mut part)?;
        filtered.push(
            plane
                .iter()
                .zip(&moved)
                .map(|(p, m)| zero * p + m)
                .collect(),
        );
    }
    Ok(filtered)
}

/// The largest half-size in px of the pattern the non-zero orders carry.
const ORDER_REACH: usize = 64;
/// The share of the pattern's light the non-zero orders carry.
const ORDER_CORE: f64 = 0.98;

/// The comb with the window placed at each of its pixels, by direct
/// scattering or by FFT convolution, whichever the operation counts say is
/// cheaper.
fn spread_orders(
    comb: &[f64],
    window: &Window,
    extent: &Extent,
    control: &mut Control,
) -> Result<Vec<f64>> {
    let entries = comb.iter().filter(|v| **v != 0.0).count() as f64;
    let side = 2 * window.reach + 1;
    let direct = entries * (side * side) as f64;
    // Measured on two cores: scattering costs ~1.7 ns per multiply-add, the
    // FFT route ~1.8 s per plane of a 4K kernel, as much as 0.3·P·log₂P
    // multiply-adds for P padded pixels.
    let padded = (2 * extent.width) as f64 * (2 * extent.height) as f64;
    let fft = 0.3 * padded * padded.log2();
    if direct <= fft {
        return scatter(comb, window, extent, control);
    }
    let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
    match Kernel::from_planes(side, side, vec![plane]) {
        Ok(kernel) => {
            let comb: Vec<f32> = comb.iter().map(|&v| v as f32).collect();
            let convolver = Convolver::new(
                &[kernel.planes()[0].as_slice()],
                (side, side),
                extent.width,
                extent.height,
                Centre::Include,
                &mut control.part(0.0, 0.5),
            )?;
            Ok(convolver
                .convolve(&comb, 0, &mut control.part(0.5, 1.0))?
                .into_iter()
                .map(|v| f64::from(v).max(0.0))
                .collect())
        }
        Err(_) => scatter(comb, window, extent, control),
    }
}

/// A square window of a plane around its centre, normalised to Σ = 1.
struct Window {
    reach: usize,
    values: Vec<f64>,
}

/// The smallest window (half-size ≤ `max_reach`) around the centre that
/// holds `share` of the plane's light.
fn core_window(plane: &[f64], extent: &Extent, share: f64, max_reach: usize) -> Window {
    let (w, h) = (extent.width, extent.height);
    let (cx, cy) = (w / 2, h / 2);
    let limit = max_reach.min(cx).min(cy).min(w - 1 - cx).min(h - 1 - cy);
    // Light per square ring (Chebyshev distance from the centre).
    let mut rings = vec![0.0; limit + 1];
    for y in cy - limit..=cy + limit {
        for x in cx - limit..=cx + limit {
            rings[x.abs_diff(cx).max(y.abs_diff(cy))] += plane[y * w + x];
        }
    }
    let total: f64 = plane.iter().sum();
    let mut reach = limit;
    let mut held = 0.0;
    for (r, light) in rings.iter().enumerate() {
        held += light;
        if held >= share * total {
            reach = r;
            break;
        }
    }
    let side = 2 * reach + 1;
    let mut values = Vec::with_capacity(side * side);
    for y in cy - reach..=cy + reach {
        values.extend_from_slice(&plane[y * w + cx - reach..=y * w + cx + reach]);
    }
    let sum: f64 = values.iter().sum();
    if sum > 0.0 {
        values.iter_mut().for_each(|v| *v /= sum);
    }
    Window { reach, values }
}

/// The comb with the window placed at each of its pixels (zero outside the
/// extent). Each output row gathers the comb rows within reach, so rows run
/// in parallel and the sums come out in the same order every run.
fn scatter(
    comb: &[f64],
    window: &Window,
    extent: &Extent,
    control: &mut Control,
) -> Result<Vec<f64>> {
    let (w, h) = (extent.width, extent.height);
    let reach = window.reach as i64;
    let side = 2 * window.reach + 1;
    let entries: Vec<Vec<(usize, f64)>> = comb
        .chunks(w)
        .map(|row| {
            row.iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(x, v)| (x, *v))
                .collect()
        })
        .collect();
    let mut out = vec![0.0; w * h];
    for_each_row(&mut out, w, control, |y, row| {
        for dy in -reach..=reach {
            let source = y as i64 - dy;
            if source < 0 || source >= h as i64 {
                continue;
            }
            let window_row = &window.values[(dy + reach) as usize * side..][..side];
            for &(x0, value) in &entries[source as usize] {
                for (k, weight) in window_row.iter().enumerate() {
                    let x = x0 as i64 + k as i64 - reach;
                    if x >= 0 && x < w as i64 {
                        row[x as usize] += value * weight;
                    }
                }
            }
        }
    })?;
    Ok(out)
}

/// The filter's non-zero orders for plane `c`: each order m at x = ν_m λ f,
/// with its share |c_m|² of the light, spread bilinearly over the pixels, for
/// every wavelength of the plane (so orders disperse into spectra).
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
        for (nu, share) in optics
            .orders
            .iter()
            .filter(|(nu, _)| nu[0] != 0.0 || nu[1] != 0.0)
        {
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::Cancel;

    #[test]
    fn scattering_and_fft_spread_orders_alike() {
        let extent = Extent::new(47, 33).unwrap();
        let mut comb = vec![0.0; 47 * 33];
        for (i, v) in [
            (5usize, 0.3),
            (400, 0.01),
            (777, 0.2),
            (1500, 0.05),
            (46, 0.1),
        ] {
            comb[i] = v;
        }
        let values: Vec<f64> = (0..49).map(|i| 1.0 + (i % 7) as f64 * 0.3).collect();
        let sum: f64 = values.iter().sum();
        let window = Window {
            reach: 3,
            values: values.iter().map(|v| v / sum).collect(),
        };
        let cancel = Cancel::new();
        let mut quiet = Control::quiet(&cancel);
        let direct = scatter(&comb, &window, &extent, &mut quiet).unwrap();
        let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
        let kernel = Kernel::from_planes(7, 7, vec![plane]).unwrap();
        let comb32: Vec<f32> = comb.iter().map(|&v| v as f32).collect();
        let convolver = Convolver::new(
            &[kernel.planes()[0].as_slice()],
            (7, 7),
            47,
            33,
            Centre::Include,
            &mut quiet,
        )
        .unwrap();
        let fft = convolver.convolve(&comb32, 0, &mut quiet).unwrap();
        for (a, b) in direct.iter().zip(&fft) {
            assert!((a - f64::from(*b)).abs() < 1e-6, "{a} vs {b}");
        }
    }
}
