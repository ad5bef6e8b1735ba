//! Planned allocation: every buffer a technique creates is recorded first, then checked
//! against the device's limits before any work, so that an oversized frame is a typed
//! [`BackendError::OutOfMemory`] naming the buffer, never an invalid binding or a crash.

use crate::backend::Backend;
use crate::device::error::BackendError;
use crate::device::handle::ResourceId;
use crate::frame::plan::BufferPlan;
use crate::recording::{Recording, Step};

/// The buffers a recording creates, checked against the device.
#[derive(Clone, Debug, Default)]
pub struct Allocation {
    /// Every buffer created (to free later).
    pub owned: Vec<ResourceId>,
    /// Total bytes.
    pub bytes: u64,
    /// Name and size of each buffer, for the frame plan.
    pub buffers: Vec<BufferPlan>,
}

/// Checks every buffer that `rec` creates or uploads against the device's largest buffer
/// (and, on wgpu and Vulkan, its largest storage binding) and returns them, before `rec`
/// is executed.
pub fn planned_allocation(
    backend: &dyn Backend,
    rec: &Recording,
) -> Result<Allocation, BackendError> {
    let largest = backend.capabilities().max_buffer_bytes;
    let mut a = Allocation::default();
    for s in &rec.steps {
        let (id, b, label) = match s {
            Step::Create { id, bytes, label } => (*id, *bytes, *label),
            Step::Upload { id, data, label } => (*id, data.len() as u64, *label),
            _ => continue,
        };
        if b > largest {
            return Err(BackendError::OutOfMemory {
                bytes: b,
                what: format!(
                    "{label}: the {} backend's device binds at most {largest} bytes per buffer",
                    backend.name()
                ),
            });
        }
        a.bytes += b;
        a.owned.push(id);
        a.buffers.push(BufferPlan {
            name: label.into(),
            bytes: b,
        });
    }
    Ok(a)
}
