//! Errors of the library's front door: what a technique's `new`, `frame` and updates
//! return.

use crate::device::device_scene::BuildError;
use crate::device::error::BackendError;
use crate::frame::output::{stems, Output};

/// Errors of the library's front door.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    #[error("invalid scene: {0}")]
    /// The scene failed validation (the message names the offending path).
    InvalidScene(String),
    #[error("invalid parameter: {0}")]
    /// A setting or argument is out of range (the message names it).
    InvalidParameter(String),
    #[error("unsupported: {0}")]
    /// The technique cannot do what was asked in its current configuration (the message
    /// says why), e.g. a non-blocking frame of a technique that reads back mid-frame.
    Unsupported(String),
    #[error("{technique} has no output '{output}'; its outputs: {}", stems(has))]
    /// The technique has no such output (`has`: the outputs it has).
    NoSuchOutput {
        /// The technique's registry name.
        technique: &'static str,
        /// The output asked for.
        output: Output,
        /// The technique's outputs.
        has: Vec<Output>,
    },
    #[error("output '{output}' was not requested (the settings' `frame.outputs`)")]
    /// The output exists but the settings did not ask for it, so the frame did not make it.
    OutputNotRequested {
        /// The output asked for.
        output: Output,
    },
    #[error(transparent)]
    /// The backend failed (driver, memory, device lost, ...).
    Backend(#[from] BackendError),
}

impl From<BuildError> for Error {
    fn from(e: BuildError) -> Error {
        match e {
            BuildError::Scene { .. } => Error::InvalidScene(e.to_string()),
            BuildError::HostMemory { bytes, what } => Error::Backend(BackendError::OutOfMemory {
                bytes,
                what: format!("{what} (host memory)"),
            }),
        }
    }
}
