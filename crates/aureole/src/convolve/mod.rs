//! Convolution: the optical chain composes by convolution (MODEL.md §2, §8).

pub mod fft;
