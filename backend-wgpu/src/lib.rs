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

mod dispatch;
mod pool;
mod submission;
mod texture;

use caustica_core::backend::{
    Backend, BackendError, Capabilities, DeviceType, Finished, PassTime, Submission,
};
use caustica_core::device::handle::ResourceId;
use caustica_core::device::launch::Launch;
use caustica_core::recording::{Recording, Step};
use caustica_shaders as shaders;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// Smallest buffer and binding: one element of the largest array element type a kernel
/// binds (`GpuLight`, 64 bytes), since wgpu requires a runtime-sized array binding to hold
/// one element. Kernels never read the dummy: counts come from parameters, and
/// `arrayLength(&nodes) / 5` of a 64-byte dummy is 0.
pub(crate) const MIN_BINDING_BYTES: u64 = 64;

/// A device buffer and its logical size in bytes (at least `MIN_BINDING_BYTES` are
/// allocated, and an empty buffer binds as that dummy).
struct DeviceBuffer {
    buffer: wgpu::Buffer,
    bytes: u64,
}

/// The wgpu backend.
pub struct WgpuBackend {
    /// Released in `Drop` inside `driver_entry` (see there), hence `ManuallyDrop`.
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
    buffers: HashMap<ResourceId, DeviceBuffer>,
    /// Errors wgpu reports outside an error scope (validation, device loss).
    uncaptured: Arc<Mutex<Vec<String>>>,
    /// Submissions not yet collected ([`Backend::submit`], [`WgpuBackend::encode`]).
    in_flight: HashMap<u64, submission::InFlight>,
    /// Results of submissions waited for before they were polled (a host too far ahead).
    finished: caustica_core::backend::UncollectedResults,
    next_submission: u64,
    /// Query sets and staging reused across submissions.
    pool: pool::SubmissionPool,
}

/// Compiles kernel `name` with its override constants set to `constants`; a WGSL or
/// pipeline validation error is a typed error.
fn create_pipeline(
    device: &wgpu::Device,
    name: &str,
    constants: &[(&'static str, u32)],
) -> Result<wgpu::ComputePipeline, BackendError> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let src = shaders::module_source(name).map_err(BackendError::Driver)?;
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    };
    // Every check wgpu offers stays on but one: naga's loop bounding, which gives every
    // loop an iteration counter (a 64-bit decrement and a test per iteration) so that a
    // driver may not assume that an endless loop ends. In the traversal's inner loop that
    // costs on every node visit (see the README's 2 ms section for the measured gain).
    //
    // SAFETY: `force_loop_bounding: false` requires that no loop of these shaders runs
    // forever. Every loop of caustica's kernels (the `shaders` crate's WGSL, which nobody
    // else supplies) is bounded: by a count from the dispatch's parameters (photons,
    // bounces, splits, pixels of a footprint, A-Trous taps, cluster children), by a
    // fixed-size stack whose pushes are guarded by its size, or by the BVH traversal,
    // which visits each node of a tree at most once (the node buffer is built by
    // `DeviceScene`, never taken from a user). Bounds checks remain as wgpu sets them.
    let module = unsafe {
        device.create_shader_module_trusted(
            desc,
            wgpu::ShaderRuntimeChecks {
                force_loop_bounding: false,
                ..wgpu::ShaderRuntimeChecks::checked()
            },
        )
    };
    let overrides: Vec<(&str, f64)> = constants.iter().map(|(n, v)| (*n, *v as f64)).collect();
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(name),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &overrides,
            zero_initialize_workgroup_memory: !shaders::WORKGROUP_MEMORY_WRITTEN_FIRST
                .contains(&name),
        },
        cache: None,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(BackendError::Driver(format!(
            "WGSL pipeline creation failed ({name}): {e}"
        )));
    }
    Ok(pipeline)
}

fn unavailable(reason: impl Into<String>) -> BackendError {
    BackendError::Unavailable {
        backend: "wgpu".into(),
        reason: reason.into(),
    }
}

/// Every adapter wgpu finds on the native compute backends (Vulkan, Metal, DX12), with
/// its description.
pub fn list_adapters() -> Vec<wgpu::AdapterInfo> {
    let instance = instance();
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY))
        .iter()
        .map(|a| a.get_info())
        .collect()
}

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::PRIMARY,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    })
}

/// Preference among adapters: discrete, integrated, virtual GPU, then CPU (lavapipe).
fn adapter_rank(info: &wgpu::AdapterInfo) -> u32 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

impl WgpuBackend {
    /// Opens an adapter (`CAUSTICA_WGPU_ADAPTER=N` picks the N-th of [`list_adapters`];
    /// otherwise a GPU before a CPU adapter such as lavapipe) with the adapter's own
    /// limits and, where offered, timestamp queries.
    pub fn new() -> Result<WgpuBackend, BackendError> {
        caustica_core::backend::driver_entry(|| {
            caustica_core::backend::driver_lifecycle(WgpuBackend::open)
        })
    }

    /// [`WgpuBackend::new`]'s body.
    fn open() -> Result<WgpuBackend, BackendError> {
        let instance = instance();
        let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
        if adapters.is_empty() {
            return Err(unavailable(
                "no Vulkan/Metal/DX12 adapter; install a GPU driver or Mesa's lavapipe \
                 (scripts/install-drivers.sh)",
            ));
        }
        let adapter = match std::env::var("CAUSTICA_WGPU_ADAPTER") {
            Ok(v) => {
                let n: usize = v.trim().parse().map_err(|_| {
                    unavailable(format!("CAUSTICA_WGPU_ADAPTER='{v}' is not a number"))
                })?;
                if n >= adapters.len() {
                    return Err(unavailable(format!(
                        "CAUSTICA_WGPU_ADAPTER={n}, but there are {} adapters",
                        adapters.len()
                    )));
                }
                adapters.swap_remove(n)
            }
            Err(_) => {
                adapters.sort_by_key(|a| adapter_rank(&a.get_info()));
                adapters.swap_remove(0)
            }
        };
        let info = adapter.get_info();
        let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("caustica"),
            required_features: features,
            // lavapipe's acceleration-structure minimums exceed wgpu's defaults
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| unavailable(format!("{} refused a device: {e}", info.name)))?;
        let description = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
        let mut b = WgpuBackend::from_device(device, queue, &description)?;
        b.device_type = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => DeviceType::DiscreteGpu,
            wgpu::DeviceType::IntegratedGpu => DeviceType::IntegratedGpu,
            wgpu::DeviceType::VirtualGpu => DeviceType::VirtualGpu,
            wgpu::DeviceType::Cpu => DeviceType::SoftwareGpu,
            wgpu::DeviceType::Other => DeviceType::Other,
        };
        Ok(b)
    }

    /// Embeds the backend in a caller's renderer: uses the caller's `device` and `queue`
    /// (its features and limits; timestamps when the device has `TIMESTAMP_QUERY`).
    /// `description` names the device in [`Capabilities`].
    pub fn from_device(
        device: wgpu::Device,
        queue: wgpu::Queue,
        description: &str,
    ) -> Result<WgpuBackend, BackendError> {
        caustica_core::backend::driver_entry(|| {
            caustica_core::backend::driver_lifecycle(|| Self::adopt(device, queue, description))
        })
    }

    /// [`WgpuBackend::from_device`]'s body.
    fn adopt(
        device: wgpu::Device,
        queue: wgpu::Queue,
        description: &str,
    ) -> Result<WgpuBackend, BackendError> {
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        let sink = Arc::clone(&uncaptured);
        device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
            if let Ok(mut v) = sink.lock() {
                v.push(e.to_string());
            }
        }));
        let mut pipelines = HashMap::new();
        for (name, _) in shaders::KERNELS {
            if !shaders::VARIANT_KERNELS.contains(name) {
                pipelines.insert(name.to_string(), create_pipeline(&device, name, &[])?);
            }
        }
        Ok(WgpuBackend {
            limits: device.limits(),
            timestamps: device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
            device: std::mem::ManuallyDrop::new(device),
            queue: std::mem::ManuallyDrop::new(queue),
            description: description.to_string(),
            device_type: DeviceType::Other,
            pipelines,
            texture_pipelines: HashMap::new(),
            buffers: HashMap::new(),
            uncaptured,
            in_flight: HashMap::new(),
            finished: Default::default(),
            pool: Default::default(),
            next_submission: 0,
        })
    }

    /// Builds the pipeline of a launch's variant unless it exists.
    fn ensure_pipeline(&mut self, launch: &Launch) -> Result<(), BackendError> {
        let label = launch.variant_label();
        if !self.pipelines.contains_key(&label) {
            let p = create_pipeline(&self.device, launch.kernel, &launch.constants)?;
            self.pipelines.insert(label, p);
        }
        Ok(())
    }

    /// The device and queue in use (for a caller that embeds the backend).
    pub fn device(&self) -> (&wgpu::Device, &wgpu::Queue) {
        (&self.device, &self.queue)
    }

    /// The wgpu buffer behind a resource, for a caller that binds results directly.
    pub fn buffer(&self, id: ResourceId) -> Option<&wgpu::Buffer> {
        self.buffers.get(&id).map(|b| &b.buffer)
    }

    fn get(&self, id: ResourceId) -> Result<&DeviceBuffer, BackendError> {
        self.buffers
            .get(&id)
            .ok_or(BackendError::MissingResource(id))
    }

    /// Takes the errors wgpu reported since the last call.
    fn check_uncaptured(&self) -> Result<(), BackendError> {
        let mut v = self.uncaptured.lock().unwrap_or_else(|e| e.into_inner());
        if v.is_empty() {
            return Ok(());
        }
        let all = v.join("; ");
        v.clear();
        Err(if all.contains("lost") {
            BackendError::DeviceLost(all)
        } else {
            BackendError::Driver(all)
        })
    }

    fn wait(&self) -> Result<(), BackendError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| BackendError::DeviceLost(e.to_string()))?;
        self.check_uncaptured()
    }

    fn create(
        &mut self,
        id: ResourceId,
        bytes: u64,
        label: &str,
        data: Option<&[u8]>,
    ) -> Result<(), BackendError> {
        let size = bytes
            .max(MIN_BINDING_BYTES)
            .next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        if size > self.limits.max_buffer_size {
            return Err(BackendError::OutOfMemory {
                bytes,
                what: format!(
                    "{label} (adapter allows {} bytes per buffer)",
                    self.limits.max_buffer_size
                ),
            });
        }
        self.buffers.remove(&id);
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::COPY_SRC
                | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: data.is_some(),
        });
        if let Some(e) = pollster::block_on(scope.pop()) {
            return Err(BackendError::OutOfMemory {
                bytes,
                what: format!("{label}: {e}"),
            });
        }
        if let Some(d) = data {
            {
                let mut view = buffer
                    .slice(..)
                    .get_mapped_range_mut()
                    .map_err(|e| BackendError::Driver(format!("mapping {label}: {e}")))?;
                view.slice(..d.len()).copy_from_slice(d);
            }
            buffer.unmap();
        }
        // wgpu zero-initialises new buffers.
        self.buffers.insert(id, DeviceBuffer { buffer, bytes });
        Ok(())
    }

    /// Copies `bytes` of `buffer` to the host.
    fn read_buffer(&self, buffer: &wgpu::Buffer, bytes: u64) -> Result<Vec<u8>, BackendError> {
        if bytes == 0 {
            return Ok(Vec::new());
        }
        let size = bytes.next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut enc = self.device.create_command_encoder(&Default::default());
        enc.copy_buffer_to_buffer(buffer, 0, &staging, 0, size);
        self.queue.submit([enc.finish()]);
        let slice = staging.slice(..);
        let result = Arc::new(Mutex::new(None));
        let r2 = Arc::clone(&result);
        slice.map_async(wgpu::MapMode::Read, move |r| {
            if let Ok(mut g) = r2.lock() {
                *g = Some(r);
            }
        });
        self.wait()?;
        match result.lock().ok().and_then(|mut g| g.take()) {
            Some(Ok(())) => {}
            Some(Err(e)) => {
                return Err(BackendError::Driver(format!(
                    "mapping a readback buffer: {e}"
                )))
            }
            None => return Err(BackendError::Driver("readback did not complete".into())),
        }
        let out = {
            let view = slice
                .get_mapped_range()
                .map_err(|e| BackendError::Driver(format!("reading back: {e}")))?;
            let mut out = caustica_core::device::host_bytes(bytes, "reading a buffer back")?;
            out.copy_from_slice(&view[..bytes as usize]);
            out
        };
        staging.unmap();
        Ok(out)
    }
}

/// Releases the buffers, pipelines, queue and device inside
/// [`caustica_core::backend::driver_entry`], so that `CAUSTICA_SERIALIZE_DRIVERS=1` covers
/// the backend's destruction too (docs/embedding.md, "Threads").
impl Drop for WgpuBackend {
    fn drop(&mut self) {
        // the device's destruction with the other creations and destructions below the
        // API (caustica_core::backend::driver_lifecycle)
        caustica_core::backend::driver_entry(|| {
            caustica_core::backend::driver_lifecycle(|| {
                self.in_flight.clear();
                self.buffers.clear();
                self.pipelines.clear();
                self.texture_pipelines.clear();
                // SAFETY: dropped once, here; no field is used after `drop`.
                unsafe {
                    std::mem::ManuallyDrop::drop(&mut self.queue);
                    std::mem::ManuallyDrop::drop(&mut self.device);
                }
            })
        })
    }
}

impl Backend for WgpuBackend {
    fn name(&self) -> &'static str {
        "wgpu"
    }

    fn capabilities(&self) -> Capabilities {
        Capabilities {
            device: self.description.clone(),
            device_type: self.device_type,
            hardware_ray_tracing: false,
            float_atomics: false,
            int64_atomics: false,
            timestamps: self.timestamps,
            max_buffer_bytes: self
                .limits
                .max_buffer_size
                .min(self.limits.max_storage_buffer_binding_size),
            max_buffer_limit: if self.limits.max_buffer_size
                < self.limits.max_storage_buffer_binding_size
            {
                "device allocation size (max_buffer_size)"
            } else {
                "storage-binding size (max_storage_buffer_binding_size)"
            },
        }
    }

    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        caustica_core::backend::driver_entry(|| self.execute_recording(recording))
    }

    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        caustica_core::backend::driver_entry(|| {
            let b = self.get(id)?;
            self.read_buffer(&b.buffer, b.bytes)
        })
    }

    fn submit(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        caustica_core::backend::driver_entry(|| {
            let mut enc = self.device.create_command_encoder(&Default::default());
            let s = self.encode(recording, readbacks, &mut enc)?;
            let index = self.queue.submit([enc.finish()]);
            self.submitted(&s, Some(index))?;
            Ok(s)
        })
    }

    fn poll(
        &mut self,
        submission: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        caustica_core::backend::driver_entry(|| self.poll_submission(submission, wait))
    }

    fn variants(&self) -> Vec<String> {
        caustica_core::kernels::variant_labels(self.pipelines.keys())
    }
}

impl WgpuBackend {
    /// [`Backend::execute`]'s body (the trait method runs it under
    /// [`caustica_core::backend::driver_entry`]).
    fn execute_recording(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        self.check_uncaptured()?;
        let mut timer = dispatch::Timer::new(self, kernel_count(recording));
        let mut enc = self.device.create_command_encoder(&Default::default());
        self.encode_steps(recording, &mut enc, &mut timer, true)?;
        timer.resolve(&mut enc);
        self.queue.submit([enc.finish()]);
        self.wait()?;
        timer.finish(self)
    }

    /// Records every step of `recording` into `enc`, in order. Creations happen at once
    /// (zeroed or mapped at creation); writes go through staging copies in `enc`.
    /// `alone`: without timestamp queries, each kernel is submitted and waited for on its
    /// own so the host can time it (never in a non-blocking submission).
    fn encode_steps(
        &mut self,
        recording: &Recording,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut dispatch::Timer,
        alone: bool,
    ) -> Result<(), BackendError> {
        for step in &recording.steps {
            match step {
                Step::Create { id, bytes, label } => self.create(*id, *bytes, label, None)?,
                Step::Upload { id, data, label } => {
                    self.create(*id, data.len() as u64, label, Some(data))?
                }
                Step::Write {
                    id,
                    offset,
                    data,
                    label,
                } => {
                    let dst = self.get(*id)?;
                    if offset + data.len() as u64 > dst.bytes {
                        return Err(BackendError::BadArgument(format!(
                            "{label}: write of {} bytes at {offset} into a buffer of {}",
                            data.len(),
                            dst.bytes
                        )));
                    }
                    if !data.is_empty() {
                        // a staging copy in the encoder, ordered with the kernels around it
                        // (queue.write_buffer would land before the whole submission)
                        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some("write staging"),
                            size: data.len() as u64,
                            usage: wgpu::BufferUsages::COPY_SRC,
                            mapped_at_creation: true,
                        });
                        {
                            let mut view =
                                staging.slice(..).get_mapped_range_mut().map_err(|e| {
                                    BackendError::Driver(format!("mapping {label}: {e}"))
                                })?;
                            view.copy_from_slice(data);
                        }
                        staging.unmap();
                        enc.copy_buffer_to_buffer(
                            &staging,
                            0,
                            &dst.buffer,
                            *offset,
                            data.len() as u64,
                        );
                    }
                }
                Step::Clear { id } => enc.clear_buffer(&self.get(*id)?.buffer, 0, None),
                Step::Free { id } => {
                    // wgpu keeps the memory until the commands using it have finished
                    self.buffers.remove(id);
                }
                Step::Kernel(k) => {
                    if let Some(l) = k.launch()? {
                        self.ensure_pipeline(l)?;
                    }
                    dispatch::record(self, enc, timer, k)?;
                    if !self.timestamps && alone {
                        // No GPU timestamps: each kernel runs alone, timed by the host.
                        let done = std::mem::replace(
                            enc,
                            self.device.create_command_encoder(&Default::default()),
                        );
                        let t0 = std::time::Instant::now();
                        self.queue.submit([done.finish()]);
                        self.wait()?;
                        timer.host_time(t0.elapsed().as_secs_f64());
                    }
                }
            }
        }
        Ok(())
    }
}

/// Kernel steps of a recording (timestamp pairs to reserve).
fn kernel_count(recording: &Recording) -> u32 {
    recording
        .steps
        .iter()
        .filter(|s| matches!(s, Step::Kernel(_)))
        .count() as u32
}
