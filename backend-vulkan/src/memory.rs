//! Buffers: device-local storage buffers (with device addresses, usable as
//! acceleration-structure build input), and host-visible buffers for staging, parameters,
//! the shader binding table and readback. Each owns its memory and is freed on drop.

use crate::context::{vk_error, Context};
use ash::vk;
use caustica_core::backend::BackendError;
use std::sync::Arc;

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

/// Storage buffers: read and written by kernels, copied, read by AS builds.
pub fn storage_usage() -> vk::BufferUsageFlags {
    vk::BufferUsageFlags::STORAGE_BUFFER
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
