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

mod accel;
mod arena;
mod context;
mod dispatch;
mod memory;
mod pipelines;
mod submission;

use ash::vk;
use caustica_core::backend::{
    Backend, BackendError, Capabilities, DeviceType, Finished, PassTime, Submission,
};
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::{Recording, Step};
use context::{vk_error, Context};
use memory::Buffer;
use std::collections::HashMap;
use std::sync::Arc;

pub use context::DEVICE_EXTENSIONS;

/// Smallest buffer and descriptor range: one element of the largest array element a
/// kernel binds (`GpuLight`, 64 bytes); kernels never read the dummy of an empty buffer.
const MIN_BINDING_BYTES: u64 = 64;

/// Words of the photon counters (core::gpu::counter::WORDS) times the 64 banks that ray
/// generation shaders add into to spread their atomics.
const COUNTER_BANK_BYTES: u64 = 64 * 20 * 4;

struct DeviceBuffer {
    buffer: Buffer,
    bytes: u64,
    /// Process-unique stamp of this allocation (a `Create` or `Upload` makes a new one):
    /// a scene's acceleration structures remember those of their sources.
    generation: u64,
}

/// A fresh [`DeviceBuffer::generation`].
fn next_generation() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// The Vulkan backend.
pub struct VulkanBackend {
    // field order is drop order: everything before `ctx`, which destroys the device
    buffers: HashMap<ResourceId, DeviceBuffer>,
    scenes: HashMap<ResourceId, accel::SceneAccel>,
    /// Bottom-level acceleration structures built so far ([`VulkanBackend::bottom_level_builds`]).
    bottom_level_builds: u64,
    /// Top levels (TLAS nodes and instance records) written into prepared scenes' node
    /// buffers by the recording being executed, by buffer: the refit's input.
    written_top_levels: HashMap<ResourceId, Vec<[u32; 4]>>,
    /// Pipelines by variant label (`kernel` or `kernel[SWITCH=0/1,...]`).
    pipelines: HashMap<String, pipelines::Pipeline>,
    /// Submissions on the device, oldest first ([`submission`]).
    in_flight: Vec<submission::InFlight>,
    /// Frame slots free for the next submission (pools, arena, fence: kept, reset).
    free_slots: Vec<submission::FrameSlot>,
    /// Results of submissions retired before they were polled.
    finished: caustica_core::backend::UncollectedResults,
    next_submission: u64,
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
        caustica_core::backend::driver_entry(|| VulkanBackend::with_validation(validation))
    }

    /// As [`VulkanBackend::new`], with the Khronos validation layer on or off (on: used
    /// where installed, and any validation error fails the `execute` that caused it).
    pub fn with_validation(validation: bool) -> Result<VulkanBackend, BackendError> {
        // instance, device and pipelines are created one backend at a time (see
        // `context::serialised`)
        context::serialised(|| VulkanBackend::with_context(Context::new(validation)?))
    }

    /// Whether the validation layer is active on this backend's instance.
    pub fn validation_active(&self) -> bool {
        self.ctx.validation_active()
    }

    /// Embeds the backend in a caller's renderer: its instance, physical device, device
    /// and a queue of `queue_family` (which must support compute). `device` must have
    /// been created from `physical` with [`DEVICE_EXTENSIONS`] and the features
    /// `bufferDeviceAddress`, `scalarBlockLayout`, `accelerationStructure` and
    /// `rayTracingPipeline`. The backend submits to `queue` (the caller must not use it
    /// from another thread meanwhile) and destroys only what it created.
    pub fn from_raw(
        entry: ash::Entry,
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        queue_family: u32,
        queue: vk::Queue,
    ) -> Result<VulkanBackend, BackendError> {
        context::serialised(|| {
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

    fn with_context(ctx: Context) -> Result<VulkanBackend, BackendError> {
        let ctx = Arc::new(ctx);
        let d = &ctx.device;
        let pool = unsafe {
            d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }
        .map_err(vk_error("creating a command pool"))?;
        let fence = match unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(f) => f,
            Err(e) => {
                unsafe { d.destroy_command_pool(pool, None) };
                return Err(vk_error("creating a fence")(e));
            }
        };
        let counter_banks = Buffer::new(
            &ctx,
            COUNTER_BANK_BYTES,
            memory::storage_usage(),
            false,
            "counter banks",
        );
        let counter_banks = match counter_banks {
            Ok(b) => b,
            Err(e) => {
                unsafe {
                    d.destroy_fence(fence, None);
                    d.destroy_command_pool(pool, None);
                }
                return Err(e);
            }
        };
        let mut backend = VulkanBackend {
            buffers: HashMap::new(),
            scenes: HashMap::new(),
            bottom_level_builds: 0,
            written_top_levels: HashMap::new(),
            in_flight: Vec::new(),
            free_slots: Vec::new(),
            finished: Default::default(),
            next_submission: 0,
            timeline: None,
            pipelines: HashMap::new(),
            counter_banks,
            pool,
            fence,
            ctx,
        };
        backend.pipelines = dispatch::create_pipelines(&backend.ctx)?;
        // the banks start at zero; the reduce pass leaves them zeroed after every use
        let banks = backend.counter_banks.buffer;
        backend.one_shot(&|cmd| unsafe {
            backend
                .ctx
                .device
                .cmd_fill_buffer(cmd, banks, 0, vk::WHOLE_SIZE, 0)
        })?;
        Ok(backend)
    }

    /// Records `f` into a fresh command buffer, submits it and waits.
    fn one_shot(&self, f: &dyn Fn(vk::CommandBuffer)) -> Result<(), BackendError> {
        let cmd = self.begin()?;
        f(cmd);
        self.submit_and_wait(cmd)
    }

    fn begin(&self) -> Result<vk::CommandBuffer, BackendError> {
        self.begin_reusing(None)
    }

    /// Begins `reuse` (a finished submission's command buffer, reset here) or a newly
    /// allocated command buffer.
    fn begin_reusing(
        &self,
        reuse: Option<vk::CommandBuffer>,
    ) -> Result<vk::CommandBuffer, BackendError> {
        let d = &self.ctx.device;
        let cmd = match reuse {
            Some(cmd) => {
                unsafe { d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()) }
                    .map_err(vk_error("resetting a command buffer"))?;
                cmd
            }
            None => unsafe {
                d.allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(self.pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
            }
            .map_err(vk_error("allocating a command buffer"))?[0],
        };
        unsafe {
            d.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
        }
        .map_err(vk_error("beginning a command buffer"))?;
        // ordered after every earlier submission's work on the queue (submissions do not
        // wait for each other on the host; a barrier's first scope reaches back through
        // submission order)
        dispatch::barrier(d, cmd);
        Ok(cmd)
    }

    fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> Result<(), BackendError> {
        let d = &self.ctx.device;
        let result = (|| unsafe {
            d.end_command_buffer(cmd)
                .map_err(vk_error("ending a command buffer"))?;
            let cmds = [cmd];
            d.queue_submit(
                self.ctx.queue,
                &[vk::SubmitInfo::default().command_buffers(&cmds)],
                self.fence,
            )
            .map_err(vk_error("vkQueueSubmit"))?;
            d.wait_for_fences(&[self.fence], true, u64::MAX)
                .map_err(vk_error("waiting for the device"))?;
            d.reset_fences(&[self.fence])
                .map_err(vk_error("resetting a fence"))
        })();
        unsafe { d.free_command_buffers(self.pool, &[cmd]) };
        result?;
        self.check_validation()
    }

    fn check_validation(&self) -> Result<(), BackendError> {
        let errors = self.ctx.take_validation_errors();
        if errors.is_empty() {
            Ok(())
        } else {
            Err(BackendError::Driver(format!(
                "Vulkan validation: {}",
                errors.join(" | ")
            )))
        }
    }

    fn get(&self, id: ResourceId) -> Result<&DeviceBuffer, BackendError> {
        self.buffers
            .get(&id)
            .ok_or(BackendError::MissingResource(id))
    }

    fn new_storage(&self, bytes: u64, what: &str) -> Result<Buffer, BackendError> {
        Buffer::new(
            &self.ctx,
            bytes.max(MIN_BINDING_BYTES),
            memory::storage_usage(),
            false,
            what,
        )
    }

    /// Copies `bytes` of a device buffer to the host.
    fn read_device(&self, buffer: vk::Buffer, bytes: u64) -> Result<Vec<u8>, BackendError> {
        self.read_device_range(buffer, 0, bytes)
    }

    /// Copies `bytes` of a device buffer from byte `offset` to the host.
    fn read_device_range(
        &self,
        buffer: vk::Buffer,
        offset: u64,
        bytes: u64,
    ) -> Result<Vec<u8>, BackendError> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let staging = Buffer::new(
            &self.ctx,
            bytes,
            vk::BufferUsageFlags::TRANSFER_DST,
            true,
            "readback",
        )?;
        let dst = staging.buffer;
        self.one_shot(&|cmd| unsafe {
            self.ctx.device.cmd_copy_buffer(
                cmd,
                buffer,
                dst,
                &[vk::BufferCopy::default().src_offset(offset).size(bytes)],
            )
        })?;
        staging.read(bytes as usize)
    }
}

impl Drop for VulkanBackend {
    fn drop(&mut self) {
        caustica_core::backend::driver_entry(|| unsafe {
            let _ = self.ctx.device.queue_wait_idle(self.ctx.queue);
            // the device is idle: every submission's objects and slot can go
            self.in_flight.clear();
            self.free_slots.clear();
            if let Some(t) = self.timeline.take() {
                self.ctx.device.destroy_semaphore(t, None);
            }
            self.ctx.device.destroy_fence(self.fence, None);
            self.ctx.device.destroy_command_pool(self.pool, None);
        })
    }
}

impl Backend for VulkanBackend {
    fn name(&self) -> &'static str {
        "vulkan"
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            device: self.ctx.name.clone(),
            device_type: match self.ctx.device_type {
                vk::PhysicalDeviceType::DISCRETE_GPU => DeviceType::DiscreteGpu,
                vk::PhysicalDeviceType::INTEGRATED_GPU => DeviceType::IntegratedGpu,
                vk::PhysicalDeviceType::VIRTUAL_GPU => DeviceType::VirtualGpu,
                vk::PhysicalDeviceType::CPU => DeviceType::SoftwareGpu,
                _ => DeviceType::Other,
            },
            hardware_ray_tracing: true,
            float_atomics: false,
            int64_atomics: false,
            timestamps: self.ctx.timestamps,
            max_buffer_bytes: self
                .ctx
                .max_allocation
                .min(self.ctx.limits.max_storage_buffer_range as u64),
            max_buffer_limit: if self.ctx.max_allocation
                < self.ctx.limits.max_storage_buffer_range as u64
            {
                "device allocation size (maxMemoryAllocationSize)"
            } else {
                "storage-binding size (maxStorageBufferRange)"
            },
        }
    }

    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        caustica_core::backend::driver_entry(|| {
            let mut s = self.submit_recording(recording, &[])?;
            let f = self.poll_submission(&mut s, true)?;
            Ok(f.map(|f| f.times).unwrap_or_default())
        })
    }

    fn submit(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        caustica_core::backend::driver_entry(|| self.submit_recording(recording, readbacks))
    }

    fn poll(
        &mut self,
        submission: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        caustica_core::backend::driver_entry(|| self.poll_submission(submission, wait))
    }

    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        caustica_core::backend::driver_entry(|| {
            let b = self.get(id)?;
            self.read_device(b.buffer.buffer, b.bytes)
        })
    }

    fn variants(&self) -> Vec<String> {
        caustica_core::kernels::variant_labels(self.pipelines.keys())
    }
}

/// Steps other than kernels, shared by the recording loop.
fn is_kernel(s: &Step) -> bool {
    matches!(s, Step::Kernel(_))
}
