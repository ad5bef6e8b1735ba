//! Kernel launches, described once for every GPU-style backend: each registry kernel's
//! arguments in the order its OpenCL C signature and WGSL bindings use, the bytes every
//! buffer must hold, the number of threads, and the argument checks (so a wrong argument
//! is an error, never an out-of-bounds device write). A backend maps the arguments to its
//! own API and launches `threads` work-items of 64.

use crate::backend::BackendError;
use crate::gpu::{counter, DepositTexel, GBufferTexel, Photon};
use crate::recording::{Buf, Kernel, ResourceId, SceneArgs};
use std::mem::size_of;

/// One argument of a launch.
#[derive(Clone, Debug, PartialEq)]
pub enum LaunchArg {
    /// A device buffer, bound with its logical size `bytes`; the launch reads or writes
    /// up to `need` bytes of it.
    Buffer {
        id: ResourceId,
        bytes: u64,
        need: u64,
        what: &'static str,
    },
    /// A parameter block (`#[repr(C)]` Pod bytes): a uniform buffer in WGSL, a small
    /// read-only buffer in OpenCL.
    Params(Vec<u8>),
    /// An element count passed as a scalar to OpenCL kernels; WGSL derives it with
    /// `arrayLength` of the matching buffer, so wgpu skips it.
    Count(u32),
}

/// A kernel launch: `threads` work-items (kernels skip the excess of whole groups).
#[derive(Clone, Debug, PartialEq)]
pub struct Launch {
    pub kernel: &'static str,
    /// Compiled switches of this launch's variant (empty for kernels without variants);
    /// see [`crate::kernels::TraceVariant`].
    pub constants: Vec<(&'static str, bool)>,
    pub threads: u64,
    pub args: Vec<LaunchArg>,
}

impl Launch {
    /// The variant's label (`kernel[NAME=0,...]`), the key of a backend's pipeline cache.
    pub fn variant_label(&self) -> String {
        crate::kernels::variant_label(self.kernel, &self.constants)
    }
}

const GBUFFER_TEXEL: u64 = size_of::<GBufferTexel>() as u64;
const IMAGE_TEXEL: u64 = 16;
const MAP_TEXEL: u64 = size_of::<DepositTexel>() as u64;
const PHOTON: u64 = size_of::<Photon>() as u64;
const COUNTERS: u64 = 4 * counter::WORDS as u64;

fn bad(why: String) -> BackendError {
    BackendError::BadArgument(why)
}

struct Args(Vec<LaunchArg>);

impl Args {
    fn buf<T>(&mut self, b: Buf<T>, need: u64, what: &'static str) -> &mut Self {
        self.0.push(LaunchArg::Buffer {
            id: b.id,
            bytes: b.bytes(),
            need: need.max(b.bytes()),
            what,
        });
        self
    }

    fn params<T: bytemuck::Pod>(&mut self, p: &T) -> &mut Self {
        self.0
            .push(LaunchArg::Params(bytemuck::bytes_of(p).to_vec()));
        self
    }

    fn count(&mut self, n: u32) -> &mut Self {
        self.0.push(LaunchArg::Count(n));
        self
    }

    /// vertices, triangles, materials, lights, BVH nodes, node count.
    fn scene(&mut self, s: &SceneArgs) -> Result<&mut Self, BackendError> {
        if !s.bvh_nodes.len.is_multiple_of(5) {
            return Err(bad(
                "BVH node buffer is not a whole number of 80-byte nodes".into(),
            ));
        }
        Ok(self
            .buf(s.vertices, 0, "vertices")
            .buf(s.triangles, 0, "triangles")
            .buf(s.materials, 0, "materials")
            .buf(s.lights, 0, "lights")
            .buf(s.bvh_nodes, 0, "bvh nodes")
            .count(s.bvh_nodes.len / 5))
    }
}

fn texels(w: u32, h: u32) -> u64 {
    w as u64 * h as u64
}

fn tiles(w: u32, h: u32, tile_size: u32) -> Result<u64, BackendError> {
    if tile_size == 0 {
        return Err(bad("tile_size is 0".into()));
    }
    Ok(texels(w.div_ceil(tile_size), h.div_ceil(tile_size)))
}

impl Kernel {
    /// The launch of this kernel, or `None` for `prepare_scene` (GPU-style backends
    /// traverse the uploaded node array as it is; only its shape is checked).
    pub fn launch(&self) -> Result<Option<Launch>, BackendError> {
        let mut a = Args(Vec::new());
        let mut constants = Vec::new();
        let threads = match self {
            Kernel::PrepareScene { scene } => {
                a.scene(scene)?;
                return Ok(None);
            }
            Kernel::PrimaryGbuffer {
                scene,
                camera,
                gbuffer,
            } => {
                let n = texels(camera.width, camera.height);
                a.scene(scene)?
                    .params(camera)
                    .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer");
                n
            }
            Kernel::DirectLight {
                scene,
                params,
                gbuffer,
                out,
            } => {
                if params.max_specular_depth > crate::sspm::MAX_SPECULAR_DEPTH {
                    return Err(bad(format!(
                        "direct_light: max_specular_depth {} exceeds {}",
                        params.max_specular_depth,
                        crate::sspm::MAX_SPECULAR_DEPTH
                    )));
                }
                if params.light_count > scene.lights.len {
                    return Err(bad(
                        "direct_light: light_count exceeds the light buffer".into()
                    ));
                }
                let n = texels(params.camera.width, params.camera.height);
                a.scene(scene)?
                    .params(params)
                    .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")
                    .buf(*out, n * IMAGE_TEXEL, "direct image");
                n
            }
            Kernel::TracePhotons {
                scene,
                variant,
                params,
                photons,
                photon_count,
                counters,
            } => {
                if params.count > photons.len {
                    return Err(bad(format!(
                        "photon buffer holds {} photons, the batch traces {}",
                        photons.len, params.count
                    )));
                }
                if params.light >= scene.lights.len {
                    return Err(bad("trace_photons: light index out of range".into()));
                }
                a.scene(scene)?
                    .params(params)
                    .buf(*photons, 0, "photons")
                    .count(photons.len)
                    .buf(*photon_count, 4, "photon count")
                    .buf(*counters, COUNTERS, "counters");
                constants = variant.constants().to_vec();
                params.count as u64
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
                a.params(params)
                    .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")
                    .buf(*photons, photons.len as u64 * PHOTON, "photons")
                    .count(photons.len)
                    .buf(*photon_count, 4, "photon count")
                    .buf(*counters, COUNTERS, "counters")
                    .buf(*photon_map, n * MAP_TEXEL, "photon map");
                // one work-item per photon slot; the kernel reads how many are filled
                photons.len as u64
            }
            Kernel::ResolveCaustics {
                params,
                gbuffer,
                photon_map,
                out,
            } => {
                let n = texels(params.camera.width, params.camera.height);
                a.params(params)
                    .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")
                    .buf(*photon_map, n * MAP_TEXEL, "photon map")
                    .buf(*out, n * IMAGE_TEXEL, "caustic image");
                n
            }
            Kernel::TileHitDistance {
                params,
                photon_map,
                tiles: t,
            } => {
                let c = &params.camera;
                let n = texels(c.width, c.height);
                let nt = tiles(c.width, c.height, params.tile_size)?;
                a.params(params)
                    .buf(*photon_map, n * MAP_TEXEL, "photon map")
                    .buf(*t, nt * 4, "tiles");
                nt
            }
            Kernel::BilateralGather {
                params,
                gbuffer,
                tiles: t,
                input,
                out,
            } => {
                let c = &params.camera;
                let n = texels(c.width, c.height);
                let nt = tiles(c.width, c.height, params.tile_size)?;
                a.params(params)
                    .buf(*gbuffer, n * GBUFFER_TEXEL, "gbuffer")
                    .buf(*t, nt * 4, "tiles")
                    .buf(*input, n * IMAGE_TEXEL, "input image")
                    .buf(*out, n * IMAGE_TEXEL, "output image");
                n
            }
            Kernel::Composite {
                direct,
                caustics,
                out,
            } => {
                let n = out.len as u64;
                a.count(out.len)
                    .buf(*direct, n * IMAGE_TEXEL, "direct image")
                    .buf(*caustics, n * IMAGE_TEXEL, "caustic image")
                    .buf(*out, n * IMAGE_TEXEL, "composite image");
                n
            }
        };
        Ok(Some(Launch {
            kernel: self.name(),
            constants,
            threads,
            args: a.0,
        }))
    }
}

/// Registry kernel names (every GPU-style backend implements all of them).
pub fn all_kernel_names() -> Vec<&'static str> {
    crate::kernels::KERNELS.iter().map(|k| k.name).collect()
}

/// Checks that a device buffer of `held` bytes can serve `arg` (a backend calls this with
/// its own buffer sizes).
pub fn check_buffer(arg: &LaunchArg, held: u64) -> Result<(), BackendError> {
    if let LaunchArg::Buffer { id, need, what, .. } = arg {
        if held < *need {
            return Err(bad(format!(
                "{what}: buffer {id:?} holds {held} bytes, the launch needs {need}"
            )));
        }
    }
    Ok(())
}
