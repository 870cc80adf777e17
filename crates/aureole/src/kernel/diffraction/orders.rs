//! Star filters and gratings: their diffraction orders. A family of lines
//! shifts copies of the stop's pattern to the orders m·λf/d, each with its
//! share |c_m|² of the light; every wavelength lands elsewhere, so the
//! orders disperse into spectra (docs/physics.md §6).

use super::near::NearField;
use super::Spectrum;
use crate::control::{for_each_row, Control};
use crate::convolve::{self, Composing};
use crate::error::Result;
use crate::kernel::{Extent, Kernel, Sending};
use crate::optics::aperture::Optics;
use rayon::prelude::*;

/// The pattern of a stop seen through the filter: the zero order keeps the
/// whole pattern, scaled by its share. Every other order holds
/// |c_m|² ≲ (e/d)² of the light: it carries the window of the pattern
/// within [`ORDER_REACH`] px, renormalised, so what an order loses is its
/// faintest halo. An order lands between pixels: the window is placed by
/// whole pixels, bilinearly, and near its centre, where that would blur
/// the core and its rings, corrected to the pattern of the order's own
/// wavelength evaluated at its place ([`Cores`]).
pub(super) fn through_filter(
    optics: &Optics,
    spectrum: &Spectrum,
    planes: Vec<Vec<f64>>,
    (extent, pitch_mm): (&Extent, f64),
    weights_total: &[f64],
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Vec<Vec<f64>>> {
    let zero: f64 = optics
        .orders
        .iter()
        .filter(|(nu, _)| nu[0] == 0.0 && nu[1] == 0.0)
        .map(|(_, w)| w)
        .sum();
    let windows: Vec<Window> = planes
        .iter()
        .map(|plane| centre_window(plane, extent, ORDER_REACH))
        .collect();
    let cores = Cores::new(optics, spectrum, &windows, pitch_mm, extent.sending);
    let share = 1.0 / planes.len().max(1) as f64;
    let mut filtered = Vec::with_capacity(planes.len());
    for (c, plane) in planes.iter().enumerate() {
        let orders = Orders {
            optics,
            spectrum,
            c,
            extent,
            pitch_mm,
            total: weights_total[c],
        };
        let comb = comb(&orders, extent);
        let mut part = control.part(c as f64 * share, (c + 1) as f64 * share);
        let mut moved = spread_orders(
            &comb,
            &windows[c],
            extent,
            composing,
            &mut part.part(0.0, 0.9),
        )?;
        cores.correct(c, &orders, extent, &mut moved, &mut part.part(0.9, 1.0))?;
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

/// The comb with the window placed at each of its pixels, by direct
/// scattering or by FFT convolution, whichever the operation counts say is
/// cheaper.
fn spread_orders(
    comb: &[f64],
    window: &Window,
    extent: &Extent,
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Vec<f64>> {
    let entries = comb.iter().filter(|v| **v != 0.0).count() as f64;
    let side = 2 * window.reach + 1;
    let direct = entries * (side * side) as f64;
    // Measured on two cores: scattering costs ~1.7 ns per multiply-add, the
    // FFT route ~1.8 s per plane of a 4K kernel, as much as 0.3·P·log₂P
    // multiply-adds for P padded pixels.
    let padded = (2 * extent.width) as f64 * (2 * extent.height) as f64;
    let fft = 0.3 * padded * libm::log2(padded);
    if direct <= fft {
        return scatter(comb, window, extent, control);
    }
    let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
    match Kernel::from_planes(side, side, vec![plane]) {
        Ok(kernel) => {
            let comb: Vec<f32> = comb.iter().map(|&v| v as f32).collect();
            let size = (extent.width, extent.height);
            let composed = convolve::compose(
                &kernel.planes()[0],
                (side, side),
                &comb,
                size,
                composing,
                control,
            )?;
            Ok(composed
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
    /// The plane's light within it, before normalising.
    sum: f64,
}

/// The square window of a plane around its centre, half-size `max_reach`
/// or as much as the plane holds.
fn centre_window(plane: &[f64], extent: &Extent, max_reach: usize) -> Window {
    let (w, h) = (extent.width, extent.height);
    let (cx, cy) = (w / 2, h / 2);
    let reach = max_reach.min(cx).min(cy).min(w - 1 - cx).min(h - 1 - cy);
    let side = 2 * reach + 1;
    let mut values = Vec::with_capacity(side * side);
    for y in cy - reach..=cy + reach {
        values.extend_from_slice(&plane[y * w + cx - reach..=y * w + cx + reach]);
    }
    let sum: f64 = values.iter().sum();
    if sum > 0.0 {
        values.iter_mut().for_each(|v| *v /= sum);
    }
    Window { reach, values, sum }
}

impl Window {
    /// Its value `dx`, `dy` px right of and below its centre (0 outside).
    fn at(&self, dx: i64, dy: i64) -> f64 {
        let reach = self.reach as i64;
        if dx.abs() > reach || dy.abs() > reach {
            return 0.0;
        }
        self.values[((dy + reach) * (2 * reach + 1) + dx + reach) as usize]
    }
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

/// Where a non-zero order of one wavelength lands, in px from the
/// kernel's left and top edges (pixel centres at whole numbers), and its
/// share of a plane's light.
struct Order {
    x: f64,
    y: f64,
    weight: f64,
    /// The wavelength's index in the spectrum.
    line: usize,
}

/// The filter's non-zero orders for plane `c`: each order m at x = ν_m λ f,
/// with its share |c_m|² of the light, for every wavelength of the plane
/// (so orders disperse into spectra). A star filter has millions of them
/// (pairs of families, in every wavelength: 55 million for four families
/// at 200 µm): they are produced as they are used, never stored, and only
/// the few bright enough to need their cores corrected are kept.
struct Orders<'a> {
    optics: &'a Optics,
    spectrum: &'a Spectrum,
    c: usize,
    extent: &'a Extent,
    pitch_mm: f64,
    total: f64,
}

impl Orders<'_> {
    fn each(&self, mut visit: impl FnMut(Order)) {
        let (cx, cy) = (
            (self.extent.width / 2) as f64,
            (self.extent.height / 2) as f64,
        );
        for (line, (lambda_nm, weights)) in self.spectrum.iter().enumerate() {
            if weights[self.c] == 0.0 {
                continue;
            }
            let to_px = lambda_nm * 1e-6 * self.optics.focal_mm / self.pitch_mm;
            for (nu, share) in self
                .optics
                .orders
                .iter()
                .filter(|(nu, _)| nu[0] != 0.0 || nu[1] != 0.0)
            {
                visit(Order {
                    x: cx + nu[0] * to_px,
                    y: cy - nu[1] * to_px,
                    weight: share * weights[self.c] / self.total,
                    line,
                });
            }
        }
    }
}

/// The orders spread bilinearly over the pixels about them.
fn comb(orders: &Orders, extent: &Extent) -> Vec<f64> {
    let (width, height) = (extent.width, extent.height);
    let mut comb = vec![0.0; width * height];
    orders.each(|order| {
        let (x0, y0) = (order.x.floor(), order.y.floor());
        let (fx, fy) = (order.x - x0, order.y - y0);
        for (dx, dy, w) in [
            (0.0, 0.0, (1.0 - fx) * (1.0 - fy)),
            (1.0, 0.0, fx * (1.0 - fy)),
            (0.0, 1.0, (1.0 - fx) * fy),
            (1.0, 1.0, fx * fy),
        ] {
            let (x, y) = (x0 + dx, y0 + dy);
            if x >= 0.0 && y >= 0.0 && (x as usize) < width && (y as usize) < height {
                comb[y as usize * width + x as usize] += order.weight * w;
            }
        }
    });
    comb
}

/// Sub-pixel places per pixel and axis at which the cores are evaluated;
/// between them they are interpolated. On rings through the first orders
/// (5 µm pixels, f/8) the angular profile is then within 0.12 % of the
/// exact pattern in one wavelength and 0.65 % in 17 (4 places: 0.5 % and
/// 1.2 %; whole pixels: 10–19 %).
const PHASES: usize = 8;

/// The most light the orders left to their bilinear places may hold.
const UNCORRECTED: f64 = 1e-4;

/// What placing an order's window bilinearly by whole pixels gets wrong
/// about its core: for each sub-pixel place (a, b)/[`PHASES`] of the
/// order, the pattern centred there minus the bilinear mix of the window,
/// over the pixels within `reach` of the order, per plane. The pattern's
/// core is as narrow as λN, and a pixel-integrated pattern moved by half a
/// pixel is not the mean of the pattern moved by 0 and by 1.
struct Cores {
    reach: usize,
    /// Per plane, per wavelength, per place (b·(PHASES + 1) + a), the
    /// block of (2·reach + 2)² pixels from (−reach, −reach) about the
    /// order's pixel.
    blocks: Vec<Vec<Vec<Vec<f64>>>>,
}

impl Cores {
    fn new(
        optics: &Optics,
        spectrum: &Spectrum,
        windows: &[Window],
        pitch_mm: f64,
        sending: Sending,
    ) -> Cores {
        let longest = spectrum.iter().map(|(l, _)| *l).fold(0.0, f64::max);
        let lambda_n_px = longest * 1e-6 * optics.focal_mm / optics.diameter_mm / pitch_mm;
        // Whole-pixel placing blurs the core and the rings about it, which
        // keep the pattern's finest detail out to many λN: 4 λN left 8 % of
        // a ring's profile wrong where it passed 3 px from an order, 12 λN
        // 1.5 %, as little as the window's edge.
        let reach = ((12.0 * lambda_n_px).ceil() as usize).clamp(3, 24);
        let side = 2 * reach + 2;
        let places = (PHASES + 1) * (PHASES + 1);
        // A pupil that delays no part of the light gives a centrosymmetric
        // pattern: the place (1 − fx, 1 − fy) sees the block of (fx, fy)
        // turned by half a turn, so only the first half of the places is
        // evaluated.
        let evaluated = if optics.pupil.is_real() {
            places / 2 + 1
        } else {
            places
        };
        let singles: Vec<Spectrum> = spectrum
            .iter()
            .map(|(lambda_nm, _)| vec![(*lambda_nm, vec![1.0])])
            .collect();
        let nears: Vec<NearField<'_>> = singles
            .iter()
            .map(|single| NearField::new(optics, single, (pitch_mm, sending)))
            .collect();
        let exact: Vec<Vec<f64>> = (0..spectrum.len() * evaluated)
            .into_par_iter()
            .map(|n| {
                let (fx, fy) = place(n % evaluated);
                pattern_about(&nears[n / evaluated], reach, fx, fy, pitch_mm)
            })
            .collect();
        let blocks = windows
            .iter()
            .map(|window| {
                (0..spectrum.len())
                    .map(|line| {
                        let mut line_blocks: Vec<Vec<f64>> = Vec::with_capacity(places);
                        for k in 0..places {
                            if k >= evaluated {
                                let turned = line_blocks[places - 1 - k].iter().rev().copied();
                                line_blocks.push(turned.collect());
                                continue;
                            }
                            let (fx, fy) = place(k);
                            let pattern = &exact[line * evaluated + k];
                            let mut block = vec![0.0; side * side];
                            for (n, value) in block.iter_mut().enumerate() {
                                let x = (n % side) as i64 - reach as i64;
                                let y = (n / side) as i64 - reach as i64;
                                let placed = (1.0 - fx) * (1.0 - fy) * window.at(x, y)
                                    + fx * (1.0 - fy) * window.at(x - 1, y)
                                    + (1.0 - fx) * fy * window.at(x, y - 1)
                                    + fx * fy * window.at(x - 1, y - 1);
                                *value = pattern[n] / window.sum - placed;
                            }
                            line_blocks.push(block);
                        }
                        line_blocks
                    })
                    .collect()
            })
            .collect();
        Cores { reach, blocks }
    }

    /// Adds to `out` the corrections of plane `c`'s orders, interpolated
    /// between the sub-pixel places about each.
    fn correct(
        &self,
        c: usize,
        orders: &Orders,
        extent: &Extent,
        out: &mut [f64],
        control: &mut Control,
    ) -> Result<()> {
        let (w, h) = (extent.width as i64, extent.height as i64);
        let reach = self.reach as i64;
        let side = 2 * self.reach + 2;
        let scale = PHASES as f64;
        let weakest = weakest_corrected(orders);
        // Each corrected order's pixel, the four places about it with
        // their weights, and its share, sorted by row.
        let mut placed: Vec<Placed> = Vec::new();
        orders.each(|order| {
            if order.weight < weakest {
                return;
            }
            let (x0, y0) = (order.x.floor(), order.y.floor());
            let (px, py) = ((order.x - x0) * scale, (order.y - y0) * scale);
            let a = (px.floor() as usize).min(PHASES - 1);
            let b = (py.floor() as usize).min(PHASES - 1);
            let (ta, tb) = (px - a as f64, py - b as f64);
            let blocks = &self.blocks[c][order.line];
            let at = |a: usize, b: usize| blocks[b * (PHASES + 1) + a].as_slice();
            let mix = [
                (at(a, b), (1.0 - ta) * (1.0 - tb)),
                (at(a + 1, b), ta * (1.0 - tb)),
                (at(a, b + 1), (1.0 - ta) * tb),
                (at(a + 1, b + 1), ta * tb),
            ];
            let placed_order = Placed {
                x0: x0 as i64,
                y0: y0 as i64,
                mix,
                weight: order.weight,
            };
            if placed_order.y0 + reach + 1 >= 0 && placed_order.y0 - reach < h {
                placed.push(placed_order);
            }
        });
        placed.sort_by_key(|p| (p.y0, p.x0));
        // Each output row gathers the orders whose blocks cover it, so rows
        // run in parallel and the sums come out in the same order every
        // run.
        for_each_row(out, extent.width, control, |y, row| {
            let y = y as i64;
            let first = placed.partition_point(|p| p.y0 + reach + 1 < y);
            let last = placed.partition_point(|p| p.y0 - reach <= y);
            for p in &placed[first..last] {
                let v = (y - p.y0 + reach) as usize;
                for u in 0..side {
                    let x = p.x0 - reach + u as i64;
                    if x >= 0 && x < w {
                        let k = v * side + u;
                        let blend: f64 = p.mix.iter().map(|&(block, t)| t * block[k]).sum();
                        row[x as usize] += p.weight * blend;
                    }
                }
            }
        })
    }
}

/// An order to correct: its pixel, the blocks of the four places about it
/// with their weights, and its share.
struct Placed<'a> {
    x0: i64,
    y0: i64,
    mix: [(&'a [f64], f64); 4],
    weight: f64,
}

/// The weakest share an order may have and still be corrected: the orders
/// below it keep their bilinear place, and what they hold together, at
/// most [`UNCORRECTED`] of the light, lands within a pixel or two of where
/// it belongs. Found by the shares' binary exponents, in one pass.
fn weakest_corrected(orders: &Orders) -> f64 {
    let mut light = vec![0.0; 1100];
    let exponent = |w: f64| (-libm::log2(w).floor()).clamp(0.0, 1099.0) as usize;
    orders.each(|order| light[exponent(order.weight)] += order.weight);
    let mut held = 0.0;
    for (e, l) in light.iter().enumerate().rev() {
        held += l;
        if held > UNCORRECTED {
            return libm::exp2(-(e as f64));
        }
    }
    f64::INFINITY
}

/// The sub-pixel place (fx, fy) of block `k`.
fn place(k: usize) -> (f64, f64) {
    let step = PHASES as f64;
    (
        (k % (PHASES + 1)) as f64 / step,
        (k / (PHASES + 1)) as f64 / step,
    )
}

/// One wavelength's pattern (unit light) integrated over the
/// (2·`reach` + 2)² pixels from (−`reach`, −`reach`) about the pixel whose
/// centre lies (`fx`, `fy`) px left of and above the pattern's centre.
fn pattern_about(near: &NearField<'_>, reach: usize, fx: f64, fy: f64, pitch_mm: f64) -> Vec<f64> {
    let side = 2 * reach + 2;
    let offset = |n: usize, f: f64| n as f64 - reach as f64 - f;
    let mut block = vec![0.0; side * side];
    for (v, row) in block.chunks_mut(side).enumerate() {
        let dy = offset(v, fy);
        let xs: Vec<f64> = (0..side).map(|u| offset(u, fx) * pitch_mm).collect();
        // The pixels about the centre get the core's denser quadrature, as
        // in the pattern itself.
        let dense = |u: usize| offset(u, fx).abs() < 1.5 && dy.abs() < 1.5;
        let mut start = 0;
        while start < side {
            let core = dense(start);
            let end = (start..side).find(|&u| dense(u) != core).unwrap_or(side);
            near.add_many(&xs[start..end], -dy * pitch_mm, core, &mut row[start..end]);
            start = end;
        }
    }
    block
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::Cancel;
    use crate::kernel::Sending;

    #[test]
    fn scattering_and_fft_spread_orders_alike() {
        let extent = Extent::new(47, 33).unwrap().sent_by(Sending::Point);
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
            sum,
        };
        let cancel = Cancel::new();
        let mut quiet = Control::quiet(&cancel);
        let direct = scatter(&comb, &window, &extent, &mut quiet).unwrap();
        let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
        let kernel = Kernel::from_planes(7, 7, vec![plane]).unwrap();
        let comb32: Vec<f32> = comb.iter().map(|&v| v as f32).collect();
        let fft = convolve::compose(
            &kernel.planes()[0],
            (7, 7),
            &comb32,
            (47, 33),
            &mut Composing::cpu(),
            &mut quiet,
        )
        .unwrap();
        for (a, b) in direct.iter().zip(&fft) {
            assert!((a - f64::from(*b)).abs() < 1e-6, "{a} vs {b}");
        }
    }
}
