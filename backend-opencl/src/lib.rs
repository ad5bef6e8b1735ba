#![warn(missing_docs)]
//! caustica OpenCL backend: every registry kernel in OpenCL C 1.2 (`kernels/<kernel>.cl`
//! beside the shared files of `kernels/common/`, functions named as core's scalar
//! functions), software traversal of core's flattened CWBVH, the counter-based RNG and the
//! fixed-point deposit with 32-bit atomics. Runs on any OpenCL platform: PoCL on CPUs,
//! NVIDIA's driver on the GPU machine.
//!
//! The OpenCL API comes through `opencl3`/`cl3` with their `dynamic` feature: the ICD
//! loader (`libOpenCL.so.1`, from Debian's `ocl-icd-libopencl1`) is opened with `dlopen`
//! on first use, not linked, so a binary with this backend starts on a machine without
//! OpenCL and this backend reports itself unavailable there (no loader, no platform or no
//! device), with what to install. No development package is needed to build it.
//!
//! Buffers stay on the device between passes and recordings; data comes back only
//! through [`Backend::read`] and a submission's readbacks. Kernel times are device
//! timestamps (profiling events). [`Backend::submit`] only enqueues (writes and readbacks
//! non-blocking, a marker event last, a flush): the host's frame loop does not wait.

mod device;
mod dispatch;
mod error;
pub mod program;

use caustica_core::backend::{Backend, BackendError, Capabilities, Finished, PassTime, Submission};
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::{Recording, Step};
use device::DeviceState;
pub use device::{list_devices, DeviceSummary};
use error::cl_error;
use opencl3::command_queue::{CommandQueue, CL_QUEUE_PROFILING_ENABLE};
use opencl3::event::Event;
use opencl3::event::CL_COMPLETE;
use opencl3::kernel::Kernel;
use opencl3::memory::{Buffer, ClMem, CL_MAP_READ, CL_MEM_ALLOC_HOST_PTR, CL_MEM_READ_WRITE};
use opencl3::types::{CL_BLOCKING, CL_NON_BLOCKING};
use std::collections::HashMap;
use std::sync::Arc;

/// A device buffer and its logical size in bytes (OpenCL buffers are at least 4 bytes).
struct DeviceBuffer {
    mem: Buffer<u8>,
    bytes: u64,
}

/// Largest single fill command (bytes): 1 GiB.
const FILL_CHUNK: usize = 1 << 30;

/// The OpenCL backend.
pub struct OpenClBackend {
    state: Arc<DeviceState>,
    queue: CommandQueue,
    buffers: HashMap<ResourceId, DeviceBuffer>,
    /// Labels of the kernel variants this backend has run (their programs are built once
    /// per device and shared, see [`device::DeviceState::program_for`]).
    variants: std::sync::Mutex<std::collections::BTreeSet<String>>,
    /// Submissions not yet collected ([`Backend::submit`]), by number.
    in_flight: HashMap<u64, InFlight>,
    next_submission: u64,
}

impl OpenClBackend {
    /// Records that a launch ran variant `label`.
    fn note_variant(&self, label: String) {
        let mut v = self.variants.lock().unwrap_or_else(|e| e.into_inner());
        v.insert(label);
    }

    /// Opens the chosen device (`CAUSTICA_OPENCL_DEVICE=N`, else the first GPU, else the
    /// first device). No loader, platform or device, or a failed kernel build, is an error.
    pub fn new() -> Result<OpenClBackend, BackendError> {
        caustica_core::backend::driver_entry(OpenClBackend::open)
    }

    /// [`OpenClBackend::new`]'s body.
    fn open() -> Result<OpenClBackend, BackendError> {
        let (platform, device) = device::choose_device()?;
        let state = device::device_state(platform, device)?;
        // clCreateCommandQueue (OpenCL 1.2): PoCL's and NVIDIA's platforms both have it.
        #[allow(deprecated)]
        let queue = unsafe {
            CommandQueue::create(&state.context, state.device.id(), CL_QUEUE_PROFILING_ENABLE)
        }
        .map_err(cl_error("creating the command queue"))?;
        Ok(OpenClBackend {
            state,
            queue,
            buffers: HashMap::new(),
            variants: Default::default(),
            in_flight: HashMap::new(),
            next_submission: 0,
        })
    }

    /// The device in use.
    pub fn device(&self) -> &DeviceSummary {
        &self.state.info
    }

    /// `sizeof` of every shared struct as the device compiler lays it out, in the order
    /// of `kernels/common/types.cl`'s `struct_sizes` (checked against Rust's `size_of` in
    /// tests).
    pub fn device_struct_sizes(&mut self) -> Result<Vec<u32>, BackendError> {
        let mem = unsafe {
            Buffer::<u32>::create(
                &self.state.context,
                CL_MEM_READ_WRITE,
                16,
                std::ptr::null_mut(),
            )
        }
        .map_err(cl_error("creating a buffer"))?;
        let kernel = Kernel::create(&self.state.program, "struct_sizes")
            .map_err(cl_error("creating a kernel"))?;
        unsafe { kernel.set_arg(0, &mem.get()) }.map_err(cl_error("setting a kernel argument"))?;
        let mut out = vec![0u32; 16];
        let global: [usize; 3] = [1, 1, 1];
        unsafe {
            self.queue
                .enqueue_nd_range_kernel(
                    kernel.get(),
                    1,
                    std::ptr::null(),
                    global.as_ptr(),
                    std::ptr::null(),
                    &[],
                )
                .map_err(cl_error("struct_sizes"))?;
            self.queue
                .enqueue_read_buffer(&mem, CL_BLOCKING, 0, &mut out, &[])
                .map_err(cl_error("reading a buffer"))?;
        }
        out.truncate(12);
        Ok(out)
    }

    /// Compiles `src` on this backend's device (diagnostics and tests: the error of a
    /// failed build carries the driver's build log).
    pub fn build_test_program(&self, src: &str) -> Result<(), BackendError> {
        program::build_source(&self.state.context, self.state.device.id(), src).map(|_| ())
    }

    /// Creates buffer `id` of `bytes` bytes (at least 4), uploading `data` or zeroing it.
    fn create(
        &mut self,
        id: ResourceId,
        bytes: u64,
        label: &str,
        data: Option<&[u8]>,
    ) -> Result<(), BackendError> {
        let oom = || BackendError::OutOfMemory {
            bytes,
            what: format!(
                "{label} (over the device allocation size, CL_DEVICE_MAX_MEM_ALLOC_SIZE = {} \
                 bytes)",
                self.state.info.max_alloc_bytes
            ),
        };
        if bytes > self.state.info.max_alloc_bytes {
            return Err(oom());
        }
        let size = usize::try_from(bytes.max(4)).map_err(|_| oom())?;
        if self.state.info.host_memory {
            // PoCL backs a buffer with host memory and aborts the process (an assertion in
            // pocl_util.c) when that allocation fails: reserve the same size here first
            // (address space only, nothing is touched) and report failure as an error.
            let mut probe: Vec<u8> = Vec::new();
            probe
                .try_reserve_exact(size)
                .map_err(|_| BackendError::OutOfMemory {
                    bytes,
                    what: format!(
                        "{label} (host memory: this OpenCL device keeps its buffers in host \
                         memory, and {bytes} bytes could not be reserved)"
                    ),
                })?;
        }
        // Drop a replaced buffer first so that its memory is free for the new one.
        self.buffers.remove(&id);
        let mut mem = unsafe {
            Buffer::<u8>::create(
                &self.state.context,
                CL_MEM_READ_WRITE,
                size,
                std::ptr::null_mut(),
            )
        }
        .map_err(cl_error("creating a buffer"))?;
        match data {
            Some(d) if !d.is_empty() => unsafe {
                self.queue
                    .enqueue_write_buffer(&mut mem, CL_BLOCKING, 0, d, &[])
                    .map_err(cl_error("uploading a buffer"))?;
            },
            _ => fill_zero(&self.queue, &mut mem, size)?,
        }
        self.buffers.insert(id, DeviceBuffer { mem, bytes });
        Ok(())
    }

    /// The buffer `id`, or `MissingResource`.
    fn buffer(&self, id: ResourceId) -> Result<&DeviceBuffer, BackendError> {
        self.buffers
            .get(&id)
            .ok_or(BackendError::MissingResource(id))
    }
}

/// Zeroes `size` bytes of `mem`, in fills of at most [`FILL_CHUNK`] bytes: NVIDIA's
/// OpenCL faults (CL_NV_INVALID_MEM_ACCESS) filling a 4 GiB buffer in one command
/// (seen with the 8192x8192 G-buffer, issue 7).
fn fill_zero(queue: &CommandQueue, mem: &mut Buffer<u8>, size: usize) -> Result<(), BackendError> {
    let mut offset = 0;
    while offset < size {
        let n = (size - offset).min(FILL_CHUNK);
        unsafe { queue.enqueue_fill_buffer(mem, &[0u8], offset, n, &[]) }
            .map_err(cl_error("clearing a buffer"))?;
        offset += n;
    }
    Ok(())
}

impl Backend for OpenClBackend {
    fn name(&self) -> &'static str {
        "opencl"
    }

    fn capabilities(&self) -> Capabilities {
        let i = &self.state.info;
        Capabilities {
            device: format!("{} ({}, {})", i.name, i.platform, i.version),
            device_type: i.device_type,
            hardware_ray_tracing: false,
            float_atomics: false,
            int64_atomics: i.int64_atomics,
            timestamps: true,
            max_buffer_bytes: i.max_alloc_bytes,
            max_buffer_limit: "device allocation size (CL_DEVICE_MAX_MEM_ALLOC_SIZE)",
        }
    }

    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        caustica_core::backend::driver_entry(|| self.execute_recording(recording))
    }

    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        caustica_core::backend::driver_entry(|| self.read_back(id))
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

    fn variants(&self) -> Vec<String> {
        let v = self.variants.lock().unwrap_or_else(|e| e.into_inner());
        v.iter().cloned().collect()
    }
}

/// A submission on the queue ([`Backend::submit`]): what it must keep alive until it has
/// run, and what it gives back.
struct InFlight {
    /// Kernel names and their profiling events.
    kernels: Vec<(&'static str, Event)>,
    /// Data of non-blocking writes (read by the device until the submission is done).
    _writes: Vec<Vec<u8>>,
    /// Kernel objects and parameter buffers of the launches (released once done).
    _launches: Vec<dispatch::Launched>,
    /// Pinned buffers the readbacks are copied into, mapped once copied.
    readbacks: Vec<PinnedReadback>,
    /// A marker after everything else: complete when the submission is.
    done: Event,
}

/// A readback's landing place: a host-allocated (pinned) buffer, copied into on the
/// device and mapped without blocking. NVIDIA's driver performs a "non-blocking" read into
/// pageable host memory synchronously (measured: `submit` took the whole frame), so the
/// copy goes device to pinned buffer and the host reads the mapping once the submission's
/// marker has completed.
struct PinnedReadback {
    pinned: Buffer<u8>,
    mapped: *mut std::ffi::c_void,
    bytes: u64,
}

/// Kernel times from profiling events (the commands have completed).
fn pass_times(kernels: &[(&'static str, Event)]) -> Result<Vec<PassTime>, BackendError> {
    kernels
        .iter()
        .map(|(kernel, e)| {
            let start = e
                .profiling_command_start()
                .map_err(cl_error("reading a kernel timestamp"))?;
            let end = e
                .profiling_command_end()
                .map_err(cl_error("reading a kernel timestamp"))?;
            Ok(PassTime {
                kernel,
                seconds: end.saturating_sub(start) as f64 * 1e-9,
            })
        })
        .collect()
}

impl OpenClBackend {
    /// [`Backend::execute`]'s body (the trait method runs it under
    /// [`caustica_core::backend::driver_entry`]).
    fn execute_recording(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        let (mut writes, mut launches) = (Vec::new(), Vec::new());
        let kernels = self.enqueue(recording, &mut writes, &mut launches)?;
        self.queue
            .finish()
            .map_err(cl_error("waiting for the device"))?;
        pass_times(&kernels)
    }

    /// Enqueues every step of `recording` on the in-order queue. Writes do not block: their
    /// data is copied into `writes`, which must outlive the commands. Creations upload
    /// blocking (they are set-up work, not a frame's).
    fn enqueue(
        &mut self,
        recording: &Recording,
        writes: &mut Vec<Vec<u8>>,
        launches: &mut Vec<dispatch::Launched>,
    ) -> Result<Vec<(&'static str, Event)>, BackendError> {
        let mut pending: Vec<(&'static str, Event)> = Vec::new();
        for step in &recording.steps {
            match step {
                Step::Create { id, bytes, label } => self.create(*id, *bytes, label, None)?,
                Step::Upload { id, data, label } => {
                    self.create(*id, data.len() as u64, label, Some(data))?
                }
                Step::Write {
                    id, offset, data, ..
                } => {
                    let b = self
                        .buffers
                        .get_mut(id)
                        .ok_or(BackendError::MissingResource(*id))?;
                    if offset + data.len() as u64 > b.bytes {
                        return Err(BackendError::BadArgument(format!(
                            "write of {} bytes at {offset} into a buffer of {}",
                            data.len(),
                            b.bytes
                        )));
                    }
                    if !data.is_empty() {
                        writes.push(data.clone());
                        let data = writes.last().expect("just pushed");
                        // SAFETY: `data` lives in `writes` (its heap block does not move)
                        // until the queue has finished this command.
                        unsafe {
                            self.queue.enqueue_write_buffer(
                                &mut b.mem,
                                CL_NON_BLOCKING,
                                *offset as usize,
                                data,
                                &[],
                            )
                        }
                        .map_err(cl_error("writing into a buffer"))?;
                    }
                }
                Step::Clear { id } => {
                    let b = self
                        .buffers
                        .get_mut(id)
                        .ok_or(BackendError::MissingResource(*id))?;
                    fill_zero(&self.queue, &mut b.mem, b.bytes.max(4) as usize)?;
                }
                Step::Free { id } => {
                    // OpenCL keeps the memory until the commands using it have finished
                    self.buffers.remove(id);
                }
                Step::Kernel(k) => {
                    if let Some((event, launched)) = dispatch::run(self, k)? {
                        pending.push((k.name(), event));
                        launches.push(launched);
                    }
                }
            }
        }
        Ok(pending)
    }

    /// [`Backend::submit`]'s body: enqueue, non-blocking reads of `readbacks`, a marker,
    /// a flush; no wait.
    fn submit_recording(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        if self.in_flight.len() >= caustica_core::backend::MAX_UNCOLLECTED {
            let oldest = *self.in_flight.keys().min().expect("not empty");
            if let Some(f) = self.in_flight.remove(&oldest) {
                f.done
                    .wait()
                    .map_err(cl_error("waiting for an uncollected submission"))?;
            }
        }
        let (mut writes, mut launches) = (Vec::new(), Vec::new());
        let kernels = self.enqueue(recording, &mut writes, &mut launches)?;
        let mut landing = Vec::with_capacity(readbacks.len());
        for id in readbacks {
            let b = self.buffer(*id)?;
            let size = b.bytes.max(4) as usize;
            let mut pinned = unsafe {
                Buffer::<u8>::create(
                    &self.state.context,
                    CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR,
                    size,
                    std::ptr::null_mut(),
                )
            }
            .map_err(cl_error("creating a readback buffer"))?;
            let mut mapped = std::ptr::null_mut();
            // SAFETY: both buffers are this backend's and at least `bytes` long; the
            // mapping is read only after the submission's marker has completed.
            unsafe {
                if b.bytes > 0 {
                    self.queue
                        .enqueue_copy_buffer(&b.mem, &mut pinned, 0, 0, b.bytes as usize, &[])
                        .map_err(cl_error("copying a buffer for readback"))?;
                }
                self.queue
                    .enqueue_map_buffer(
                        &pinned,
                        CL_NON_BLOCKING,
                        CL_MAP_READ,
                        0,
                        size,
                        &mut mapped,
                        &[],
                    )
                    .map_err(cl_error("mapping a readback buffer"))?;
            }
            landing.push(PinnedReadback {
                pinned,
                mapped,
                bytes: b.bytes,
            });
        }
        let done = unsafe { self.queue.enqueue_marker_with_wait_list(&[]) }
            .map_err(cl_error("enqueueing a submission's marker"))?;
        self.queue.flush().map_err(cl_error("flushing the queue"))?;
        self.next_submission += 1;
        let id = self.next_submission;
        self.in_flight.insert(
            id,
            InFlight {
                kernels,
                _launches: launches,
                _writes: writes,
                readbacks: landing,
                done,
            },
        );
        Ok(Submission::pending(id))
    }

    /// [`Backend::poll`]'s body.
    fn poll_submission(
        &mut self,
        s: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        if !s.is_pending() {
            return s.take_finished().map(Some);
        }
        let Some(f) = self.in_flight.get(&s.id) else {
            return Err(BackendError::BadArgument(format!(
                "submission {} is not one of this backend's, or its result was discarded \
                 ({} newer submissions were left uncollected)",
                s.id,
                caustica_core::backend::MAX_UNCOLLECTED
            )));
        };
        if wait {
            f.done
                .wait()
                .map_err(cl_error("waiting for a submission"))?;
        } else {
            let status = f
                .done
                .command_execution_status()
                .map_err(cl_error("querying a submission"))?;
            if status.0 < 0 {
                return Err(BackendError::Driver(format!(
                    "a submission failed on the device (status {})",
                    status.0
                )));
            }
            if status.0 != CL_COMPLETE {
                return Ok(None);
            }
        }
        let f = self.in_flight.remove(&s.id).expect("looked up above");
        s.mark_collected();
        let mut readbacks = Vec::with_capacity(f.readbacks.len());
        for r in &f.readbacks {
            let mut out = caustica_core::device::host_bytes(r.bytes, "a submission's readback")?;
            // SAFETY: the map completed before the marker; it covers `bytes` bytes.
            unsafe {
                std::ptr::copy_nonoverlapping(r.mapped as *const u8, out.as_mut_ptr(), out.len());
                self.queue
                    .enqueue_unmap_mem_object(r.pinned.get(), r.mapped, &[])
                    .map_err(cl_error("unmapping a readback buffer"))?;
            }
            readbacks.push(out);
        }
        Ok(Some(Finished {
            times: pass_times(&f.kernels)?,
            readbacks,
        }))
    }

    /// [`Backend::read`]'s body.
    fn read_back(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        let b = self.buffer(id)?;
        let mut out = caustica_core::device::host_bytes(b.bytes, "reading a buffer back")?;
        if !out.is_empty() {
            unsafe {
                self.queue
                    .enqueue_read_buffer(&b.mem, CL_BLOCKING, 0, &mut out, &[])
                    .map_err(cl_error("reading a buffer"))?;
            }
        }
        Ok(out)
    }
}
