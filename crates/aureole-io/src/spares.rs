//! Buffers a frame sequence hands back for its later frames: a file's
//! bytes, decoded planes and the samples an EXR is encoded from.
//!
//! Memory the process has not touched costs a page fault and the kernel's
//! zeroing every 4 KiB; on a 4K frame that is as much time as the codecs.
//! A [`Spares`] made with [`Spares::keeping`] lends the buffers earlier
//! frames gave back instead: a file read with
//! [`crate::read::read_image_reusing`] is decoded into them, its
//! [`crate::formats::Original`] carries the same `Spares` to the writer,
//! which encodes into them and gives them back, and
//! [`crate::job::Input::give_back_planes`] returns the frame's planes once
//! the camera is done with them.

use std::sync::{Arc, Mutex, PoisonError};

use exr::prelude::f16;

/// Buffers lent to one frame at a time and kept between frames; cloning
/// shares them. The default keeps nothing: every buffer is fresh.
#[derive(Debug, Clone, Default)]
pub struct Spares(Option<Arc<Mutex<Shelves>>>);

/// The buffers held, by kind.
#[derive(Debug, Default)]
struct Shelves {
    floats: Shelf<f32>,
    halves: Shelf<f16>,
    bytes: Shelf<u8>,
}

/// Buffers of one kind, at most [`Shelf::MOST`] of them.
#[derive(Debug)]
struct Shelf<T>(Vec<Vec<T>>);

impl<T> Default for Shelf<T> {
    fn default() -> Self {
        Shelf(Vec::new())
    }
}

impl<T: Clone> Shelf<T> {
    /// More than a frame in flight holds of one kind (a frame's colour,
    /// alpha and other views, read, applied and written at once); beyond
    /// it a buffer given back is freed.
    const MOST: usize = 24;

    /// The smallest buffer held that holds `n` values, emptied.
    fn find(&mut self, n: usize) -> Option<Vec<T>> {
        let (at, _) = self
            .0
            .iter()
            .enumerate()
            .filter(|(_, v)| v.capacity() >= n)
            .min_by_key(|(_, v)| v.capacity())?;
        let mut buffer = self.0.swap_remove(at);
        buffer.clear();
        Some(buffer)
    }

    /// The largest buffer held, emptied.
    fn largest(&mut self) -> Option<Vec<T>> {
        let (at, _) = self
            .0
            .iter()
            .enumerate()
            .max_by_key(|(_, v)| v.capacity())?;
        let mut buffer = self.0.swap_remove(at);
        buffer.clear();
        Some(buffer)
    }

    /// `n` zeros, in the smallest buffer held that holds them, or `None`.
    fn take(&mut self, n: usize) -> Option<Vec<T>>
    where
        T: Default + Clone,
    {
        let mut buffer = self.find(n)?;
        buffer.resize(n, T::default());
        Some(buffer)
    }

    fn give(&mut self, buffer: Vec<T>) {
        if buffer.capacity() == 0 {
            return;
        }
        if self.0.len() == Self::MOST {
            // The smallest goes: it is the least likely to fit a frame.
            if let Some((at, _)) = self
                .0
                .iter()
                .enumerate()
                .min_by_key(|(_, v)| v.capacity())
                .filter(|(_, v)| v.capacity() < buffer.capacity())
            {
                self.0.swap_remove(at);
            } else {
                return;
            }
        }
        self.0.push(buffer);
    }

    fn bytes(&self) -> usize {
        self.0
            .iter()
            .map(|v| v.capacity() * std::mem::size_of::<T>())
            .sum()
    }
}

impl Spares {
    /// Spares that keep what is given back, for a sequence of frames.
    pub fn keeping() -> Spares {
        Spares(Some(Arc::new(Mutex::new(Shelves::default()))))
    }

    fn with<R>(&self, f: impl FnOnce(&mut Shelves) -> R) -> Option<R> {
        let shelves = self.0.as_ref()?;
        let mut shelves = shelves.lock().unwrap_or_else(PoisonError::into_inner);
        Some(f(&mut shelves))
    }

    /// `n` zeros as f32, in a buffer given back if one holds them, else a
    /// fresh one ([`aureole::image::zeros`]: a refusal by the allocator is
    /// an error, not an abort).
    pub fn floats(&self, n: usize) -> aureole::Result<Vec<f32>> {
        match self.with(|s| s.floats.take(n)).flatten() {
            Some(buffer) => Ok(buffer),
            None => aureole::image::zeros(n),
        }
    }

    /// `n` zeros as half floats, as [`Spares::floats`].
    pub fn halves(&self, n: usize) -> aureole::Result<Vec<f16>> {
        match self.with(|s| s.halves.take(n)).flatten() {
            Some(buffer) => Ok(buffer),
            None => aureole::image::zeros(n),
        }
    }

    /// An empty byte buffer that holds at least `n` bytes without growing;
    /// a refusal by the allocator is an error.
    pub fn bytes(&self, n: usize) -> aureole::Result<Vec<u8>> {
        // None holds them: the largest grows, rather than a new one
        // joining it on the shelf.
        let mut bytes = self
            .with(|s| s.bytes.find(n).or_else(|| s.bytes.largest()))
            .flatten()
            .unwrap_or_default();
        bytes
            .try_reserve(n)
            .map_err(|_| aureole::Error::Allocation { bytes: n as u64 })?;
        Ok(bytes)
    }

    /// Keeps `buffer` for a later [`Spares::floats`].
    pub fn give_floats(&self, buffer: Vec<f32>) {
        self.with(|s| s.floats.give(buffer));
    }

    /// Keeps `buffer` for a later [`Spares::halves`].
    pub fn give_halves(&self, buffer: Vec<f16>) {
        self.with(|s| s.halves.give(buffer));
    }

    /// Keeps `buffer` for a later [`Spares::bytes`].
    pub fn give_bytes(&self, buffer: Vec<u8>) {
        self.with(|s| s.bytes.give(buffer));
    }

    /// Keeps the planes (and alpha) of `image`.
    pub fn give_image(&self, image: aureole::Image) {
        for plane in image.planes.into_iter().chain(image.alpha) {
            self.give_floats(plane);
        }
    }

    /// Bytes held for later frames.
    pub fn held(&self) -> usize {
        self.with(|s| s.floats.bytes() + s.halves.bytes() + s.bytes.bytes())
            .unwrap_or(0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_buffer_the_allocator_refuses_is_an_error_not_an_abort() {
        let spares = Spares::keeping();
        let huge = usize::MAX / 4;
        for refused in [
            spares.floats(huge).map(drop),
            spares.halves(huge).map(drop),
            spares.bytes(huge).map(drop),
        ] {
            assert!(
                matches!(refused, Err(aureole::Error::Allocation { .. })),
                "{refused:?}"
            );
        }
    }

    #[test]
    fn a_buffer_given_back_is_lent_again_zeroed() {
        let spares = Spares::keeping();
        let mut plane = spares.floats(1000).unwrap();
        plane.fill(3.0);
        let at = plane.as_ptr();
        spares.give_floats(plane);
        let again = spares.floats(600).unwrap();
        assert_eq!(again.as_ptr(), at, "the same memory");
        assert_eq!(again.len(), 600);
        assert!(again.iter().all(|&v| v == 0.0));
        assert_eq!(spares.held(), 0);
    }

    #[test]
    fn the_smallest_buffer_that_fits_is_lent() {
        let spares = Spares::keeping();
        let (big, small) = (spares.halves(5000).unwrap(), spares.halves(2000).unwrap());
        let small_at = small.as_ptr();
        spares.give_halves(big);
        spares.give_halves(small);
        let lent = spares.halves(1500).unwrap();
        assert_eq!(lent.as_ptr(), small_at);
        let fresh = spares.halves(9000).unwrap();
        assert_eq!(fresh.len(), 9000, "none fits: a fresh one");
        assert_eq!(spares.held(), 5000 * 2);
    }

    #[test]
    fn byte_buffers_come_back_empty_with_room() {
        let spares = Spares::keeping();
        let mut bytes = spares.bytes(100).unwrap();
        bytes.extend_from_slice(&[7; 100]);
        let at = bytes.as_ptr();
        spares.give_bytes(bytes);
        let again = spares.bytes(80).unwrap();
        assert!(again.is_empty());
        assert!(again.capacity() >= 80);
        assert_eq!(again.as_ptr(), at);
    }

    #[test]
    fn a_byte_buffer_too_small_grows_instead_of_joining_a_new_one() {
        let spares = Spares::keeping();
        spares.give_bytes(Vec::with_capacity(100));
        let bigger = spares.bytes(300).unwrap();
        assert!(bigger.capacity() >= 300);
        spares.give_bytes(bigger);
        assert!(
            spares.held() >= 300 && spares.held() < 400,
            "{}",
            spares.held()
        );
    }

    #[test]
    fn the_default_keeps_nothing() {
        let spares = Spares::default();
        spares.give_floats(vec![1.0; 100]);
        assert_eq!(spares.held(), 0);
        assert_eq!(spares.floats(10).unwrap(), vec![0.0; 10]);
    }

    #[test]
    fn a_full_shelf_keeps_the_largest() {
        let spares = Spares::keeping();
        for n in 1..=Shelf::<f32>::MOST {
            spares.give_floats(vec![0.0; n]);
        }
        spares.give_floats(vec![0.0; 1000]);
        spares.give_floats(vec![0.0; 1]);
        let held = spares.held() / 4;
        let expected: usize = (2..=Shelf::<f32>::MOST).sum::<usize>() + 1000;
        assert_eq!(held, expected);
    }
}
