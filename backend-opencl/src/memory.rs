//! Buffers: device buffers created zeroed (in fills of at most [`FILL_CHUNK`] bytes) or
//! uploaded, read back blocking; and the staging of submissions in pinned memory.
//!
//! The staging is pinned host memory, reused per submission (no allocation per frame). On
//! NVIDIA's driver every host-to-device copy from pageable memory, and every buffer made with
//! `CL_MEM_COPY_HOST_PTR`, waits for the work queued before it, and releasing device
//! memory synchronises the device: a "non-blocking" submission that made a parameter
//! buffer per launch took the whole frame on the host. So a submission takes a *staging
//! slot*, kept across submissions: one device buffer holding every launch's parameters
//! (each launch binds a sub-buffer of it), filled by one non-blocking write from pinned
//! host memory, which also stages the recording's `Step::Write` data; and pinned host
//! memory the readbacks land in. A slot is reused once its submission has completed.

use crate::device::cl_error;
use crate::OpenClBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::{Recording, Step};
use opencl3::command_queue::CommandQueue;
use opencl3::context::Context;
use opencl3::memory::{Buffer, ClMem, CL_MAP_READ, CL_MAP_WRITE, CL_MEM_ALLOC_HOST_PTR};
use opencl3::memory::{CL_MEM_READ_ONLY, CL_MEM_READ_WRITE};
use opencl3::types::CL_BLOCKING;

/// A device buffer and its logical size in bytes (OpenCL buffers are at least 4 bytes).
pub(crate) struct DeviceBuffer {
    pub mem: Buffer<u8>,
    pub bytes: u64,
}

/// Largest single fill command (bytes): 1 GiB.
pub(crate) const FILL_CHUNK: usize = 1 << 30;

impl OpenClBackend {
    /// Creates buffer `id` of `bytes` bytes (at least 4), uploading `data` or zeroing it.
    pub(crate) fn create(
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
        self.buffers.remove(id);
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

    /// The staging layout of `recording` with `readbacks`.
    pub(crate) fn layout(
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
            let bytes = self.buffers.get(*id)?.bytes as usize;
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

    /// [`caustica_core::backend::Backend::read`]'s body.
    pub(crate) fn read_resource(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        let b = self.buffers.get(id)?;
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

/// Zeroes `size` bytes of `mem`, in fills of at most [`FILL_CHUNK`] bytes: NVIDIA's
/// OpenCL faults (CL_NV_INVALID_MEM_ACCESS) filling a 4 GiB buffer in one command
/// (seen with the 8192x8192 G-buffer of the stiff catalogue).
pub(crate) fn fill_zero(
    queue: &CommandQueue,
    mem: &mut Buffer<u8>,
    size: usize,
) -> Result<(), BackendError> {
    let mut offset = 0;
    while offset < size {
        let n = (size - offset).min(FILL_CHUNK);
        unsafe { queue.enqueue_fill_buffer(mem, &[0u8], offset, n, &[]) }
            .map_err(cl_error("clearing a buffer"))?;
        offset += n;
    }
    Ok(())
}

/// Where a recording's staged bytes go in a slot: each parameter block's offset in the
/// parameter buffer (aligned for sub-buffers), each write's offset in the pinned upload
/// memory (after the parameters), each readback's in the pinned readback memory.
pub(crate) struct StagingLayout {
    pub params: Vec<(usize, usize)>,
    pub params_bytes: usize,
    pub writes: Vec<usize>,
    pub upload_bytes: usize,
    pub readbacks: Vec<(usize, usize)>,
    pub readback_bytes: usize,
}

/// Pinned host memory: a `CL_MEM_ALLOC_HOST_PTR` buffer mapped once when made and kept
/// mapped; no command ever names the buffer itself, only its host pointer as the source or
/// destination of a copy (which the driver then runs as an asynchronous DMA).
pub struct Pinned {
    buffer: Buffer<u8>,
    ptr: *mut u8,
    size: usize,
    queue: opencl3::types::cl_command_queue,
}

impl Pinned {
    /// `size` bytes of pinned memory (the map waits for the queue: only when a slot is
    /// made or grown).
    fn new(queue: &CommandQueue, context: &Context, size: usize) -> Result<Pinned, BackendError> {
        let size = size.max(256);
        let buffer = unsafe {
            Buffer::<u8>::create(
                context,
                CL_MEM_READ_WRITE | CL_MEM_ALLOC_HOST_PTR,
                size,
                std::ptr::null_mut(),
            )
        }
        .map_err(cl_error("allocating pinned staging memory"))?;
        let mut ptr = std::ptr::null_mut();
        unsafe {
            queue.enqueue_map_buffer(
                &buffer,
                CL_BLOCKING,
                CL_MAP_READ | CL_MAP_WRITE,
                0,
                size,
                &mut ptr,
                &[],
            )
        }
        .map_err(cl_error("mapping pinned staging memory"))?;
        Ok(Pinned {
            buffer,
            ptr: ptr as *mut u8,
            size,
            queue: queue.get(),
        })
    }

    pub fn bytes(&self, at: usize, len: usize) -> &[u8] {
        assert!(at + len <= self.size, "pinned range out of bounds");
        // SAFETY: the mapping covers `size` bytes and stays mapped while `self` lives
        unsafe { std::slice::from_raw_parts(self.ptr.add(at), len) }
    }

    pub fn bytes_mut(&mut self, at: usize, len: usize) -> &mut [u8] {
        assert!(at + len <= self.size, "pinned range out of bounds");
        // SAFETY: as `bytes`; `&mut self` makes the view unique
        unsafe { std::slice::from_raw_parts_mut(self.ptr.add(at), len) }
    }
}

impl Drop for Pinned {
    fn drop(&mut self) {
        // unmapped before the release (the queue outlives every slot: the backend waits
        // for it before dropping them)
        let unmapped = unsafe {
            opencl3::command_queue::enqueue_unmap_mem_object(
                self.queue,
                self.buffer.get(),
                self.ptr as *mut std::ffi::c_void,
                0,
                std::ptr::null(),
            )
        };
        if let Ok(e) = unmapped {
            drop(opencl3::event::Event::from(e));
        }
    }
}

/// The staging one submission uses (see the module doc).
#[derive(Default)]
pub struct StagingSlot {
    /// Device buffer of the launches' parameters, and its size.
    pub params: Option<Buffer<u8>>,
    params_size: usize,
    /// Pinned: the parameters (first `params_size` bytes used) then the writes' data.
    pub upload: Option<Pinned>,
    /// Pinned: where the readbacks land.
    pub readback: Option<Pinned>,
}

impl StagingSlot {
    /// Readies the slot for `params` bytes of parameters, `upload` bytes of pinned upload
    /// staging in all (parameters included) and `readback` bytes of readbacks, growing
    /// what is too small.
    pub fn prepare(
        &mut self,
        queue: &CommandQueue,
        context: &Context,
        params: usize,
        upload: usize,
        readback: usize,
    ) -> Result<(), BackendError> {
        if params > self.params_size || self.params.is_none() {
            let size = params.max(4096).next_power_of_two();
            self.params = Some(
                unsafe {
                    Buffer::<u8>::create(context, CL_MEM_READ_ONLY, size, std::ptr::null_mut())
                }
                .map_err(cl_error("allocating the kernel parameter buffer"))?,
            );
            self.params_size = size;
        }
        if self.upload.as_ref().is_none_or(|p| p.size < upload) {
            self.upload = Some(Pinned::new(
                queue,
                context,
                upload.max(4096).next_power_of_two(),
            )?);
        }
        if readback > 0 && self.readback.as_ref().is_none_or(|p| p.size < readback) {
            self.readback = Some(Pinned::new(queue, context, readback.next_power_of_two())?);
        }
        Ok(())
    }

    /// The parameters' device buffer.
    pub fn params(&self) -> &Buffer<u8> {
        self.params.as_ref().expect("prepared")
    }
}
