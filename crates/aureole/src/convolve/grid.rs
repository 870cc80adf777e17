//! The padded grid of an FFT convolution: how large the period must be so
//! that nothing wraps around, rounded up to sizes the FFT is fast at, and
//! whether the column transforms can be pruned; and the transforms
//! planned for it.

use std::sync::Arc;

use realfft::{ComplexToReal, FftNum, RealFftPlanner, RealToComplex};
use rustfft::{Fft, FftPlanner};

/// An engine's transforms of its period, in `T`: rows real-to-complex and
/// back, columns complex both ways.
pub(super) struct Transforms<T: FftNum> {
    pub row_fft: Arc<dyn RealToComplex<T>>,
    pub row_ifft: Arc<dyn ComplexToReal<T>>,
    pub column_fft: Arc<dyn Fft<T>>,
    pub column_ifft: Arc<dyn Fft<T>>,
}

impl<T: FftNum> Transforms<T> {
    /// The transforms of rows of `row` samples and columns of `column`.
    pub fn plan(row: usize, column: usize) -> Transforms<T> {
        let mut real = RealFftPlanner::<T>::new();
        let mut complex = FftPlanner::<T>::new();
        Transforms {
            row_fft: real.plan_fft_forward(row),
            row_ifft: real.plan_fft_inverse(row),
            column_fft: complex.plan_fft_forward(column),
            column_ifft: complex.plan_fft_inverse(column),
        }
    }
}

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

/// The padded FFT size, columns × rows, of the f32 engine for a linear
/// convolution of `width`×`height` images with a
/// `kernel_width`×`kernel_height` kernel centred at its middle.
pub fn padded_size(
    kernel_width: usize,
    kernel_height: usize,
    width: usize,
    height: usize,
) -> (usize, usize) {
    Grid::new((kernel_width, kernel_height), (width, height), true).padded()
}

/// The shortest period along one axis that avoids wrap-around: output x
/// in [0, W) must not alias with the full linear result, which spans
/// [−c, W + K − 2 − c] for a kernel of K centred at c = K/2, and the kernel
/// must not overlap itself.
fn needed(kernel: usize, image: usize) -> usize {
    let c = kernel / 2;
    (image + kernel - 1 - c).max(image + c).max(kernel)
}

/// How the columns are transformed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum ColumnTransform {
    /// One transform of the whole padded column.
    Full(usize),
    /// Two transforms of half the padded length 2N each way (the image
    /// rows fit in the first half): the even frequencies of x and of
    /// x·e^{−iπn/N}.
    Halves(usize),
}

impl ColumnTransform {
    /// The length of each 1-D transform.
    pub fn transform_length(self) -> usize {
        match self {
            ColumnTransform::Full(p) => p,
            ColumnTransform::Halves(n) => n,
        }
    }

    /// The padded column length P.
    pub fn length(self) -> usize {
        match self {
            ColumnTransform::Full(p) => p,
            ColumnTransform::Halves(n) => 2 * n,
        }
    }

    /// The cheaper of a full and a pruned column transform for `height`
    /// image rows and a period of at least `needed`, by the n·log₂n count.
    fn cheaper(needed: usize, height: usize) -> ColumnTransform {
        let cost = |n: usize| n as f64 * libm::log2(n as f64);
        let full = fast_size(needed);
        let half = fast_size(needed.div_ceil(2).max(height));
        if 4.0 * cost(half) < 2.0 * cost(full) {
            ColumnTransform::Halves(half)
        } else {
            ColumnTransform::Full(full)
        }
    }
}

/// The period of a convolution: `px` columns, and the column transform.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Grid {
    pub px: usize,
    pub columns: ColumnTransform,
}

impl Grid {
    /// The grid for `image` (width, height) and a `kernel` (width, height)
    /// centred at its middle; with `prune`, pruned column transforms where
    /// they are cheaper.
    pub fn new(kernel: (usize, usize), image: (usize, usize), prune: bool) -> Grid {
        let rows = needed(kernel.1, image.1);
        Grid {
            px: fast_size(needed(kernel.0, image.0)),
            columns: if prune {
                ColumnTransform::cheaper(rows, image.1)
            } else {
                ColumnTransform::Full(fast_size(rows))
            },
        }
    }

    /// Columns × rows of the period.
    pub fn padded(&self) -> (usize, usize) {
        (self.px, self.columns.length())
    }

    /// Columns of a row's real-to-complex spectrum.
    pub fn spectrum_width(&self) -> usize {
        self.px / 2 + 1
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

    #[test]
    fn columns_are_pruned_when_the_rows_fit_in_half_the_period() {
        // A full-frame kernel: 2H − 1 rows need a period of 2H.
        let cheaper = ColumnTransform::cheaper;
        assert_eq!(cheaper(4319, 2160), ColumnTransform::Halves(2160));
        assert_eq!(cheaper(2159, 1080), ColumnTransform::Halves(1080));
        // A small kernel: halves would need N ≥ H, more than one period.
        assert_eq!(cheaper(1100, 1000), ColumnTransform::Full(1125));
    }
}
