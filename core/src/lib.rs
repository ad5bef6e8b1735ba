#![allow(clippy::neg_cmp_op_on_partial_ord, clippy::nonminimal_bool)]
#![warn(missing_docs)]
// NaN-rejecting comparisons such as `!(x > 0.0)` are deliberate: they are true for NaN.
//! caustica core: the techniques written once against the [`Backend`]
//! trait. Core depends on no backend. It is built in layers; a lower layer never imports
//! a higher one:
//!
//! 1. [`math`]: scalar optics, sampling, RNG, packing, pixel footprint, geometry, fixed
//!    point; every shader port mirrors these functions by name.
//! 2. [`scene`]: the scene model, built-in scenes, the JSON format, validation.
//! 3. [`device`]: Pod element layouts shared with the shaders, the flattened scene with
//!    its CWBVH, typed buffer handles, lowered launches, typed device errors.
//! 4. [`kernels`]: the one list of kernels, one file per kernel declaration.
//! 5. [`recording`] and [`backend`]: the `Recording` core builds and the object-safe
//!    `Backend` trait that executes it.
//! 6. [`frame`]: what every technique shares (the `Technique` seam, plans, stats,
//!    allocation, temporal resources, emission, images, metrics).
//! 7. [`techniques`]: one folder per technique and the one registry of names.

pub mod backend;
pub mod device;
pub mod frame;
pub mod kernels;
pub mod math;
pub mod recording;
pub mod scene;
pub mod techniques;

pub use backend::{Backend, BackendError, Capabilities, DeviceType, Finished, Submission};
pub use frame::error::Error;
pub use frame::output::{Output, Outputs};
pub use frame::plan::FramePlan;
pub use frame::receivers::atlas::settings::{AtlasSettings, PlaneSettings};
pub use frame::receivers::screen::ScreenSettings;
pub use frame::settings::{Dispersion, FrameSettings, TechniqueSettings, TraceSettings};
pub use frame::stats::FrameStats;
pub use frame::submitted::{FrameTicket, RecordedFrame};
pub use frame::technique::{OutputInfo, Progress, Technique};
pub use scene::Scene;
pub use techniques::adaptive_caustics::TraversalSettings;
pub use techniques::sspm::{GatherFilter, Sspm, SspmSettings};
