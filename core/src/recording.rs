//! Backend-neutral recordings (DESIGN 3, "core records, backends execute"): typed steps
//! over opaque typed handles. Core builds a [`Recording`], a backend executes it; data
//! stays on the device between steps and recordings until freed, and is read back only
//! through [`crate::backend::Backend::read`].

use crate::gpu::*;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU32, Ordering};

/// Opaque id of a device resource, unique in the process.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ResourceId(pub u32);

static NEXT_ID: AtomicU32 = AtomicU32::new(1);

impl ResourceId {
    fn fresh() -> ResourceId {
        ResourceId(NEXT_ID.fetch_add(1, Ordering::Relaxed))
    }
}

/// Typed handle to a device buffer of `len` elements of `T`.
#[derive(Debug)]
pub struct Buf<T> {
    pub id: ResourceId,
    pub len: u32,
    _t: PhantomData<fn() -> T>,
}

impl<T> Clone for Buf<T> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<T> Copy for Buf<T> {}

impl<T> Buf<T> {
    /// Size in bytes.
    pub fn bytes(&self) -> u64 {
        self.len as u64 * std::mem::size_of::<T>() as u64
    }
}

/// A linear HDR image on the device: `width * height` RGBA f32 texels, row-major from the
/// top-left. Radiance in W/(sr m^2) per channel unless stated otherwise.
pub type ImageBuf = Buf<[f32; 4]>;

/// Scene buffers made by `prepare_scene`.
#[derive(Clone, Copy, Debug)]
pub struct SceneArgs {
    pub vertices: Buf<GpuVertex>,
    pub triangles: Buf<GpuTriangle>,
    pub materials: Buf<GpuMaterial>,
    pub lights: Buf<GpuLight>,
    pub bvh_nodes: Buf<[u32; 4]>,
}

/// One kernel dispatch with its typed arguments. Module docs of each backend's kernel
/// state what it reads and writes; names match [`crate::kernels::KERNELS`].
#[derive(Clone, Debug)]
pub enum Kernel {
    /// Makes the uploaded scene traceable (builds or adopts the acceleration structure).
    PrepareScene { scene: SceneArgs },
    /// Primary visibility: one camera ray per pixel, writes the G-buffer.
    PrimaryGbuffer {
        scene: SceneArgs,
        camera: GpuCamera,
        gbuffer: Buf<GBufferTexel>,
    },
    /// Direct lighting with shadow rays (and specular chains from mirror/glass pixels).
    DirectLight {
        scene: SceneArgs,
        params: DirectParams,
        gbuffer: Buf<GBufferTexel>,
        out: ImageBuf,
    },
    /// Emits and traces photons `params.first .. first + count` of one light; appends
    /// stored photons to `photons` at `photon_count[0]` and adds to `counters`.
    TracePhotons {
        scene: SceneArgs,
        /// The compiled variant to run (the frame plan's; it must cover every material
        /// feature of the scene).
        variant: crate::kernels::TraceVariant,
        params: TraceParams,
        photons: Buf<Photon>,
        photon_count: Buf<u32>,
        counters: Buf<u32>,
    },
    /// Projects the `photon_count[0]` stored photons to screen and adds them in fixed
    /// point to the screen-space photon map.
    DepositScreen {
        params: DepositParams,
        gbuffer: Buf<GBufferTexel>,
        photons: Buf<Photon>,
        photon_count: Buf<u32>,
        counters: Buf<u32>,
        photon_map: Buf<DepositTexel>,
    },
    /// Converts the fixed-point photon map to radiance (seed 000 Eq. 5); `out.a` holds the
    /// mean hit distance of the pixel's photons (0 without photons).
    ResolveCaustics {
        params: DepositParams,
        gbuffer: Buf<GBufferTexel>,
        photon_map: Buf<DepositTexel>,
        out: ImageBuf,
    },
    /// Mean hit distance per `tile_size^2` tile (photon-weighted; 0 for empty tiles).
    TileHitDistance {
        params: GatherParams,
        photon_map: Buf<DepositTexel>,
        tiles: Buf<f32>,
    },
    /// One direction of the separable edge-aware bilateral photon gather.
    BilateralGather {
        params: GatherParams,
        gbuffer: Buf<GBufferTexel>,
        tiles: Buf<f32>,
        input: ImageBuf,
        out: ImageBuf,
    },
    /// `out = direct + caustics` (rgb; a = 1).
    Composite {
        direct: ImageBuf,
        caustics: ImageBuf,
        out: ImageBuf,
    },
}

impl Kernel {
    /// The registry name of this kernel.
    pub fn name(&self) -> &'static str {
        match self {
            Kernel::PrepareScene { .. } => "prepare_scene",
            Kernel::PrimaryGbuffer { .. } => "primary_gbuffer",
            Kernel::DirectLight { .. } => "direct_light",
            Kernel::TracePhotons { .. } => "trace_photons",
            Kernel::DepositScreen { .. } => "deposit_screen",
            Kernel::ResolveCaustics { .. } => "resolve_caustics",
            Kernel::TileHitDistance { .. } => "tile_hit_distance",
            Kernel::BilateralGather { .. } => "bilateral_gather",
            Kernel::Composite { .. } => "composite",
        }
    }
}

/// One step of a recording.
#[derive(Clone, Debug)]
pub enum Step {
    /// Creates a zero-filled buffer of `bytes` bytes.
    Create {
        id: ResourceId,
        bytes: u64,
        label: &'static str,
    },
    /// Creates (or replaces) a buffer holding `data`.
    Upload {
        id: ResourceId,
        data: Vec<u8>,
        label: &'static str,
    },
    /// Fills an existing buffer with zeros.
    Clear { id: ResourceId },
    /// Runs a kernel.
    Kernel(Kernel),
    /// Releases a buffer.
    Free { id: ResourceId },
}

/// An ordered list of steps.
#[derive(Clone, Debug, Default)]
pub struct Recording {
    pub steps: Vec<Step>,
}

impl Recording {
    pub fn new() -> Recording {
        Recording::default()
    }

    /// Records creation of a zeroed buffer of `len` elements.
    pub fn create<T>(&mut self, len: u32, label: &'static str) -> Buf<T> {
        let buf = Buf {
            id: ResourceId::fresh(),
            len,
            _t: PhantomData,
        };
        self.steps.push(Step::Create {
            id: buf.id,
            bytes: buf.bytes(),
            label,
        });
        buf
    }

    /// Records an upload of `data` into a new buffer.
    pub fn upload<T: bytemuck::Pod>(&mut self, data: &[T], label: &'static str) -> Buf<T> {
        let buf = Buf {
            id: ResourceId::fresh(),
            len: data.len() as u32,
            _t: PhantomData,
        };
        self.steps.push(Step::Upload {
            id: buf.id,
            data: bytemuck::cast_slice(data).to_vec(),
            label,
        });
        buf
    }

    pub fn clear<T>(&mut self, buf: Buf<T>) {
        self.steps.push(Step::Clear { id: buf.id });
    }

    pub fn kernel(&mut self, k: Kernel) {
        self.steps.push(Step::Kernel(k));
    }

    pub fn free<T>(&mut self, buf: Buf<T>) {
        self.steps.push(Step::Free { id: buf.id });
    }
}
