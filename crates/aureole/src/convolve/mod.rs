//! Convolution: the optical chain composes by convolution (MODEL.md §2), and
//! images are convolved with the chain's kernel (§8).

pub mod double;
pub mod plan;
