//! The plugin's own allocator: large buffers freed are kept, up to a
//! bound, for the next ones of about their size.
//!
//! A frame's work maps and frees about 1.5 GB of buffers (a 4K kernel's
//! planes, the spectra, the frame's planes). glibc maps each buffer of
//! more than 32 MiB on its own and unmaps it when freed, so every one took
//! its pages again through page faults and the kernel's zeroing: 0.8 s of
//! a 4K frame's 2 s when a lens changes. The command line tunes glibc for
//! its whole process (aureole-cli's allocator.rs); a plugin lives in a
//! host's process, whose allocator is the host's to tune, so the plugin
//! keeps its own: only its Rust allocations go through this, and what it
//! keeps is given back when the host purges caches or the last instance
//! goes.

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::UnsafeCell;
use std::sync::atomic::{AtomicBool, Ordering};

/// Buffers from this size up are kept when freed.
const LARGE: usize = 4 << 20;
/// Every large buffer is aligned to this, so a kept one serves any.
const ALIGN: usize = 64;
/// The most bytes kept.
const CAP: usize = 1 << 30;
/// How many freed buffers are kept, and how many handed-out buffers can
/// be larger than asked.
const SLOTS: usize = 64;

/// (address, size) pairs; an address of 0 is an empty slot.
type Slots = [(usize, usize); SLOTS];

struct Blocks {
    /// Freed buffers kept.
    free: Slots,
    /// Kept buffers handed out for a smaller request: their real size.
    larger: Slots,
    kept: usize,
}

/// The allocator: the system's, with large freed buffers kept.
pub struct Reusing {
    lock: AtomicBool,
    blocks: UnsafeCell<Blocks>,
}

// The blocks are only touched under the lock.
unsafe impl Sync for Reusing {}

impl Reusing {
    pub const fn new() -> Reusing {
        Reusing {
            lock: AtomicBool::new(false),
            blocks: UnsafeCell::new(Blocks {
                free: [(0, 0); SLOTS],
                larger: [(0, 0); SLOTS],
                kept: 0,
            }),
        }
    }

    /// `work` on the blocks, under a spin lock: an allocator may not
    /// allocate, and the lock is held for a scan of 64 slots.
    fn with<R>(&self, work: impl FnOnce(&mut Blocks) -> R) -> R {
        while self
            .lock
            .compare_exchange_weak(false, true, Ordering::Acquire, Ordering::Relaxed)
            .is_err()
        {
            std::hint::spin_loop();
        }
        // SAFETY: the lock is held: no other reference exists.
        let outcome = work(unsafe { &mut *self.blocks.get() });
        self.lock.store(false, Ordering::Release);
        outcome
    }

    /// A kept buffer for `size` bytes: the smallest of those at most a
    /// quarter larger.
    fn take(&self, size: usize) -> Option<*mut u8> {
        self.with(|b| {
            let fits = |s: usize| s >= size && s <= 2 * size;
            let (i, &(address, real)) = b
                .free
                .iter()
                .enumerate()
                .filter(|(_, (a, s))| *a != 0 && fits(*s))
                .min_by_key(|(_, (_, s))| *s)?;
            if real != size {
                let slot = b.larger.iter().position(|(a, _)| *a == 0)?;
                b.larger[slot] = (address, real);
            }
            b.free[i] = (0, 0);
            b.kept -= real;
            Some(address as *mut u8)
        })
    }

    /// Gives every kept buffer back to the system.
    pub fn release(&self) {
        let free = self.with(|b| {
            b.kept = 0;
            std::mem::replace(&mut b.free, [(0, 0); SLOTS])
        });
        for (address, size) in free.into_iter().filter(|(a, _)| *a != 0) {
            // SAFETY: allocated below with this size and ALIGN, and no
            // longer in any slot.
            unsafe { System.dealloc(address as *mut u8, layout(size)) };
        }
    }
}

impl Default for Reusing {
    fn default() -> Reusing {
        Reusing::new()
    }
}

fn layout(size: usize) -> Layout {
    // A size a Layout was made with, rounded to no more than ALIGN.
    Layout::from_size_align(size, ALIGN).unwrap_or(Layout::new::<u8>())
}

fn large(layout: Layout) -> bool {
    layout.size() >= LARGE && layout.align() <= ALIGN
}

unsafe impl GlobalAlloc for Reusing {
    unsafe fn alloc(&self, asked: Layout) -> *mut u8 {
        if !large(asked) {
            // SAFETY: the caller's layout, as given.
            return unsafe { System.alloc(asked) };
        }
        match self.take(asked.size()) {
            Some(address) => address,
            // SAFETY: a non-zero size and a valid alignment.
            None => unsafe { System.alloc(layout(asked.size())) },
        }
    }

    unsafe fn alloc_zeroed(&self, asked: Layout) -> *mut u8 {
        if !large(asked) {
            // SAFETY: the caller's layout, as given.
            return unsafe { System.alloc_zeroed(asked) };
        }
        match self.take(asked.size()) {
            Some(address) => {
                // SAFETY: a kept buffer of at least this size.
                unsafe { address.write_bytes(0, asked.size()) };
                address
            }
            // SAFETY: a non-zero size and a valid alignment.
            None => unsafe { System.alloc_zeroed(layout(asked.size())) },
        }
    }

    unsafe fn dealloc(&self, address: *mut u8, asked: Layout) {
        if !large(asked) {
            // SAFETY: allocated by the system with this layout.
            return unsafe { System.dealloc(address, asked) };
        }
        let kept = self.with(|b| {
            let real = match b.larger.iter_mut().find(|(a, _)| *a == address as usize) {
                Some(slot) => std::mem::take(slot).1,
                None => asked.size(),
            };
            let slot = b.free.iter().position(|(a, _)| *a == 0);
            match slot {
                Some(i) if b.kept + real <= CAP => {
                    b.free[i] = (address as usize, real);
                    b.kept += real;
                    None
                }
                _ => Some(real),
            }
        });
        if let Some(real) = kept {
            // SAFETY: allocated by the system with this size and ALIGN.
            unsafe { System.dealloc(address, layout(real)) };
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_large_buffer_freed_serves_the_next_of_about_its_size_and_is_given_back() {
        let pool = Reusing::new();
        let size = 16 << 20;
        let asked = Layout::from_size_align(size, 8).expect("a layout");
        // SAFETY: the allocator's contract: each buffer freed once, with
        // the layout it was asked with.
        unsafe {
            let first = pool.alloc(asked);
            first.write_bytes(1, size);
            pool.dealloc(first, asked);
            // A smaller request takes the kept buffer, zeroed when asked.
            let smaller = Layout::from_size_align(size - 4096, 8).expect("a layout");
            let second = pool.alloc_zeroed(smaller);
            assert_eq!(second, first);
            assert!(std::slice::from_raw_parts(second, size - 4096)
                .iter()
                .all(|&b| b == 0));
            // Freed with its own layout, it goes back at its real size.
            pool.dealloc(second, smaller);
            assert_eq!(pool.with(|b| b.kept), size);
            // One less than half its size is not served from it.
            let larger = Layout::from_size_align(size / 2 - 1, 8).expect("a layout");
            let third = pool.alloc(larger);
            assert_ne!(third, first);
            pool.dealloc(third, larger);
        }
        pool.release();
        assert_eq!(
            pool.with(|b| (b.kept, b.free.iter().filter(|(a, _)| *a != 0).count())),
            (0, 0)
        );
    }

    #[test]
    fn small_and_over_aligned_buffers_go_straight_to_the_system() {
        let pool = Reusing::new();
        for asked in [
            Layout::from_size_align(1024, 8),
            Layout::from_size_align(8 << 20, 4096),
        ] {
            let asked = asked.expect("a layout");
            // SAFETY: freed once with its layout.
            unsafe {
                let p = pool.alloc(asked);
                assert_eq!(p as usize % asked.align(), 0);
                pool.dealloc(p, asked);
            }
        }
        assert_eq!(pool.with(|b| b.kept), 0);
    }
}
