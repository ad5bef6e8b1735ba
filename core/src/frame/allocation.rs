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

impl Allocation {
    /// Frees every buffer now and forgets them.
    pub fn free(&mut self, backend: &mut dyn Backend) -> Result<(), BackendError> {
        let mut rec = Recording::new();
        self.free_into(&mut rec);
        if !rec.steps.is_empty() {
            backend.execute(&rec)?;
        }
        Ok(())
    }

    /// The buffers and their bytes (leak reports, statistics).
    pub fn count(&self) -> (usize, u64) {
        (self.owned.len(), self.bytes)
    }

    /// Records every buffer freed and forgets them.
    pub fn free_into(&mut self, rec: &mut Recording) {
        for id in std::mem::take(&mut self.owned) {
            rec.steps.push(Step::Free { id });
        }
        self.bytes = 0;
        self.buffers.clear();
    }
}

/// Checks every buffer `rec` creates against the device ([`planned_allocation`]), then
/// runs it; if it fails, what it made is freed before the error.
pub fn allocate(
    backend: &mut dyn Backend,
    rec: &Recording,
    frame: Option<(u32, u32)>,
) -> Result<Allocation, BackendError> {
    let mut alloc = planned_allocation(backend, rec, frame)?;
    if let Err(e) = backend.execute(rec) {
        let _ = alloc.free(backend);
        return Err(e);
    }
    Ok(alloc)
}

/// Checks every buffer that `rec` creates or uploads against the device's largest buffer
/// (its allocation limit or, on wgpu and Vulkan, its storage-binding size, whichever is
/// smaller) and returns them, before `rec` is executed. `frame` is the image size: when
/// a per-pixel buffer is too large, the error says which frame size would fit.
pub fn planned_allocation(
    backend: &dyn Backend,
    rec: &Recording,
    frame: Option<(u32, u32)>,
) -> Result<Allocation, BackendError> {
    let caps = backend.capabilities();
    let largest = caps.max_buffer_bytes;
    let mut a = Allocation::default();
    for s in &rec.steps {
        let (id, b, label) = match s {
            Step::Create { id, bytes, label } => (*id, *bytes, *label),
            Step::Upload { id, data, label } => (*id, data.len() as u64, *label),
            _ => continue,
        };
        if b > largest {
            let fit = frame
                .and_then(|(w, h)| fitting_frame(w, h, b, largest))
                .map(|(fw, fh)| format!("; at this aspect ratio a frame of {fw}x{fh} fits"))
                .unwrap_or_default();
            return Err(BackendError::OutOfMemory {
                bytes: b,
                what: format!(
                    "{label}: over the {} backend's {} of {largest} bytes per buffer{fit}",
                    backend.name(),
                    caps.max_buffer_limit
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

/// The largest `w' x h'` of aspect `w : h` whose per-pixel buffer (`bytes` for `w x h`
/// pixels, so `bytes / (w h)` per pixel) fits in `limit`; None when `bytes` is not a
/// per-pixel buffer of that frame or nothing fits.
pub fn fitting_frame(w: u32, h: u32, bytes: u64, limit: u64) -> Option<(u32, u32)> {
    let pixels = w as u64 * h as u64;
    if pixels == 0 || !bytes.is_multiple_of(pixels) {
        return None;
    }
    let per_pixel = bytes / pixels;
    let max_pixels = limit / per_pixel;
    let scale = (max_pixels as f64 / pixels as f64).sqrt();
    let (mut fw, mut fh) = (
        (w as f64 * scale).floor() as u64,
        (h as f64 * scale).floor() as u64,
    );
    while fw * fh > max_pixels && fw > 0 && fh > 0 {
        // rounding of the square root: shrink until it fits
        fw -= 1;
        fh = fh.min(fw * h as u64 / w as u64 + 1);
    }
    (fw > 0 && fh > 0).then_some((fw as u32, fh as u32))
}

/// Default photons per batch (Sspm, CausticMap, AdaptiveCaustics): 2^22, a 2048^2 grid in
/// one batch (a 128 MiB photon buffer). Fewer, larger batches keep a large GPU busy: on
/// an H200, Sspm's trace of 2048^2 photons took 4.33 ms in four batches of 2^20 and 3.31
/// ms in one on Vulkan (`sphere`; 2.85 and 2.20 on `cornell`; H200, 2026-12-02,
/// `docs/performance.md`, "What the kernels do for speed").
pub const DEFAULT_PHOTONS_PER_BATCH: u32 = 1 << 22;

/// Bytes of one stored photon ([`crate::device::layout::Photon`]).
const PHOTON_BYTES: u64 = 32;

/// Photons a batch holds: the `wanted` photons (a light's or a plane's), at most the
/// `setting` (`max_photons_per_batch`) and at most what the device's largest buffer holds
/// (`max_buffer_bytes`: lavapipe binds 128 MiB), at least 1. Batches only split the work:
/// the deposited sums are exact and order-free, so the image does not depend on it.
pub fn photons_per_batch(wanted: u64, setting: u32, max_buffer_bytes: u64) -> u32 {
    wanted
        .min(setting as u64)
        .min(max_buffer_bytes / PHOTON_BYTES)
        .max(1) as u32
}

#[cfg(test)]
mod tests {
    use super::fitting_frame;

    #[test]
    fn fitting_frame_fits_and_keeps_the_aspect() {
        // lavapipe: 128 MiB per binding, 64-byte G-buffer texels at 2560x1440
        let (w, h) = fitting_frame(2560, 1440, 2560 * 1440 * 64, 128 << 20).unwrap();
        assert!(w as u64 * h as u64 * 64 <= 128 << 20);
        assert!((w as f64 / h as f64 - 16.0 / 9.0).abs() < 0.01);
        assert!(w >= 1900, "{w}x{h}");
        assert_eq!(fitting_frame(10, 10, 101, 50), None);
    }
}
