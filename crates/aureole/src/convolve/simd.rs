//! The one module with `unsafe` code: work compiled for AVX2 where the CPU
//! has it. The f32 engine's element-wise complex loops around the FFTs
//! (its column strips, [`super::single`]) then take 8 lanes instead of 4,
//! and the pupil transform's sum over a pixel's samples (the near field of
//! every diffraction kernel) 4 f64 lanes instead of 2, or 8 with AVX-512
//! where the CPU has that.
//! They are the same IEEE operations in the same order (Rust never fuses a
//! multiply and an add), so the result has the same bits either way; the
//! scalar twin is the same code without the feature.

#![allow(unsafe_code)]

use std::sync::atomic::{AtomicBool, Ordering};

static SCALAR: AtomicBool = AtomicBool::new(false);

/// Makes the f32 engine's own loops take the scalar twin (`true`) or the
/// widest vectors the CPU has (`false`, the default), for this process: a
/// test holds the two to the same bits. RustFFT's transforms choose their
/// own vectors either way.
pub fn force_scalar(scalar: bool) {
    SCALAR.store(scalar, Ordering::Relaxed);
}

/// Whether the engine's loops run with AVX2 now: the CPU has it and the
/// scalar twin is not forced.
pub fn vectors_in_use() -> bool {
    #[cfg(target_arch = "x86_64")]
    if !SCALAR.load(Ordering::Relaxed) {
        return std::is_x86_feature_detected!("avx2");
    }
    false
}

/// Runs `work` compiled with the widest vectors this CPU has. `work` must
/// be `#[inline(always)]` (and what it calls), so that it is compiled into
/// the caller that has the feature.
#[inline(always)]
pub(crate) fn widest<R>(work: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if vectors_in_use() {
        // SAFETY: the CPU was just found to have AVX2.
        return unsafe { avx2(work) };
    }
    work()
}

/// [`widest`] with AVX-512 (F, VL, DQ) where the CPU has it: 8 f64 lanes
/// for the pupil transform's sums over a pixel's samples, a sixth faster
/// there (a 720p kernel of a 7-blade stop with rounded sides, the same
/// bytes). The other loops stay with AVX2: the corona's chunks ran a
/// third slower with AVX-512.
#[inline(always)]
pub(crate) fn widest_sums<R>(work: impl FnOnce() -> R) -> R {
    #[cfg(target_arch = "x86_64")]
    if vectors_in_use()
        && std::is_x86_feature_detected!("avx512f")
        && std::is_x86_feature_detected!("avx512vl")
        && std::is_x86_feature_detected!("avx512dq")
    {
        // SAFETY: the CPU was just found to have these features.
        return unsafe { avx512(work) };
    }
    widest(work)
}

/// `work` compiled for AVX-512.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx512f,avx512vl,avx512dq")]
unsafe fn avx512<R>(work: impl FnOnce() -> R) -> R {
    work()
}

/// `work` compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn avx2<R>(work: impl FnOnce() -> R) -> R {
    work()
}
