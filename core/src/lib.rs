#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::nonminimal_bool)]
// NaN-rejecting comparisons such as `!(x > 0.0)` are deliberate: they are true for NaN.
//! caustica core: the scene model, the scalar math every backend shares, the `#[repr(C)]`
//! data layouts, the [`Backend`](backend::Backend) trait with its kernel registry, and the
//! techniques as recordings of passes. Core depends on no backend.
//!
//! Module map: [`optics`] (reflect, refract, Fresnel, Beer, Cauchy), [`sampling`],
//! [`rng`], [`packing`], [`footprint`] (seed 000 Eq. 4), [`geometry`], [`fixed_point`],
//! [`scene`], [`device_scene`] (flattened arrays + CWBVH), [`gpu`] (shared structs),
//! [`emission`] (photon emission domains), [`recording`], [`backend`], [`kernels`],
//! [`plan`] (the frame plan: passes, variants, buffers), [`sspm`] (the technique), [`stats`], [`image`].

pub mod backend;
pub mod device_scene;
pub mod emission;
pub mod fixed_point;
pub mod footprint;
pub mod geometry;
pub mod gpu;
pub mod image;
pub mod kernels;
pub mod launch;
pub mod metrics;
pub mod optics;
pub mod packing;
pub mod plan;
pub mod recording;
pub mod rng;
pub mod sampling;
pub mod scene;
pub mod sspm;
pub mod stats;

pub use backend::{Backend, BackendError, Capabilities};
pub use plan::{FramePlan, Output, Outputs};
pub use scene::Scene;
pub use sspm::{Sspm, SspmSettings};
pub use stats::FrameStats;

/// Errors of the library's front door.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("invalid scene: {0}")]
    InvalidScene(String),
    #[error("invalid parameter: {0}")]
    InvalidParameter(String),
    #[error(transparent)]
    Backend(#[from] BackendError),
}
