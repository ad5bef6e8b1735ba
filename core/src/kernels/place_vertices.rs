//! `place_vertices`: an instance's world vertices placed on the device from the
//! object-space vertices it keeps (`crate::device::placement`).

use super::{bind, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::Buf;
use crate::device::layout::{GpuVertex, PlacementParams};

/// Per vertex `i < params.count`: `vertices[world_first + i]` = object vertex
/// `object_vertices[object_first + i]` placed by the instance's transform
/// ([`crate::device::placement::place_vertices`], the definition: position through
/// `world_from_object`, normal through the normal matrix and renormalised, +Y where its
/// length's reciprocal is not finite and positive; u and v kept). Positions in scene units,
/// object space in, world space out. Reads: the object vertices. Writes: the run of world
/// vertices, nothing else. Where a device rounds otherwise than the host (WGSL may fuse a
/// product into a sum), a vertex may differ from the host's placement, whose boxes the
/// host keeps, in its last bits: rays meet an instance's triangles at the object-space
/// positions of the node buffer, so these world vertices only shade the hits.
#[derive(Clone, Copy, Debug)]
pub struct PlaceVertices {
    /// The instance's placement and its runs.
    pub params: PlacementParams,
    /// The instances' object-space vertices (the scene's `object_vertices`).
    pub object_vertices: Buf<GpuVertex>,
    /// The scene's world vertices.
    pub vertices: Buf<GpuVertex>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("object_vertices", Read),
    bind("vertices", ReadWrite),
];

impl KernelDecl for PlaceVertices {
    const INFO: KernelInfo = KernelInfo::compute("place_vertices", BINDINGS, "all (instances)");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let vertex = std::mem::size_of::<GpuVertex>() as u64;
        let end = |first: u32, len: u32, what: &str| {
            let end = first as u64 + p.count as u64;
            if end > len as u64 {
                return Err(BackendError::BadArgument(format!(
                    "place_vertices: vertices {first}..{end} of the {what} are past its {len}"
                )));
            }
            Ok(end * vertex)
        };
        let object_end = end(p.object_first, self.object_vertices.len, "object vertices")?;
        let world_end = end(p.world_first, self.vertices.len, "world vertices")?;
        a.params("params", p)?
            .buf("object_vertices", self.object_vertices, object_end)?
            .buf("vertices", self.vertices, world_end)?;
        Ok(Some(p.count as u64))
    }
}
