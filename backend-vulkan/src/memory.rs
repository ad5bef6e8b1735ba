//! Buffers: device-local storage buffers (with device addresses, usable as
//! acceleration-structure build input), and host-visible buffers for staging, parameters,
//! the shader binding table and readback. Each owns its memory and is freed on drop. The
//! backend's buffers by resource, read back through a staging copy; and the [`Arena`].
//!
//! The arena: host-visible scratch memory reused by every `execute` (no allocation per
//! kernel): kernel parameters (uniforms) and the staging copies of uploads and writes are
//! bump-allocated
//! from one mapped buffer, which is reset when an execute starts (each execute waits for
//! its work before it returns, so nothing of the last one is still read). A request that
//! does not fit gets its own buffer for this execute, as before, and the arena grows to fit
//! the whole execute's requests at the next reset (up to [`MAX_ARENA_BYTES`]: larger
//! uploads, such as whole scenes, keep their own staging).

use crate::device::{vk_error, Context};
use crate::VulkanBackend;
use ash::vk;
use caustica_core::backend::BackendError;
use caustica_core::device::handle::ResourceId;
use std::sync::Arc;

/// Smallest buffer and descriptor range: one element of the largest array element a
/// kernel binds (`GpuLight`, 64 bytes); kernels never read the dummy of an empty buffer.
pub(crate) const MIN_BINDING_BYTES: u64 = 64;

/// Words of the photon counters (core::gpu::counter::WORDS) times the 64 banks that ray
/// generation shaders add into to spread their atomics.
pub(crate) const COUNTER_BANK_BYTES: u64 = 64 * 20 * 4;

/// One of the backend's buffers and its logical size in bytes.
pub(crate) struct DeviceBuffer {
    pub buffer: Buffer,
    pub bytes: u64,
    /// Process-unique stamp of this allocation (a `Create` or `Upload` makes a new one):
    /// a scene's acceleration structures remember those of their sources.
    pub generation: u64,
}

/// A fresh [`DeviceBuffer::generation`].
pub(crate) fn next_generation() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT: AtomicU64 = AtomicU64::new(1);
    NEXT.fetch_add(1, Ordering::Relaxed)
}

/// A buffer and its memory.
pub struct Buffer {
    ctx: Arc<Context>,
    pub buffer: vk::Buffer,
    memory: vk::DeviceMemory,
    /// Allocated size (bytes).
    pub size: u64,
    /// Mapped pointer of host-visible buffers.
    mapped: Option<*mut u8>,
}

/// Storage buffers: read and written by kernels, copied, read by AS builds and as the
/// sizes of indirect launches.
pub fn storage_usage() -> vk::BufferUsageFlags {
    vk::BufferUsageFlags::STORAGE_BUFFER
        | vk::BufferUsageFlags::INDIRECT_BUFFER
        | vk::BufferUsageFlags::TRANSFER_SRC
        | vk::BufferUsageFlags::TRANSFER_DST
        | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS
        | vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
}

impl Buffer {
    /// A buffer of `size` bytes; `host` makes it host-visible, coherent and mapped.
    pub fn new(
        ctx: &Arc<Context>,
        size: u64,
        usage: vk::BufferUsageFlags,
        host: bool,
        what: &str,
    ) -> Result<Buffer, BackendError> {
        let oom = |e: vk::Result| match vk_error("allocating a buffer")(e) {
            BackendError::OutOfMemory { .. } => BackendError::OutOfMemory {
                bytes: size,
                what: what.to_string(),
            },
            other => other,
        };
        if size > ctx.max_allocation {
            return Err(BackendError::OutOfMemory {
                bytes: size,
                what: format!(
                    "{what} (the device allocates at most {} bytes at once)",
                    ctx.max_allocation
                ),
            });
        }
        let d = &ctx.device;
        let buffer = unsafe {
            d.create_buffer(
                &vk::BufferCreateInfo::default()
                    .size(size.max(4))
                    .usage(usage | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS)
                    .sharing_mode(vk::SharingMode::EXCLUSIVE),
                None,
            )
        }
        .map_err(oom)?;
        let req = unsafe { d.get_buffer_memory_requirements(buffer) };
        let flags = if host {
            vk::MemoryPropertyFlags::HOST_VISIBLE | vk::MemoryPropertyFlags::HOST_COHERENT
        } else {
            vk::MemoryPropertyFlags::DEVICE_LOCAL
        };
        let Some(type_index) = ctx.memory_type(req.memory_type_bits, flags) else {
            unsafe { d.destroy_buffer(buffer, None) };
            return Err(BackendError::Unsupported(format!(
                "no memory type {flags:?} for {what}"
            )));
        };
        let mut alloc_flags =
            vk::MemoryAllocateFlagsInfo::default().flags(vk::MemoryAllocateFlags::DEVICE_ADDRESS);
        let memory = match unsafe {
            d.allocate_memory(
                &vk::MemoryAllocateInfo::default()
                    .allocation_size(req.size)
                    .memory_type_index(type_index)
                    .push_next(&mut alloc_flags),
                None,
            )
        } {
            Ok(m) => m,
            Err(e) => {
                unsafe { d.destroy_buffer(buffer, None) };
                return Err(oom(e));
            }
        };
        let bound = unsafe { d.bind_buffer_memory(buffer, memory, 0) };
        let mapped = if host && bound.is_ok() {
            unsafe { d.map_memory(memory, 0, vk::WHOLE_SIZE, vk::MemoryMapFlags::empty()) }
                .ok()
                .map(|p| p as *mut u8)
        } else {
            None
        };
        let b = Buffer {
            ctx: Arc::clone(ctx),
            buffer,
            memory,
            size,
            mapped,
        };
        bound.map_err(vk_error("binding buffer memory"))?;
        if host && b.mapped.is_none() {
            return Err(BackendError::Driver(format!("could not map {what}")));
        }
        Ok(b)
    }

    /// A host-visible buffer holding `data`.
    pub fn with_data(
        ctx: &Arc<Context>,
        data: &[u8],
        usage: vk::BufferUsageFlags,
        what: &str,
    ) -> Result<Buffer, BackendError> {
        let b = Buffer::new(ctx, data.len() as u64, usage, true, what)?;
        b.write(0, data);
        Ok(b)
    }

    /// Writes into a host-visible buffer.
    pub fn write(&self, offset: usize, data: &[u8]) {
        if let Some(p) = self.mapped {
            let n = data.len().min((self.size as usize).saturating_sub(offset));
            // SAFETY: the mapping covers `size` bytes and `offset + n <= size`.
            unsafe { std::ptr::copy_nonoverlapping(data.as_ptr(), p.add(offset), n) };
        }
    }

    /// Reads `len` bytes of a host-visible buffer.
    pub fn read(&self, len: usize) -> Result<Vec<u8>, BackendError> {
        let mut out = caustica_core::device::host_bytes(
            len.min(self.size as usize) as u64,
            "reading a buffer back",
        )?;
        if let Some(p) = self.mapped {
            // SAFETY: the mapping covers `size` bytes.
            unsafe { std::ptr::copy_nonoverlapping(p, out.as_mut_ptr(), out.len()) };
        }
        Ok(out)
    }

    pub fn address(&self) -> vk::DeviceAddress {
        unsafe {
            self.ctx.device.get_buffer_device_address(
                &vk::BufferDeviceAddressInfo::default().buffer(self.buffer),
            )
        }
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        unsafe {
            if self.mapped.is_some() {
                self.ctx.device.unmap_memory(self.memory);
            }
            self.ctx.device.destroy_buffer(self.buffer, None);
            self.ctx.device.free_memory(self.memory, None);
        }
    }
}

impl VulkanBackend {
    /// A device-local storage buffer of `bytes` bytes (at least [`MIN_BINDING_BYTES`]).
    pub(crate) fn new_storage(&self, bytes: u64, what: &str) -> Result<Buffer, BackendError> {
        Buffer::new(
            &self.ctx,
            bytes.max(MIN_BINDING_BYTES),
            storage_usage(),
            false,
            what,
        )
    }

    /// Copies `bytes` of a device buffer to the host.
    pub(crate) fn read_device(
        &self,
        buffer: vk::Buffer,
        bytes: u64,
    ) -> Result<Vec<u8>, BackendError> {
        self.read_device_range(buffer, 0, bytes)
    }

    /// Copies `bytes` of a device buffer from byte `offset` to the host.
    pub(crate) fn read_device_range(
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

    /// [`caustica_core::backend::Backend::read`]'s body.
    pub(crate) fn read_resource(&self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        let b = self.buffers.get(id)?;
        self.read_device(b.buffer.buffer, b.bytes)
    }
}

/// Largest arena (bytes): enough for a frame's parameters and its per-frame writes.
pub const MAX_ARENA_BYTES: u64 = 64 << 20;

/// A bump allocator over one host-visible, mapped buffer.
#[derive(Default)]
pub struct Arena {
    buffer: Option<Buffer>,
    size: u64,
    used: u64,
    /// What the last execute asked for in all (the next reset's size).
    wanted: u64,
}

impl Arena {
    /// Starts an execute: grows the buffer to what the last one wanted (within
    /// [`MAX_ARENA_BYTES`]) and empties it.
    pub fn reset(&mut self, ctx: &Arc<Context>) -> Result<(), BackendError> {
        let want = self.wanted.min(MAX_ARENA_BYTES);
        if want > self.size {
            let size = want.next_power_of_two().clamp(64 << 10, MAX_ARENA_BYTES);
            self.buffer = Some(Buffer::new(
                ctx,
                size,
                vk::BufferUsageFlags::UNIFORM_BUFFER
                    | vk::BufferUsageFlags::STORAGE_BUFFER
                    | vk::BufferUsageFlags::TRANSFER_SRC
                    // parameter words copied in from the device (`ParamPatch`)
                    | vk::BufferUsageFlags::TRANSFER_DST,
                true,
                "host arena (parameters and staging)",
            )?);
            self.size = size;
        }
        self.used = 0;
        self.wanted = 0;
        Ok(())
    }

    /// `data` copied into the arena at an offset aligned to `align`: the buffer and the
    /// offset, or `None` when it does not fit (the caller makes its own buffer; the arena
    /// grows at the next reset).
    pub fn put(&mut self, data: &[u8], align: u64) -> Option<(vk::Buffer, u64)> {
        let len = data.len() as u64;
        if len > MAX_ARENA_BYTES / 4 {
            return None; // a scene upload: its own staging, not a reason to grow
        }
        // an upper bound of this execute's total, for the next reset
        self.wanted += len + align;
        let buffer = self.buffer.as_ref()?;
        let at = self.used.next_multiple_of(align.max(1));
        if at + len > self.size {
            return None;
        }
        buffer.write(at as usize, data);
        self.used = at + len;
        Some((buffer.buffer, at))
    }
}
