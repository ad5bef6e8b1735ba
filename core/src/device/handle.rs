//! Opaque typed handles to device resources (an id plus `PhantomData`, as
//! kajiya's render-graph handles). A [`Buf`] names a buffer a backend holds; core never
//! sees device memory, only these ids.

use crate::device::layout::*;
use std::marker::PhantomData;
use std::sync::atomic::{AtomicU32, Ordering};

/// Opaque id of a device resource, unique in the process.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct ResourceId(pub u32);

static NEXT_ID: AtomicU32 = AtomicU32::new(1);

impl ResourceId {
    pub(crate) fn fresh() -> ResourceId {
        ResourceId(NEXT_ID.fetch_add(1, Ordering::Relaxed))
    }
}

/// Typed handle to a device buffer of `len` elements of `T`.
#[derive(Debug)]
pub struct Buf<T> {
    /// The resource's id, by which the backend holds the buffer.
    pub id: ResourceId,
    /// Number of `T` elements.
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
    /// A handle with a fresh process-unique id (a recording hands it out with the step
    /// that creates the buffer).
    pub(crate) fn fresh(len: u32) -> Buf<T> {
        Buf {
            id: ResourceId::fresh(),
            len,
            _t: PhantomData,
        }
    }

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
    /// Mesh vertices ([`GpuVertex`]).
    pub vertices: Buf<GpuVertex>,
    /// Triangles in BVH leaf order ([`GpuTriangle`]).
    pub triangles: Buf<GpuTriangle>,
    /// Material table ([`GpuMaterial`]).
    pub materials: Buf<GpuMaterial>,
    /// Lights ([`GpuLight`]).
    pub lights: Buf<GpuLight>,
    /// The two-level acceleration structure: 80-byte slots of 5 x `[u32; 4]`
    /// ([`crate::device::acceleration`]: TLAS, instance records, BLASes, object-space
    /// positions).
    pub bvh_nodes: Buf<[u32; 4]>,
    /// The instances' object-space vertices, level after level
    /// ([`crate::device::device_scene::SceneInstances::object_vertices`]), which
    /// `place_vertices` places into `vertices` (no kernel binds it otherwise).
    pub object_vertices: Buf<GpuVertex>,
    /// How many levels (static level and instances) `bvh_nodes` holds: the TLAS capacity
    /// and the records' place follow from it (read by Vulkan's `prepare_scene`).
    pub levels: u32,
}

/// The frame's G-buffer as [`GBUFFER_PLANES`] device buffers of 16 bytes per pixel (see
/// [`GBufferTexel::to_planes`]): kernels bind the planes in order, each a storage buffer
/// no larger than an RGBA f32 image.
#[derive(Clone, Copy, Debug)]
pub struct GBufferPlanes {
    /// Plane `k`: bytes `16k .. 16k + 16` of every pixel's texel.
    pub planes: [Buf<GBufferPlaneTexel>; GBUFFER_PLANES],
}

impl GBufferPlanes {
    /// Texels (pixels) per plane.
    pub fn len(&self) -> u32 {
        self.planes[0].len
    }

    /// Whether the planes hold no texel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Size in bytes of all planes.
    pub fn bytes(&self) -> u64 {
        self.planes.iter().map(|p| p.bytes()).sum()
    }
}

/// The screen photon map as [`DEPOSIT_PLANES`] device buffers of u32 words
/// (`DEPOSIT_PLANE_WORDS[k]` per pixel; see [`deposit_word`]).
#[derive(Clone, Copy, Debug)]
pub struct PhotonMapPlanes {
    /// Plane `k`: words `DEPOSIT_PLANE_FIRST[k] ..` of every pixel's [`DepositTexel`].
    pub planes: [Buf<u32>; DEPOSIT_PLANES],
}

impl PhotonMapPlanes {
    /// Texels (pixels) per plane.
    pub fn len(&self) -> u32 {
        self.planes[0].len / DEPOSIT_PLANE_WORDS[0] as u32
    }

    /// Whether the planes hold no texel.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Size in bytes of all planes.
    pub fn bytes(&self) -> u64 {
        self.planes.iter().map(|p| p.bytes()).sum()
    }
}

impl<T> Buf<T> {
    /// The same buffer seen as elements of `U`, which must have `T`'s size (checked at
    /// compile time): e.g. 32-byte photon slots read as `GiPhoton`s or `Photon`s.
    pub fn reinterpret<U>(self) -> Buf<U> {
        const { assert!(std::mem::size_of::<T>() == std::mem::size_of::<U>()) };
        Buf {
            id: self.id,
            len: self.len,
            _t: PhantomData,
        }
    }
}
