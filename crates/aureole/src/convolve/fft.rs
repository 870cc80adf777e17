//! Linear 2-D convolution through real-to-complex FFTs, with zero padding to
//! fast (5-smooth) sizes so that nothing wraps around.

use std::sync::Arc;

use rayon::prelude::*;
use realfft::num_complex::Complex;
use realfft::{RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

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

/// Convolves two `width`×`height` planes (row-major, top row first) whose
/// origin is at column `width/2`, row `height/2`, and returns the result over
/// the same window: out(o) = Σ a(p) b(o − p) for offsets o inside the window,
/// without wrap-around.
pub fn convolve_same(a: &[f64], b: &[f64], width: usize, height: usize) -> Vec<f64> {
    debug_assert_eq!(a.len(), width * height);
    debug_assert_eq!(b.len(), width * height);
    let (cx, cy) = (width / 2, height / 2);
    // An offset o in the window must not alias with any offset of the full
    // linear result, which spans [−2c, 2(w − 1 − c)]: that needs a period of
    // at least w + c.
    let px = fast_size(width + cx);
    let py = fast_size(height + cy);
    let spectrum_a = Spectrum::forward(a, width, height, 0, 0, px, py);
    // b is placed with its origin at index 0, so the product's index equals
    // the offset of a's window.
    let spectrum_b = Spectrum::forward(b, width, height, cx, cy, px, py);
    let product = spectrum_a.multiply(spectrum_b);
    product.inverse(width, height)
}

/// A 2-D spectrum stored column by column: `columns` × `py`.
struct Spectrum {
    data: Vec<Complex<f64>>,
    px: usize,
    py: usize,
    column_ifft: Arc<dyn Fft<f64>>,
}

impl Spectrum {
    /// Transforms a plane placed so that its element (cx, cy) lands at index
    /// (0, 0) of the px×py period (the rest wrapped).
    fn forward(
        plane: &[f64],
        width: usize,
        height: usize,
        cx: usize,
        cy: usize,
        px: usize,
        py: usize,
    ) -> Spectrum {
        let row_fft: Arc<dyn RealToComplex<f64>> =
            RealFftPlanner::<f64>::new().plan_fft_forward(px);
        let mut planner = FftPlanner::<f64>::new();
        let column_fft = planner.plan_fft_forward(py);
        let column_ifft = planner.plan_fft_inverse(py);
        let columns = px / 2 + 1;

        let mut rows = vec![Complex::new(0.0, 0.0); height * columns];
        rows.par_chunks_mut(columns)
            .zip(plane.par_chunks(width))
            .for_each_init(
                || (row_fft.make_input_vec(), row_fft.make_scratch_vec()),
                |(input, scratch), (out, src)| {
                    input.iter_mut().for_each(|v| *v = 0.0);
                    for (x, &v) in src.iter().enumerate() {
                        input[(x + px - cx) % px] = v;
                    }
                    // Lengths come from the plan itself, so this cannot fail.
                    let _ = row_fft.process_with_scratch(input, out, scratch);
                },
            );

        let mut data = vec![Complex::new(0.0, 0.0); columns * py];
        data.par_chunks_mut(py)
            .enumerate()
            .for_each(|(column, out)| {
                for (y, row) in rows.chunks(columns).enumerate() {
                    out[(y + py - cy) % py] = row[column];
                }
                column_fft.process(out);
            });
        Spectrum {
            data,
            px,
            py,
            column_ifft,
        }
    }

    fn multiply(mut self, other: Spectrum) -> Spectrum {
        self.data
            .par_iter_mut()
            .zip(other.data.par_iter())
            .for_each(|(a, b)| *a *= *b);
        self
    }

    /// The first `width`×`height` elements of the inverse transform, scaled
    /// by 1/(px·py).
    fn inverse(mut self, width: usize, height: usize) -> Vec<f64> {
        let (px, py) = (self.px, self.py);
        let columns = px / 2 + 1;
        let column_ifft = &self.column_ifft;
        self.data
            .par_chunks_mut(py)
            .for_each(|column| column_ifft.process(column));

        let inverse = RealFftPlanner::<f64>::new().plan_fft_inverse(px);
        let scale = 1.0 / (px as f64 * py as f64);
        let data = &self.data;
        let mut out = vec![0.0; width * height];
        out.par_chunks_mut(width).enumerate().for_each_init(
            || {
                (
                    inverse.make_input_vec(),
                    inverse.make_output_vec(),
                    inverse.make_scratch_vec(),
                )
            },
            |(input, output, scratch), (y, dst)| {
                for (column, v) in input.iter_mut().enumerate() {
                    *v = data[column * py + y];
                }
                // The real inverse refuses round-off in the imaginary parts of
                // the DC and Nyquist bins, which a real signal has as zero.
                input[0].im = 0.0;
                if px % 2 == 0 {
                    input[columns - 1].im = 0.0;
                }
                let _ = inverse.process_with_scratch(input, output, scratch);
                for (d, v) in dst.iter_mut().zip(output.iter()) {
                    *d = v * scale;
                }
            },
        );
        out
    }
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

    fn direct(a: &[f64], b: &[f64], w: usize, h: usize) -> Vec<f64> {
        let (cx, cy) = ((w / 2) as i64, (h / 2) as i64);
        let at = |p: &[f64], x: i64, y: i64| {
            let (i, j) = (x + cx, y + cy);
            if i < 0 || j < 0 || i >= w as i64 || j >= h as i64 {
                0.0
            } else {
                p[j as usize * w + i as usize]
            }
        };
        let mut out = vec![0.0; w * h];
        for oy in -cy..h as i64 - cy {
            for ox in -cx..w as i64 - cx {
                let mut s = 0.0;
                for py in -cy..h as i64 - cy {
                    for px in -cx..w as i64 - cx {
                        s += at(a, px, py) * at(b, ox - px, oy - py);
                    }
                }
                out[(oy + cy) as usize * w + (ox + cx) as usize] = s;
            }
        }
        out
    }

    #[test]
    fn matches_the_direct_sum_without_wrap_around() {
        for (w, h) in [(1, 1), (5, 4), (8, 7), (12, 9), (3, 16)] {
            let a: Vec<f64> = (0..w * h).map(|i| ((i * 37 % 11) as f64) - 3.0).collect();
            let b: Vec<f64> = (0..w * h).map(|i| ((i * 13 % 7) as f64) + 0.5).collect();
            let fast = convolve_same(&a, &b, w, h);
            let slow = direct(&a, &b, w, h);
            for (f, s) in fast.iter().zip(&slow) {
                assert!(
                    (f - s).abs() < 1e-9 * (1.0 + s.abs()),
                    "{w}x{h}: {f} vs {s}"
                );
            }
        }
    }
}
