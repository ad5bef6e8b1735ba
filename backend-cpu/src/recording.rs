//! The recording interpreter: every step of a [`Recording`] at once, in order (buffer
//! steps on host memory, `memory.rs`), and each kernel run on the backend's thread pool by
//! its module in [`crate::kernels`] (the dispatch is generated from core's kernel list),
//! which hands the kernel's buffers to its function. The views the kernels' modules share
//! are here: the scene ([`SceneView`]), the G-buffer and photon map planes, a photon map
//! as atomics, and the host-memory check of a kernel's temporary result.
//!
//! [`Backend::execute`]: caustica_core::backend::Backend::execute

use crate::kernels;
use crate::memory::Storage;
use crate::traversal::SceneView;
use crate::CpuBackend;
use caustica_core::backend::{BackendError, PassTime};
use caustica_core::device::handle::{GBufferPlanes, PhotonMapPlanes, SceneArgs};
use caustica_core::device::layout::{GBufferView, PhotonMapView};
use caustica_core::kernels::Kernel;
use caustica_core::recording::{Recording, Step};

impl CpuBackend {
    /// [`Backend::execute`]'s body: each step at once, in order; kernels on the backend's
    /// thread pool, timed by the host clock.
    pub(crate) fn execute_recording(
        &mut self,
        recording: &Recording,
    ) -> Result<Vec<PassTime>, BackendError> {
        let mut times = Vec::new();
        for step in &recording.steps {
            match step {
                Step::Create { id, bytes, label } => {
                    self.host.take(*bytes, label)?;
                    let s =
                        Storage::zeroed(*bytes, label).inspect_err(|_| self.host.give(*bytes))?;
                    self.insert_buffer(*id, s);
                }
                Step::Upload { id, data, label } => {
                    let bytes = data.len() as u64;
                    self.host.take(bytes, label)?;
                    let mut s =
                        Storage::zeroed(bytes, label).inspect_err(|_| self.host.give(bytes))?;
                    s.write_all(data)?;
                    self.insert_buffer(*id, s);
                }
                Step::Write {
                    id,
                    offset,
                    data,
                    label,
                } => self.get_mut(*id)?.write_at(label, *offset, data)?,
                Step::Clear { id } => self.get_mut(*id)?.clear(),
                Step::Free { id } => {
                    if let Some(s) = self.buffers.remove(*id) {
                        self.host.give(s.len());
                    }
                }
                Step::Kernel(k) if !k.patches().is_empty() => {
                    // parameter words from the device: read from host memory now, after
                    // every earlier step
                    let patched = k.with_device_params(|id, word, words| {
                        let bytes = self.get(id)?.bytes();
                        let (a, b) = (word as usize * 4, (word as usize + words as usize) * 4);
                        bytes.get(a..b).map(<[u8]>::to_vec).ok_or_else(|| {
                            BackendError::BadArgument(format!(
                                "{}: a parameter patch reads words {word}..+{words} of a \
                                 buffer of {} bytes",
                                k.name(),
                                bytes.len()
                            ))
                        })
                    })?;
                    self.variants.note(&patched)?;
                    times.push(self.run_timed(&patched)?);
                }
                Step::Kernel(k) => {
                    self.variants.note(k)?;
                    times.push(self.run_timed(k)?);
                }
            }
        }
        Ok(times)
    }

    /// Runs kernel `k` on the host: its buffers handed to its function by its module in
    /// [`crate::kernels`] (the dispatch is generated from core's list).
    pub(crate) fn run_kernel(&mut self, k: &Kernel) -> Result<(), BackendError> {
        kernels::run(self, k)
    }

    /// Scene `s`'s buffers as the traversal reads them (the traced kernels).
    pub(crate) fn view(&self, s: &SceneArgs) -> Result<SceneView<'_>, BackendError> {
        Ok(SceneView {
            vertices: self.get(s.vertices.id)?.as_slice(s.vertices.len)?,
            triangles: self.get(s.triangles.id)?.as_slice(s.triangles.len)?,
            materials: self.get(s.materials.id)?.as_slice(s.materials.len)?,
            lights: self.get(s.lights.id)?.as_slice(s.lights.len)?,
            nodes: self.get(s.bvh_nodes.id)?.as_slice(s.bvh_nodes.len)?,
        })
    }

    /// A photon map's planes as the atomics the deposit kernels add to.
    pub(crate) fn map_atomics(
        &self,
        m: &PhotonMapPlanes,
    ) -> Result<kernels::deposit_screen::MapPlanes<'_>, BackendError> {
        let [a, b, c] = m.planes;
        Ok([
            self.get(a.id)?.as_atomic_u64(a.bytes())?,
            self.get(b.id)?.as_atomic_u64(b.bytes())?,
            self.get(c.id)?.as_atomic_u64(c.bytes())?,
        ])
    }

    /// The G-buffer's planes (the kernels read texels through the view).
    pub(crate) fn gbuffer(&self, g: &GBufferPlanes) -> Result<GBufferView<'_>, BackendError> {
        let [a, b, c, d] = g.planes;
        Ok(GBufferView {
            planes: [
                self.get(a.id)?.as_slice(a.len)?,
                self.get(b.id)?.as_slice(b.len)?,
                self.get(c.id)?.as_slice(c.len)?,
                self.get(d.id)?.as_slice(d.len)?,
            ],
        })
    }

    /// The photon map's planes.
    pub(crate) fn photon_map(
        &self,
        m: &PhotonMapPlanes,
    ) -> Result<PhotonMapView<'_>, BackendError> {
        let [a, b, c] = m.planes;
        Ok(PhotonMapView {
            planes: [
                self.get(a.id)?.as_slice(a.len)?,
                self.get(b.id)?.as_slice(b.len)?,
                self.get(c.id)?.as_slice(c.len)?,
            ],
        })
    }
}

/// The CPU kernels build their result in a temporary vector (rayon's `collect`, which
/// aborts when the host cannot give it) before it is copied into the destination buffer:
/// reserve that much first, so that out of host memory is an error. The reservation is
/// released at once (address space only, nothing is touched); the kernel's own
/// allocation then finds the room.
pub(crate) fn reserve_temporary<T>(count: u64, what: &str) -> Result<(), BackendError> {
    let bytes = count.saturating_mul(std::mem::size_of::<T>() as u64);
    let oom = || BackendError::OutOfMemory {
        bytes,
        what: format!("{what} (host memory, the CPU kernel's result)"),
    };
    let n = usize::try_from(bytes).map_err(|_| oom())?;
    let mut probe: Vec<u8> = Vec::new();
    probe.try_reserve_exact(n).map_err(|_| oom())
}
