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
