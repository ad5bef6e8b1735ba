//! The `Backend` trait: small and object-safe (DESIGN 3), so `Box<dyn Backend>` gives
//! run-time backend choice. A backend owns kernels and resources; core owns algorithms.

pub use crate::device::error::BackendError;
use crate::device::handle::{Buf, ResourceId};
use crate::recording::Recording;

/// What a backend's device can do (queried, not cfg'd).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Capabilities {
    /// Human-readable device name.
    pub device: String,
    pub hardware_ray_tracing: bool,
    pub float_atomics: bool,
    pub int64_atomics: bool,
    pub timestamps: bool,
    /// Largest single buffer the device accepts (bytes).
    pub max_buffer_bytes: u64,
}

/// Wall or device time of one executed kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    pub kernel: &'static str,
    pub seconds: f64,
}

/// A compute backend.
pub trait Backend {
    /// Short name used on the command line (`cpu`, `opencl`, ...).
    fn name(&self) -> &'static str;
    fn capabilities(&self) -> Capabilities;
    /// Names of the registry kernels this backend implements.
    fn kernels(&self) -> Vec<&'static str>;
    /// Executes every step in order; returns the time of each kernel step.
    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError>;
    /// Reads a buffer's bytes back to the host.
    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError>;
    /// Labels of the kernel variants this backend has compiled so far (GPU backends:
    /// pipelines/programs built on demand; CPU: the monomorphised variants it has run),
    /// as [`crate::kernels::variant_label`] writes them. Conformance checks that a scene
    /// compiles no variant it does not need.
    fn variants(&self) -> Vec<String>;
}

/// Reads a typed buffer back.
pub fn read_buf<T: bytemuck::Pod>(
    backend: &mut dyn Backend,
    buf: Buf<T>,
) -> Result<Vec<T>, BackendError> {
    let bytes = backend.read(buf.id)?;
    if bytes.len() as u64 != buf.bytes() {
        return Err(BackendError::BadArgument(format!(
            "buffer {:?} holds {} bytes, expected {}",
            buf.id,
            bytes.len(),
            buf.bytes()
        )));
    }
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}
