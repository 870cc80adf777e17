//! Linear ("same"-size) convolution of images with a fixed kernel through
//! real-to-complex FFTs in f32: the kernel's spectrum is computed once and
//! reused for every channel and every image of the same size. Zero padding
//! to 5-smooth sizes keeps light from wrapping around the frame.

use std::sync::{Arc, Mutex};

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use super::fft::fast_size;
use crate::kernel::Kernel;

/// Row spectra and column strips of one convolution.
type Buffers = (Vec<Complex<f32>>, Vec<Complex<f32>>);

/// Columns transformed together: a strip of them fills a few cache lines
/// per row.
const STRIP: usize = 16;

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
    let side = |k: usize, n: usize| {
        let c = k / 2;
        fast_size((n + k - 1 - c).max(n + c).max(k))
    };
    (side(kernel_width, width), side(kernel_height, height))
}

/// Convolves `width`×`height` planes with one kernel, channel by channel.
pub struct Convolver {
    width: usize,
    height: usize,
    px: usize,
    py: usize,
    /// One spectrum per kernel channel, stored column by column
    /// (`px/2 + 1` columns of `py` values).
    spectra: Vec<Vec<Complex<f32>>>,
    row_fft: Arc<dyn RealToComplex<f32>>,
    row_ifft: Arc<dyn ComplexToReal<f32>>,
    /// Row spectra and column strips, kept between calls.
    scratch: Mutex<Buffers>,
    column_fft: Arc<dyn Fft<f32>>,
    column_ifft: Arc<dyn Fft<f32>>,
}

impl Convolver {
    /// Plans the convolution of `width`×`height` images with `kernel`
    /// (centre at column `w/2`, row `h/2`) and transforms the kernel.
    pub fn new(kernel: &Kernel, width: usize, height: usize) -> Convolver {
        let (kw, kh) = (kernel.width(), kernel.height());
        let (cx, cy) = kernel.centre();
        let (px, py) = padded_size(kw, kh, width, height);
        let mut real_planner = RealFftPlanner::<f32>::new();
        let mut planner = FftPlanner::<f32>::new();
        let mut plan = Convolver {
            width,
            height,
            px,
            py,
            spectra: Vec::new(),
            row_fft: real_planner.plan_fft_forward(px),
            row_ifft: real_planner.plan_fft_inverse(px),
            scratch: Mutex::new((Vec::new(), Vec::new())),
            column_fft: planner.plan_fft_forward(py),
            column_ifft: planner.plan_fft_inverse(py),
        };
        plan.spectra = kernel
            .channels()
            .iter()
            .map(|k| {
                plan.forward(|row, input| {
                    // Kernel row j sits at offset j − cy, wrapped.
                    let j = (row + cy) % py;
                    if j >= kh {
                        return false;
                    }
                    for (i, &v) in k[j * kw..(j + 1) * kw].iter().enumerate() {
                        input[(i + px - cx) % px] = v;
                    }
                    true
                })
            })
            .collect();
        plan
    }

    /// The padded FFT size, columns × rows.
    pub fn padded_size(&self) -> (usize, usize) {
        (self.px, self.py)
    }

    /// How many kernel channels there are.
    pub fn channels(&self) -> usize {
        self.spectra.len()
    }

    /// `plane` (row-major, `width`×`height`) convolved with kernel channel
    /// `channel`, over the same frame; light beyond the frame is lost.
    ///
    /// Only the H image rows are transformed and kept: their spectra go into
    /// a buffer of strips of [`STRIP`] columns, row by row, so that each
    /// strip's column transforms (padded to py, multiplied by the kernel's
    /// spectrum, transformed back and cut to the H output rows) work in
    /// cache, with no transpose of the whole plane.
    pub fn convolve(&self, plane: &[f32], channel: usize) -> Vec<f32> {
        let (w, h, px, py) = (self.width, self.height, self.px, self.py);
        let count = px / 2 + 1;
        let strips = count.div_ceil(STRIP);
        let zero = Complex::new(0.0, 0.0);

        // Row transforms, written strip-major: strip s, row r, column j.
        // Reuse the plan's buffers when no other call holds them: fresh
        // ones cost page faults and zeroing on every frame.
        let mut held = self.scratch.try_lock();
        let mut own = (Vec::new(), Vec::new());
        let (rows, buffer) = match held.as_deref_mut() {
            Ok(buffers) => (&mut buffers.0, &mut buffers.1),
            Err(_) => (&mut own.0, &mut own.1),
        };
        rows.resize(h * count, zero);
        buffer.resize(strips * h * STRIP, zero);
        let row_fft = &self.row_fft;
        rows.par_chunks_mut(count)
            .zip(plane.par_chunks(w))
            .for_each_init(
                || (row_fft.make_input_vec(), row_fft.make_scratch_vec()),
                |(input, scratch), (out, src)| {
                    input[..w].copy_from_slice(src);
                    input[w..].iter_mut().for_each(|v| *v = 0.0);
                    let _ = row_fft.process_with_scratch(input, out, scratch);
                },
            );
        let rows = &*rows;
        buffer
            .par_chunks_mut(h * STRIP)
            .enumerate()
            .for_each(|(s, strip)| {
                let first = s * STRIP;
                let width = STRIP.min(count - first);
                for (r, row) in rows.chunks(count).enumerate() {
                    strip[r * STRIP..r * STRIP + width].copy_from_slice(&row[first..first + width]);
                }
            });

        // Column transforms, strip by strip, multiplied by the kernel.
        let kernel = &self.spectra[channel];
        let (column_fft, column_ifft) = (&self.column_fft, &self.column_ifft);
        buffer.par_chunks_mut(h * STRIP).enumerate().for_each_init(
            || {
                (
                    vec![zero; py],
                    vec![
                        zero;
                        column_fft
                            .get_inplace_scratch_len()
                            .max(column_ifft.get_inplace_scratch_len())
                    ],
                )
            },
            |(column, scratch), (s, strip)| {
                let first = s * STRIP;
                for j in 0..STRIP.min(count - first) {
                    for (r, v) in column[..h].iter_mut().enumerate() {
                        *v = strip[r * STRIP + j];
                    }
                    column[h..].iter_mut().for_each(|v| *v = zero);
                    column_fft.process_with_scratch(column, scratch);
                    let k = &kernel[(first + j) * py..(first + j + 1) * py];
                    for (a, b) in column.iter_mut().zip(k) {
                        *a *= *b;
                    }
                    column_ifft.process_with_scratch(column, scratch);
                    for (r, v) in column[..h].iter().enumerate() {
                        strip[r * STRIP + j] = *v;
                    }
                }
            },
        );

        // Inverse row transforms of the H output rows.
        let scale = 1.0 / (px as f32 * py as f32);
        let row_ifft = &self.row_ifft;
        let mut out = vec![0f32; w * h];
        out.par_chunks_mut(w).enumerate().for_each_init(
            || {
                (
                    row_ifft.make_input_vec(),
                    row_ifft.make_output_vec(),
                    row_ifft.make_scratch_vec(),
                )
            },
            |(input, output, scratch), (y, dst)| {
                for (s, chunk) in input.chunks_mut(STRIP).enumerate() {
                    let at = s * h * STRIP + y * STRIP;
                    chunk.copy_from_slice(&buffer[at..at + chunk.len()]);
                }
                // A real signal's DC and Nyquist bins are real; the inverse
                // refuses their round-off.
                input[0].im = 0.0;
                if px % 2 == 0 {
                    input[count - 1].im = 0.0;
                }
                let _ = row_ifft.process_with_scratch(input, output, scratch);
                for (d, v) in dst.iter_mut().zip(output.iter()) {
                    *d = v * scale;
                }
            },
        );
        out
    }

    /// The 2-D spectrum, column by column, of the px×py plane whose rows
    /// `fill` writes (returning false for an all-zero row).
    fn forward<F>(&self, fill: F) -> Vec<Complex<f32>>
    where
        F: Fn(usize, &mut [f32]) -> bool + Sync,
    {
        let (px, py) = (self.px, self.py);
        let count = px / 2 + 1;
        let zero = Complex::new(0.0, 0.0);
        let row_fft = &self.row_fft;
        let mut rows = vec![zero; py * count];
        rows.par_chunks_mut(count).enumerate().for_each_init(
            || (row_fft.make_input_vec(), row_fft.make_scratch_vec()),
            |(input, scratch), (row, out)| {
                input.iter_mut().for_each(|v| *v = 0.0);
                if fill(row, input) {
                    let _ = row_fft.process_with_scratch(input, out, scratch);
                }
            },
        );
        let column_fft = &self.column_fft;
        let mut columns = vec![zero; count * py];
        columns
            .par_chunks_mut(py)
            .enumerate()
            .for_each(|(c, column)| {
                for (r, v) in column.iter_mut().enumerate() {
                    *v = rows[r * count + c];
                }
                column_fft.process(column);
            });
        columns
    }
}
