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
mod staging;

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
use opencl3::memory::{Buffer, ClMem, CL_MEM_READ_ONLY, CL_MEM_READ_WRITE};
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
    /// Results of submissions retired before they were polled.
    finished: caustica_core::backend::UncollectedResults,
    /// Staging slots free for the next submission ([`staging`]).
    free_slots: Vec<staging::StagingSlot>,
    /// Alignment of parameter sub-buffers (`CL_DEVICE_MEM_BASE_ADDR_ALIGN`, bytes).
    param_align: usize,
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
        caustica_core::backend::driver_entry(|| {
            caustica_core::backend::driver_lifecycle(OpenClBackend::open)
        })
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
        // sub-buffer origins must be multiples of the base address alignment (bits)
        let param_align = (state
            .device
            .mem_base_addr_align()
            .map_err(cl_error("querying CL_DEVICE_MEM_BASE_ADDR_ALIGN"))?
            as usize
            / 8)
        .max(16);
        Ok(OpenClBackend {
            state,
            queue,
            buffers: HashMap::new(),
            variants: Default::default(),
            in_flight: HashMap::new(),
            finished: Default::default(),
            free_slots: Vec::new(),
            param_align,
            next_submission: 0,
        })
    }

    /// The OpenCL event that completes with `submission` (its marker), while it is on
    /// the queue: a host with its own OpenCL work on this context waits on it (retain it
    /// with `clRetainEvent` to keep it past the submission's collection). `None` once the
    /// submission was collected.
    pub fn submission_event(&self, submission: &Submission) -> Option<opencl3::types::cl_event> {
        self.in_flight.get(&submission.id).map(|f| f.done.get())
    }

    /// The device in use.
    pub fn device(&self) -> &DeviceSummary {
        &self.state.info
    }

    /// `sizeof` of every shared struct as the device compiler lays it out, in the order
    /// of the generated `kernels/common/layout.cl`'s `struct_sizes`, which is core's
    /// layout table's (`caustica_core::device::layout_table::structs`; checked against
    /// Rust's `size_of` in tests).
    pub fn device_struct_sizes(&mut self) -> Result<Vec<u32>, BackendError> {
        let n = caustica_core::device::layout_table::structs().len();
        let mem = unsafe {
            Buffer::<u32>::create(
                &self.state.context,
                CL_MEM_READ_WRITE,
                n,
                std::ptr::null_mut(),
            )
        }
        .map_err(cl_error("creating a buffer"))?;
        let kernel = Kernel::create(&self.state.program, "struct_sizes")
            .map_err(cl_error("creating a kernel"))?;
        unsafe { kernel.set_arg(0, &mem.get()) }.map_err(cl_error("setting a kernel argument"))?;
        let mut out = vec![0u32; n];
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
/// (seen with the 8192x8192 G-buffer of the stiff catalogue).
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

/// Waits for the queue, then releases the submissions and staging slots (their pinned
/// memory is unmapped on the queue, which must still exist) before the queue goes.
impl Drop for OpenClBackend {
    fn drop(&mut self) {
        caustica_core::backend::driver_entry(|| {
            let _ = self.queue.finish();
            self.in_flight.clear();
            self.finished.clear();
            self.free_slots.clear();
            let _ = self.queue.finish();
        })
    }
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
    /// Kernel objects of the launches and the parameters' sub-buffers (released once
    /// done).
    _launches: Vec<dispatch::Launched>,
    _params: Vec<Buffer<u8>>,
    /// The staging slot (parameters, write data, readback landing).
    slot: staging::StagingSlot,
    /// Offset and size of each readback in the slot's pinned readback memory.
    readbacks: Vec<(usize, usize)>,
    /// A marker after everything else: complete when the submission is.
    done: Event,
}

/// Submissions on the device at once; the next waits for the oldest.
const MAX_FRAMES_IN_FLIGHT: usize = 3;

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

/// Where a recording's staged bytes go in a slot: each parameter block's offset in the
/// parameter buffer (aligned for sub-buffers), each write's offset in the pinned upload
/// memory (after the parameters), each readback's in the pinned readback memory.
struct StagingLayout {
    params: Vec<(usize, usize)>,
    params_bytes: usize,
    writes: Vec<usize>,
    upload_bytes: usize,
    readbacks: Vec<(usize, usize)>,
    readback_bytes: usize,
}

impl OpenClBackend {
    /// [`Backend::execute`]'s body (the trait method runs it under
    /// [`caustica_core::backend::driver_entry`]).
    fn execute_recording(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        let mut s = self.submit_recording(recording, &[])?;
        let f = self.poll_submission(&mut s, true)?;
        Ok(f.map(|f| f.times).unwrap_or_default())
    }

    /// The staging layout of `recording` with `readbacks`.
    fn layout(
        &self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<StagingLayout, BackendError> {
        let align = self.param_align;
        let mut params = Vec::new();
        let mut at = 0usize;
        for step in &recording.steps {
            if let Step::Kernel(k) = step {
                if let Some(l) = k.launch()? {
                    for a in &l.args {
                        if let caustica_core::device::launch::LaunchArg::Params(p) = a {
                            params.push((at, p.len()));
                            at = (at + p.len().max(4)).next_multiple_of(align);
                        }
                    }
                }
            }
        }
        let params_bytes = at.max(4);
        let mut writes = Vec::new();
        let mut up = params_bytes.next_multiple_of(16);
        for step in &recording.steps {
            if let Step::Write { data, .. } = step {
                writes.push(up);
                up = (up + data.len()).next_multiple_of(16);
            }
        }
        let mut rb = Vec::new();
        let mut r = 0usize;
        for id in readbacks {
            let bytes = self.buffer(*id)?.bytes as usize;
            rb.push((r, bytes));
            r = (r + bytes).next_multiple_of(16);
        }
        Ok(StagingLayout {
            params,
            params_bytes,
            writes,
            upload_bytes: up,
            readbacks: rb,
            readback_bytes: r,
        })
    }

    /// A staging slot: a free one, a new one, or (with [`MAX_FRAMES_IN_FLIGHT`] on the
    /// queue) the oldest submission's once it has finished, its result kept for its poll.
    fn take_slot(&mut self) -> Result<staging::StagingSlot, BackendError> {
        if let Some(s) = self.free_slots.pop() {
            return Ok(s);
        }
        if self.in_flight.len() >= MAX_FRAMES_IN_FLIGHT {
            let oldest = *self.in_flight.keys().min().expect("not empty");
            let f = self.in_flight.remove(&oldest).expect("a key");
            let result = self.retire(f, true);
            self.finished.keep(oldest, result);
            if let Some(s) = self.free_slots.pop() {
                return Ok(s);
            }
        }
        Ok(staging::StagingSlot::default())
    }

    /// A finished (or, with `wait`, waited-for) submission's result; its slot back in the
    /// free list.
    fn retire(&mut self, f: InFlight, wait: bool) -> Result<Finished, BackendError> {
        let waited = if wait {
            f.done.wait().map_err(cl_error("waiting for a submission"))
        } else {
            Ok(())
        };
        let result = waited.and_then(|_| {
            let times = pass_times(&f.kernels)?;
            let mut readbacks = Vec::with_capacity(f.readbacks.len());
            for (at, bytes) in &f.readbacks {
                let mut out =
                    caustica_core::device::host_bytes(*bytes as u64, "a submission's readback")?;
                if let Some(p) = &f.slot.readback {
                    out.copy_from_slice(p.bytes(*at, *bytes));
                }
                readbacks.push(out);
            }
            Ok(Finished { times, readbacks })
        });
        self.free_slots.push(f.slot);
        result
    }

    /// [`Backend::submit`]'s body: the recording's parameters and write data staged in a
    /// slot's pinned memory and uploaded by non-blocking copies, every step enqueued, the
    /// readbacks copied into pinned memory, a marker, a flush; no wait (see
    /// [`staging`]). Creations upload blocking (set-up work, not a frame's).
    fn submit_recording(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        let layout = self.layout(recording, readbacks)?;
        let mut slot = self.take_slot()?;
        let staged = self.enqueue(recording, readbacks, &layout, &mut slot);
        let (kernels, launches, params) = match staged {
            Ok(x) => x,
            Err(e) => {
                // what was enqueued may still read the slot: let it finish first
                let _ = self.queue.finish();
                self.free_slots.push(slot);
                return Err(e);
            }
        };
        let done = match unsafe { self.queue.enqueue_marker_with_wait_list(&[]) }
            .map_err(cl_error("enqueueing a submission's marker"))
            .and_then(|d| {
                self.queue
                    .flush()
                    .map_err(cl_error("flushing the queue"))
                    .map(|_| d)
            }) {
            Ok(d) => d,
            Err(e) => {
                let _ = self.queue.finish();
                self.free_slots.push(slot);
                return Err(e);
            }
        };
        self.next_submission += 1;
        let id = self.next_submission;
        self.in_flight.insert(
            id,
            InFlight {
                kernels,
                _launches: launches,
                _params: params,
                slot,
                readbacks: layout.readbacks,
                done,
            },
        );
        Ok(Submission::pending(id))
    }

    /// Enqueues `recording` with its staging in `slot` (laid out by `layout`), then the
    /// readbacks into the slot's pinned memory.
    #[allow(clippy::type_complexity)]
    fn enqueue(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
        layout: &StagingLayout,
        slot: &mut staging::StagingSlot,
    ) -> Result<
        (
            Vec<(&'static str, Event)>,
            Vec<dispatch::Launched>,
            Vec<Buffer<u8>>,
        ),
        BackendError,
    > {
        slot.prepare(
            &self.queue,
            &self.state.context,
            layout.params_bytes,
            layout.upload_bytes,
            layout.readback_bytes,
        )?;
        // the parameters: into pinned memory, one non-blocking copy to the device, one
        // sub-buffer per block
        let mut params = Vec::with_capacity(layout.params.len());
        {
            let upload = slot.upload.as_mut().expect("prepared");
            let mut k = 0;
            for step in &recording.steps {
                if let Step::Kernel(rk) = step {
                    if let Some(l) = rk.launch()? {
                        for a in &l.args {
                            if let caustica_core::device::launch::LaunchArg::Params(p) = a {
                                let (at, len) = layout.params[k];
                                upload.bytes_mut(at, len).copy_from_slice(p);
                                k += 1;
                            }
                        }
                    }
                }
            }
        }
        if !layout.params.is_empty() {
            let upload = slot.upload.as_ref().expect("prepared");
            let src = upload.bytes(0, layout.params_bytes);
            let dst = slot.params.as_mut().expect("prepared");
            // SAFETY: `src` is pinned memory the slot keeps until the submission is done
            unsafe {
                self.queue
                    .enqueue_write_buffer(dst, CL_NON_BLOCKING, 0, src, &[])
            }
            .map_err(cl_error("uploading kernel parameters"))?;
            for (at, len) in &layout.params {
                params.push(
                    unsafe {
                        slot.params()
                            .create_sub_buffer(CL_MEM_READ_ONLY, *at, (*len).max(4))
                    }
                    .map_err(cl_error("making a parameter sub-buffer"))?,
                );
            }
        }
        let mut pending: Vec<(&'static str, Event)> = Vec::new();
        let mut launches = Vec::new();
        let (mut next_write, mut next_param) = (0usize, 0usize);
        for step in &recording.steps {
            match step {
                Step::Create { id, bytes, label } => self.create(*id, *bytes, label, None)?,
                Step::Upload { id, data, label } => {
                    self.create(*id, data.len() as u64, label, Some(data))?
                }
                Step::Write {
                    id, offset, data, ..
                } => {
                    let at = layout.writes[next_write];
                    next_write += 1;
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
                        let upload = slot.upload.as_mut().expect("prepared");
                        upload.bytes_mut(at, data.len()).copy_from_slice(data);
                        let src = upload.bytes(at, data.len());
                        // SAFETY: pinned memory the slot keeps until the submission is done
                        unsafe {
                            self.queue.enqueue_write_buffer(
                                &mut b.mem,
                                CL_NON_BLOCKING,
                                *offset as usize,
                                src,
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
                    let blocks = match k.launch()? {
                        Some(l) => l
                            .args
                            .iter()
                            .filter(|a| {
                                matches!(a, caustica_core::device::launch::LaunchArg::Params(_))
                            })
                            .count(),
                        None => 0,
                    };
                    let mine = &params[next_param..next_param + blocks];
                    next_param += blocks;
                    if let Some((event, launched)) = dispatch::run(self, k, mine)? {
                        pending.push((k.name(), event));
                        launches.push(launched);
                    }
                }
            }
        }
        if let Some(landing) = slot.readback.as_mut() {
            for (id, (at, bytes)) in readbacks.iter().zip(&layout.readbacks) {
                if *bytes == 0 {
                    continue;
                }
                let b = self.buffer(*id)?;
                let dst = landing.bytes_mut(*at, *bytes);
                // SAFETY: pinned memory the slot keeps, unread, until the marker completes
                unsafe {
                    self.queue
                        .enqueue_read_buffer(&b.mem, CL_NON_BLOCKING, 0, dst, &[])
                }
                .map_err(cl_error("reading a buffer back"))?;
            }
        }
        Ok((pending, launches, params))
    }

    /// [`Backend::poll`]'s body.
    fn poll_submission(
        &mut self,
        s: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        if let Some(answer) = self.finished.settle(s) {
            return answer;
        }
        let Some(f) = self.in_flight.get(&s.id) else {
            return Err(caustica_core::backend::unknown_submission(s.id));
        };
        if !wait {
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
        self.retire(f, wait).map(Some)
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
