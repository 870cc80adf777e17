//! # aureole
//!
//! What a real camera adds around bright lights, computed from physics, for
//! HDR images whose pixels hold luminance in cd/m²: **bloom** (light
//! scattered in the lens and the emulsion), **corona** (star rays from
//! diffraction on the stop and on filters) and human-eye **glare** after Vos.
//! The model is Ďurikovič and Kolchin's, "Physically-Based Model of
//! Photographic Effects for Night and Day Scenes", read through MODEL.md.
//!
//! A PSF is P(r, φ) = (1 − ε) δ(r) + ε f(r, φ); each effect gives ε and f,
//! and a [`Kernel`] is the PSF averaged over pixel areas with ΣK = 1. A
//! [`Plan`] holds a kernel and its spectrum for one image size and applies
//! the camera to any number of images: the light of pixels brighter than the
//! threshold is spread, the rest stays (MODEL.md §7).
//!
//! Load, plan, apply, save:
//!
//! ```
//! use aureole::io::{read::read_image, write::{write_linear, LinearOptions}};
//! use aureole::{presets, ApplyOptions, Config, Plan};
//!
//! # let dir = tempfile::tempdir().unwrap();
//! # let night = dir.path().join("night.exr");
//! # write_linear(&night, &aureole::demo::night_street(320, 180), LinearOptions::default())?;
//! // An HDR image whose pixels are cd/m² (or whose whiteLuminance says how many).
//! let image = read_image(&night)?.image;
//! let scale = image.white_luminance.map_or(1.0, f64::from);
//!
//! // The camera: presets and config files compose like on the command line.
//! let mut config = Config::default();
//! config.apply(presets::find("paper-fig5-both")?.config()?);
//!
//! // Built once per image size; light from any pixel can reach the whole frame.
//! let plan = Plan::new(&config, image.width, image.height, None)?;
//! let options = ApplyOptions { threshold: 100.0, scale, ..ApplyOptions::default() };
//! let result = plan.apply(&image, &options, &mut |done| eprintln!("{:.0} %", done * 100.0))?;
//! assert!(result.energy_out <= result.energy_in * (1.0 + 1e-6));
//!
//! write_linear(&dir.path().join("camera.exr"), &result.image, LinearOptions::default())?;
//! # Ok::<(), aureole::Error>(())
//! ```
//!
//! Kernels alone:
//!
//! ```
//! use aureole::{presets, Config, Extent};
//!
//! let mut config = Config::default();
//! config.apply(presets::find("paper-fig5-both")?.config()?);
//! let kernel = config.kernel(&Extent::new(129, 129)?)?;
//! assert!((kernel.sum(0) - 1.0).abs() < 1e-5);
//! # Ok::<(), aureole::Error>(())
//! ```

pub mod apply;
pub mod camera;
pub mod config;
pub mod convolve;
pub mod demo;
pub mod display;
pub mod error;
#[doc(hidden)]
pub mod fuzzing;
pub mod image;
pub mod io;
pub mod kernel;
pub mod memory;
pub mod plot;
pub mod presets;
pub mod psf;
pub mod units;

pub use apply::{Applied, ApplyOptions, Method, Plan};
pub use camera::Camera;
pub use config::{Config, ConfigFile};
pub use error::{Error, Result};
pub use image::{Image, Layout};
pub use kernel::{Extent, Kernel};
pub use psf::{Aperture, Bloom, Corona, Effect, Filter, Vos};
pub use units::{Length, Unit};

/// The README's Rust examples, run as doctests so that they stay true.
#[doc = include_str!("../../../README.md")]
#[cfg(doctest)]
pub struct ReadmeDoctests;

/// The guide's Rust example, run as a doctest for the same reason.
#[doc = include_str!("../../../docs/guide.md")]
#[cfg(doctest)]
pub struct GuideDoctests;
