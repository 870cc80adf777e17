//! Rasterising a diffraction PSF (docs/physics.md §6): each pixel gets the
//! mean over its area of PSF_λ(x) = |Â(x/(λf))|² / ((λf)² · area), for each
//! wavelength, weighted by each plane's sensitivity; a filter's orders then
//! shift copies of the pattern.
//!
//! Near the centre the transform is evaluated exactly, supersampled
//! ([`near`]). Beyond ~60 λN the cross terms of edges whose rays differ
//! are a percent of the light: there each edge's pattern is averaged over
//! the pixel analytically, with the cross terms of parallel edges
//! ([`far`]). Filter orders are in [`orders`].

mod far;
mod near;
mod orders;

use super::{Extent, Sending};
use crate::control::{for_each_interleaved, Control};
use crate::convolve::Composing;
use crate::error::Result;
use crate::optics::aperture::spectrum::Light;
use crate::optics::aperture::Optics;
use far::FarField;
use near::{NearField, CORNERS};
use rayon::prelude::*;
use std::ops::Range;

/// Near-field pixels evaluated together: their per-pixel and per-sample
/// phase factors stay in cache.
const NEAR_RUN: usize = 32;

/// What light to integrate: (wavelength nm, weight per plane).
pub(crate) type Spectrum = Vec<(f64, Vec<f64>)>;

/// The pattern of `optics` integrated over `light` at `pitch_mm` per pixel:
/// one plane per colour (one for monochrome light), each the share of the
/// pattern's light that falls on each pixel of the extent; a filter's orders are spread where `composing` says.
pub(crate) fn pattern(
    optics: &Optics,
    light: Light,
    (extent, pitch_mm): (&Extent, f64),
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Vec<Vec<f64>>> {
    let spectrum = light.wavelengths();
    let longest = spectrum.iter().map(|(l, _)| *l).fold(0.0, f64::max) * 1e-6;
    let far_from = (48.0 * pitch_mm).max(60.0 * longest * optics.focal_mm / optics.diameter_mm);
    pattern_with(
        optics,
        &spectrum,
        (extent, pitch_mm),
        far_from,
        composing,
        control,
    )
}

/// As [`pattern`], with the far field from `far_from` mm out.
fn pattern_with(
    optics: &Optics,
    spectrum: &Spectrum,
    (extent, pitch_mm): (&Extent, f64),
    far_from: f64,
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Vec<Vec<f64>>> {
    let planes = spectrum.first().map_or(1, |(_, w)| w.len());
    let (width, height) = (extent.width, extent.height);
    let (cx, cy) = (width / 2, height / 2);
    let weights_total: Vec<f64> = (0..planes)
        .map(|c| spectrum.iter().map(|(_, w)| w[c]).sum::<f64>())
        .collect();
    let near = NearField::new(optics, spectrum, (pitch_mm, extent.sending));
    let reach = pitch_mm * libm::hypot(width as f64, height as f64) / 2.0;
    let far = FarField::new(
        optics,
        spectrum,
        &weights_total,
        (pitch_mm, extent.sending),
        reach,
    );
    let filtered = optics.orders.len() > 1;

    let far2 = far_from * far_from;
    let tents = extent.sending == Sending::Pixel;
    let chord = Chord {
        centre: (cx, cy),
        pitch_mm,
        far2,
    };
    let rows = Rows {
        near: &near,
        far: &far,
        chord: &chord,
        weights_total: &weights_total,
        centre: (cx, cy),
        pitch_mm,
        tents,
    };
    let mut result: Vec<Vec<f64>> = (0..planes)
        .map(|_| crate::image::zeros(width * height))
        .collect::<Result<_>>()?;
    // A real pupil's pattern is centrosymmetric, PSF(−x) = PSF(x), and so
    // are the near field's quadrature and the far field's terms: the rows
    // down to the centre are computed, the rest are their mirror images.
    // Grease that delays the light breaks the symmetry: every row is
    // computed.
    let computed = if optics.pupil.is_real() {
        (cy + 1).min(height)
    } else {
        height
    };
    // An even width leaves the first column, left of the centre, without
    // a mirror image right of it.
    let alone = (2 * cx + 1).saturating_sub(width).min(width);
    // A pupil mirrored across an axis mirrors the pattern across both:
    // the computed rows' columns left of the centre are those right of it.
    let mirrored = computed < height && optics.pupil.is_mirror_symmetric();
    let spans: Vec<Range<usize>> = if mirrored {
        [0..alone, cx..width]
            .into_iter()
            .filter(|span| !span.is_empty())
            .collect()
    } else {
        let every = 0..width;
        vec![every]
    };
    let mut rasterising = control.part(0.0, if filtered { 0.8 } else { 1.0 });
    // The near field's rows, about the centre, cost the most.
    let mut filling = rasterising.part(0.0, if tents { 0.3 } else { 1.0 });
    for_each_interleaved(
        &mut plane_rows(&mut result, width, 0..computed),
        &mut filling,
        |j, row| {
            for span in &spans {
                rows.fill(j, row, span.clone());
            }
        },
    )?;
    if tents {
        let mut summing = rasterising.part(0.3, 1.0);
        let share = 1.0 / spans.len() as f64;
        for (s, span) in spans.iter().enumerate() {
            near_tents(
                &near,
                &chord,
                &mut result,
                width,
                0..computed,
                span.clone(),
                &mut summing.part(s as f64 * share, (s + 1) as f64 * share),
            )?;
        }
    }
    if mirrored {
        mirror_left(&mut result, width, cx, computed, alone);
    }
    mirror_below(&mut result, width, (cx, cy), computed);
    if alone > 0 && computed < height {
        plane_rows(&mut result, width, computed..height)
            .par_iter_mut()
            .enumerate()
            .for_each(|(k, row)| rows.fill(computed + k, row, 0..alone));
        if tents {
            let cancel = control.cancel();
            let mut quiet = Control::quiet(&cancel);
            near_tents(
                &near,
                &chord,
                &mut result,
                width,
                computed..height,
                0..alone,
                &mut quiet,
            )?;
        }
    }
    control.check()?;
    held_share(
        optics,
        spectrum,
        result,
        (extent, pitch_mm),
        &weights_total,
        composing,
        control,
    )
}

/// The fields of `result` divided into the share of the light the extent
/// holds, through the filter where there is one.
fn held_share(
    optics: &Optics,
    spectrum: &Spectrum,
    mut result: Vec<Vec<f64>>,
    (extent, pitch_mm): (&Extent, f64),
    weights_total: &[f64],
    composing: &mut Composing,
    control: &mut Control,
) -> Result<Vec<Vec<f64>>> {
    // The fields are the pattern's energy per pixel (Parseval: each
    // wavelength's whole pattern holds its weight), so dividing by the
    // weights leaves each plane the share of the light the extent holds;
    // the rest falls beyond it. Each plane's sum is taken as it is
    // divided, its chunks in cache.
    let mut sums: Vec<f64> = result
        .iter_mut()
        .zip(weights_total)
        .map(|(plane, total)| chunked_sum(plane, Some(*total)))
        .collect();
    if optics.orders.len() > 1 {
        result = orders::through_filter(
            optics,
            spectrum,
            result,
            (extent, pitch_mm),
            weights_total,
            composing,
            &mut control.part(0.8, 1.0),
        )?;
        // The light the filter passes, in all its orders, is the light the
        // exposure was set on.
        let passed: f64 = optics.orders.iter().map(|(_, w)| w).sum();
        if passed > 0.0 {
            for plane in &mut result {
                plane.par_iter_mut().for_each(|v| *v /= passed);
            }
        }
        sums = result
            .iter_mut()
            .map(|plane| chunked_sum(plane, None))
            .collect();
    }
    // The far field's asymptotic terms may add up to a hair more than the
    // pupil's light over a wide extent (2·10⁻⁴ for a vaned mirror over
    // 128 px): a kernel never makes light.
    for (plane, total) in result.iter_mut().zip(sums) {
        if total > 1.0 {
            plane.par_iter_mut().for_each(|v| *v /= total);
        }
    }
    Ok(result)
}

/// The sum of `plane`, by chunks of 2¹⁶ values on every core (the same
/// sum for any number of them), each chunk divided by `divisor` first
/// where there is one.
fn chunked_sum(plane: &mut [f64], divisor: Option<f64>) -> f64 {
    plane
        .par_chunks_mut(1 << 16)
        .map(|chunk| {
            if let Some(divisor) = divisor {
                chunk.iter_mut().for_each(|v| *v /= divisor);
            }
            chunk.iter().sum::<f64>()
        })
        .collect::<Vec<f64>>()
        .iter()
        .sum()
}

/// The rows below the first `computed` of each plane (`width` wide) as the
/// mirror images, through `centre`, of those above: a centrosymmetric
/// pattern's.
fn mirror_below(planes: &mut [Vec<f64>], width: usize, (cx, cy): (usize, usize), computed: usize) {
    for plane in planes {
        let (top, bottom) = plane.split_at_mut(computed * width);
        bottom
            .par_chunks_mut(width)
            .enumerate()
            .for_each(|(k, row)| {
                let mirror = &top[(2 * cy - computed - k) * width..][..width];
                // Column i mirrors column 2cx − i, where that lies in the row.
                let first = (2 * cx + 1).saturating_sub(width);
                let last = (2 * cx).min(width - 1);
                if first <= last {
                    for (value, m) in row[first..=last]
                        .iter_mut()
                        .zip(mirror[2 * cx - last..=2 * cx - first].iter().rev())
                    {
                        *value = *m;
                    }
                }
            });
    }
}

/// Columns `alone`..`cx` of the first `computed` rows of each plane
/// (`width` wide) as the mirror images, across the centre column `cx`, of
/// those right of it: a pattern mirrored across both axes.
fn mirror_left(planes: &mut [Vec<f64>], width: usize, cx: usize, computed: usize, alone: usize) {
    for plane in planes {
        plane[..computed * width]
            .par_chunks_mut(width)
            .for_each(|row| {
                let (left, right) = row.split_at_mut(cx);
                for (value, mirror) in left[alone..].iter_mut().rev().zip(&right[1..]) {
                    *value = *mirror;
                }
            });
    }
}

/// What fills a pattern's rows: the near and far fields, where the near
/// field lies, and the grid.
struct Rows<'a> {
    near: &'a NearField<'a>,
    far: &'a FarField,
    chord: &'a Chord,
    /// Per plane, the total weight of the spectrum's wavelengths.
    weights_total: &'a [f64],
    centre: (usize, usize),
    pitch_mm: f64,
    /// Light sent by a pixel: the near pixels are summed from unit squares
    /// after the rows are filled ([`near_tents`]).
    tents: bool,
}

impl Rows<'_> {
    /// The pixels of row `j` in `columns` (the planes' rows in `row`): a
    /// run of near pixels about the centre (a circle's chord), far ones on
    /// either side, computed with the planes side by side and then dealt
    /// out.
    fn fill(&self, j: usize, row: &mut [&mut [f64]], columns: Range<usize>) {
        let (cx, cy) = self.centre;
        let (pitch_mm, planes) = (self.pitch_mm, self.weights_total.len());
        let y = (cy as f64 - j as f64) * pitch_mm;
        let x = |i: usize| (i as f64 - cx as f64) * pitch_mm;
        let chord = self.chord.of_row(j, columns.clone());
        let first = columns.start;
        let mut values = vec![0.0; columns.len() * planes];
        let mut scratch = far::Row::default();
        for side in [columns.start..chord.start, chord.end..columns.end] {
            if !side.is_empty() {
                let out = &mut values[(side.start - first) * planes..(side.end - first) * planes];
                self.far.row(
                    x(side.start),
                    y,
                    pitch_mm,
                    self.weights_total,
                    &mut scratch,
                    out,
                );
            }
        }
        // The near pixels lie together, in runs of a few dozen sharing
        // their sample offsets (the core's, denser, apart).
        let core = |i: usize| i.abs_diff(cx) <= 1 && j.abs_diff(cy) <= 1;
        let pixels: Vec<usize> = if self.tents {
            Vec::new()
        } else {
            chord.collect()
        };
        for run in pixels.chunk_by(|&a, &b| core(a) == core(b)) {
            for part in run.chunks(NEAR_RUN) {
                let xs: Vec<f64> = part.iter().map(|&i| x(i)).collect();
                let at = (part[0] - first) * planes;
                self.near.add_many(
                    &xs,
                    y,
                    core(part[0]),
                    &mut values[at..at + xs.len() * planes],
                );
            }
        }
        for (c, plane_row) in row.iter_mut().enumerate() {
            for (value, pixel) in plane_row[columns.clone()]
                .iter_mut()
                .zip(values.chunks_exact(planes))
            {
                *value = pixel[c];
            }
        }
    }
}

/// Where the near field lies: the pixels closer than √`far2` mm to the
/// centre pixel's centre.
struct Chord {
    centre: (usize, usize),
    pitch_mm: f64,
    far2: f64,
}

impl Chord {
    /// The near pixels of row `j` within `columns`, which lie together.
    fn of_row(&self, j: usize, columns: Range<usize>) -> Range<usize> {
        let ((cx, cy), pitch_mm, far2) = (self.centre, self.pitch_mm, self.far2);
        let y = (cy as f64 - j as f64) * pitch_mm;
        if y * y >= far2 {
            return columns.start..columns.start;
        }
        let x = |i: usize| (i as f64 - cx as f64) * pitch_mm;
        let reach = ((far2 - y * y).sqrt() / pitch_mm).ceil() as usize;
        let near = |i: usize| x(i).powi(2) + y * y < far2;
        let lo = (cx + 1).saturating_sub(reach).max(columns.start);
        let hi = cx.saturating_add(reach).min(columns.end);
        let lo = (lo..hi).find(|&i| near(i)).unwrap_or(hi);
        let hi = (lo..hi).rfind(|&i| near(i)).map_or(lo, |i| i + 1);
        lo..hi
    }
}

/// Square rows evaluated together before their light is dealt out.
const SQUARE_ROWS: usize = 32;

/// Adds to the near pixels of `rows` × `columns` the near field under
/// their tents (light sent by a pixel, docs/physics.md §2), summed from
/// the unit squares between pixel centres: square row k lies between
/// pixel rows k − 1 and k, square i between columns i − 1 and i, and each
/// gives its four corner pixels their share (`NearField::add_squares`).
/// The squares are evaluated in parallel and dealt out in order, so that
/// every pixel adds its four in the same order on any number of threads.
fn near_tents(
    near: &NearField<'_>,
    chord: &Chord,
    result: &mut [Vec<f64>],
    width: usize,
    rows: Range<usize>,
    columns: Range<usize>,
    control: &mut Control,
) -> Result<()> {
    let planes = result.len();
    let ((cx, cy), pitch_mm) = (chord.centre, chord.pitch_mm);
    let chords: Vec<Range<usize>> = rows
        .clone()
        .map(|j| chord.of_row(j, columns.clone()))
        .collect();
    let row_chord = |j: usize| {
        if rows.contains(&j) {
            chords[j - rows.start].clone()
        } else {
            0..0
        }
    };
    // The squares of square row k: those touching a near pixel of the
    // rows above and below.
    let squares_of = |k: usize| {
        let (above, below) = (k.checked_sub(1).map_or(0..0, row_chord), row_chord(k));
        match (above.is_empty(), below.is_empty()) {
            (true, true) => 0..0,
            (false, true) => above.start..above.end + 1,
            (true, false) => below.start..below.end + 1,
            (false, false) => above.start.min(below.start)..above.end.max(below.end) + 1,
        }
    };
    let square_rows: Vec<usize> = (rows.start..=rows.end)
        .filter(|&k| !squares_of(k).is_empty())
        .collect();
    let batches = square_rows.chunks(SQUARE_ROWS).count().max(1);
    for (b, batch) in square_rows.chunks(SQUARE_ROWS).enumerate() {
        control.check()?;
        let evaluated: Vec<(usize, Range<usize>, Vec<f64>)> = batch
            .par_iter()
            .map(|&k| {
                let squares = squares_of(k);
                let y = (cy as f64 - k as f64 + 0.5) * pitch_mm;
                let x = |i: usize| (i as f64 - cx as f64 - 0.5) * pitch_mm;
                let core = |i: usize| {
                    (cx.saturating_sub(1)..=cx + 2).contains(&i)
                        && (cy.saturating_sub(1)..=cy + 2).contains(&k)
                };
                let mut values = vec![0.0; squares.len() * CORNERS * planes];
                let all: Vec<usize> = squares.clone().collect();
                for run in all.chunk_by(|&a, &b| core(a) == core(b)) {
                    for part in run.chunks(NEAR_RUN) {
                        let xs: Vec<f64> = part.iter().map(|&i| x(i)).collect();
                        let at = (part[0] - squares.start) * CORNERS * planes;
                        let out = &mut values[at..at + xs.len() * CORNERS * planes];
                        near.add_squares(&xs, y, core(part[0]), out);
                    }
                }
                (k, squares, values)
            })
            .collect();
        for (k, squares, values) in evaluated {
            let (above, below) = (k.checked_sub(1).map_or(0..0, row_chord), row_chord(k));
            for (n, i) in squares.enumerate() {
                // Top left, top right, bottom left, bottom right.
                let pixels = [
                    (i.checked_sub(1), k.checked_sub(1), &above),
                    (Some(i), k.checked_sub(1), &above),
                    (i.checked_sub(1), Some(k), &below),
                    (Some(i), Some(k), &below),
                ];
                for (c, (column, row, near_ones)) in pixels.into_iter().enumerate() {
                    let (Some(column), Some(row)) = (column, row) else {
                        continue;
                    };
                    if !near_ones.contains(&column) || column >= width {
                        continue;
                    }
                    let share = &values[(n * CORNERS + c) * planes..][..planes];
                    for (plane, v) in result.iter_mut().zip(share) {
                        plane[row * width + column] += v;
                    }
                }
            }
        }
        control.report((b + 1) as f64 / batches as f64);
    }
    Ok(())
}

/// Rows `rows` of every plane, each row as its planes' slices.
fn plane_rows(planes: &mut [Vec<f64>], width: usize, rows: Range<usize>) -> Vec<Vec<&mut [f64]>> {
    let mut out: Vec<Vec<&mut [f64]>> = rows
        .clone()
        .map(|_| Vec::with_capacity(planes.len()))
        .collect();
    for plane in planes {
        let chunk = &mut plane[rows.start * width..rows.end * width];
        for (row, slice) in out.iter_mut().zip(chunk.chunks_mut(width)) {
            row.push(slice);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::control::Cancel;
    use crate::kernel::Sending;
    use crate::optics::Aperture;

    const SIDE: usize = 141;

    /// A stop of `blades` (0: round) at f/`f_number` on a 50 mm lens.
    pub(super) fn stop(blades: u32, roundness: f64, f_number: f64) -> Optics {
        let aperture = Aperture {
            blades,
            roundness,
            ..stop_parameters()
        };
        lens(aperture, f_number)
    }

    /// A telescope: a round stop, an obstruction of 0.3 and 4 vanes, f/8.
    fn telescope() -> Optics {
        lens(
            Aperture {
                blades: 0,
                obstruction: 0.3,
                vanes: 4,
                ..stop_parameters()
            },
            8.0,
        )
    }

    /// `aperture` in a 50 mm lens at `f_number` on full frame.
    fn lens(aperture: Aperture, f_number: f64) -> Optics {
        let camera = crate::CameraGeometry {
            sensor_width_mm: Some(36.0),
            focal_length_mm: Some(50.0),
            f_number: Some(f_number),
            ..Default::default()
        };
        aperture.optics(&camera, 1.0, 0).unwrap()
    }

    /// A stop's parameters: straight blades turned by 5°, no obstruction.
    fn stop_parameters() -> Aperture {
        Aperture {
            blades: 7,
            rotation_deg: 5.0,
            roundness: 0.0,
            spectral: true,
            wavelength_nm: 550.0,
            obstruction: 0.0,
            vanes: 0,
            vane_width: 0.02,
            ..Aperture::new(7)
        }
    }

    /// The 17 wavelengths and their R, G, B weights.
    fn light() -> Spectrum {
        Light::Spectral.wavelengths()
    }

    /// [`pattern_with`], neither reporting nor cancelled.
    fn rasterise_with(
        optics: &Optics,
        spectrum: &Spectrum,
        extent: &Extent,
        pitch_mm: f64,
        far_from: f64,
    ) -> Vec<Vec<f64>> {
        let cancel = Cancel::new();
        let mut control = Control::quiet(&cancel);
        pattern_with(
            optics,
            spectrum,
            (extent, pitch_mm),
            far_from,
            &mut Composing::cpu(),
            &mut control,
        )
        .unwrap()
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
        let extent = Extent::new(SIDE, SIDE).unwrap().sent_by(Sending::Point);
        let mut fast = rasterise_with(&optics, &light, &extent, pitch, 48.0 * pitch);
        let mut exact = rasterise_with(&optics, &light, &extent, pitch, f64::INFINITY);
        (fast.swap_remove(1), exact.swap_remove(1))
    }

    /// The light of `plane` between radii `r0` and `r1` px, in `bins`
    /// sectors from the +x axis.
    fn sectors(plane: &[f64], r0: f64, r1: f64, bins: usize) -> Vec<f64> {
        sectors_of(plane, SIDE, r0, r1, bins)
    }

    /// The light of `plane` (`side` px square) between radii `r0` and `r1`
    /// px, in `bins` sectors from the +x axis.
    fn sectors_of(plane: &[f64], side: usize, r0: f64, r1: f64, bins: usize) -> Vec<f64> {
        let mut out = vec![0.0; bins];
        let centre = (side / 2) as f64;
        for (i, v) in plane.iter().enumerate() {
            let (dx, dy) = ((i % side) as f64 - centre, centre - (i / side) as f64);
            let r = libm::hypot(dx, dy);
            if r >= r0 && r < r1 {
                let turn =
                    libm::atan2(dy, dx).rem_euclid(std::f64::consts::TAU) / std::f64::consts::TAU;
                out[((turn * bins as f64) as usize).min(bins - 1)] += v;
            }
        }
        out
    }

    /// `a`'s light over `b`'s, and their relative L2 distance.
    fn light_and_l2(a: &[f64], b: &[f64]) -> (f64, f64) {
        let light = a.iter().sum::<f64>() / b.iter().sum::<f64>();
        let distance = a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
        let norm = b.iter().map(|y| y * y).sum::<f64>();
        (light, (distance / norm).sqrt())
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
            let extent = Extent::new(SIDE, SIDE).unwrap().sent_by(Sending::Point);
            let cancel = Cancel::new();
            let planes = pattern(
                &optics,
                Light::Spectral,
                (&extent, pitch),
                &mut Composing::cpu(),
                &mut Control::quiet(&cancel),
            )
            .unwrap();
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

    #[test]
    fn the_far_field_averages_rays_over_square_pixels_at_any_angle() {
        // At the 4K pitch and f/8 a ray is about a pixel wide and crosses
        // the pixels at its own angle: pixel by pixel on 1-px rings beyond
        // r_far (48 px), against the exact transform. Taking the square for
        // a strip as wide as its projection put 10 % (7 blades) to 97 %
        // (4 blades at 0°, rays along the diagonals) of the angular
        // profile's L2 norm in the wrong place; multiplying the pixel's
        // means of a pair's sinc² and cosine, 18 %. Light sent by a pixel
        // is held to the exact transform under each pixel's tent: the
        // square's far field was 3–17 % off there, and left the rays'
        // brightest pixels 14 % brighter beyond r_far than within it.
        let pitch = 36.0 / 3840.0;
        for (blades, rotation, light) in [
            (3, 0.0, Light::Spectral),
            (7, 5.0, Light::Spectral),
            (4, 0.0, Light::Spectral),
            (4, 0.0, Light::Monochrome(550.0)),
            (4, 20.0, Light::Monochrome(550.0)),
            (6, 15.0, Light::Spectral),
        ] {
            let optics = lens(
                Aperture {
                    blades,
                    rotation_deg: rotation,
                    ..stop_parameters()
                },
                8.0,
            );
            for (r, sending) in [60.0, 100.0, 140.0]
                .into_iter()
                .flat_map(|r| [(r, Sending::Point), (r, Sending::Pixel)])
            {
                let sent = (pitch, sending);
                let (fast, exact) = far_and_exact_sent_by(&optics, light, sent, r, 180);
                for (c, (a, b)) in fast.iter().zip(&exact).enumerate() {
                    let (total, l2) = light_and_l2(a, b);
                    assert!(
                        (total - 1.0).abs() < 0.01 && l2 < 0.01,
                        "{blades} blades at {rotation}°, {light:?}, {sending:?}, plane {c}, \
                         ring {r} px: light ×{total:.4}, angular L2 {l2:.4}"
                    );
                }
            }
        }
    }

    #[test]
    fn the_far_field_draws_the_discs_fringes() {
        // A round stop's rim, and an obstruction's with it, send light out
        // in rings: each disc's ⟨J₁²⟩ swings by its −sin 2z, and two
        // concentric discs beat at z₁ ∓ z₂. At the 4K pitch and f/8 the
        // pixel averages them only in part, and by the angle at which the
        // rings cross it. Without them a round stop's rings were 1.5 % off
        // in angular L2, with an obstruction of 0.3 up to 22 %, and 16 % of
        // a ring's light was missing or added.
        let mono = Light::Monochrome(550.0);
        for (obstruction, lights) in [
            (0.0, vec![mono]),
            (0.3, vec![mono, Light::Spectral]),
            (0.5, vec![Light::Monochrome(450.0)]),
        ] {
            let optics = lens(
                Aperture {
                    blades: 0,
                    obstruction,
                    ..stop_parameters()
                },
                8.0,
            );
            let what = format!("obstruction {obstruction}");
            far_field_holds(&optics, &lights, &[50.0, 80.0, 130.0], 0.005, 0.006, &what);
        }
    }

    #[test]
    fn a_vanes_ends_beat_with_the_discs() {
        // A telescope's spider: 4 vanes from an obstruction of 0.3 to the
        // rim. Each vane's ends lie on a disc's rim, where the disc's
        // stationary point and the end have one phase along the vane: their
        // cross term does not oscillate. Without it the rings at 80–250 px
        // were 2.5–4.3 % off in angular L2 in one wavelength and 6–11 % in
        // 17 lines. Each end also beats with the other disc, with a phase
        // that turns along the vane: without that the ring at 50 px was 4 %
        // off in one wavelength (now 1.9 %).
        let optics = telescope();
        let lights = [Light::Monochrome(550.0), Light::Spectral];
        far_field_holds(
            &optics,
            &lights,
            &[50.0, 80.0, 130.0, 250.0],
            0.01,
            0.022,
            "a telescope",
        );
    }

    #[test]
    fn a_vanes_sides_interfere_with_the_blades_beside_them() {
        // Three vanes in a hexagonal stop run to its corners, their sides
        // parallel to the blades across them but shorter: the fields share
        // a ray, with sincs of two widths, sinc(πu/λ)·sinc(πur/λ). Without
        // their cross terms the rings at 50–250 px were 3–7 % off in
        // angular L2 in one wavelength.
        let optics = lens(
            Aperture {
                blades: 6,
                vanes: 3,
                ..stop_parameters()
            },
            8.0,
        );
        let lights = [Light::Monochrome(550.0), Light::Spectral];
        far_field_holds(
            &optics,
            &lights,
            &[50.0, 130.0, 250.0],
            0.015,
            0.01,
            "6 blades, 3 vanes",
        );
    }

    /// Asserts that on 1-px rings at `radii` (the 4K pitch) the far field
    /// of `optics` holds the exact transform's light within `light` and
    /// its angular profile within `l2` (relative L2, 2° sectors), in each
    /// of `lights` and each plane.
    fn far_field_holds(
        optics: &Optics,
        lights: &[Light],
        radii: &[f64],
        light: f64,
        l2: f64,
        what: &str,
    ) {
        let pitch = 36.0 / 3840.0;
        for &colour in lights {
            for &r in radii {
                let (fast, exact) = far_and_exact_on_ring(optics, colour, pitch, r, 180);
                for (c, (a, b)) in fast.iter().zip(&exact).enumerate() {
                    let (total, error) = light_and_l2(a, b);
                    assert!(
                        (total - 1.0).abs() < light && error < l2,
                        "{what}, {colour:?}, plane {c}, ring {r} px: light ×{total:.4}, \
                         angular L2 {error:.4}"
                    );
                }
            }
        }
    }

    /// The far field's and the exact transform's light in the pixels of
    /// the 1-px ring at `r` px, per plane in `bins` sectors: each pixel
    /// evaluated both ways, so that no kernel need be rasterised.
    fn far_and_exact_on_ring(
        optics: &Optics,
        light: Light,
        pitch: f64,
        r: f64,
        bins: usize,
    ) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        far_and_exact_sent_by(optics, light, (pitch, Sending::Point), r, bins)
    }

    /// [`far_and_exact_on_ring`] for light sent as `sending` says.
    fn far_and_exact_sent_by(
        optics: &Optics,
        light: Light,
        (pitch, sending): (f64, Sending),
        r: f64,
        bins: usize,
    ) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
        let spectrum = light.wavelengths();
        let planes = spectrum[0].1.len();
        let totals: Vec<f64> = (0..planes)
            .map(|c| spectrum.iter().map(|(_, w)| w[c]).sum())
            .collect();
        let near = NearField::new(optics, &spectrum, (pitch, sending));
        let far = FarField::new(
            optics,
            &spectrum,
            &totals,
            (pitch, sending),
            (r + 2.0) * pitch,
        );
        let mut scratch = far::Row::default();
        let (mut fast, mut exact) = (vec![vec![0.0; bins]; planes], vec![vec![0.0; bins]; planes]);
        for (dx, dy, bin) in ring_pixels(r, bins) {
            let (x, y) = (dx * pitch, dy * pitch);
            let (mut a, mut b) = (vec![0.0; planes], vec![0.0; planes]);
            far.row(x, y, pitch, &totals, &mut scratch, &mut a);
            near.add_many(&[x], y, false, &mut b);
            for c in 0..planes {
                fast[c][bin] += a[c];
                exact[c][bin] += b[c];
            }
        }
        (fast, exact)
    }

    #[test]
    fn a_filters_orders_are_the_stops_pattern_at_their_own_places() {
        // Lines at 20° every 180 µm on 7 blades at f/8 on 5 µm pixels
        // (λN = 0.88 px in 550 nm): order m lands m·30.6 px out along 110°
        // in 550 nm, between pixels. Each order must be the stop's pattern
        // in its own wavelength, centred there, with the share |c_m|²: the
        // kernel against Σ |c_m|² P_λ(x − x_m), P_λ the exact transform
        // integrated over each pixel about x_m itself, on 1-px rings.
        // Placing the pattern by whole pixels, bilinearly, put 10 % and 19 %
        // of the angular profile wrong on the rings through the first
        // orders in 550 nm; carrying the plane's mean pattern in every
        // wavelength, 1–2.4 % (seen against a round stop).
        let (pitch, side) = (0.005, 101);
        let extent = Extent::new(side, side).unwrap().sent_by(Sending::Point);
        for colour in [Light::Monochrome(550.0), Light::Spectral] {
            let optics = lens(
                Aperture {
                    spectral: colour == Light::Spectral,
                    filters: vec![crate::optics::aperture::Filter {
                        angle_deg: 20.0,
                        spacing_um: 180.0,
                        width_um: 12.0,
                    }],
                    ..stop_parameters()
                },
                8.0,
            );
            let spectrum = colour.wavelengths();
            let kernel = rasterise_with(&optics, &spectrum, &extent, pitch, f64::INFINITY);
            // Beyond the first orders the halos of orders outside the
            // kernel, which it leaves out, reach 1 %. Each ring's light is
            // taken relative to the ring at 10 px, as the kernel holds less
            // than all the light.
            let rings = [10.0, 20.0, 30.0, 31.0];
            let exact: Vec<_> = rings
                .iter()
                .map(|&r| orders_on_ring(&optics, &spectrum, pitch, r, 90))
                .collect();
            for (c, plane) in kernel.iter().enumerate() {
                let ours: Vec<_> = rings
                    .iter()
                    .map(|&r| sectors_of(plane, side, r - 0.5, r + 0.5, 90))
                    .collect();
                let sum = |v: &Vec<f64>| v.iter().sum::<f64>();
                let shape = |v: &Vec<f64>| v.iter().map(|x| x / sum(v)).collect::<Vec<_>>();
                for (k, r) in rings.iter().enumerate() {
                    let (_, error) = light_and_l2(&shape(&ours[k]), &shape(&exact[k][c]));
                    let light =
                        sum(&ours[k]) / sum(&ours[0]) * sum(&exact[0][c]) / sum(&exact[k][c]);
                    assert!(
                        (light - 1.0).abs() < 0.01 && error < 0.01,
                        "{colour:?}, plane {c}, ring {r} px: light ×{light:.4}, \
                         angular L2 {error:.4}"
                    );
                }
            }
        }
    }

    /// A filter's orders summed exactly on the 1-px ring at `r` px, per
    /// plane in `bins` sectors: Σ over wavelengths and orders of
    /// |c_m|² P_λ(x − x_m), each pixel integrated about x_m itself.
    fn orders_on_ring(
        optics: &Optics,
        spectrum: &Spectrum,
        pitch: f64,
        r: f64,
        bins: usize,
    ) -> Vec<Vec<f64>> {
        let planes = spectrum[0].1.len();
        let mut out = vec![vec![0.0; bins]; planes];
        let total: Vec<f64> = (0..planes)
            .map(|c| spectrum.iter().map(|(_, w)| w[c]).sum())
            .collect();
        for (lambda_nm, weights) in spectrum {
            let single = vec![(*lambda_nm, vec![1.0])];
            let near = NearField::exact(optics, &single, (pitch, Sending::Point));
            let to_mm = lambda_nm * 1e-6 * optics.focal_mm;
            for (dx, dy, bin) in ring_pixels(r, bins) {
                let mut light = 0.0;
                for (nu, share) in &optics.orders {
                    let mut pixel = [0.0];
                    let (x, y) = (dx * pitch - nu[0] * to_mm, dy * pitch - nu[1] * to_mm);
                    near.add_many(&[x], y, false, &mut pixel);
                    light += share * pixel[0];
                }
                for c in 0..planes {
                    out[c][bin] += light * weights[c] / total[c];
                }
            }
        }
        out
    }

    /// The pixels of the 1-px ring at `r` px about the centre: their
    /// offsets right and up, px, and their sector of `bins` from the +x
    /// axis.
    fn ring_pixels(r: f64, bins: usize) -> Vec<(f64, f64, usize)> {
        let reach = r.ceil() as i64 + 1;
        let mut pixels = Vec::new();
        for j in -reach..=reach {
            for i in -reach..=reach {
                let (dx, dy) = (i as f64, j as f64);
                if (libm::hypot(dx, dy) - r).abs() < 0.5 {
                    let t = libm::atan2(dy, dx).rem_euclid(std::f64::consts::TAU)
                        / std::f64::consts::TAU;
                    pixels.push((dx, dy, ((t * bins as f64) as usize).min(bins - 1)));
                }
            }
        }
        pixels
    }

    #[test]
    fn the_mirrored_half_is_the_pattern_on_even_and_odd_extents() {
        // Rows below the centre are the mirror images of those above; an
        // even width leaves one column to compute. A 42 × 42 kernel (centre
        // at 21, 21) is the top-left corner of a 43 × 43 one, with the far
        // field from 10 px out so that both fields are mirrored.
        let (optics, light) = (stop(7, 0.0, 8.0), light());
        let pitch = 36.0 / 3840.0;
        let rasterise = |side: usize| {
            let extent = Extent::new(side, side).unwrap().sent_by(Sending::Point);
            rasterise_with(&optics, &light, &extent, pitch, 10.0 * pitch)
        };
        let (even, odd) = (rasterise(42), rasterise(43));
        for (e, o) in even.iter().zip(&odd) {
            let corner: Vec<f64> = (0..42 * 42).map(|k| o[(k / 42) * 43 + k % 42]).collect();
            for (k, (a, b)) in e.iter().zip(&corner).enumerate() {
                assert!(
                    (a - b).abs() <= 1e-9 * b.abs().max(1e-300),
                    "pixel {} {}: {a} vs {b}",
                    k % 42,
                    k / 42,
                );
            }
        }
    }

    #[test]
    fn a_stop_mirrored_across_an_axis_is_computed_on_a_quarter() {
        // Turned by 0° a stop's blade tip lies on +x: the pattern's left
        // half is its right half mirrored. Turned by 2·10⁻⁷° the pupil is
        // no longer its mirror image (by 10⁻⁸ mm), every column is
        // computed, and the pattern moves by 10⁻⁷ px at most here. The
        // exact transform is the same on both halves to its round-off; the
        // far field's asymptotic terms (from 10 px out here) may differ
        // between mirror images by their own error (2 % at 10 px here), and
        // the mirrored half takes the right one's.
        let pitch = 36.0 / 3840.0;
        let turned = |blades: u32, vanes: u32, rotation_deg: f64| {
            let aperture = Aperture {
                blades,
                vanes,
                obstruction: if vanes > 0 { 0.3 } else { 0.0 },
                rotation_deg,
                ..stop_parameters()
            };
            lens(aperture, 8.0)
        };
        for (blades, vanes) in [(6, 0), (7, 0), (0, 4)] {
            let (mirrored, whole) = (turned(blades, vanes, 0.0), turned(blades, vanes, 2e-7));
            assert!(mirrored.pupil.is_mirror_symmetric());
            assert!(!whole.pupil.is_mirror_symmetric());
            for (side, sending) in [(42, Sending::Point), (43, Sending::Pixel)] {
                let extent = Extent::new(side, side).unwrap().sent_by(sending);
                let cx = side / 2;
                for far_from in [f64::INFINITY, 10.0 * pitch] {
                    let a = rasterise_with(&mirrored, &light(), &extent, pitch, far_from);
                    let b = rasterise_with(&whole, &light(), &extent, pitch, far_from);
                    for (a, b) in a.iter().zip(&b) {
                        let peak = b.iter().fold(0.0f64, |m, v| m.max(*v));
                        for (k, (u, v)) in a.iter().zip(b).enumerate() {
                            let (i, j) = (k % side, k / side);
                            // Far, the rows above the centre: those below
                            // are their mirror images through it.
                            let mirror = (2 * cx).checked_sub(i).filter(|&m| m < side);
                            match (far_from.is_finite(), j <= cx, i < cx, mirror) {
                                (true, false, ..) => continue,
                                (true, true, true, Some(m)) => {
                                    assert_eq!(*u, a[j * side + m], "{blades} blades: {i} {j}");
                                    continue;
                                }
                                _ => {}
                            }
                            assert!(
                                (u - v).abs() <= 1e-6 * v.abs() + 1e-10 * peak,
                                "{blades} blades, {vanes} vanes, {side} px: {i} {j}: {u} vs {v}",
                            );
                        }
                    }
                }
            }
        }
    }

    #[test]
    fn a_pattern_has_the_same_bytes_on_any_number_of_threads() {
        // Rows are computed apart, mirrored, and summed in fixed chunks;
        // the far field from 10 px out, pairs, fringes and rims included,
        // and a star filter's orders with their cores.
        let pitch = 36.0 / 3840.0;
        let family = |angle_deg| crate::optics::aperture::Filter {
            angle_deg,
            spacing_um: 200.0,
            width_um: 10.0,
        };
        let star = lens(
            Aperture {
                blades: 0,
                filters: vec![family(0.0), family(90.0)],
                ..stop_parameters()
            },
            8.0,
        );
        for (optics, light, side) in [
            (stop(7, 0.0, 8.0), light(), 61),
            (telescope(), light(), 61),
            (star, light(), 61),
            (
                stop(8, 0.0, 8.0),
                Light::Monochrome(550.0).wavelengths(),
                60,
            ),
        ] {
            let run = |threads| {
                rayon::ThreadPoolBuilder::new()
                    .num_threads(threads)
                    .build()
                    .unwrap()
                    .install(|| {
                        let extent = Extent::new(side, side).unwrap().sent_by(Sending::Point);
                        rasterise_with(&optics, &light, &extent, pitch, 10.0 * pitch)
                    })
            };
            assert_eq!(run(1), run(3));
        }
    }

    #[test]
    fn parallel_edges_in_one_wavelength_interfere_along_their_ray() {
        // In 550 nm light at the 4K pitch, opposite blades of an even stop
        // share a ray and draw fringes along it; rings one pixel wide beyond
        // the far field's start (112 px at f/32, 77 px at f/22) against the
        // exact transform. Without the pairs' cross terms the 8-blade ring
        // at 120 px held 63 % too much light (angular L2 80 %).
        let pitch = 36.0 / 3840.0;
        let side = 301;
        let light = Light::Monochrome(550.0);
        for (optics, radii, what) in [
            (stop(8, 0.0, 32.0), [120.0, 140.0], "8 blades at f/32"),
            (stop(6, 0.0, 22.0), [100.0, 140.0], "6 blades at f/22"),
        ] {
            let extent = Extent::new(side, side).unwrap().sent_by(Sending::Point);
            let cancel = Cancel::new();
            let mut control = Control::quiet(&cancel);
            let fast = pattern(
                &optics,
                light,
                (&extent, pitch),
                &mut Composing::cpu(),
                &mut control,
            )
            .unwrap()
            .swap_remove(0);
            let spectrum = light.wavelengths();
            let exact =
                rasterise_with(&optics, &spectrum, &extent, pitch, f64::INFINITY).swap_remove(0);
            for r in radii {
                let (a, b) = (ring(&fast, side, r, 180), ring(&exact, side, r, 180));
                let (total, l2) = light_and_l2(&a, &b);
                assert!(
                    (total - 1.0).abs() < 0.02 && l2 < 0.03,
                    "{what}, ring {r} px: light ×{total:.3}, angular L2 {l2:.3}"
                );
            }
        }
    }

    /// The light of `plane` (`side` px square) on the ring of width 1 px
    /// at `r0` px, in `bins` sectors from the +x axis.
    fn ring(plane: &[f64], side: usize, r0: f64, bins: usize) -> Vec<f64> {
        sectors_of(plane, side, r0 - 0.5, r0 + 0.5, bins)
    }
}
