//! Linear ("same"-size) convolution in f64, for scenes whose range f32
//! cannot hold: FFT round-off is about the unit round-off times the largest
//! value, so a sun of 10⁹ cd/m² leaves ~100 cd/m² of noise in f32 over a
//! night sky of 10⁻² cd/m², and ~10⁻⁷ cd/m² in f64. Slower and twice the
//! memory of [`super::plan::Convolver`], so it is used only when the range
//! asks for it.

use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

use super::plan::{fast_size, needed};
use crate::kernel::Kernel;

/// The kernel's spectra (its centre weight left out) and the transforms
/// for one image size.
pub struct DoubleConvolver {
    width: usize,
    height: usize,
    px: usize,
    py: usize,
    /// Per kernel channel, column-major: column u holds its `py` values.
    spectra: Vec<Vec<Complex<f64>>>,
    row_fft: Arc<dyn RealToComplex<f64>>,
    row_ifft: Arc<dyn ComplexToReal<f64>>,
    column_fft: Arc<dyn Fft<f64>>,
    column_ifft: Arc<dyn Fft<f64>>,
}

impl DoubleConvolver {
    /// Plans the convolution of `width`×`height` images with `kernel` less
    /// its centre weight, and transforms the kernel.
    pub fn without_centre(kernel: &Kernel, width: usize, height: usize) -> DoubleConvolver {
        let (kw, kh) = (kernel.width(), kernel.height());
        let (cx, cy) = kernel.centre();
        let px = fast_size(needed(kw, width));
        let py = fast_size(needed(kh, height));
        let mut real_planner = RealFftPlanner::<f64>::new();
        let mut planner = FftPlanner::<f64>::new();
        let mut convolver = DoubleConvolver {
            width,
            height,
            px,
            py,
            spectra: Vec::new(),
            row_fft: real_planner.plan_fft_forward(px),
            row_ifft: real_planner.plan_fft_inverse(px),
            column_fft: planner.plan_fft_forward(py),
            column_ifft: planner.plan_fft_inverse(py),
        };
        convolver.spectra = kernel
            .channels()
            .iter()
            .map(|plane| {
                // Kernel row j, wrapped so that its centre sits at 0.
                let rows = (0..kh).into_par_iter().map(|j| {
                    let mut row = vec![0.0; px];
                    for i in 0..kw {
                        if (i, j) != (cx, cy) {
                            row[(i + px - cx) % px] = f64::from(plane[j * kw + i]);
                        }
                    }
                    ((j + py - cy) % py, row)
                });
                convolver.transform(rows.collect())
            })
            .collect();
        convolver
    }

    /// The 2-D spectrum, column-major, of the rows given as (padded row
    /// index, real row of length `px`); other rows are zero.
    fn transform(&self, rows: Vec<(usize, Vec<f64>)>) -> Vec<Complex<f64>> {
        let half = self.px / 2 + 1;
        let py = self.py;
        let spectra: Vec<(usize, Vec<Complex<f64>>)> = rows
            .into_par_iter()
            .map(|(index, mut row)| {
                let mut spectrum = self.row_fft.make_output_vec();
                // The lengths are the planned ones, so this cannot fail.
                let _ = self.row_fft.process(&mut row, &mut spectrum);
                (index, spectrum)
            })
            .collect();
        let mut columns = vec![Complex::new(0.0, 0.0); half * py];
        columns
            .par_chunks_mut(py)
            .enumerate()
            .for_each(|(u, column)| {
                for (index, spectrum) in &spectra {
                    column[*index] = spectrum[u];
                }
                self.column_fft.process(column);
            });
        columns
    }

    /// `plane` (row-major, `width`×`height`) convolved with kernel channel
    /// `channel` less its centre, over the same frame.
    pub fn convolve(&self, plane: &[f64], channel: usize) -> Vec<f64> {
        let (w, h, px, py) = (self.width, self.height, self.px, self.py);
        let half = px / 2 + 1;
        let rows = (0..h)
            .map(|y| {
                let mut row = vec![0.0; px];
                row[..w].copy_from_slice(&plane[y * w..(y + 1) * w]);
                (y, row)
            })
            .collect();
        let mut columns = self.transform(rows);
        let kernel = &self.spectra[channel];
        let scale = 1.0 / (px * py) as f64;
        columns
            .par_chunks_mut(py)
            .zip(kernel.par_chunks(py))
            .for_each(|(column, k)| {
                for (v, k) in column.iter_mut().zip(k) {
                    *v *= k * scale;
                }
                self.column_ifft.process(column);
            });
        let mut out = vec![0.0; w * h];
        out.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
            let mut spectrum: Vec<Complex<f64>> = (0..half).map(|u| columns[u * py + y]).collect();
            // The inverse real transform wants exactly real end bins; after
            // the column passes they hold round-off.
            spectrum[0].im = 0.0;
            if px % 2 == 0 {
                spectrum[half - 1].im = 0.0;
            }
            let mut real = self.row_ifft.make_output_vec();
            let _ = self.row_ifft.process(&mut spectrum, &mut real);
            row.copy_from_slice(&real[..w]);
        });
        out
    }
}
