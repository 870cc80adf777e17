//! The C allocator's settings for a frame sequence.
//!
//! The buffers a frame needs are kept from frame to frame by the library
//! (decoded planes, FFT planes and scratch, encode buffers). What it cannot
//! keep are the `exr` crate's chunks: each compressed chunk is a new
//! vector that its writer consumes, 15 MB of them per 4K frame. glibc
//! hands memory that size back to the kernel as soon as it is freed (its
//! per-thread heaps are trimmed once 128 KiB lie free at their top, and
//! the threshold above which it maps memory of its own moves with what is
//! freed), so the next frame takes it again through page faults and the
//! kernel's zeroing. Fixed thresholds keep freed memory for reuse; the peak
//! is what it was, since a frame frees what the next one needs.

/// Keeps freed memory below 64 MiB in the allocator's heaps, and maps
/// buffers of 4 MiB and more on their own (the library keeps those).
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
pub fn keep_freed_memory() {
    // SAFETY: mallopt only sets two of glibc's tunable parameters, which
    // it reads under its own locks; it touches no memory of ours.
    unsafe {
        libc::mallopt(libc::M_MMAP_THRESHOLD, 4 << 20);
        libc::mallopt(libc::M_TRIM_THRESHOLD, 64 << 20);
    }
}

/// Other allocators keep their own policy.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn keep_freed_memory() {}
