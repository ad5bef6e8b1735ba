//! Typed device failures: what a backend reports instead of panicking.

use crate::device::handle::ResourceId;

/// Typed backend failures; backends never panic on these.
#[derive(Clone, Debug, thiserror::Error)]
pub enum BackendError {
    #[error("backend '{backend}' is not available: {reason}")]
    Unavailable { backend: String, reason: String },
    #[error("unsupported: {0}")]
    Unsupported(String),
    #[error("out of memory allocating {bytes} bytes for {what}")]
    OutOfMemory { bytes: u64, what: String },
    #[error("unknown resource {0:?} (freed or never created)")]
    MissingResource(ResourceId),
    #[error("bad kernel argument: {0}")]
    BadArgument(String),
    #[error("device lost: {0}")]
    DeviceLost(String),
    #[error("driver error: {0}")]
    Driver(String),
}
