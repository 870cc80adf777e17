//! # aureole-io
//!
//! Files and pictures for [aureole](aureole): HDR images in and out
//! (OpenEXR, Radiance `.hdr`, PFM, and PNG, JPEG, TIFF pictures), kernels as
//! files and log-scaled pictures, the display path (exposure, tone curves,
//! sRGB), profile plots, the built-in demo scene, and the memory this
//! machine can give. Every format sits in one table, [`formats::FORMATS`];
//! every write is atomic.
//!
//! Read, apply, write:
//!
//! ```
//! use aureole::{presets, Config, Frame, FrameOptions, Session};
//! use aureole_io::limits::Limits;
//! use aureole_io::read::read_image;
//! use aureole_io::write::{write_linear, LinearOptions};
//!
//! # let dir = tempfile::tempdir().unwrap();
//! # let night = dir.path().join("night.exr");
//! # write_linear(&night, &aureole_io::demo::night_street(160, 90), LinearOptions::default())?;
//! let image = read_image(&night, Limits::NONE)?.image;
//! let frame = Frame::new(image, &FrameOptions::default())?;
//!
//! let mut config = Config::default();
//! config.merge(presets::find("paper-fig5-both")?.config()?);
//! let mut session = Session::new(config);
//! let applied = session.apply(&frame, &Default::default(), &mut |_, _| {})?;
//!
//! write_linear(&dir.path().join("camera.exr"), &applied.image, LinearOptions::default())?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod atomic;
pub mod compression;
pub mod demo;
pub mod display;
pub mod error;
pub mod formats;
#[doc(hidden)]
pub mod fuzzing;
pub mod job;
pub mod kernel;
pub mod lens_drawing;
pub mod lenses;
pub mod limits;
pub mod measured;
#[cfg(feature = "plot")]
pub mod plot;
pub mod rating;
pub mod read;
pub mod spares;
pub mod write;

pub use error::{Error, Result};

/// The README's Rust examples, run as doctests so that they stay true.
#[doc = include_str!("../../../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

/// The library page's examples, run as doctests for the same reason.
#[doc = include_str!("../../../docs/library.md")]
#[cfg(doctest)]
pub struct LibraryDoctests;

/// The guide's Rust example, run as a doctest for the same reason.
#[doc = include_str!("../../../docs/guide.md")]
#[cfg(doctest)]
pub struct GuideDoctests;
