#![warn(missing_docs)]
//! caustica wgpu backend: every registry kernel as a WGSL compute shader (the
//! `caustica-shaders` crate's `wgsl/<kernel>.wgsl`, functions named as core's scalar
//! functions), software traversal of core's flattened CWBVH, u32 atomics for the
//! fixed-point deposit.
//!
//! Pipelines are created once, buffers stay on the device between passes and recordings,
//! data comes back only through [`Backend::read`]. Per-pass GPU timestamps are used where
//! the adapter has `TIMESTAMP_QUERY`; otherwise each kernel is submitted alone and timed
//! by the host. Embedding: [`WgpuBackend::from_device`] takes the caller's device and
//! queue, [`WgpuBackend::encode`] records a recording (a whole frame) into the caller's
//! command encoder without submitting or waiting, and
//! [`WgpuBackend::encode_image_to_texture`] writes a result image (the caustics, say) into
//! the caller's texture in the same encoder.
//!
//! The crate's files, as in every caustica backend: `lib.rs` (this: the public face and
//! the backend trait's implementation, which delegates), `device.rs` (the adapter, device
//! and queue, capabilities), `memory.rs` (buffers: creation, upload, readback),
//! `pipelines.rs` (the compute pipelines by variant), `recording.rs` (the interpreter
//! that encodes a recording's steps), `submission.rs` (submit, poll, timestamps, the pooled
//! query sets and staging); and `texture.rs` (results written into a caller's texture).
//!
//! [`Backend::read`]: caustica_core::backend::Backend::read

mod device;
mod memory;
mod pipelines;
mod recording;
mod submission;
mod texture;

pub use device::list_adapters;

use caustica_core::backend::{
    backend_lifecycle, BackendError, DeviceType, ResourceTable, Submissions,
};
use caustica_core::device::handle::ResourceId;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// The wgpu backend.
pub struct WgpuBackend {
    /// Released in `Drop` inside the driver locks (see there), hence `ManuallyDrop`.
    device: std::mem::ManuallyDrop<wgpu::Device>,
    queue: std::mem::ManuallyDrop<wgpu::Queue>,
    description: String,
    /// The adapter's type (`Other` for a caller's device, whose adapter is not known).
    device_type: DeviceType,
    limits: wgpu::Limits,
    timestamps: bool,
    /// Pipelines by variant label (`kernel` or `kernel[SWITCH=0/1,...]`).
    pipelines: HashMap<String, wgpu::ComputePipeline>,
    texture_pipelines: HashMap<wgpu::TextureFormat, wgpu::ComputePipeline>,
    buffers: ResourceTable<memory::DeviceBuffer>,
    /// Errors wgpu reports outside an error scope (validation, device loss).
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// Submissions not yet collected (`Backend::submit`, [`WgpuBackend::encode`]) and
    /// the results of those waited for before they were polled (a host too far ahead).
    submissions: Submissions<submission::InFlight>,
    /// Query sets and staging reused across submissions.
    pool: submission::SubmissionPool,
}

impl WgpuBackend {
    /// Opens an adapter (`CAUSTICA_WGPU_ADAPTER=N` picks the N-th of [`list_adapters`];
    /// otherwise a GPU before a CPU adapter such as lavapipe) with the adapter's own
    /// limits and, where offered, timestamp queries.
    pub fn new() -> Result<WgpuBackend, BackendError> {
        backend_lifecycle(WgpuBackend::open)
    }

    /// Embeds the backend in a caller's renderer: uses the caller's `device` and `queue`
    /// (its features and limits; timestamps when the device has `TIMESTAMP_QUERY`).
    /// `description` names the device in [`Capabilities`]. The device stays the caller's:
    /// caustica installs no uncaptured-error handler on it (the caller's own keeps
    /// receiving the device's errors, caustica's included); caustica's pipeline and buffer
    /// creation check their own errors with error scopes.
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        description: &str,
    ) -> Result<WgpuBackend, BackendError> {
        backend_lifecycle(|| Self::adopt(device, queue, description, false))
    }

    /// The device and queue in use (for a caller that embeds the backend).
    pub fn device(&self) -> (&wgpu::Device, &wgpu::Queue) {
        (&self.device, &self.queue)
    }

    /// The wgpu buffer behind a resource, for a caller that binds results directly.
    pub fn buffer(&self, id: ResourceId) -> Option<&wgpu::Buffer> {
        self.buffers.get(id).ok().map(|b| &b.buffer)
    }
}

/// Releases the buffers, pipelines, queue and device inside
/// [`caustica_core::backend::backend_lifecycle`], so that `CAUSTICA_SERIALIZE_DRIVERS=1`
/// covers the backend's destruction too, and the device's destruction is serialised with
/// the other creations and destructions below the API (docs/embedding.md, "Threads").
impl Drop for WgpuBackend {
    fn drop(&mut self) {
        backend_lifecycle(|| {
            self.submissions.clear();
            self.buffers.clear();
            self.pipelines.clear();
            self.texture_pipelines.clear();
            // SAFETY: dropped once, here; no field is used after `drop`.
            unsafe {
                std::mem::ManuallyDrop::drop(&mut self.queue);
                std::mem::ManuallyDrop::drop(&mut self.device);
            }
        })
    }
}

caustica_core::driver_backend!(WgpuBackend, "wgpu");

impl WgpuBackend {
    /// The compiled kernel variants, labelled ([`caustica_core::kernels::variant_label`]).
    pub(crate) fn variant_labels(&self) -> Vec<String> {
        caustica_core::kernels::variant_labels(self.pipelines.keys())
    }
}
