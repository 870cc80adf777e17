//! The pipeline (docs/physics.md §7–8): a [`Plan`] applies one kernel to
//! images of one size; a [`Session`] is what front ends call, deciding the
//! input scale, bad samples, plan reuse and memory the same way for all of
//! them.

mod cost;
mod ghosts;
mod layers;
mod options;
mod plan;
mod precision;
mod session;
pub mod sphere;
mod splat;
mod threshold;

pub use ghosts::{DisplayWindow, GhostSummary, KeptRays};
pub use layers::GlareLayer;
pub use options::{Applied, ApplyOptions, Arithmetic, Method};
pub use plan::Plan;
pub use precision::f32_round_off;
pub use session::{Costs, Frame, FrameOptions, ScaleSource, Session, Stage};
pub use threshold::spread_fraction;
