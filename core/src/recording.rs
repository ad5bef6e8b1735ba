//! Backend-neutral recordings ("core records, backends execute"): typed steps
//! over opaque typed handles ([`crate::device::handle`]). Core builds a [`Recording`], a
//! backend executes it; data stays on the device between steps and recordings until
//! freed, and is read back only through [`crate::backend::Backend::read`].

use crate::device::device_scene::DeviceScene;
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes, ResourceId, SceneArgs};
use crate::device::launch::{Launch, LaunchArg, ParamPatch};
use crate::device::layout::{
    deposit_to_planes, gbuffer_to_planes, DepositTexel, GBufferTexel, DEPOSIT_PLANE_WORDS,
};
use crate::kernels::{Kernel, PlaceVertices, PrepareScene};

/// A kernel as recorded: its typed arguments and their lowering, done once when it was
/// recorded (an argument error surfaces when the recording is executed).
#[derive(Clone, Debug)]
pub struct RecordedKernel {
    kernel: Kernel,
    lowered: Result<Option<Launch>, BackendError>,
    patches: Vec<ParamPatch>,
}

/// `kernel`'s launch with `patches` (checked against its one parameter block).
fn lower(kernel: &Kernel, patches: &[ParamPatch]) -> Result<Option<Launch>, BackendError> {
    let Some(mut launch) = kernel.launch()? else {
        return match patches.is_empty() {
            true => Ok(None),
            false => Err(BackendError::BadArgument(format!(
                "{}: a kernel that launches nothing takes no parameter patch",
                kernel.name()
            ))),
        };
    };
    if patches.is_empty() {
        return Ok(Some(launch));
    }
    let mut blocks = launch.args.iter().filter_map(|a| match a {
        LaunchArg::Params(p) => Some(p.len()),
        _ => None,
    });
    let (Some(len), None) = (blocks.next(), blocks.next()) else {
        return Err(BackendError::BadArgument(format!(
            "{}: parameter patches need exactly one parameter block",
            kernel.name()
        )));
    };
    if kernel.clone().params_mut().is_none() {
        return Err(BackendError::BadArgument(format!(
            "{}: its parameters cannot come from the device",
            kernel.name()
        )));
    }
    for p in patches {
        p.check_block(len)?;
    }
    launch.patches = patches.to_vec();
    Ok(Some(launch))
}

impl RecordedKernel {
    /// Lowers `kernel` ([`Kernel::launch`]).
    pub fn new(kernel: Kernel) -> RecordedKernel {
        RecordedKernel::patched(kernel, Vec::new())
    }

    /// Lowers `kernel` with parameter words that come from the device ([`ParamPatch`]).
    pub fn patched(kernel: Kernel, patches: Vec<ParamPatch>) -> RecordedKernel {
        let lowered = lower(&kernel, &patches);
        RecordedKernel {
            kernel,
            lowered,
            patches,
        }
    }

    /// The parameter words that come from the device.
    pub fn patches(&self) -> &[ParamPatch] {
        &self.patches
    }

    /// The kernel with its patched parameter words read by `read(src, first word, words)`
    /// (a backend whose buffers are host memory: the CPU), lowered again without patches.
    pub fn with_device_params(
        &self,
        mut read: impl FnMut(ResourceId, u32, u32) -> Result<Vec<u8>, BackendError>,
    ) -> Result<RecordedKernel, BackendError> {
        let mut kernel = self.kernel.clone();
        if let Some(bytes) = kernel.params_mut() {
            for p in &self.patches {
                p.check_block(bytes.len())?;
                let words = read(p.src, p.src_word, p.words)?;
                if words.len() as u64 != p.bytes() {
                    return Err(BackendError::BadArgument(format!(
                        "a parameter patch read {} bytes for {} words",
                        words.len(),
                        p.words
                    )));
                }
                let at = p.offset as usize;
                bytes[at..at + words.len()].copy_from_slice(&words);
            }
        }
        Ok(RecordedKernel::new(kernel))
    }

    /// The kernel's launch (`None` for `prepare_scene`), or why its arguments are bad.
    pub fn launch(&self) -> Result<Option<&Launch>, BackendError> {
        match &self.lowered {
            Ok(l) => Ok(l.as_ref()),
            Err(e) => Err(e.clone()),
        }
    }

    /// The kernel's typed arguments.
    pub fn kernel(&self) -> &Kernel {
        &self.kernel
    }

    /// Changes the kernel's arguments and lowers it again (tools that rewrite recordings,
    /// such as conformance's mutant backends).
    pub fn modify(&mut self, f: impl FnOnce(&mut Kernel)) {
        f(&mut self.kernel);
        self.lowered = lower(&self.kernel, &self.patches);
    }

    /// The registry name of the kernel.
    pub fn name(&self) -> &'static str {
        self.kernel.name()
    }
}

/// A write's bytes, held as 4-byte words (a write's length is a multiple of 4), so that a
/// vector of 4-byte-aligned elements becomes one without a copy
/// ([`Recording::write_owned`]: a deformed instance's vertices, megabytes at a time).
/// Reads as `[u8]`.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct WordBytes(Vec<u32>);

impl WordBytes {
    /// The bytes of `data` (copied; a multiple of 4 bytes long).
    pub fn copied<T: bytemuck::Pod>(data: &[T]) -> WordBytes {
        WordBytes(bytemuck::pod_collect_to_vec(data))
    }

    /// The bytes of `data`, taken over without a copy where its elements are 4-byte
    /// aligned (else copied; a multiple of 4 bytes long).
    pub fn owned<T: bytemuck::Pod>(data: Vec<T>) -> WordBytes {
        match bytemuck::allocation::try_cast_vec::<T, u32>(data) {
            Ok(words) => WordBytes(words),
            Err((_, data)) => WordBytes::copied(&data),
        }
    }
}

impl std::ops::Deref for WordBytes {
    type Target = [u8];

    fn deref(&self) -> &[u8] {
        bytemuck::cast_slice(&self.0)
    }
}

/// Checks a write of `n` elements into `buf` from element `first` on: inside the buffer,
/// in elements a multiple of 4 bytes long.
fn check_write<T>(buf: Buf<T>, first: u32, n: usize, label: &str) -> Result<(), BackendError> {
    if first as u64 + n as u64 > buf.len as u64 || !std::mem::size_of::<T>().is_multiple_of(4) {
        return Err(BackendError::BadArgument(format!(
            "{label}: write of {n} elements at {first} into a buffer of {}",
            buf.len
        )));
    }
    Ok(())
}

/// One step of a recording.
// A kernel step carries its lowered launch inline (a few hundred bytes): recordings hold
// tens of steps, and boxing each kernel would only add an allocation per dispatch.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Debug)]
pub enum Step {
    /// Creates a zero-filled buffer of `bytes` bytes.
    Create {
        /// Handle of the new buffer.
        id: ResourceId,
        /// Its size (bytes).
        bytes: u64,
        /// Its name, for errors, the frame plan and debuggers.
        label: &'static str,
    },
    /// Creates (or replaces) a buffer holding `data`.
    Upload {
        /// Handle of the buffer.
        id: ResourceId,
        /// The bytes it holds afterwards.
        data: Vec<u8>,
        /// Its name, for errors, the frame plan and debuggers.
        label: &'static str,
    },
    /// Writes `data` into an existing buffer from byte `offset` on (the rest of the buffer
    /// unchanged; ordered with the steps around it, as every step is). Offset and length
    /// are multiples of 4.
    Write {
        /// Handle of the buffer.
        id: ResourceId,
        /// First byte written.
        offset: u64,
        /// The bytes written there.
        data: WordBytes,
        /// Its name, for errors and debuggers.
        label: &'static str,
    },
    /// Fills an existing buffer with zeros.
    Clear {
        /// Handle of the buffer.
        id: ResourceId,
    },
    /// Runs a kernel.
    Kernel(RecordedKernel),
    /// Releases a buffer.
    Free {
        /// Handle of the buffer.
        id: ResourceId,
    },
}

/// Labels of the G-buffer's planes (errors and the frame plan name them).
pub const GBUFFER_LABELS: [&str; 4] = [
    "gbuffer plane 0 (position, depth)",
    "gbuffer plane 1 (normal, geometric normal)",
    "gbuffer plane 2 (albedo, material)",
    "gbuffer plane 3 (uv, view distance, flags)",
];

/// Labels of the screen photon map's planes.
pub const PHOTON_MAP_LABELS: [&str; 3] = [
    "screen photon map plane 0 (flux r, g)",
    "screen photon map plane 1 (flux b, hit distance)",
    "screen photon map plane 2 (photons)",
];

/// An ordered list of steps.
#[derive(Clone, Debug, Default)]
pub struct Recording {
    /// The steps, executed in order.
    pub steps: Vec<Step>,
}

impl Recording {
    /// An empty recording.
    pub fn new() -> Recording {
        Recording::default()
    }

    /// Records creation of a zeroed buffer of `len` elements.
    pub fn create<T>(&mut self, len: u32, label: &'static str) -> Buf<T> {
        let buf = Buf::fresh(len);
        self.steps.push(Step::Create {
            id: buf.id,
            bytes: buf.bytes(),
            label,
        });
        buf
    }

    /// How many kernel steps the recording holds (the timestamp pairs a backend reserves).
    pub fn kernel_count(&self) -> u32 {
        self.steps
            .iter()
            .filter(|s| matches!(s, Step::Kernel(_)))
            .count() as u32
    }

    /// Records an upload of `data` into a new buffer.
    pub fn upload<T: bytemuck::Pod>(&mut self, data: &[T], label: &'static str) -> Buf<T> {
        let buf = Buf::fresh(data.len() as u32);
        self.steps.push(Step::Upload {
            id: buf.id,
            data: bytemuck::cast_slice(data).to_vec(),
            label,
        });
        buf
    }

    /// Records an upload of `data` into the existing buffer `buf` (same length: a
    /// per-frame update such as moved lights).
    pub fn update<T: bytemuck::Pod>(
        &mut self,
        buf: Buf<T>,
        data: &[T],
        label: &'static str,
    ) -> Result<(), BackendError> {
        if data.len() as u64 != buf.len as u64 {
            return Err(BackendError::BadArgument(format!(
                "{label}: update of {} elements into a buffer of {}",
                data.len(),
                buf.len
            )));
        }
        self.steps.push(Step::Upload {
            id: buf.id,
            data: bytemuck::cast_slice(data).to_vec(),
            label,
        });
        Ok(())
    }

    /// Records a write of `data` into `buf` from element `first` on (a part of an existing
    /// buffer: moved instances' vertices, the TLAS). Elements must be a multiple of 4
    /// bytes long.
    pub fn write<T: bytemuck::Pod>(
        &mut self,
        buf: Buf<T>,
        first: u32,
        data: &[T],
        label: &'static str,
    ) -> Result<(), BackendError> {
        self.push_write(buf, first, data.len(), label, || WordBytes::copied(data))
    }

    /// Records a write of `data` into `buf` from element `first` on, as
    /// [`Recording::write`] does, taking `data` over without a copy (4-byte-aligned
    /// elements).
    pub fn write_owned<T: bytemuck::Pod>(
        &mut self,
        buf: Buf<T>,
        first: u32,
        data: Vec<T>,
        label: &'static str,
    ) -> Result<(), BackendError> {
        let n = data.len();
        self.push_write(buf, first, n, label, || WordBytes::owned(data))
    }

    /// Checks a write of `n` elements into `buf` from element `first` on and records it
    /// with the bytes `data` makes.
    fn push_write<T: bytemuck::Pod>(
        &mut self,
        buf: Buf<T>,
        first: u32,
        n: usize,
        label: &'static str,
        data: impl FnOnce() -> WordBytes,
    ) -> Result<(), BackendError> {
        check_write(buf, first, n, label)?;
        self.steps.push(Step::Write {
            id: buf.id,
            offset: first as u64 * std::mem::size_of::<T>() as u64,
            data: data(),
            label,
        });
        Ok(())
    }

    /// Records the upload of every scene buffer and the `prepare_scene` kernel.
    pub fn upload_scene(&mut self, ds: &DeviceScene) -> SceneArgs {
        let scene = SceneArgs {
            vertices: self.upload(&ds.vertices, "vertices"),
            triangles: self.upload(&ds.triangles, "triangles"),
            materials: self.upload(&ds.materials, "materials"),
            lights: self.upload(&ds.lights, "lights"),
            bvh_nodes: self.upload(&ds.bvh_nodes, "bvh nodes"),
            object_vertices: self.upload(&ds.instances.object_vertices, "object vertices"),
            levels: ds.instances.levels.len() as u32,
        };
        // the instances' world vertices as a move places them, on the device, so that a
        // moved scene stays bitwise a fresh one where the device rounds otherwise than the
        // host (the vertices uploaded are the host's placement, for the static level)
        for p in ds.instances.placements() {
            self.kernel(PlaceVertices {
                params: p,
                object_vertices: scene.object_vertices,
                vertices: scene.vertices,
            });
        }
        self.kernel(PrepareScene { scene });
        scene
    }

    /// Records a move of instances into the uploaded scene
    /// ([`crate::device::device_scene::InstanceMove`]): `place_vertices` for each moved
    /// instance, the top level written (taken over without a copy) and the
    /// `prepare_scene` that refits the acceleration structure (Vulkan: its TLAS rebuilt in
    /// place).
    pub fn move_instances(
        &mut self,
        m: crate::device::device_scene::InstanceMove,
        scene: &SceneArgs,
    ) -> Result<(), BackendError> {
        // a recording that holds earlier moves not yet run (Sspm's pending updates) keeps
        // only the latest: the same runs are placed again, the top level written again,
        // and one prepare_scene follows
        let superseded = |s: &Step| match s {
            Step::Write {
                id, offset, data, ..
            } => *id == scene.bvh_nodes.id && *offset == 0 && data.len() == m.top_level.len() * 16,
            Step::Kernel(k) => match k.kernel() {
                Kernel::PrepareScene(p) => p.scene.bvh_nodes.id == scene.bvh_nodes.id,
                Kernel::PlaceVertices(p) => {
                    p.vertices.id == scene.vertices.id
                        && m.placements.iter().any(|q| {
                            (q.world_first, q.count) == (p.params.world_first, p.params.count)
                        })
                }
                _ => false,
            },
            _ => false,
        };
        self.steps.retain(|s| !superseded(s));
        for params in m.placements {
            self.kernel(PlaceVertices {
                params,
                object_vertices: scene.object_vertices,
                vertices: scene.vertices,
            });
        }
        self.write_owned(
            scene.bvh_nodes,
            0,
            m.top_level,
            "top-level BVH and instance records",
        )?;
        self.kernel(PrepareScene { scene: *scene });
        Ok(())
    }

    /// Records the writes of an instance update into the uploaded scene: a move
    /// ([`Recording::move_instances`]) or a deformation (its object-space vertices,
    /// triangles, BLAS region and object-space positions, then the move's placement and
    /// writes and the `prepare_scene` after them; Vulkan rebuilds the deformed level's
    /// BLAS, keeping the others). Check it first with [`Recording::check_instance_update`]
    /// where nothing may change on an error.
    pub fn update_instances(
        &mut self,
        u: crate::device::device_scene::InstanceUpdate,
        scene: &SceneArgs,
    ) -> Result<(), BackendError> {
        use crate::device::device_scene::InstanceUpdate;
        match u {
            InstanceUpdate::Moved(m) => self.move_instances(m, scene),
            InstanceUpdate::Deformed(d) => {
                let (first, v) = d.object_vertices;
                self.write_owned(
                    scene.object_vertices,
                    first,
                    v,
                    "deformed instance object vertices",
                )?;
                let (first, t) = d.triangles;
                self.write_owned(scene.triangles, first, t, "deformed instance triangles")?;
                for (first, n) in d.nodes {
                    self.write_owned(
                        scene.bvh_nodes,
                        first,
                        n,
                        "deformed instance BLAS and positions",
                    )?;
                }
                self.move_instances(d.moved, scene)
            }
        }
    }

    /// The error [`Recording::update_instances`] would give for `u`, if any (a write or a
    /// placement out of its buffer), without recording anything.
    pub fn check_instance_update(
        u: &crate::device::device_scene::InstanceUpdate,
        scene: &SceneArgs,
    ) -> Result<(), BackendError> {
        use crate::device::device_scene::InstanceUpdate;
        if let InstanceUpdate::Deformed(d) = u {
            let (first, v) = &d.object_vertices;
            check_write(
                scene.object_vertices,
                *first,
                v.len(),
                "deformed instance object vertices",
            )?;
            let (first, t) = &d.triangles;
            check_write(
                scene.triangles,
                *first,
                t.len(),
                "deformed instance triangles",
            )?;
            for (first, n) in &d.nodes {
                check_write(
                    scene.bvh_nodes,
                    *first,
                    n.len(),
                    "deformed instance BLAS and positions",
                )?;
            }
        }
        let m = u.moved();
        for p in &m.placements {
            let n = p.count as usize;
            check_write(scene.vertices, p.world_first, n, "moved instance vertices")?;
            check_write(
                scene.object_vertices,
                p.object_first,
                n,
                "moved instance object vertices",
            )?;
        }
        check_write(
            scene.bvh_nodes,
            0,
            m.top_level.len(),
            "top-level BVH and instance records",
        )
    }

    /// Records creation of a zeroed G-buffer of `pixels` texels, as its planes.
    pub fn create_gbuffer(&mut self, pixels: u32) -> GBufferPlanes {
        GBufferPlanes {
            planes: GBUFFER_LABELS.map(|label| self.create(pixels, label)),
        }
    }

    /// Records an upload of G-buffer texels into new planes.
    pub fn upload_gbuffer(&mut self, texels: &[GBufferTexel]) -> GBufferPlanes {
        let planes = gbuffer_to_planes(texels);
        GBufferPlanes {
            planes: std::array::from_fn(|k| self.upload(&planes[k], GBUFFER_LABELS[k])),
        }
    }

    /// Records creation of a zeroed screen photon map of `pixels` texels, as its planes.
    pub fn create_photon_map(&mut self, pixels: u32) -> PhotonMapPlanes {
        // at most 4 words a pixel: 4 x 16384^2 (the largest camera) fits a u32 length
        PhotonMapPlanes {
            planes: std::array::from_fn(|k| {
                let words = pixels.saturating_mul(DEPOSIT_PLANE_WORDS[k] as u32);
                self.create(words, PHOTON_MAP_LABELS[k])
            }),
        }
    }

    /// Records an upload of photon-map texels into new planes.
    pub fn upload_photon_map(&mut self, texels: &[DepositTexel]) -> PhotonMapPlanes {
        let planes = deposit_to_planes(texels);
        PhotonMapPlanes {
            planes: std::array::from_fn(|k| self.upload(&planes[k], PHOTON_MAP_LABELS[k])),
        }
    }

    /// Records zero-filling every plane of the photon map.
    pub fn clear_photon_map(&mut self, m: &PhotonMapPlanes) {
        for p in m.planes {
            self.clear(p);
        }
    }

    /// Records zero-filling `buf`.
    pub fn clear<T>(&mut self, buf: Buf<T>) {
        self.steps.push(Step::Clear { id: buf.id });
    }

    /// Records a kernel, lowering it once ([`RecordedKernel`]).
    pub fn kernel(&mut self, k: impl Into<Kernel>) {
        self.steps.push(Step::Kernel(RecordedKernel::new(k.into())));
    }

    /// Records a kernel launch whose parameter words `patches` come from the device
    /// ([`ParamPatch`]: written by earlier steps, copied there before the launch).
    pub fn kernel_patched(&mut self, k: impl Into<Kernel>, patches: Vec<ParamPatch>) {
        self.steps
            .push(Step::Kernel(RecordedKernel::patched(k.into(), patches)));
    }

    /// Records the release of `buf`.
    pub fn free<T>(&mut self, buf: Buf<T>) {
        self.steps.push(Step::Free { id: buf.id });
    }
}
