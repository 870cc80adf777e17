//! The one module with `unsafe` code: the f32 engine's column strips
//! compiled for AVX2 where the CPU has it, beside their scalar twin
//! ([`Convolver::strip`]). The element-wise complex loops around the FFTs
//! then take 8 lanes instead of 4. They are the same IEEE operations in the
//! same order (Rust never fuses a multiply and an add), so the result has
//! the same bits either way.

#![allow(unsafe_code)]

use realfft::num_complex::Complex;

use super::single::{Convolver, Strip};

/// One strip's columns through [`Convolver::strip`], with the widest
/// vectors this CPU has.
pub(super) fn strip(
    convolver: &Convolver,
    strip: &Strip,
    out: &mut [Complex<f32>],
    column: &mut [Complex<f32>],
    scratch: &mut [Complex<f32>],
) {
    #[cfg(target_arch = "x86_64")]
    if std::is_x86_feature_detected!("avx2") {
        // SAFETY: the CPU was just found to have AVX2.
        unsafe { strip_avx2(convolver, strip, out, column, scratch) };
        return;
    }
    convolver.strip(strip, out, column, scratch);
}

/// [`Convolver::strip`] compiled for AVX2; it is inlined here.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn strip_avx2(
    convolver: &Convolver,
    strip: &Strip,
    out: &mut [Complex<f32>],
    column: &mut [Complex<f32>],
    scratch: &mut [Complex<f32>],
) {
    convolver.strip(strip, out, column, scratch)
}
