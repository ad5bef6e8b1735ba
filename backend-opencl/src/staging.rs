//! Host staging in pinned memory, reused per submission (no allocation per frame). On NVIDIA's
//! driver every host-to-device copy from pageable memory, and every buffer created with
//! `CL_MEM_COPY_HOST_PTR`, waits for the work queued before it, and releasing device
//! memory synchronises the device: a "non-blocking" submission that made a parameter
//! buffer per launch took the whole frame on the host. So a submission takes a *staging
//! slot*, kept across submissions: one device buffer holding every launch's parameters
//! (each launch binds a sub-buffer of it), filled by one non-blocking write from pinned
//! host memory, which also stages the recording's `Step::Write` data; and pinned host
//! memory the readbacks land in. A slot is reused once its submission has completed.

use crate::error::cl_error;
use caustica_core::backend::BackendError;
use opencl3::command_queue::CommandQueue;
use opencl3::context::Context;
use opencl3::memory::{Buffer, ClMem, CL_MAP_READ, CL_MAP_WRITE, CL_MEM_ALLOC_HOST_PTR};
use opencl3::memory::{CL_MEM_READ_ONLY, CL_MEM_READ_WRITE};
use opencl3::types::CL_BLOCKING;

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
