//! Star filters and gratings: their diffraction orders. A family of lines
//! shifts copies of the stop's pattern to the orders m·λf/d, each with its
//! share |c_m|² of the light; every wavelength lands elsewhere, so the
//! orders disperse into spectra (docs/physics.md §6).

use super::near::NearField;
use super::Spectrum;
use crate::control::{for_each, for_each_row, Control};
use crate::convolve::pool::Scratch;
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
    let lattice = Lattice(&optics.orders);
    let lines = Lines::new(optics, spectrum, pitch_mm, weights_total);
    let combs = combs(&lattice, &lines, extent, &mut control.part(0.0, 0.1))?;
    let weakest = weakest_corrected(&lattice, &lines, weights_total.len());
    let corrected = Corrected::new(&lattice, &lines, weakest);
    let share = 0.9 / planes.len().max(1) as f64;
    let mut filtered = Vec::with_capacity(planes.len());
    // Each plane becomes its zero order, and the other orders are added
    // into it: a 4K star filter's three f64 planes are not held twice.
    for (c, (mut plane, comb)) in planes.into_iter().zip(combs).enumerate() {
        let mut part = control.part(0.1 + c as f64 * share, 0.1 + (c + 1) as f64 * share);
        plane.par_iter_mut().for_each(|p| *p *= zero);
        add_orders(
            &comb,
            &windows[c],
            extent,
            &mut plane,
            composing,
            &mut part.part(0.0, 0.9),
        )?;
        drop(comb);
        cores.correct(&corrected, c, extent, &mut plane, &mut part.part(0.9, 1.0))?;
        filtered.push(plane);
    }
    Ok(filtered)
}

/// The largest half-size in px of the pattern the non-zero orders carry.
const ORDER_REACH: usize = 64;

/// Adds to `out` the comb with the window placed at each of its pixels, by
/// direct scattering or by FFT convolution, whichever the operation counts
/// say is cheaper.
fn add_orders(
    comb: &[f32],
    window: &Window,
    extent: &Extent,
    out: &mut [f64],
    composing: &mut Composing,
    control: &mut Control,
) -> Result<()> {
    let entries = comb.iter().filter(|v| **v != 0.0).count() as f64;
    let side = 2 * window.reach + 1;
    let direct = entries * (side * side) as f64;
    // Measured on two cores: scattering costs ~1.7 ns per multiply-add, the
    // FFT route ~1.8 s per plane of a 4K kernel, as much as 0.3·P·log₂P
    // multiply-adds for P padded pixels.
    let padded = (2 * extent.width) as f64 * (2 * extent.height) as f64;
    let fft = 0.3 * padded * libm::log2(padded);
    if direct <= fft {
        return scatter(comb, window, extent, out, control);
    }
    let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
    match Kernel::from_planes(side, side, vec![plane]) {
        Ok(kernel) => {
            let size = (extent.width, extent.height);
            let composed = convolve::compose(
                &kernel.planes()[0],
                (side, side),
                comb,
                size,
                composing,
                control,
            )?;
            out.par_iter_mut()
                .zip(composed)
                .for_each(|(o, v)| *o += f64::from(v).max(0.0));
            Ok(())
        }
        Err(_) => scatter(comb, window, extent, out, control),
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

/// Adds to `out` the comb with the window placed at each of its pixels
/// (nothing outside the extent). Each output row gathers the comb rows
/// within reach, so rows run in parallel and the sums come out in the same
/// order every run.
fn scatter(
    comb: &[f32],
    window: &Window,
    extent: &Extent,
    out: &mut [f64],
    control: &mut Control,
) -> Result<()> {
    let (w, h) = (extent.width, extent.height);
    let reach = window.reach as i64;
    let side = 2 * window.reach + 1;
    let entries: Vec<Vec<(usize, f64)>> = comb
        .chunks(w)
        .map(|row| {
            row.iter()
                .enumerate()
                .filter(|(_, v)| **v != 0.0)
                .map(|(x, v)| (x, f64::from(*v)))
                .collect()
        })
        .collect();
    for_each_row(out, w, control, |y, row| {
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
    })
}

/// The filter's orders, (ν, share |c_m|²), sorted by ν_y (as
/// [`Optics::orders`] are), so that those of one wavelength that land in a
/// band of rows lie together; the zero order among them is skipped. A
/// star filter has millions (pairs of families: 3.2 million for four
/// families at 200 µm, in every wavelength of the light).
struct Lattice<'a>(&'a [([f64; 2], f64)]);

impl Lattice<'_> {
    /// The non-zero orders.
    fn moved(&self) -> impl Iterator<Item = &([f64; 2], f64)> {
        self.0.iter().filter(|(nu, _)| nu != &[0.0, 0.0])
    }
}

/// Each wavelength of the light: px per cycle/mm of an order's shift
/// (λf over the pitch), and its weight in each plane over the plane's
/// total, by which an order's share is multiplied.
struct Lines(Vec<(f64, Vec<f64>)>);

impl Lines {
    fn new(optics: &Optics, spectrum: &Spectrum, pitch_mm: f64, totals: &[f64]) -> Lines {
        Lines(
            spectrum
                .iter()
                .map(|(lambda_nm, weights)| {
                    let shares = weights.iter().zip(totals).map(|(w, t)| w / t);
                    (
                        lambda_nm * 1e-6 * optics.focal_mm / pitch_mm,
                        shares.collect(),
                    )
                })
                .collect(),
        )
    }
}

/// Rows of the combs filled together: bands run in parallel, and every
/// pixel's sum comes out in the same order (wavelength, then ν_y) on any
/// number of threads.
const COMB_ROWS: usize = 16;

/// Each plane's orders spread bilinearly over the pixels about them, the
/// planes together: the orders' places are found once for all of them.
/// Summed in f64 band by band and kept in f32, the precision the FFT that
/// spreads them takes: three planes' combs hold the memory one plane's
/// did in f64 beside its f32 copy.
fn combs(
    lattice: &Lattice,
    lines: &Lines,
    extent: &Extent,
    control: &mut Control,
) -> Result<Vec<Vec<f32>>> {
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = ((width / 2) as f64, (height / 2) as f64);
    let planes = lines.0.first().map_or(0, |(_, shares)| shares.len());
    let mut combs: Vec<Vec<f32>> = (0..planes)
        .map(|_| crate::image::zeros(width * height))
        .collect::<Result<_>>()?;
    let mut bands: Vec<Vec<&mut [f32]>> = Vec::new();
    for comb in &mut combs {
        for (b, band) in comb.chunks_mut(COMB_ROWS * width).enumerate() {
            if b == bands.len() {
                bands.push(Vec::with_capacity(planes));
            }
            bands[b].push(band);
        }
    }
    let orders = lattice.0;
    let sums: Scratch<Vec<f64>> = Scratch::default();
    for_each(&mut bands, control, |b, band| {
        let top = b * COMB_ROWS;
        let rows = band.first().map_or(0, |plane| plane.len() / width);
        let (first, end) = (top as f64, (top + rows) as f64);
        let size = rows * width;
        let mut sum = sums.lend(Vec::new);
        sum.clear();
        sum.resize(size * planes, 0.0);
        for (to_px, shares) in &lines.0 {
            // The orders whose rows y0 = ⌊y⌋ or y0 + 1 lie in the band,
            // y = cy − ν_y·to_px, and a row more on either side against
            // round-off: each is checked below.
            let lowest = (cy - end - 1.0) / to_px;
            let highest = (cy - first + 2.0) / to_px;
            let from = orders.partition_point(|(nu, _)| nu[1] < lowest);
            let to = orders.partition_point(|(nu, _)| nu[1] <= highest);
            for (nu, share) in &orders[from..to.max(from)] {
                if nu == &[0.0, 0.0] {
                    continue;
                }
                let (x, y) = (cx + nu[0] * to_px, cy - nu[1] * to_px);
                let (x0, y0) = (x.floor(), y.floor());
                for (dx, dy, w) in bilinear(x - x0, y - y0) {
                    let (x, y) = (x0 + dx as f64, y0 + dy as f64);
                    if x >= 0.0 && y >= first && x < width as f64 && y < end {
                        let at = (y as usize - top) * width + x as usize;
                        for (c, plane_share) in shares.iter().enumerate() {
                            sum[c * size + at] += share * plane_share * w;
                        }
                    }
                }
            }
        }
        for (c, plane) in band.iter_mut().enumerate() {
            for (value, s) in plane.iter_mut().zip(&sum[c * size..(c + 1) * size]) {
                *value = *s as f32;
            }
        }
    })?;
    Ok(combs)
}

/// The orders bright enough to have their cores corrected in some plane
/// and wavelength (a share of at least `weakest`), the brightest first.
struct Corrected<'a> {
    lattice: &'a Lattice<'a>,
    lines: &'a Lines,
    by_share: Vec<usize>,
    weakest: Vec<f64>,
}

impl<'a> Corrected<'a> {
    fn new(lattice: &'a Lattice<'a>, lines: &'a Lines, weakest: Vec<f64>) -> Corrected<'a> {
        // An order is corrected in plane c where its share times its
        // wavelength's weight reaches the plane's weakest, so in some
        // wavelength where it does with the largest weight.
        let largest: Vec<f64> = (0..weakest.len())
            .map(|c| lines.0.iter().map(|(_, s)| s[c]).fold(0.0, f64::max))
            .collect();
        let orders = lattice.0;
        let mut by_share: Vec<usize> = (0..orders.len())
            .filter(|&i| {
                let (nu, share) = orders[i];
                nu != [0.0, 0.0] && largest.iter().zip(&weakest).any(|(l, w)| share * l >= *w)
            })
            .collect();
        by_share.sort_unstable_by(|&a, &b| orders[b].1.total_cmp(&orders[a].1).then(a.cmp(&b)));
        Corrected {
            lattice,
            lines,
            by_share,
            weakest,
        }
    }

    /// Visits every order corrected in plane `c`: its place in px from
    /// the kernel's left and top edges (pixel centres at whole numbers),
    /// its share of the plane and its wavelength's index, the brightest of
    /// each wavelength first.
    fn each(&self, c: usize, centre: (f64, f64), mut visit: impl FnMut(f64, f64, f64, usize)) {
        let orders = self.lattice.0;
        for (line, (to_px, shares)) in self.lines.0.iter().enumerate() {
            for &i in &self.by_share {
                let (nu, share) = orders[i];
                let weight = share * shares[c];
                if weight < self.weakest[c] {
                    break;
                }
                visit(
                    centre.0 + nu[0] * to_px,
                    centre.1 - nu[1] * to_px,
                    weight,
                    line,
                );
            }
        }
    }
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
        let sources: Vec<Source> = (0..places)
            .map(|k| Source::of(k, optics.pupil.is_round(), optics.pupil.is_real()))
            .collect();
        let evaluated: Vec<usize> = (0..places).filter(|&k| sources[k].place == k).collect();
        let singles: Vec<Spectrum> = spectrum
            .iter()
            .map(|(lambda_nm, _)| vec![(*lambda_nm, vec![1.0])])
            .collect();
        let nears: Vec<NearField<'_>> = singles
            .iter()
            .map(|single| NearField::new(optics, single, (pitch_mm, sending)))
            .collect();
        let count = evaluated.len();
        let exact: Vec<Vec<f64>> = (0..spectrum.len() * count)
            .into_par_iter()
            .map(|n| {
                let (fx, fy) = place(evaluated[n % count]);
                pattern_about(&nears[n / count], reach, fx, fy, pitch_mm)
            })
            .collect();
        // Each place's evaluated pattern, by its index in `exact`.
        let at: Vec<usize> = sources
            .iter()
            .map(|source| evaluated.partition_point(|&e| e < source.place))
            .collect();
        let blocks = windows
            .iter()
            .map(|window| {
                // The window placed bilinearly at each place: the same for
                // every wavelength.
                let placed: Vec<Vec<f64>> = (0..places)
                    .map(|k| {
                        let (fx, fy) = place(k);
                        let corners = bilinear(fx, fy);
                        (0..side * side)
                            .map(|n| {
                                let x = (n % side) as i64 - reach as i64;
                                let y = (n / side) as i64 - reach as i64;
                                corners
                                    .iter()
                                    .map(|&(dx, dy, w)| w * window.at(x - dx as i64, y - dy as i64))
                                    .sum()
                            })
                            .collect()
                    })
                    .collect();
                (0..spectrum.len())
                    .map(|line| {
                        (0..places)
                            .map(|k| {
                                let pattern = &exact[line * count + at[k]];
                                placed[k]
                                    .iter()
                                    .enumerate()
                                    .map(|(n, placed)| {
                                        pattern[sources[k].pixel(n, side)] / window.sum - placed
                                    })
                                    .collect()
                            })
                            .collect()
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
        corrected: &Corrected,
        c: usize,
        extent: &Extent,
        out: &mut [f64],
        control: &mut Control,
    ) -> Result<()> {
        let (w, h) = (extent.width as i64, extent.height as i64);
        let reach = self.reach as i64;
        let side = 2 * self.reach + 2;
        let scale = PHASES as f64;
        let centre = ((w / 2) as f64, (h / 2) as f64);
        // Each corrected order's pixel, the place below and left of it and
        // how far it lies towards the next, its wavelength and share.
        let within = |y: f64| {
            let y0 = y.floor() as i64;
            y0 + reach + 1 >= 0 && y0 - reach < h
        };
        // Counted first, as the filter's orders are (Aperture::orders).
        let mut length = 0;
        corrected.each(c, centre, |_, y, _, _| length += usize::from(within(y)));
        let mut placed: Vec<Placed> = Vec::with_capacity(length);
        corrected.each(c, centre, |x, y, weight, line| {
            let (x0, y0) = (x.floor(), y.floor());
            let (px, py) = ((x - x0) * scale, (y - y0) * scale);
            let a = (px.floor() as usize).min(PHASES - 1);
            let b = (py.floor() as usize).min(PHASES - 1);
            if within(y) {
                placed.push(Placed {
                    x0: x0 as i64,
                    y0: y0 as i64,
                    place: (b * (PHASES + 1) + a) as u32,
                    line: line as u32,
                    towards: (px - a as f64, py - b as f64),
                    weight,
                });
            }
        });
        // By row (counting), each row's in the order visited.
        let lowest = -reach - 1;
        let mut starts = vec![0usize; (h + 2 * reach + 2) as usize];
        for p in &placed {
            starts[(p.y0 - lowest) as usize + 1] += 1;
        }
        for k in 1..starts.len() {
            starts[k] += starts[k - 1];
        }
        let mut next = starts.clone();
        let mut slots: Vec<usize> = placed
            .iter()
            .map(|p| {
                let slot = &mut next[(p.y0 - lowest) as usize];
                *slot += 1;
                *slot - 1
            })
            .collect();
        // Each to its slot, in place, cycle by cycle: a second list of
        // them would hold a hundred bytes per order more.
        for i in 0..placed.len() {
            while slots[i] != i {
                let j = slots[i];
                placed.swap(i, j);
                slots.swap(i, j);
            }
        }
        let start = |y0: i64| starts[(y0 - lowest).clamp(0, starts.len() as i64 - 1) as usize];
        // Each output row gathers the orders whose blocks cover it, so rows
        // run in parallel and the sums come out in the same order every
        // run.
        for_each_row(out, extent.width, control, |y, row| {
            let y = y as i64;
            for p in &placed[start(y - reach - 1)..start(y + reach + 1)] {
                let v = (y - p.y0 + reach) as usize;
                // The block's columns u that fall within the row.
                let left = p.x0 - reach;
                let (from, to) = (
                    (-left).clamp(0, side as i64),
                    (w - left).clamp(0, side as i64),
                );
                if from >= to {
                    continue;
                }
                let (from, to) = (from as usize, to as usize);
                let x = (left + from as i64) as usize;
                let blocks = &self.blocks[c][p.line as usize];
                let mix = bilinear(p.towards.0, p.towards.1).map(|(da, db, t)| {
                    let place = p.place as usize + db * (PHASES + 1) + da;
                    (&blocks[place][v * side + from..v * side + to], t)
                });
                let block = |m: usize| mix[m].0;
                let (t0, t1, t2, t3) = (mix[0].1, mix[1].1, mix[2].1, mix[3].1);
                let out = row[x..x + to - from].iter_mut();
                let blocks = block(0).iter().zip(block(1)).zip(block(2)).zip(block(3));
                for (o, (((b0, b1), b2), b3)) in out.zip(blocks) {
                    *o += p.weight * (t0 * b0 + t1 * b1 + t2 * b2 + t3 * b3);
                }
            }
        })
    }
}

/// An order to correct: its pixel, the sub-pixel place below and left of
/// it (b·(PHASES + 1) + a) and its fractions of the way to the next along
/// each axis, its wavelength's index and its share. Its four places' blocks
/// are looked up where its rows are summed: a star filter corrects a
/// million orders, and 48 bytes each instead of their four slices (120)
/// keep that list the least of what its kernel holds.
struct Placed {
    x0: i64,
    y0: i64,
    place: u32,
    line: u32,
    towards: (f64, f64),
    weight: f64,
}

/// The weakest share an order may have and still be corrected, per plane:
/// the orders below it keep their bilinear place, and what they hold
/// together, at most [`UNCORRECTED`] of the light, lands within a pixel or
/// two of where it belongs. Found by the shares' binary exponents, each
/// wavelength apart and then added in order.
fn weakest_corrected(lattice: &Lattice, lines: &Lines, planes: usize) -> Vec<f64> {
    const EXPONENTS: usize = 1100;
    // ⌊−log₂ w⌋ from the bits: w = m·2^e, 1 ≤ m < 2.
    let exponent = |w: f64| {
        let e = ((w.to_bits() >> 52) & 0x7ff) as i64 - 1023;
        (-e).clamp(0, EXPONENTS as i64 - 1) as usize
    };
    let per_line: Vec<Vec<f64>> = lines
        .0
        .par_iter()
        .map(|(_, shares)| {
            let mut light = vec![0.0; EXPONENTS * planes];
            for (_, order) in lattice.moved() {
                for (c, share) in shares.iter().enumerate() {
                    let w = order * share;
                    light[c * EXPONENTS + exponent(w)] += w;
                }
            }
            light
        })
        .collect();
    (0..planes)
        .map(|c| {
            let mut held = 0.0;
            for e in (0..EXPONENTS).rev() {
                held += per_line.iter().map(|l| l[c * EXPONENTS + e]).sum::<f64>();
                if held > UNCORRECTED {
                    return libm::exp2(-(e as f64));
                }
            }
            f64::INFINITY
        })
        .collect()
}

/// Where the exact pattern about a sub-pixel place comes from: the place
/// evaluated, and how its block is turned. A pupil that delays no part of
/// the light gives a centrosymmetric pattern: the place (1 − fx, 1 − fy)
/// sees the block of (fx, fy) turned by half a turn, so half the places
/// are evaluated. A round one's pattern is mirrored across both axes and
/// the diagonals too: 15 places of the 81 are evaluated, those with
/// fx ≤ fy ≤ ½.
struct Source {
    place: usize,
    /// The block's rows and columns swapped, then its columns and its
    /// rows reversed.
    transposed: bool,
    mirrored: [bool; 2],
}

impl Source {
    fn of(k: usize, round: bool, real: bool) -> Source {
        let (a, b) = (k % (PHASES + 1), k / (PHASES + 1));
        let alone = Source {
            place: k,
            transposed: false,
            mirrored: [false, false],
        };
        if round {
            let fold = |a: usize| (a.min(PHASES - a), a > PHASES - a);
            let ((a1, mirror_u), (b1, mirror_v)) = (fold(a), fold(b));
            let (a2, b2) = (a1.min(b1), a1.max(b1));
            Source {
                place: b2 * (PHASES + 1) + a2,
                transposed: a1 > b1,
                mirrored: [mirror_u, mirror_v],
            }
        } else if real && k > (PHASES + 1) * (PHASES + 1) / 2 {
            Source {
                place: (PHASES + 1) * (PHASES + 1) - 1 - k,
                transposed: false,
                mirrored: [true, true],
            }
        } else {
            alone
        }
    }

    /// The pixel of the evaluated block that pixel `n` of this place's
    /// block is, blocks `side` wide.
    fn pixel(&self, n: usize, side: usize) -> usize {
        let (mut u, mut v) = (n % side, n / side);
        if self.mirrored[0] {
            u = side - 1 - u;
        }
        if self.mirrored[1] {
            v = side - 1 - v;
        }
        if self.transposed {
            (u, v) = (v, u);
        }
        v * side + u
    }
}

/// The four corners about a point (fx, fy) past the first, as offsets
/// from it, with their bilinear weights.
fn bilinear(fx: f64, fy: f64) -> [(usize, usize, f64); 4] {
    [
        (0, 0, (1.0 - fx) * (1.0 - fy)),
        (1, 0, fx * (1.0 - fy)),
        (0, 1, (1.0 - fx) * fy),
        (1, 1, fx * fy),
    ]
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

    /// A star filter of three families on a 50 mm f/8 lens, its 17
    /// wavelengths and their planes' totals.
    fn star() -> (Optics, Spectrum, Vec<f64>) {
        let family = |angle_deg| crate::optics::aperture::Filter {
            angle_deg,
            spacing_um: 200.0,
            width_um: 10.0,
        };
        let aperture = crate::optics::Aperture {
            blades: 0,
            spectral: true,
            filters: vec![family(0.0), family(45.0), family(90.0)],
            ..crate::optics::Aperture::new(7)
        };
        let camera = crate::CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: Some(8.0),
            ..Default::default()
        };
        let optics = aperture.optics(&camera, 1.0, 0).unwrap();
        let spectrum = crate::optics::aperture::spectrum::Light::Spectral.wavelengths();
        let totals = (0..3)
            .map(|c| spectrum.iter().map(|(_, w)| w[c]).sum())
            .collect();
        (optics, spectrum, totals)
    }

    #[test]
    fn the_combs_bands_place_every_order_as_one_pass_does() {
        // 87 rows: bands of 16 and a last of 7; orders straddle every
        // band's edge.
        let pitch = 0.012;
        let (optics, spectrum, totals) = star();
        let extent = Extent::new(203, 87).unwrap();
        let lattice = Lattice(&optics.orders);
        let lines = Lines::new(&optics, &spectrum, pitch, &totals);
        let cancel = Cancel::new();
        let combs = combs(&lattice, &lines, &extent, &mut Control::quiet(&cancel)).unwrap();
        let (w, h) = (203usize, 87usize);
        let mut one: Vec<Vec<f64>> = vec![vec![0.0; w * h]; 3];
        for (to_px, shares) in &lines.0 {
            for (nu, share) in Lattice(&optics.orders).moved() {
                let (x, y) = (101.0 + nu[0] * to_px, 43.0 - nu[1] * to_px);
                let (x0, y0) = (x.floor(), y.floor());
                for (dx, dy, f) in bilinear(x - x0, y - y0) {
                    let (x, y) = (x0 + dx as f64, y0 + dy as f64);
                    if x >= 0.0 && y >= 0.0 && x < w as f64 && y < h as f64 {
                        for (plane, s) in one.iter_mut().zip(shares) {
                            plane[y as usize * w + x as usize] += share * s * f;
                        }
                    }
                }
            }
        }
        // The bands' sums are the single pass's to 1e-12, kept in f32.
        for (banded, one) in combs.iter().zip(&one) {
            let total: f64 = one.iter().sum();
            assert!(total > 1e-3, "{total}");
            for (a, b) in banded.iter().zip(one) {
                let a = f64::from(*a);
                assert!(
                    (a - b).abs() <= 6e-8 * b.abs() + 1e-12 * total,
                    "{a} against {b}"
                );
            }
        }
    }

    #[test]
    fn the_orders_left_uncorrected_hold_at_most_their_share() {
        // Below the weakest corrected share lies at most UNCORRECTED of
        // each plane's light, and below twice it, more: the threshold is
        // the highest power of two that keeps to it.
        let (optics, spectrum, totals) = star();
        let lattice = Lattice(&optics.orders);
        let lines = Lines::new(&optics, &spectrum, 0.012, &totals);
        let weakest = weakest_corrected(&lattice, &lines, 3);
        for (c, weakest) in weakest.iter().enumerate() {
            let below = |threshold: f64| -> f64 {
                let mut light = 0.0;
                for (_, shares) in &lines.0 {
                    for (_, share) in lattice.moved() {
                        let w = share * shares[c];
                        if w < threshold {
                            light += w;
                        }
                    }
                }
                light
            };
            assert!(below(*weakest) <= UNCORRECTED, "plane {c}");
            assert!(below(2.0 * weakest) > UNCORRECTED, "plane {c}");
        }
        let corrected = Corrected::new(&lattice, &lines, weakest.clone());
        for c in 0..3 {
            let mut count = 0;
            corrected.each(c, (0.0, 0.0), |_, _, w, _| {
                assert!(w >= weakest[c]);
                count += 1;
            });
            let all: usize = lines
                .0
                .iter()
                .map(|(_, s)| {
                    lattice
                        .moved()
                        .filter(|(_, o)| o * s[c] >= weakest[c])
                        .count()
                })
                .sum();
            assert_eq!(count, all, "plane {c}");
        }
    }

    #[test]
    fn a_places_core_turned_from_another_is_its_own() {
        // A round stop (the star filter's) and a 7-blade one: every place's
        // pattern about an order, evaluated, against the block of the
        // place it is taken from, turned.
        let (round, _, _) = star();
        let camera = crate::CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: Some(8.0),
            ..Default::default()
        };
        let bladed = crate::optics::Aperture::new(7)
            .optics(&camera, 1.0, 0)
            .unwrap();
        assert!(round.pupil.is_round() && !bladed.pupil.is_round() && bladed.pupil.is_real());
        let (pitch, reach) = (0.004, 4);
        let side = 2 * reach + 2;
        let light = vec![(550.0, vec![1.0])];
        for optics in [&round, &bladed] {
            let near = NearField::new(optics, &light, (pitch, Sending::Pixel));
            let places = (PHASES + 1) * (PHASES + 1);
            let mut evaluated = 0;
            for k in 0..places {
                let source = Source::of(k, optics.pupil.is_round(), optics.pupil.is_real());
                evaluated += usize::from(source.place == k);
                let (fx, fy) = place(k);
                let own = pattern_about(&near, reach, fx, fy, pitch);
                let (sx, sy) = place(source.place);
                let theirs = pattern_about(&near, reach, sx, sy, pitch);
                let peak = own.iter().fold(0.0f64, |a, b| a.max(*b));
                for (n, value) in own.iter().enumerate() {
                    let turned = theirs[source.pixel(n, side)];
                    assert!(
                        (value - turned).abs() <= 1e-12 * peak,
                        "place {k}, pixel {n}: {value} against {turned}"
                    );
                }
            }
            assert_eq!(evaluated, if optics.pupil.is_round() { 15 } else { 41 });
        }
    }

    #[test]
    fn scattering_and_fft_spread_orders_alike() {
        let extent = Extent::new(47, 33).unwrap().sent_by(Sending::Point);
        let mut comb = vec![0.0f32; 47 * 33];
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
        let mut direct = vec![0.0; 47 * 33];
        scatter(&comb, &window, &extent, &mut direct, &mut quiet).unwrap();
        let plane: Vec<f32> = window.values.iter().map(|&v| v as f32).collect();
        let kernel = Kernel::from_planes(7, 7, vec![plane]).unwrap();
        let fft = convolve::compose(
            &kernel.planes()[0],
            (7, 7),
            &comb,
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
