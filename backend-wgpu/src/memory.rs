//! Buffers: storage buffers created zeroed or mapped at creation (at least
//! [`MIN_BINDING_BYTES`]), read back through a mappable staging copy.

use crate::WgpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::handle::ResourceId;
use std::sync::{Arc, Mutex};

/// Smallest buffer and binding: one element of the largest array element type a kernel
/// binds (`GpuLight`, 64 bytes), since wgpu requires a runtime-sized array binding to hold
/// one element. Kernels never read the dummy: counts come from parameters, and
/// `arrayLength(&nodes) / 5` of a 64-byte dummy is 0.
pub(crate) const MIN_BINDING_BYTES: u64 = 64;

/// A device buffer and its logical size in bytes (at least `MIN_BINDING_BYTES` are
/// allocated, and an empty buffer binds as that dummy).
pub(crate) struct DeviceBuffer {
    pub buffer: wgpu::Buffer,
    pub bytes: u64,
}

impl WgpuBackend {
    /// Creates buffer `id` (a `Step::Create`, or a `Step::Upload` of `data`).
    pub(crate) fn create(
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
        self.buffers.remove(id);
        let scope = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let buffer = self.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(label),
            size,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
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
    pub(crate) fn read_buffer(
        &self,
        buffer: &wgpu::Buffer,
        bytes: u64,
    ) -> Result<Vec<u8>, BackendError> {
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

    /// [`caustica_core::backend::Backend::read`]'s body.
    pub(crate) fn read_resource(&self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        let b = self.buffers.get(id)?;
        self.read_buffer(&b.buffer, b.bytes)
    }
}
