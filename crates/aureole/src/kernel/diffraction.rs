//! Rasterising a diffraction PSF: each pixel gets the mean over its area
//! of PSF_λ(x) = |Â(x/(λf))|² / ((λf)² · area), for each wavelength, weighted
//! by each channel's sensitivity; filter orders then convolve the pattern.
//!
//! Near the centre the transform is evaluated exactly, supersampled. Beyond
//! ~60 λN the interference between different edges oscillates faster than a
//! pixel and the spectrum can show: there the pattern is the incoherent sum
//! of each edge's |F_k|² = L²(x·n)² sinc²(πu/λ) / (4π²|x|⁴·area), u the
//! offset across the edge's ray times L/f, averaged over the pixel
//! analytically, and each disc's ⟨J₁²⟩ term R λ f / (2π²|x|³·area).

use rayon::prelude::*;

use super::{Extent, Kernel};
use crate::convolve::plan::Convolver;
use crate::psf::aperture::Optics;
use crate::psf::pupil::EdgeTerm;

/// What light to integrate: (wavelength nm, weight per channel).
pub(crate) type Spectrum = Vec<(f64, Vec<f64>)>;

/// One plane per channel, each normalised to Σ = 1.
pub(crate) fn rasterise(
    optics: &Optics,
    spectrum: &Spectrum,
    extent: &Extent,
    pitch_mm: f64,
) -> Vec<Vec<f64>> {
    let longest = spectrum.iter().map(|(l, _)| *l).fold(0.0, f64::max) * 1e-6;
    let far_from = (48.0 * pitch_mm).max(60.0 * longest * optics.focal_mm / optics.diameter_mm);
    rasterise_with(optics, spectrum, extent, pitch_mm, far_from)
}

/// As [`rasterise`], with the far field from `far_from` mm out.
fn rasterise_with(
    optics: &Optics,
    spectrum: &Spectrum,
    extent: &Extent,
    pitch_mm: f64,
    far_from: f64,
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
    // The centre pixel and its neighbours hold most of the light: with
    // pixels wider than λN the Airy core is a fraction of a pixel wide, and
    // a few samples that miss or hit it would set the share of everything
    // else. Eight samples per fringe there, for every wavelength.
    let dense = (8.0 * pitch_mm * optics.diameter_mm / (shortest * f))
        .ceil()
        .clamp(grid as f64, 128.0) as usize;
    let weights_total: Vec<f64> = (0..channels)
        .map(|c| spectrum.iter().map(|(_, w)| w[c]).sum::<f64>())
        .collect();

    let far = FarField::new(optics, spectrum, &weights_total);

    let mut planes = vec![vec![0.0; width * height]; channels];
    let mut rows: Vec<Vec<f64>> = vec![Vec::new(); height];
    rows.par_iter_mut().enumerate().for_each(|(j, row)| {
        *row = vec![0.0; width * channels];
        let y = (cy as f64 - j as f64) * pitch_mm;
        for i in 0..width {
            let x = (i as f64 - cx as f64) * pitch_mm;
            if x.hypot(y) >= far_from {
                for c in 0..channels {
                    // Weighted like the exact sum below, undone after it.
                    row[i * channels + c] = weights_total[c] * far.energy(c, x, y, pitch_mm);
                }
                continue;
            }
            for (k, (lambda_nm, weights)) in spectrum.iter().enumerate() {
                let lambda = lambda_nm * 1e-6;
                let scale = 1.0 / (lambda * f);
                // Sample cells' centres, moved by a different fraction per
                // wavelength (golden-ratio steps), spread over the pixel.
                let (ox, oy) = (
                    frac(0.5 + 0.618_034 * k as f64),
                    frac(0.5 + 0.754_878 * k as f64),
                );
                let samples = if i.abs_diff(cx) <= 1 && j.abs_diff(cy) <= 1 {
                    dense * dense
                } else {
                    grid * grid
                };
                let mut sum = 0.0;
                for n in 0..samples {
                    let (u, v) = kronecker(n, ox, oy);
                    let (sx, sy) = (x + pitch_mm * (u - 0.5), y + pitch_mm * (v - 0.5));
                    sum += optics.pupil.intensity([sx * scale, sy * scale]);
                }
                // Energy in the pixel: mean PSF × pixel area.
                let energy = sum / samples as f64 * scale * scale / area * pitch_mm * pitch_mm;
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
        // The zero order keeps the whole pattern. Every other order holds
        // |c_m|² ≲ (e/d)² of the light: it carries the window of the pattern
        // that holds 98 % of its light (the Airy core and its first rings),
        // renormalised, so what an order loses is its faint halo.
        let zero: f64 = optics
            .orders
            .iter()
            .filter(|(nu, _)| nu[0] == 0.0 && nu[1] == 0.0)
            .map(|(_, w)| w)
            .sum();
        planes = planes
            .iter()
            .enumerate()
            .map(|(c, plane)| {
                let comb = order_comb(optics, spectrum, c, extent, pitch_mm, weights_total[c]);
                let window = core_window(plane, extent, ORDER_CORE, ORDER_REACH);
                let moved = spread_orders(&comb, &window, extent);
                plane
                    .iter()
                    .zip(&moved)
                    .map(|(p, m)| zero * p + m)
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

/// Point `n` of the R2 sequence (Roberts 2018, steps 1/g and 1/g², g the
/// plastic number) moved by (ox, oy), in the unit square: evenly spread for
/// any run of consecutive points, and on no lattice. A lattice of samples
/// in every pixel is one lattice over the whole kernel, whose moiré with
/// the Airy rings draws a cross along the axes.
fn kronecker(n: usize, ox: f64, oy: f64) -> (f64, f64) {
    const G: f64 = 1.324_717_957_244_746;
    let n = n as f64;
    (frac(ox + n / G), frac(oy + n / (G * G)))
}

fn frac(v: f64) -> f64 {
    v - v.floor()
}

/// The far field: incoherent sums over edges and discs (module docs).
struct FarField {
    /// (L², normal, unit direction along, L/f) per straight edge.
    edges: Vec<(f64, [f64; 2], [f64; 2], f64)>,
    /// Pieces of curved sides: the curve's radius of curvature there
    /// (L / the normal's turn, mm), the normal's angle and the turn before
    /// and after it (rad).
    fans: Vec<(f64, f64, [f64; 2])>,
    discs: Vec<f64>,
    /// Per channel: the spectrum-averaged ∫₀ᵘ sinc²(πu'/λ) du'.
    tables: Vec<Cumulative>,
    /// Per channel: the sensitivity-weighted mean wavelength, mm.
    mean_lambda: Vec<f64>,
    area: f64,
    focal: f64,
}

/// G(u) = ∫₀ᵘ g, g(u) = Σ w sinc²(πu/λ) / Σ w, tabulated finely, with the
/// tail g ≈ ⟨λ²⟩/(2π²u²) beyond.
struct Cumulative {
    step: f64,
    values: Vec<f64>,
    tail: f64,
}

impl Cumulative {
    fn new(light: &[(f64, f64)]) -> Cumulative {
        let total: f64 = light.iter().map(|(_, w)| w).sum();
        let shortest = light.iter().map(|(l, _)| *l).fold(f64::INFINITY, f64::min);
        let longest = light.iter().map(|(l, _)| *l).fold(0.0, f64::max);
        let step = shortest / 32.0;
        let count = (256.0 * longest / step).ceil() as usize;
        let g = |u: f64| {
            light
                .iter()
                .map(|(l, w)| {
                    let z = std::f64::consts::PI * u / l;
                    let s = if z.abs() < 1e-9 { 1.0 } else { z.sin() / z };
                    w * s * s
                })
                .sum::<f64>()
                / total
        };
        let mut values = Vec::with_capacity(count + 1);
        let mut sum = 0.0;
        let mut last = g(0.0);
        values.push(0.0);
        for k in 1..=count {
            let next = g(k as f64 * step);
            sum += 0.5 * (last + next) * step;
            values.push(sum);
            last = next;
        }
        let mean_square = light.iter().map(|(l, w)| w * l * l).sum::<f64>() / total;
        Cumulative {
            step,
            values,
            tail: mean_square / (2.0 * std::f64::consts::PI.powi(2)),
        }
    }

    /// G(u), odd in u.
    fn at(&self, u: f64) -> f64 {
        let a = u.abs();
        let end = (self.values.len() - 1) as f64 * self.step;
        let g = if a >= end {
            self.values[self.values.len() - 1] + self.tail * (1.0 / end - 1.0 / a)
        } else {
            let position = a / self.step;
            let k = position as usize;
            let t = position - k as f64;
            self.values[k] * (1.0 - t) + self.values[k + 1] * t
        };
        g.copysign(u)
    }
}

impl FarField {
    fn new(optics: &Optics, spectrum: &Spectrum, weights_total: &[f64]) -> FarField {
        let (edges, discs) = optics.pupil.far_field_terms();
        let f = optics.focal_mm;
        let channels = weights_total.len();
        let light = |c: usize| -> Vec<(f64, f64)> {
            spectrum.iter().map(|(l, w)| (l * 1e-6, w[c])).collect()
        };
        let (curved, straight): (Vec<EdgeTerm>, Vec<EdgeTerm>) =
            edges.into_iter().partition(|e| e.fan.is_some());
        FarField {
            edges: straight
                .into_iter()
                .map(|e| (e.length * e.length, e.normal, e.along, e.length / f))
                .collect(),
            fans: curved
                .into_iter()
                .filter_map(|e| {
                    let [before, after] = e.fan?;
                    (before + after > 0.0).then(|| {
                        (
                            e.length / (before + after),
                            e.normal[1].atan2(e.normal[0]),
                            [before, after],
                        )
                    })
                })
                .collect(),
            discs,
            tables: (0..channels).map(|c| Cumulative::new(&light(c))).collect(),
            mean_lambda: (0..channels)
                .map(|c| {
                    spectrum.iter().map(|(l, w)| l * 1e-6 * w[c]).sum::<f64>() / weights_total[c]
                })
                .collect(),
            area: optics.pupil.area(),
            focal: f,
        }
    }

    /// The light of channel `c` in the pixel at (x, y) mm.
    fn energy(&self, c: usize, x: f64, y: f64, pitch: f64) -> f64 {
        let r2 = x * x + y * y;
        let table = &self.tables[c];
        let mut sum = 0.0;
        for (l2, n, a, l_over_f) in &self.edges {
            let along = x * n[0] + y * n[1];
            let across = x * a[0] + y * a[1];
            // The pixel spans this much across the ray (a strip as wide as
            // the square's projection).
            let half = 0.5 * pitch * (a[0].abs() + a[1].abs());
            let (u1, u2) = ((across - half) * l_over_f, (across + half) * l_over_f);
            let mean = (table.at(u2) - table.at(u1)) / (u2 - u1);
            sum += l2 * along * along * mean;
        }
        let mut value = sum / (4.0 * std::f64::consts::PI.powi(2) * r2 * r2);
        let r = r2.sqrt();
        let r3 = r2 * r;
        if !self.fans.is_empty() {
            // By stationary phase, the points of a curved side whose normal
            // is ±x/|x| send ρ λ f / (4π² |x|³) there (two such points on a
            // disc give its ⟨J₁²⟩ term), ρ the radius of curvature; each
            // piece covers its share of the normal's directions, averaged
            // over the angle the pixel spans.
            let phi = y.atan2(x);
            let half = 0.5 * pitch * (x.abs() + y.abs()) / r2;
            let mut covered = 0.0;
            for (rho, normal, [before, after]) in &self.fans {
                for side in [0.0, std::f64::consts::PI] {
                    let offset = wrap(phi - normal - side);
                    let overlap = (offset + half).min(*after) - (offset - half).max(-before);
                    if overlap > 0.0 {
                        covered += rho * overlap;
                    }
                }
            }
            value += covered / (2.0 * half) * self.mean_lambda[c] * self.focal
                / (4.0 * std::f64::consts::PI.powi(2) * r3);
        }
        for radius in &self.discs {
            value += radius * self.mean_lambda[c] * self.focal
                / (2.0 * std::f64::consts::PI.powi(2) * r3);
        }
        value / self.area * pitch * pitch
    }
}

/// An angle brought into (−π, π].
fn wrap(angle: f64) -> f64 {
    let turns = (angle / std::f64::consts::TAU).round();
    angle - turns * std::f64::consts::TAU
}

/// The largest half-size in px of the pattern the non-zero orders carry.
const ORDER_REACH: usize = 64;
/// The share of the pattern's light the non-zero orders carry.
const ORDER_CORE: f64 = 0.98;

/// The comb with the window placed at each of its pixels, by direct
/// scattering or by FFT convolution, whichever the operation counts say is
/// cheaper.
fn spread_orders(comb: &[f64], window: &Window, extent: &Extent) -> Vec<f64> {
    let entries = comb.iter().filter(|v| **v != 0.0).count() as f64;
    let side = 2 * window.reach + 1;
    let direct = entries * (side * side) as f64;
    // Measured on two cores: scattering costs ~1.7 ns per multiply-add, the
    // FFT route ~1.8 s per channel of a 4K kernel, as much as 0.3·P·log₂P
    // multiply-adds for P padded pixels.
    let padded = (2 * extent.width) as f64 * (2 * extent.height) as f64;
    let fft = 0.3 * padded * padded.log2();
    if direct <= fft {
        return scatter(comb, window, extent);
    }
    let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
    match Kernel::from_planes(side, side, vec![plane]) {
        Ok(kernel) => {
            let comb: Vec<f32> = comb.iter().map(|&v| v as f32).collect();
            Convolver::new(&kernel, extent.width, extent.height)
                .convolve(&comb, 0)
                .into_iter()
                .map(|v| f64::from(v).max(0.0))
                .collect()
        }
        Err(_) => scatter(comb, window, extent),
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
fn scatter(comb: &[f64], window: &Window, extent: &Extent) -> Vec<f64> {
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
    out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
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
    });
    out
}

/// The filter's non-zero orders for channel `c`: each order m at x = ν_m λ f, with
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
    use crate::psf::spectrum;
    use crate::psf::Aperture;

    const SIDE: usize = 141;

    /// A stop of `blades` (0: round) at f/`f_number` on a 50 mm lens.
    fn stop(blades: u32, roundness: f64, f_number: f64) -> Optics {
        let aperture = Aperture {
            blades,
            rotation_deg: 5.0,
            roundness,
            spectral: true,
            wavelength_nm: 550.0,
            obstruction: 0.0,
            vanes: 0,
            vane_width: 0.02,
            filters: Vec::new(),
        };
        let camera = crate::Camera {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: Some(f_number),
        };
        aperture.optics(&camera, 1.0).unwrap()
    }

    /// The 17 wavelengths and their R, G, B weights.
    fn light() -> Spectrum {
        spectrum::samples()
            .into_iter()
            .map(|(l, w)| (l, w.to_vec()))
            .collect()
    }

    /// The green plane of a stop's PSF on a 141-px square of pixels
    /// `pitch` mm, with the far field from 48 px out and exact throughout.
    fn fast_and_exact(
        blades: u32,
        roundness: f64,
        f_number: f64,
        pitch: f64,
    ) -> (Vec<f64>, Vec<f64>) {
        let (optics, light) = (stop(blades, roundness, f_number), light());
        let extent = Extent::new(SIDE, SIDE).unwrap();
        let mut fast = rasterise_with(&optics, &light, &extent, pitch, 48.0 * pitch);
        let mut exact = rasterise_with(&optics, &light, &extent, pitch, f64::INFINITY);
        (fast.swap_remove(1), exact.swap_remove(1))
    }

    /// The light of `plane` between radii `r0` and `r1` px, in `bins`
    /// sectors from the +x axis.
    fn sectors(plane: &[f64], r0: f64, r1: f64, bins: usize) -> Vec<f64> {
        let mut out = vec![0.0; bins];
        let centre = (SIDE / 2) as f64;
        for (i, v) in plane.iter().enumerate() {
            let (dx, dy) = ((i % SIDE) as f64 - centre, centre - (i / SIDE) as f64);
            let r = dx.hypot(dy);
            if r >= r0 && r < r1 {
                let turn = dy.atan2(dx).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU;
                out[((turn * bins as f64) as usize).min(bins - 1)] += v;
            }
        }
        out
    }

    #[test]
    fn a_round_stop_sends_the_airy_tail_out_of_the_centre_pixel() {
        // With pixels of half-width a ≫ λN the Airy rings average to the
        // density λN/(π³r³), so a share λN·4√2/(π³a) of the light lies
        // outside the centre pixel: the core must be integrated well enough
        // for the rest to get its share, at every wavelength.
        let (light, f_number) = (light(), 8.0);
        let optics = stop(0, 0.0, f_number);
        for pitch in [0.036, 0.027] {
            let extent = Extent::new(SIDE, SIDE).unwrap();
            let planes = rasterise(&optics, &light, &extent, pitch);
            let a = pitch / 2.0;
            for (c, plane) in planes.iter().enumerate() {
                let total: f64 = light.iter().map(|(_, w)| w[c]).sum();
                let mean_lambda = light.iter().map(|(l, w)| l * 1e-6 * w[c]).sum::<f64>() / total;
                let expected =
                    mean_lambda * f_number * 4.0 * 2f64.sqrt() / (std::f64::consts::PI.powi(3) * a);
                let outside = 1.0 - plane[(SIDE / 2) * SIDE + SIDE / 2];
                assert!(
                    (outside / expected - 1.0).abs() < 0.03,
                    "pitch {pitch} mm, channel {c}: {outside:.5} outside, {expected:.5} expected"
                );
            }
        }
    }

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
        let direct = scatter(&comb, &window, &extent);
        let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
        let kernel = Kernel::from_planes(7, 7, vec![plane]).unwrap();
        let comb32: Vec<f32> = comb.iter().map(|&v| v as f32).collect();
        let fft = Convolver::new(&kernel, 47, 33).convolve(&comb32, 0);
        for (a, b) in direct.iter().zip(&fft) {
            assert!((a - f64::from(*b)).abs() < 1e-6, "{a} vs {b}");
        }
    }

    #[test]
    fn the_far_field_carries_the_light_the_exact_transform_does() {
        // 10-px rings from 40 px out, across the switch at 48 px.
        let pitch = 36.0 / 3840.0; // a 4K frame on full frame
        for (blades, roundness) in [(0, 0.0), (6, 0.0), (7, 0.0), (8, 0.3)] {
            let (fast, exact) = fast_and_exact(blades, roundness, 8.0, pitch);
            for k in 0..3 {
                let r = 40.0 + 10.0 * k as f64;
                let (a, b) = (
                    sectors(&fast, r, r + 10.0, 1)[0],
                    sectors(&exact, r, r + 10.0, 1)[0],
                );
                assert!(
                    (a / b - 1.0).abs() < 0.1,
                    "{blades} blades, roundness {roundness}, {r} px: {a} vs {b}"
                );
            }
        }
    }

    #[test]
    fn rounded_blades_fan_their_light_where_the_exact_transform_does() {
        // f/32 on 36 µm pixels: the pieces that sample a rounded blade are
        // so short that each one's own ray would be ~20 px wide; the curve
        // they sample spreads its light only over the turn of its normal.
        let pitch = 0.036;
        for (blades, roundness) in [(8, 0.1), (6, 0.4), (5, 0.8)] {
            let (fast, exact) = fast_and_exact(blades, roundness, 32.0, pitch);
            let bins = 72;
            let (a, b) = (
                sectors(&fast, 50.0, 70.0, bins),
                sectors(&exact, 50.0, 70.0, bins),
            );
            let total: f64 = b.iter().sum();
            // Half the L1 distance between the angular distributions: the
            // share of the light that sits in the wrong 5° sector.
            let misplaced: f64 =
                a.iter().zip(&b).map(|(x, y)| (x - y).abs()).sum::<f64>() / (2.0 * total);
            assert!(
                misplaced < 0.2,
                "{blades} blades, roundness {roundness}: {misplaced:.3} of the light misplaced\n{a:?}\n{b:?}"
            );
        }
    }
}
