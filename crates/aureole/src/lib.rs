//! # aureole
//!
//! What a real camera adds around bright lights, computed from physics, for
//! HDR images whose pixels hold luminance in cd/m²: **bloom** (light
//! scattered in the lens and the emulsion), **corona** (star rays from
//! diffraction on the stop and on filters) and human-eye **glare** after Vos.
//! The model is Ďurikovič and Kolchin's, "Physically-Based Model of
//! Photographic Effects for Night and Day Scenes", as `docs/physics.md` in
//! the repository writes it down.
//!
//! The pipeline, stage by stage:
//!
//! - [`optics`]: the physical models of the optical chain (bloom, corona,
//!   Vos, the aperture with its pupil and spectrum), one module each;
//! - [`kernel`]: their PSFs as discrete kernels, ΣK ≤ 1 (rasterising,
//!   composing, diffraction's near field, far field and filter orders);
//! - [`convolve`]: the engine that spreads planes of light through a
//!   kernel, behind one trait, in f32 and f64;
//! - [`pipeline`]: the threshold, the choice between FFT and splatting and
//!   of the precision, the [`Plan`] of one image size, and the [`Session`]
//!   that every front end calls.
//!
//! This crate reads no image files, draws no plots and writes nothing to a
//! terminal: `aureole-io` has the files and pictures, `aureole-cli` the
//! command line.
//!
//! A frame sequence through one camera:
//!
//! ```
//! use aureole::{presets, ApplyOptions, Config, Frame, FrameOptions, Image, Layout, Session};
//!
//! // The camera: presets and config files compose like on the command line.
//! let mut config = Config::default();
//! config.merge(presets::find("paper-fig5-both")?.config()?);
//!
//! // A session builds the kernel once per image size and reuses it.
//! let mut session = Session::new(config).with_memory_limit(2 << 30);
//! for x in [40, 50, 60] {
//!     // An HDR image in cd/m²: a lamp moving over a dim street.
//!     let mut image = Image::filled(160, 90, Layout::Rgb, 0.05);
//!     for plane in &mut image.planes {
//!         plane[45 * 160 + x] = 5e4;
//!     }
//!     let frame = Frame::new(image, &FrameOptions::default())?;
//!     let options = ApplyOptions { threshold: Some(100.0), ..ApplyOptions::default() };
//!     let applied = session.apply(&frame, &options, &mut |stage, done| {
//!         eprintln!("{} {:.0} %", stage.describe(), done * 100.0);
//!     })?;
//!     assert!(applied.energy_out <= applied.energy_in * (1.0 + 1e-6));
//!     session.recycle(applied.image);
//! }
//! # Ok::<(), aureole::Error>(())
//! ```
//!
//! Kernels alone:
//!
//! ```
//! use aureole::{presets, Config, Extent};
//!
//! let mut config = Config::default();
//! config.merge(presets::find("paper-fig5-both")?.config()?);
//! let kernel = config.kernel(&Extent::new(129, 129)?)?;
//! // The share of the light that falls within 64 px: the rest would
//! // leave a frame this kernel is for.
//! assert!(kernel.sum(0) > 0.99 && kernel.sum(0) <= 1.0);
//! # Ok::<(), aureole::Error>(())
//! ```

#![deny(unsafe_code)]
#![warn(missing_docs)]

mod bytes;
pub mod camera;
mod check;
pub mod config;
pub mod control;
pub mod convolve;
pub mod error;
pub mod image;
pub mod kernel;
pub mod lens;
mod math;
pub mod memory;
pub mod optics;
pub mod pipeline;
pub mod presets;
pub mod rating;
pub mod schema;
mod sending;
pub mod units;
pub mod view;

pub use camera::CameraGeometry;
pub use config::{Config, ConfigFile};
pub use control::{Cancel, Control};
pub use convolve::{Composing, Device};
pub use error::{Error, Result};
pub use image::{Image, Layout, Shape};
pub use kernel::{Extent, Kernel, Sending};
pub use optics::{Aperture, Bloom, Corona, Effect, Eye, Filter, Halation, Measured, Vos};
pub use pipeline::{
    Applied, ApplyOptions, Arithmetic, DisplayWindow, Frame, FrameOptions, GhostSummary,
    GlareLayer, KeptRays, Method, Plan, ScaleSource, Session, Stage,
};
pub use units::{Length, Unit};
pub use view::{Projection, View};
