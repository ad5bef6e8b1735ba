//! `place_vertices`: an instance's world vertices placed from its object-space vertices,
//! with core's definition (`caustica_core::device::placement::place_vertices`, the
//! four-lane placement a build uses), so the host and this backend agree bit for bit.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::GpuVertex;
use caustica_core::device::placement::place_vertices;
use caustica_core::kernels::PlaceVertices;

/// Runs `place_vertices` on the host ([`super::run`]'s arm): the object run read, placed,
/// and written over the world run (nothing else of `vertices` changes).
pub(crate) fn run(cpu: &mut CpuBackend, k: &PlaceVertices) -> Result<(), BackendError> {
    let p = &k.params;
    let (object_first, world_first, n) = (
        p.object_first as usize,
        p.world_first as usize,
        p.count as usize,
    );
    let local = cpu
        .get(k.object_vertices.id)?
        .as_slice::<GpuVertex>(k.object_vertices.len)?;
    let run = local.get(object_first..object_first + n).ok_or_else(|| {
        BackendError::BadArgument("place_vertices: object run past the object vertices".into())
    })?;
    reserve_temporary::<GpuVertex>(n as u64, "the placed vertices")?;
    let world = place_vertices(p, run);
    let out = cpu
        .get_mut(k.vertices.id)?
        .as_mut_slice::<GpuVertex>(k.vertices.len)?;
    out.get_mut(world_first..world_first + n)
        .ok_or_else(|| {
            BackendError::BadArgument("place_vertices: world run past the vertices".into())
        })?
        .copy_from_slice(&world);
    Ok(())
}
