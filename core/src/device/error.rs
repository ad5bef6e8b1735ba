//! Typed device failures: what a backend reports instead of panicking.

use crate::device::handle::ResourceId;

/// Typed backend failures; backends never panic on these.
#[derive(Clone, Debug, thiserror::Error)]
pub enum BackendError {
    /// The backend cannot run here (not compiled in, no driver, loader or device).
    #[error("backend '{backend}' is not available: {reason}")]
    Unavailable {
        /// Name of the backend (`cpu`, `opencl`, `wgpu`, `vulkan`, `auto`).
        backend: String,
        /// Why it cannot run.
        reason: String,
    },
    /// The device or backend lacks something the request needs (a feature, an extension,
    /// a kernel variant; the message says which).
    #[error("unsupported: {0}")]
    Unsupported(String),
    /// A buffer could not be allocated or exceeds the device's per-buffer limit.
    #[error("out of memory allocating {bytes} bytes for {what}")]
    OutOfMemory {
        /// Size requested (bytes).
        bytes: u64,
        /// The buffer's label, with the limit or the driver's message.
        what: String,
    },
    /// A step names a resource the backend does not hold (freed or never created).
    #[error("unknown resource {0:?} (freed or never created)")]
    MissingResource(ResourceId),
    /// An invalid argument: a kernel argument or buffer that does not match the kernel's
    /// declaration, a size mismatch, a scene used before `prepare_scene`, a submission
    /// collected twice or given to another backend; reported instead of an out-of-bounds
    /// device access or a wrong result.
    #[error("bad argument: {0}")]
    BadArgument(String),
    /// The device was lost (driver reset, removal, hang); the backend cannot continue.
    #[error("device lost: {0}")]
    DeviceLost(String),
    /// The driver or API reported another error (the message quotes it).
    #[error("driver error: {0}")]
    Driver(String),
}

/// A zeroed host buffer of `bytes` bytes for `what`, or [`BackendError::OutOfMemory`]
/// naming host memory: what every backend reads device buffers back into, so that a
/// readback the host cannot hold is an error, not an abort.
pub fn host_bytes(bytes: u64, what: &str) -> Result<Vec<u8>, BackendError> {
    let oom = || BackendError::OutOfMemory {
        bytes,
        what: format!("{what} (host memory)"),
    };
    let n = usize::try_from(bytes).map_err(|_| oom())?;
    let mut v = Vec::new();
    v.try_reserve_exact(n).map_err(|_| oom())?;
    v.resize(n, 0);
    Ok(v)
}
