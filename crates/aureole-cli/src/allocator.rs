//! The C allocator's settings for a run of the command line.
//!
//! A 4K still maps and frees about 1.5 GB of buffers in its life (the
//! kernel's planes, the composition's and the frame's spectra and row
//! tiles, the result planes), and a frame sequence maps the `exr` crate's
//! compressed chunks (15 MB a 4K frame, new vectors its writer consumes)
//! on every frame. glibc maps every buffer of more than 32 MiB on its own
//! and unmaps it when freed, and it hands freed memory at the top of its
//! heaps back to the kernel, so each buffer took its pages again through
//! a page fault and the kernel's zeroing every 4 KiB: a fifth of a 4K
//! still's time, and on one core wherever one thread wrote a fresh buffer.
//! A run of the command line ends when its work does, so it keeps what it
//! frees: every buffer comes from the one heap, which is never trimmed.
//! Freed buffers are then taken again for the next ones, and the peak
//! stays about what it was (a 4K still 0.89 → 0.95 GB, a batch of 4K
//! frames as before). The studio, a server that lives on within a memory
//! budget, has a bounded policy of its own (aureole-studio's budget.rs).

/// Serves every allocation from the main heap (no buffers mapped on their
/// own, one arena for every thread, so that what one thread frees another
/// takes) and never gives freed memory back to the kernel.
#[cfg(all(target_os = "linux", target_env = "gnu"))]
#[allow(unsafe_code)]
pub fn keep_freed_memory() {
    // SAFETY: mallopt only sets three of glibc's tunable parameters, which
    // it reads under its own locks; it touches no memory of ours. Were the
    // heap unable to grow, glibc maps the memory instead.
    unsafe {
        libc::mallopt(libc::M_MMAP_MAX, 0);
        libc::mallopt(libc::M_ARENA_MAX, 1);
        libc::mallopt(libc::M_TRIM_THRESHOLD, libc::c_int::MAX);
    }
}

/// Other allocators keep their own policy.
#[cfg(not(all(target_os = "linux", target_env = "gnu")))]
pub fn keep_freed_memory() {}
