//! `prepare_scene`: makes the uploaded scene traceable.

use super::{Args, Binding, KernelDecl, KernelInfo, SCENE_BINDINGS};
use crate::device::error::BackendError;
use crate::device::handle::SceneArgs;

/// Makes the uploaded scene traceable: the CPU adopts the CWBVH nodes, Vulkan has the
/// driver build its BLAS/TLAS from the triangles; OpenCL and wgpu traverse the uploaded
/// node array as it is, so they launch nothing (the node buffer's shape is still checked).
/// Reads: vertices, triangles, materials, lights, BVH nodes. Writes: the backend's
/// acceleration structure.
#[derive(Clone, Copy, Debug)]
pub struct PrepareScene {
    /// The uploaded scene buffers.
    pub scene: SceneArgs,
}

const BINDINGS: &[Binding] = &SCENE_BINDINGS;

impl KernelDecl for PrepareScene {
    const INFO: KernelInfo = KernelInfo {
        name: "prepare_scene",
        bindings: BINDINGS,
        workgroup_size: 1,
        traced: false,
        switches: &[],
        used_by: "all",
    };

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        a.scene(&self.scene)?;
        Ok(None)
    }
}
