//! Linear ("same"-size) convolution of images with a fixed kernel through
//! real-to-complex FFTs in f32: the kernel's spectrum is computed once and
//! reused for every channel and every image of the same size. Zero padding
//! to 5-smooth sizes keeps light from wrapping around the frame.
//!
//! Only what the "same" output needs is transformed: the H image rows (the
//! padding rows are zeros), and each column transform is pruned when the
//! padded height P = 2N holds the H rows in its first half: the even and odd
//! frequencies of a column are then two transforms of length N (of x and of
//! x·e^{−iπn/N}), and the H output rows come back from two inverse transforms
//! of length N, which skips a radix-2 stage each way.

use std::sync::{Arc, Mutex};

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use crate::kernel::Kernel;

/// Row spectra (in tiles) and column results (strip-major), kept between
/// calls: fresh buffers cost page faults and zeroing on every frame.
type Buffers = (Vec<Complex<f32>>, Vec<Complex<f32>>);

/// Columns transformed together: a strip of them spans two cache lines per
/// row, and its column transforms fit in the L2 cache.
const STRIP: usize = 16;

/// Rows transformed together: row spectra are stored in tiles of
/// BLOCK rows × [`STRIP`] columns, block by block, so that a strip's column
/// pass and a block's inverse row transforms each read whole tiles.
const BLOCK: usize = 8;

/// Values in a tile.
const TILE: usize = BLOCK * STRIP;

/// The smallest 5-smooth number (2^a 3^b 5^c) at or above `n`: rustfft is
/// fastest on those sizes.
pub fn fast_size(n: usize) -> usize {
    let mut best = usize::MAX;
    let mut p2 = 1usize;
    while p2 < 2 * n.max(1) {
        let mut p3 = p2;
        while p3 < 2 * n.max(1) {
            let mut p5 = p3;
            while p5 < n {
                p5 *= 5;
            }
            best = best.min(p5);
            p3 *= 3;
        }
        p2 *= 2;
    }
    best
}

/// The FFT size for a linear convolution of `width`×`height` images with a
/// `kernel_width`×`kernel_height` kernel centred at its middle: output x in
/// [0, W) must not alias with the full linear result, which spans
/// [−cx, W + Kw − 2 − cx], and the kernel must not overlap itself; then the
/// next 5-smooth size.
pub fn padded_size(
    kernel_width: usize,
    kernel_height: usize,
    width: usize,
    height: usize,
) -> (usize, usize) {
    (
        fast_size(needed(kernel_width, width)),
        column_transform(needed(kernel_height, height), height).length(),
    )
}

/// The shortest period along one axis that avoids wrap-around.
pub(crate) fn needed(kernel: usize, image: usize) -> usize {
    let c = kernel / 2;
    (image + kernel - 1 - c).max(image + c).max(kernel)
}

/// How the columns are transformed.
#[derive(Debug, Clone, Copy, PartialEq)]
enum ColumnTransform {
    /// One transform of the whole padded column.
    Full(usize),
    /// Two transforms of half the padded length 2N each way (the image
    /// rows fit in the first half).
    Halves(usize),
}

impl ColumnTransform {
    /// The length of each 1-D transform.
    fn transform_length(self) -> usize {
        match self {
            ColumnTransform::Full(p) => p,
            ColumnTransform::Halves(n) => n,
        }
    }

    /// The padded column length P.
    fn length(self) -> usize {
        match self {
            ColumnTransform::Full(p) => p,
            ColumnTransform::Halves(n) => 2 * n,
        }
    }
}

/// The cheaper of a full and a pruned column transform for `height` image
/// rows and a period of at least `needed`, by the n·log₂n count.
fn column_transform(needed: usize, height: usize) -> ColumnTransform {
    let cost = |n: usize| n as f64 * (n as f64).log2();
    let full = fast_size(needed);
    let half = fast_size(needed.div_ceil(2).max(height));
    if 4.0 * cost(half) < 2.0 * cost(full) {
        ColumnTransform::Halves(half)
    } else {
        ColumnTransform::Full(full)
    }
}

/// What a strip task reads: strip `index` of `strips`, the row spectra in
/// tiles, the kernel's spectrum.
struct Strip<'a> {
    index: usize,
    strips: usize,
    rows: &'a [Complex<f32>],
    spectrum: &'a [Complex<f32>],
}

/// One plane to convolve.
#[derive(Debug, Clone, Copy)]
pub struct Input<'a> {
    /// Row-major, the convolver's width × height.
    pub plane: &'a [f32],
    /// The share of each pixel's light that is spread, if not all: the rest
    /// stays where it is, added back unconvolved.
    pub fractions: Option<&'a [f32]>,
    /// The kernel channel to convolve with.
    pub channel: usize,
    /// Added to the result times the plane itself: a kernel weight at the
    /// centre kept out of the FFT, where it would dominate the round-off.
    pub centre: f32,
}

/// Convolves `width`×`height` planes with one kernel, channel by channel.
pub struct Convolver {
    width: usize,
    height: usize,
    px: usize,
    columns: ColumnTransform,
    /// One spectrum per kernel channel, stored column by column (`px/2 + 1`
    /// columns of P values; for pruned columns the even frequencies, then
    /// the odd ones).
    spectra: Vec<Vec<Complex<f32>>>,
    /// e^{−iπn/N} for n < N, for pruned columns.
    twiddles: Vec<Complex<f32>>,
    row_fft: Arc<dyn RealToComplex<f32>>,
    row_ifft: Arc<dyn ComplexToReal<f32>>,
    column_fft: Arc<dyn Fft<f32>>,
    column_ifft: Arc<dyn Fft<f32>>,
    scratch: Mutex<Vec<Buffers>>,
}

impl Convolver {
    /// Plans the convolution of `width`×`height` images with `kernel`
    /// (centre at column `w/2`, row `h/2`) and transforms the kernel.
    pub fn new(kernel: &Kernel, width: usize, height: usize) -> Convolver {
        Convolver::of_kernel(kernel, width, height, false)
    }

    /// [`Convolver::new`] for a one-channel kernel given as a plane
    /// (row-major, `size` = width × height, centre in the middle), taken as
    /// it is: not normalised.
    pub(crate) fn for_plane(
        plane: &[f32],
        size: (usize, usize),
        width: usize,
        height: usize,
    ) -> Convolver {
        Convolver::build(&[plane], size, width, height, false)
    }

    /// [`Convolver::new`] for the kernel less its centre weight: the light
    /// that moves, for a caller that applies the centre exactly itself.
    pub fn without_centre(kernel: &Kernel, width: usize, height: usize) -> Convolver {
        Convolver::of_kernel(kernel, width, height, true)
    }

    fn of_kernel(kernel: &Kernel, width: usize, height: usize, leave_centre: bool) -> Convolver {
        let planes: Vec<&[f32]> = kernel.channels().iter().map(Vec::as_slice).collect();
        let size = (kernel.width(), kernel.height());
        Convolver::build(&planes, size, width, height, leave_centre)
    }

    fn build(
        planes: &[&[f32]],
        (kw, kh): (usize, usize),
        width: usize,
        height: usize,
        leave_centre: bool,
    ) -> Convolver {
        let (cx, cy) = (kw / 2, kh / 2);
        let px = fast_size(needed(kw, width));
        let columns = column_transform(needed(kh, height), height);
        let py = columns.length();
        let mut real_planner = RealFftPlanner::<f32>::new();
        let mut planner = FftPlanner::<f32>::new();
        let twiddles = match columns {
            ColumnTransform::Full(_) => Vec::new(),
            ColumnTransform::Halves(n) => (0..n)
                .map(|k| {
                    let (sin, cos) = (-std::f64::consts::PI * k as f64 / n as f64).sin_cos();
                    Complex::new(cos as f32, sin as f32)
                })
                .collect(),
        };
        let row_fft = real_planner.plan_fft_forward(px);
        let full_column = planner.plan_fft_forward(py);
        let spectra = planes
            .iter()
            .map(|plane| {
                let placed = Placed {
                    plane,
                    size: (kw, kh),
                    centre: (cx, cy),
                    leave_centre,
                };
                kernel_spectrum(&*row_fft, &*full_column, px, columns, &placed)
            })
            .collect();
        Convolver {
            width,
            height,
            px,
            columns,
            spectra,
            twiddles,
            row_fft,
            row_ifft: real_planner.plan_fft_inverse(px),
            column_fft: planner.plan_fft_forward(columns.transform_length()),
            column_ifft: planner.plan_fft_inverse(columns.transform_length()),
            scratch: Mutex::new(Vec::new()),
        }
    }

    /// The padded FFT size, columns × rows.
    pub fn padded_size(&self) -> (usize, usize) {
        (self.px, self.columns.length())
    }

    /// How many kernel channels there are.
    pub fn channels(&self) -> usize {
        self.spectra.len()
    }

    /// `plane` (row-major, `width`×`height`) convolved with kernel channel
    /// `channel`, over the same frame; light beyond the frame is lost.
    pub fn convolve(&self, plane: &[f32], channel: usize) -> Vec<f32> {
        self.convolve_all(
            &[Input {
                plane,
                fractions: None,
                channel,
                centre: 0.0,
            }],
            Vec::new(),
            &mut |_| {},
        )
        .pop()
        .unwrap_or_default()
    }

    /// Every input convolved with its kernel channel, plus its centre
    /// weight times itself, written into the planes of `recycled` where
    /// there are some (memory already mapped: fresh planes cost a page fault
    /// every 4 KiB). The planes go through each pass together, so that the
    /// kernel's spectrum is read from memory once for all of them;
    /// `progress` hears the fraction done after each pass.
    ///
    /// Rows are transformed, a block of [`BLOCK`] at a time, into tiles of
    /// [`BLOCK`] rows × [`STRIP`] columns; each strip of columns gathers its
    /// tiles, is transformed (padded, multiplied by the kernel's spectrum,
    /// transformed back and cut to the H output rows) in cache, and written
    /// strip-major; the inverse row transforms gather their block's tile from
    /// each strip. No pass transposes a whole plane.
    pub fn convolve_all(
        &self,
        inputs: &[Input],
        mut recycled: Vec<Vec<f32>>,
        progress: &mut dyn FnMut(f64),
    ) -> Vec<Vec<f32>> {
        let (w, h) = (self.width, self.height);
        let count = self.px / 2 + 1;
        let strips = count.div_ceil(STRIP);
        let zero = Complex::new(0.0, 0.0);

        // Reuse the plan's buffers when no other call holds them.
        let mut held = self.scratch.try_lock();
        let mut own = Vec::new();
        let buffers = match held.as_deref_mut() {
            Ok(buffers) => buffers,
            Err(_) => &mut own,
        };
        buffers.resize_with(inputs.len(), Default::default);
        for (rows, results) in buffers.iter_mut() {
            rows.resize(h.div_ceil(BLOCK) * strips * TILE, zero);
            results.resize(strips * h * STRIP, zero);
        }

        // Forward row transforms, a block of rows per task, into tiles:
        // block b, strip s, row, column.
        let row_fft = &self.row_fft;
        for (input, (rows, _)) in inputs.iter().zip(buffers.iter_mut()) {
            rows.par_chunks_mut(strips * TILE)
                .zip(input.plane.par_chunks(BLOCK * w))
                .enumerate()
                .for_each_init(
                    || {
                        (
                            row_fft.make_input_vec(),
                            row_fft.make_output_vec(),
                            row_fft.make_scratch_vec(),
                        )
                    },
                    |(padded, spectrum, scratch), (block, (tiles, src))| {
                        for (r, row) in src.chunks(w).enumerate() {
                            match input.fractions {
                                Some(fractions) => {
                                    let at = (block * BLOCK + r) * w;
                                    for ((p, v), f) in
                                        padded.iter_mut().zip(row).zip(&fractions[at..at + w])
                                    {
                                        *p = v * f;
                                    }
                                }
                                None => padded[..w].copy_from_slice(row),
                            }
                            padded[w..].iter_mut().for_each(|v| *v = 0.0);
                            let _ = row_fft.process_with_scratch(padded, spectrum, scratch);
                            for (s, values) in spectrum.chunks(STRIP).enumerate() {
                                let at = s * TILE + r * STRIP;
                                tiles[at..at + values.len()].copy_from_slice(values);
                            }
                        }
                    },
                );
        }
        progress(0.3);

        self.column_pass(inputs, buffers, strips);
        progress(0.7);

        // Inverse row transforms, a block of rows per task, gathered from
        // the strips (a tile's worth from each), plus the centre's light.
        let scale = 1.0 / (self.px as f32 * self.columns.length() as f32);
        let row_ifft = &self.row_ifft;
        let zero = Complex::new(0.0, 0.0);
        recycled.resize_with(inputs.len(), Vec::new);
        recycled.truncate(inputs.len());
        let outputs = inputs
            .iter()
            .zip(buffers.iter())
            .zip(recycled)
            .map(|((input, (_, results)), mut out)| {
                out.resize(w * h, 0.0);
                out.par_chunks_mut(BLOCK * w)
                    .zip(input.plane.par_chunks(BLOCK * w))
                    .enumerate()
                    .for_each_init(
                        || {
                            (
                                vec![zero; BLOCK * count],
                                row_ifft.make_output_vec(),
                                row_ifft.make_scratch_vec(),
                            )
                        },
                        |(spectra, output, scratch), (block, (dst, src))| {
                            let rows = dst.len() / w;
                            for s in 0..strips {
                                let at = s * h * STRIP + block * TILE;
                                let tile = &results[at..at + rows * STRIP];
                                let first = s * STRIP;
                                let width = STRIP.min(count - first);
                                for (r, values) in tile.chunks(STRIP).enumerate() {
                                    spectra[r * count + first..r * count + first + width]
                                        .copy_from_slice(&values[..width]);
                                }
                            }
                            for (r, ((spectrum, dst), src)) in spectra
                                .chunks_mut(count)
                                .zip(dst.chunks_mut(w))
                                .zip(src.chunks(w))
                                .enumerate()
                            {
                                let y = block * BLOCK + r;
                                // A real signal's DC and Nyquist bins are
                                // real; the inverse refuses their round-off.
                                spectrum[0].im = 0.0;
                                if self.px % 2 == 0 {
                                    spectrum[count - 1].im = 0.0;
                                }
                                let _ = row_ifft.process_with_scratch(spectrum, output, scratch);
                                let convolved = dst.iter_mut().zip(output.iter()).zip(src);
                                match input.fractions {
                                    Some(fractions) => {
                                        let at = y * w;
                                        for (((d, v), s), f) in
                                            convolved.zip(&fractions[at..at + w])
                                        {
                                            let bright = s * f;
                                            *d = v * scale + input.centre * bright + (s - bright);
                                        }
                                    }
                                    None => {
                                        for ((d, v), s) in convolved {
                                            *d = v * scale + input.centre * s;
                                        }
                                    }
                                }
                            }
                        },
                    );
                out
            })
            .collect();
        progress(1.0);
        outputs
    }

    /// The column transforms of every input, strip by strip: each strip task
    /// gathers its columns from the row spectra, and writes the H output
    /// rows of the product's inverse into its own part of `results`.
    fn column_pass(&self, inputs: &[Input], buffers: &mut [Buffers], strips: usize) {
        let h = self.height;
        let py = self.columns.length();
        let zero = Complex::new(0.0, 0.0);
        let (rows, mut results): (Vec<&[Complex<f32>]>, Vec<_>) = buffers
            .iter_mut()
            .map(|(rows, results)| (rows.as_slice(), results.chunks_mut(h * STRIP)))
            .unzip();
        // Strip s of every input, as one task.
        let tasks: Vec<Vec<&mut [Complex<f32>]>> = (0..strips)
            .map(|_| results.iter_mut().filter_map(Iterator::next).collect())
            .collect();
        let scratch_len = self
            .column_fft
            .get_inplace_scratch_len()
            .max(self.column_ifft.get_inplace_scratch_len());
        tasks.into_par_iter().enumerate().for_each_init(
            || (vec![zero; py], vec![zero; scratch_len]),
            |(column, scratch), (s, mut outs)| {
                for ((input, rows), out) in inputs.iter().zip(&rows).zip(outs.iter_mut()) {
                    let strip = Strip {
                        index: s,
                        strips,
                        rows,
                        spectrum: &self.spectra[input.channel],
                    };
                    #[cfg(target_arch = "x86_64")]
                    if std::is_x86_feature_detected!("avx2") {
                        // SAFETY: the CPU was just found to have AVX2.
                        unsafe { self.strip_avx2(&strip, out, column, scratch) };
                        continue;
                    }
                    self.strip(&strip, out, column, scratch);
                }
            },
        );
    }

    /// [`Convolver::strip`] compiled for AVX2: its element-wise complex
    /// loops around the FFTs take 8 lanes instead of 4. They are the same
    /// IEEE operations in the same order (Rust never fuses a multiply and an
    /// add), so the result has the same bits.
    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn strip_avx2(
        &self,
        strip: &Strip,
        out: &mut [Complex<f32>],
        column: &mut [Complex<f32>],
        scratch: &mut [Complex<f32>],
    ) {
        self.strip(strip, out, column, scratch)
    }

    /// One strip's columns of one input: its tiles of the row spectra into
    /// `out` (H rows of [`STRIP`] values, in cache from here on), then each
    /// column through the transforms, in place.
    #[inline(always)]
    fn strip(
        &self,
        strip: &Strip,
        out: &mut [Complex<f32>],
        column: &mut [Complex<f32>],
        scratch: &mut [Complex<f32>],
    ) {
        let h = self.height;
        let count = self.px / 2 + 1;
        let py = self.columns.length();
        let first = strip.index * STRIP;
        let width = STRIP.min(count - first);
        for (block, tiles) in strip.rows.chunks(strip.strips * TILE).enumerate() {
            let at = block * TILE;
            let n = TILE.min(h * STRIP - at);
            out[at..at + n].copy_from_slice(&tiles[strip.index * TILE..strip.index * TILE + n]);
        }
        for j in 0..width {
            let kernel = &strip.spectrum[(first + j) * py..(first + j + 1) * py];
            self.column(out, j, kernel, column, scratch);
        }
    }

    /// Column `j` of a strip (H rows of [`STRIP`] values) through the
    /// padded column transform, the product with `kernel`'s column spectrum
    /// and back, in place.
    #[inline(always)]
    fn column(
        &self,
        strip: &mut [Complex<f32>],
        j: usize,
        kernel: &[Complex<f32>],
        column: &mut [Complex<f32>],
        scratch: &mut [Complex<f32>],
    ) {
        let h = self.height;
        let zero = Complex::new(0.0, 0.0);
        match self.columns {
            ColumnTransform::Full(_) => {
                for (c, v) in column.iter_mut().zip(strip.iter().skip(j).step_by(STRIP)) {
                    *c = *v;
                }
                column[h..].iter_mut().for_each(|v| *v = zero);
            }
            ColumnTransform::Halves(n) => {
                let (even, odd) = column.split_at_mut(n);
                for (((e, o), v), t) in even
                    .iter_mut()
                    .zip(odd.iter_mut())
                    .zip(strip.iter().skip(j).step_by(STRIP))
                    .zip(&self.twiddles)
                {
                    *e = *v;
                    *o = v * t;
                }
                even[h..].iter_mut().for_each(|v| *v = zero);
                odd[h..].iter_mut().for_each(|v| *v = zero);
            }
        }
        // For pruned columns both halves go in one call: rustfft transforms
        // a buffer of several lengths one after the other.
        self.column_fft.process_with_scratch(column, scratch);
        for (a, b) in column.iter_mut().zip(kernel) {
            *a *= *b;
        }
        self.column_ifft.process_with_scratch(column, scratch);
        let values = strip.iter_mut().skip(j).step_by(STRIP);
        match self.columns {
            ColumnTransform::Full(_) => {
                for (v, c) in values.zip(column.iter()) {
                    *v = *c;
                }
            }
            ColumnTransform::Halves(n) => {
                let (even, odd) = column.split_at(n);
                for (((v, e), o), t) in values.zip(even).zip(odd).zip(&self.twiddles) {
                    *v = e + o * t.conj();
                }
            }
        }
    }
}

/// A kernel plane (row-major, kw×kh) to be placed with its centre at index
/// (0, 0) of the period, the rest wrapped.
struct Placed<'a> {
    plane: &'a [f32],
    size: (usize, usize),
    centre: (usize, usize),
    /// Leave the centre weight out.
    leave_centre: bool,
}

/// The 2-D spectrum of a placed kernel plane at px×P, column by column
/// (pruned columns: even frequencies, then odd). Only the kernel's own rows
/// are transformed and stored: the other rows of the period are zeros.
fn kernel_spectrum(
    row_fft: &dyn RealToComplex<f32>,
    column_fft: &dyn Fft<f32>,
    px: usize,
    columns: ColumnTransform,
    placed: &Placed,
) -> Vec<Complex<f32>> {
    let py = columns.length();
    let (kw, kh) = placed.size;
    let (cx, cy) = placed.centre;
    let count = px / 2 + 1;
    let zero = Complex::new(0.0, 0.0);
    let mut rows = vec![zero; kh * count];
    rows.par_chunks_mut(count).enumerate().for_each_init(
        || (row_fft.make_input_vec(), row_fft.make_scratch_vec()),
        |(input, scratch), (j, out)| {
            input.iter_mut().for_each(|v| *v = 0.0);
            for (i, &v) in placed.plane[j * kw..(j + 1) * kw].iter().enumerate() {
                input[(i + px - cx) % px] = v;
            }
            if placed.leave_centre && j == cy {
                input[0] = 0.0;
            }
            let _ = row_fft.process_with_scratch(input, out, scratch);
        },
    );
    // Column transforms, a strip of columns per task, gathered a cache line
    // or two per row rather than one value per row.
    let mut spectrum = vec![zero; count * py];
    spectrum
        .par_chunks_mut(STRIP * py)
        .enumerate()
        .for_each_init(
            || {
                (
                    vec![zero; py * STRIP],
                    vec![zero; py],
                    vec![zero; column_fft.get_inplace_scratch_len()],
                )
            },
            |(strip, column, scratch), (s, out)| {
                let first = s * STRIP;
                let width = out.len() / py;
                strip.iter_mut().for_each(|v| *v = zero);
                for (j, row) in rows.chunks(count).enumerate() {
                    // Kernel row j sits at offset j − cy, wrapped.
                    let r = (j + py - cy) % py;
                    strip[r * STRIP..r * STRIP + width].copy_from_slice(&row[first..first + width]);
                }
                for (j, out) in out.chunks_mut(py).enumerate() {
                    for (v, s) in column.iter_mut().zip(strip.iter().skip(j).step_by(STRIP)) {
                        *v = *s;
                    }
                    column_fft.process_with_scratch(column, scratch);
                    match columns {
                        ColumnTransform::Full(_) => out.copy_from_slice(column),
                        ColumnTransform::Halves(n) => {
                            let (even, odd) = out.split_at_mut(n);
                            for ((e, o), pair) in even.iter_mut().zip(odd).zip(column.chunks(2)) {
                                *e = pair[0];
                                *o = pair[1];
                            }
                        }
                    }
                }
            },
        );
    spectrum
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fast_sizes_are_5_smooth_and_minimal() {
        let smooth = |mut n: usize| {
            for p in [2, 3, 5] {
                while n % p == 0 {
                    n /= p;
                }
            }
            n == 1
        };
        for n in 1..2000 {
            let f = fast_size(n);
            assert!(f >= n && smooth(f), "{n} -> {f}");
            assert!((n..f).all(|m| !smooth(m)), "{n} -> {f} is not the smallest");
        }
    }

    #[test]
    fn columns_are_pruned_when_the_rows_fit_in_half_the_period() {
        // A full-frame kernel: 2H − 1 rows need a period of 2H.
        assert_eq!(column_transform(4319, 2160), ColumnTransform::Halves(2160));
        assert_eq!(column_transform(2159, 1080), ColumnTransform::Halves(1080));
        // A small kernel: halves would need N ≥ H, more than one period.
        assert_eq!(column_transform(1100, 1000), ColumnTransform::Full(1125));
    }
}
