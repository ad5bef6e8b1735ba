//! Registry kernels to OpenCL dispatches: argument lists (in the order of each kernel's
//! signature in `kernels/<kernel>.cl`), bounds checks of every buffer against the launch
//! size (so a wrong argument is an error, never an out-of-bounds device write), and the
//! launch itself with a profiling event.

use crate::error::cl_error;
use crate::OpenClBackend;
use caustica_core::backend::BackendError;
use caustica_core::gpu::{DepositTexel, GBufferTexel, Photon};
use caustica_core::recording::{Buf, Kernel, ResourceId, SceneArgs};
use ocl::core::{self, ArgVal, Event, Mem, MemFlags};
use std::mem::size_of;

/// Registry kernels implemented here.
pub const IMPLEMENTED: &[&str] = &[
    "prepare_scene",
    "primary_gbuffer",
    "direct_light",
    "trace_photons",
    "deposit_screen",
    "resolve_caustics",
    "tile_hit_distance",
    "bilateral_gather",
    "composite",
];

/// Threads per work-group (core's registry: 64 for every kernel).
const WORKGROUP: usize = 64;

const GBUFFER_TEXEL: u64 = size_of::<GBufferTexel>() as u64;
const IMAGE_TEXEL: u64 = 16;
const MAP_TEXEL: u64 = size_of::<DepositTexel>() as u64;
const PHOTON: u64 = size_of::<Photon>() as u64;

enum Arg {
    Buffer(ResourceId),
    /// A parameter block uploaded for this launch.
    Params(Mem),
    U32(u32),
}

struct Launch<'a> {
    backend: &'a OpenClBackend,
    args: Vec<Arg>,
}

impl<'a> Launch<'a> {
    fn new(backend: &'a OpenClBackend) -> Self {
        Launch {
            backend,
            args: Vec::new(),
        }
    }

    /// A buffer argument that must hold at least `need` bytes.
    fn buf<T>(&mut self, b: Buf<T>, need: u64, what: &str) -> Result<&mut Self, BackendError> {
        let d = self.backend.buffer(b.id)?;
        if d.bytes < need.max(b.bytes()) {
            return Err(BackendError::BadArgument(format!(
                "{what}: buffer {:?} holds {} bytes, the launch needs {}",
                b.id,
                d.bytes,
                need.max(b.bytes())
            )));
        }
        self.args.push(Arg::Buffer(b.id));
        Ok(self)
    }

    fn u32(&mut self, v: u32) -> &mut Self {
        self.args.push(Arg::U32(v));
        self
    }

    fn scene(&mut self, s: &SceneArgs) -> Result<&mut Self, BackendError> {
        if !s.bvh_nodes.len.is_multiple_of(5) {
            return Err(BackendError::BadArgument(
                "BVH node buffer is not a whole number of 80-byte nodes".into(),
            ));
        }
        self.buf(s.vertices, 0, "vertices")?;
        self.buf(s.triangles, 0, "triangles")?;
        self.buf(s.materials, 0, "materials")?;
        self.buf(s.lights, 0, "lights")?;
        self.buf(s.bvh_nodes, 0, "bvh nodes")?;
        Ok(self.u32(s.bvh_nodes.len / 5))
    }

    /// A parameter block, uploaded into a small read-only buffer.
    fn params<T: bytemuck::Pod>(&mut self, p: &T) -> Result<&mut Self, BackendError> {
        let bytes = bytemuck::bytes_of(p);
        let mem = unsafe {
            core::create_buffer(
                &self.backend.state.context,
                MemFlags::READ_ONLY | MemFlags::COPY_HOST_PTR,
                bytes.len(),
                Some(bytes),
            )
        }
        .map_err(cl_error("uploading kernel parameters"))?;
        self.args.push(Arg::Params(mem));
        Ok(self)
    }

    /// Launches `threads` work-items (rounded up to whole work-groups; kernels skip the
    /// excess). Parameter buffers may be released right after: OpenCL keeps a memory
    /// object alive until the commands using it have finished.
    fn enqueue(&self, name: &'static str, threads: u64) -> Result<Option<Event>, BackendError> {
        if threads == 0 {
            return Ok(None);
        }
        let kernel = core::create_kernel(&self.backend.state.program, name)
            .map_err(cl_error("creating a kernel"))?;
        for (index, a) in self.args.iter().enumerate() {
            let v = match a {
                Arg::Buffer(id) => ArgVal::mem(&self.backend.buffer(*id)?.mem),
                Arg::Params(m) => ArgVal::mem(m),
                Arg::U32(x) => ArgVal::scalar(x),
            };
            core::set_kernel_arg(&kernel, index as u32, v)
                .map_err(cl_error("setting a kernel argument"))?;
        }
        let global = usize::try_from(threads)
            .ok()
            .and_then(|t| t.checked_next_multiple_of(WORKGROUP))
            .ok_or_else(|| BackendError::BadArgument(format!("{name}: {threads} threads")))?;
        let mut event = Event::null();
        unsafe {
            core::enqueue_kernel(
                &self.backend.queue,
                &kernel,
                1,
                None,
                &[global, 1, 1],
                Some([WORKGROUP, 1, 1]),
                None::<Event>,
                Some(&mut event),
            )
        }
        .map_err(cl_error(name))?;
        Ok(Some(event))
    }
}

fn texels(w: u32, h: u32) -> u64 {
    w as u64 * h as u64
}

/// Enqueues one registry kernel; returns its profiling event (`None` if it did no work).
pub fn run(b: &OpenClBackend, k: &Kernel) -> Result<Option<Event>, BackendError> {
    let mut l = Launch::new(b);
    match k {
        Kernel::PrepareScene { scene } => {
            // The node array is traversed as uploaded; only its shape is checked.
            l.scene(scene)?;
            Ok(None)
        }
        Kernel::PrimaryGbuffer {
            scene,
            camera,
            gbuffer,
        } => {
            let n = texels(camera.width, camera.height);
            l.scene(scene)?
                .params(camera)?
                .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")?;
            l.enqueue("primary_gbuffer", n)
        }
        Kernel::DirectLight {
            scene,
            params,
            gbuffer,
            out,
        } => {
            let n = texels(params.camera.width, params.camera.height);
            if params.max_specular_depth > caustica_core::sspm::MAX_SPECULAR_DEPTH {
                return Err(BackendError::BadArgument(format!(
                    "direct_light: max_specular_depth {} exceeds {}",
                    params.max_specular_depth,
                    caustica_core::sspm::MAX_SPECULAR_DEPTH
                )));
            }
            if params.light_count > scene.lights.len {
                return Err(BackendError::BadArgument(
                    "direct_light: light_count exceeds the light buffer".into(),
                ));
            }
            l.scene(scene)?
                .params(params)?
                .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")?
                .buf(*out, n * IMAGE_TEXEL, "direct image")?;
            l.enqueue("direct_light", n)
        }
        Kernel::TracePhotons {
            scene,
            params,
            photons,
            photon_count,
            counters,
        } => {
            if params.count > photons.len {
                return Err(BackendError::BadArgument(format!(
                    "photon buffer holds {} photons, the batch traces {}",
                    photons.len, params.count
                )));
            }
            if params.light >= scene.lights.len {
                return Err(BackendError::BadArgument(
                    "trace_photons: light index out of range".into(),
                ));
            }
            l.scene(scene)?
                .params(params)?
                .buf(*photons, 0, "photons")?
                .u32(photons.len)
                .buf(*photon_count, 4, "photon count")?
                .buf(
                    *counters,
                    4 * caustica_core::gpu::counter::WORDS as u64,
                    "counters",
                )?;
            l.enqueue("trace_photons", params.count as u64)
        }
        Kernel::DepositScreen {
            params,
            gbuffer,
            photons,
            photon_count,
            counters,
            photon_map,
        } => {
            let n = texels(params.camera.width, params.camera.height);
            l.params(params)?
                .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")?
                .buf(*photons, photons.len as u64 * PHOTON, "photons")?
                .u32(photons.len)
                .buf(*photon_count, 4, "photon count")?
                .buf(
                    *counters,
                    4 * caustica_core::gpu::counter::WORDS as u64,
                    "counters",
                )?
                .buf(*photon_map, n * MAP_TEXEL, "photon map")?;
            // One work-item per photon slot; the kernel reads how many are filled.
            l.enqueue("deposit_screen", photons.len as u64)
        }
        Kernel::ResolveCaustics {
            params,
            gbuffer,
            photon_map,
            out,
        } => {
            let n = texels(params.camera.width, params.camera.height);
            l.params(params)?
                .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")?
                .buf(*photon_map, n * MAP_TEXEL, "photon map")?
                .buf(*out, n * IMAGE_TEXEL, "caustic image")?;
            l.enqueue("resolve_caustics", n)
        }
        Kernel::TileHitDistance {
            params,
            photon_map,
            tiles,
        } => {
            let n = texels(params.camera.width, params.camera.height);
            let ts = params.tile_size.max(1);
            let t = texels(
                params.camera.width.div_ceil(ts),
                params.camera.height.div_ceil(ts),
            );
            if params.tile_size == 0 {
                return Err(BackendError::BadArgument("tile_size is 0".into()));
            }
            l.params(params)?
                .buf(*photon_map, n * MAP_TEXEL, "photon map")?
                .buf(*tiles, t * 4, "tiles")?;
            l.enqueue("tile_hit_distance", t)
        }
        Kernel::BilateralGather {
            params,
            gbuffer,
            tiles,
            input,
            out,
        } => {
            let n = texels(params.camera.width, params.camera.height);
            let ts = params.tile_size.max(1);
            let t = texels(
                params.camera.width.div_ceil(ts),
                params.camera.height.div_ceil(ts),
            );
            if params.tile_size == 0 {
                return Err(BackendError::BadArgument("tile_size is 0".into()));
            }
            l.params(params)?
                .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")?
                .buf(*tiles, t * 4, "tiles")?
                .buf(*input, n * IMAGE_TEXEL, "input image")?
                .buf(*out, n * IMAGE_TEXEL, "output image")?;
            l.enqueue("bilateral_gather", n)
        }
        Kernel::Composite {
            direct,
            caustics,
            out,
        } => {
            let n = out.len as u64;
            l.u32(out.len)
                .buf(*direct, n * IMAGE_TEXEL, "direct image")?
                .buf(*caustics, n * IMAGE_TEXEL, "caustic image")?
                .buf(*out, n * IMAGE_TEXEL, "composite image")?;
            l.enqueue("composite", n)
        }
    }
}
