#![warn(missing_docs)]
//! caustica Vulkan backend (ash): the driver builds the acceleration structures
//! (VK_KHR_acceleration_structure) and ray-tracing pipelines (VK_KHR_ray_tracing_pipeline)
//! trace the G-buffer, the shadow rays of direct light and the photons; the other kernels
//! are compute pipelines made from the WGSL kernels of `caustica-shaders` (the wgpu
//! backend's source) through naga's SPIR-V writer.
//!
//! Buffers stay on the device between passes and recordings; reads come back only through
//! [`Backend::read`] and a submission's readbacks. Pass times are device timestamps.
//! [`Backend::submit`] records into a kept frame slot and submits once, without waiting
//! ([`submission`]); [`VulkanBackend::completion_semaphore`] is the timeline semaphore a
//! host waits on. With
//! `CAUSTICA_VULKAN_VALIDATION=1` (the conformance suite sets it) the Khronos validation
//! layer is enabled where installed, and any validation error fails the `execute` during
//! which it was reported. Every Vulkan failure is a typed error; every object is destroyed
//! on drop. Embedding: [`VulkanBackend::from_raw`] takes a caller's instance and device.
//!
//! The crate's files, as in every caustica backend: `lib.rs` (this: the public face and
//! the backend trait's implementation, which delegates), `device.rs` (instance, device and
//! queue, the validation layer, capabilities), `memory.rs` (buffers, the host arena for
//! parameters and staging), `pipelines.rs` (ray-tracing and compute pipelines by variant),
//! `recording.rs` (the interpreter that records a recording's steps into a command buffer),
//! `submission.rs` (frame slots, submit, poll, timestamps, the timeline semaphore); and
//! `accel.rs` (the driver-built acceleration structures).
//!
//! [`Backend::read`]: caustica_core::backend::Backend::read
//! [`Backend::submit`]: caustica_core::backend::Backend::submit

mod accel;
mod device;
mod memory;
mod pipelines;
mod recording;
mod submission;

use ash::vk;
use caustica_core::backend::{
    backend_lifecycle, driver_entry, BackendError, ResourceTable, Submissions,
};
use caustica_core::device::handle::ResourceId;
use device::Context;
use memory::{Buffer, DeviceBuffer};
use std::collections::HashMap;
use std::sync::Arc;

pub use device::DEVICE_EXTENSIONS;

/// The Vulkan backend.
pub struct VulkanBackend {
    // field order is drop order: everything before `ctx`, which destroys the device
    buffers: ResourceTable<DeviceBuffer>,
    scenes: HashMap<ResourceId, accel::SceneAccel>,
    /// Bottom-level acceleration structures built so far ([`VulkanBackend::bottom_level_builds`]).
    bottom_level_builds: u64,
    /// Top levels (TLAS nodes and instance records) written into prepared scenes' node
    /// buffers by the recording being executed, by buffer: the refit's input.
    written_top_levels: HashMap<ResourceId, Vec<[u32; 4]>>,
    /// Pipelines by variant label (`kernel` or `kernel[SWITCH=0/1,...]`).
    pipelines: HashMap<String, pipelines::Pipeline>,
    /// Submissions on the device, oldest first (`submission.rs`), and the results of those
    /// retired before they were polled.
    submissions: Submissions<submission::InFlight>,
    /// Frame slots free for the next submission (pools, arena, fence: kept, reset).
    free_slots: Vec<submission::FrameSlot>,
    /// Signalled with each submission's number, once a host asked for it.
    timeline: Option<vk::Semaphore>,
    counter_banks: Buffer,
    pool: vk::CommandPool,
    fence: vk::Fence,
    ctx: Arc<Context>,
}

impl VulkanBackend {
    /// Bottom-level acceleration structures built so far: one per level when a scene is
    /// prepared, then one per deformed instance (the others are kept); moves build none.
    pub fn bottom_level_builds(&self) -> u64 {
        self.bottom_level_builds
    }

    /// Opens the first device with ray-tracing pipelines (`CAUSTICA_VULKAN_DEVICE=N`
    /// picks one); `CAUSTICA_VULKAN_VALIDATION=1` enables the validation layer.
    pub fn new() -> Result<VulkanBackend, BackendError> {
        let validation = std::env::var("CAUSTICA_VULKAN_VALIDATION").is_ok_and(|v| v != "0");
        VulkanBackend::with_validation(validation)
    }

    /// As [`VulkanBackend::new`], with the Khronos validation layer on or off (on: used
    /// where installed, and any validation error fails the `execute` that caused it).
    pub fn with_validation(validation: bool) -> Result<VulkanBackend, BackendError> {
        // instance, device and pipelines are created one backend at a time
        // (`caustica_core::backend::driver_lifecycle`)
        backend_lifecycle(|| VulkanBackend::with_context(Context::new(validation)?))
    }

    /// Whether the validation layer is active on this backend's instance.
    pub fn validation_active(&self) -> bool {
        self.ctx.validation_active()
    }

    /// Embeds the backend in a caller's renderer: its instance, physical device, device
    /// and a queue of `queue_family` (which must support compute). `device` must have
    /// been created from `physical` with [`DEVICE_EXTENSIONS`] and the features
    /// `bufferDeviceAddress`, `scalarBlockLayout`, `accelerationStructure` and
    /// `rayTracingPipeline`, and `timelineSemaphore` for
    /// [`VulkanBackend::completion_semaphore`]. The backend submits to `queue` (the caller
    /// must not use it from another thread meanwhile) and destroys only what it created.
    pub fn from_raw(
        entry: ash::Entry,
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        queue_family: u32,
        queue: vk::Queue,
    ) -> Result<VulkanBackend, BackendError> {
        backend_lifecycle(|| {
            VulkanBackend::with_context(Context::adopt(
                entry,
                instance,
                physical,
                device,
                queue_family,
                queue,
            )?)
        })
    }
}

impl Drop for VulkanBackend {
    fn drop(&mut self) {
        driver_entry(|| unsafe {
            let _ = self.ctx.device.queue_wait_idle(self.ctx.queue);
            // the device is idle: every submission's objects and slot can go
            self.submissions.clear();
            self.free_slots.clear();
            if let Some(t) = self.timeline.take() {
                self.ctx.device.destroy_semaphore(t, None);
            }
            self.ctx.device.destroy_fence(self.fence, None);
            self.ctx.device.destroy_command_pool(self.pool, None);
        })
    }
}

caustica_core::driver_backend!(VulkanBackend, "vulkan");

impl VulkanBackend {
    /// The compiled kernel variants, labelled ([`caustica_core::kernels::variant_label`]).
    pub(crate) fn variant_labels(&self) -> Vec<String> {
        caustica_core::kernels::variant_labels(self.pipelines.keys())
    }
}
