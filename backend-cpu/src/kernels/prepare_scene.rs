//! `prepare_scene`: nothing to lay out on the host, the traversal reads the uploaded node
//! buffer in place; only its shape is checked ([`crate::traversal::check_nodes`]).

use crate::traversal;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::kernels::PrepareScene;

/// Runs `prepare_scene` on the host ([`super::run`]'s arm): checks the node buffer.
pub(crate) fn run(cpu: &mut CpuBackend, k: &PrepareScene) -> Result<(), BackendError> {
    let PrepareScene { scene } = k;
    // the traversal reads the node buffer in place: only its shape is checked
    let nodes = cpu
        .get(scene.bvh_nodes.id)?
        .as_slice::<[u32; 4]>(scene.bvh_nodes.len)?;
    traversal::check_nodes(nodes)?;
    Ok(())
}
