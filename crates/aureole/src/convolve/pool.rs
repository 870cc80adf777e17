//! Buffers an engine keeps from call to call: fresh memory costs zeroing
//! and a page fault every 4 KiB on every frame of a sequence.

use std::ops::{Deref, DerefMut};
use std::sync::{Mutex, MutexGuard};

/// The buffers of one engine, lent to one call at a time.
#[derive(Debug, Default)]
pub(crate) struct Pool<T>(Mutex<Vec<T>>);

/// Buffers lent by a [`Pool`], or fresh ones when another call holds the
/// pool's (two frames through one plan at once).
pub(crate) enum Lease<'a, T> {
    Pooled(MutexGuard<'a, Vec<T>>),
    Fresh(Vec<T>),
}

impl<T> Pool<T> {
    pub fn new() -> Pool<T> {
        Pool(Mutex::new(Vec::new()))
    }

    /// The pool's buffers when no other call holds them, else fresh ones.
    pub fn lease(&self) -> Lease<'_, T> {
        match self.0.try_lock() {
            Ok(buffers) => Lease::Pooled(buffers),
            Err(_) => Lease::Fresh(Vec::new()),
        }
    }
}

impl<T> Deref for Lease<'_, T> {
    type Target = Vec<T>;

    fn deref(&self) -> &Vec<T> {
        match self {
            Lease::Pooled(buffers) => buffers,
            Lease::Fresh(buffers) => buffers,
        }
    }
}

impl<T> DerefMut for Lease<'_, T> {
    fn deref_mut(&mut self) -> &mut Vec<T> {
        match self {
            Lease::Pooled(buffers) => buffers,
            Lease::Fresh(buffers) => buffers,
        }
    }
}

/// Buffers lent to the tasks of a parallel pass, one set per task, and
/// kept for the engine's next pass: rayon's `for_each_init` makes a set
/// for every piece of work it splits off, and fresh ones would come from
/// the worker threads' malloc arenas, which return freed memory to the
/// kernel at once (a page fault per 4 KiB on every frame).
#[derive(Debug, Default)]
pub(crate) struct Scratch<T>(Mutex<Vec<T>>);

/// A set lent by [`Scratch::lend`]; it goes back when dropped.
pub(crate) struct Lent<'a, T: Default> {
    value: T,
    home: &'a Scratch<T>,
}

impl<T: Default> Scratch<T> {
    /// A set given back earlier, or `make()`'s.
    pub fn lend(&self, make: impl FnOnce() -> T) -> Lent<'_, T> {
        let kept = self
            .0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .pop();
        Lent {
            value: kept.unwrap_or_else(make),
            home: self,
        }
    }
}

impl<T: Default> Drop for Lent<'_, T> {
    fn drop(&mut self) {
        let value = std::mem::take(&mut self.value);
        self.home
            .0
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner)
            .push(value);
    }
}

impl<T: Default> Deref for Lent<'_, T> {
    type Target = T;

    fn deref(&self) -> &T {
        &self.value
    }
}

impl<T: Default> DerefMut for Lent<'_, T> {
    fn deref_mut(&mut self) -> &mut T {
        &mut self.value
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_set_given_back_is_lent_again() {
        let scratch = Scratch::default();
        let at = {
            let lent = scratch.lend(|| vec![0u8; 64]);
            lent.as_ptr()
        };
        let again = scratch.lend(|| vec![1u8; 64]);
        assert_eq!(again.as_ptr(), at);
        assert_eq!(again[0], 0, "the kept set, not a new one");
        let other = scratch.lend(|| vec![2u8; 64]);
        assert_eq!(other[0], 2, "one set per task at a time");
    }
}
