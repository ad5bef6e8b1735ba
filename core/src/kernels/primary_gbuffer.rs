//! `primary_gbuffer`: primary visibility.

use super::{bind, texels, with_scene, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{GBufferPlanes, SceneArgs};
use crate::device::layout::GpuCamera;

/// Primary visibility: one camera ray per pixel (through the pixel centre, world space),
/// writes the G-buffer texel of its first hit (view depth, position, shading normal turned
/// to the camera, albedo, roughness, uv, material; `depth = 0` on a miss).
/// Reads: scene, camera. Writes: `gbuffer` (`camera.width * camera.height` texels).
#[derive(Clone, Copy, Debug)]
pub struct PrimaryGbuffer {
    /// The uploaded scene.
    pub scene: SceneArgs,
    /// The frame's camera.
    pub camera: GpuCamera,
    /// Output: one texel per pixel, row-major from the top-left.
    pub gbuffer: GBufferPlanes,
}

const BINDINGS: [Binding; 11] = with_scene([
    bind("camera", Params),
    bind("gbuffer0", ReadWrite),
    bind("gbuffer1", ReadWrite),
    bind("gbuffer2", ReadWrite),
    bind("gbuffer3", ReadWrite),
]);

impl KernelDecl for PrimaryGbuffer {
    const INFO: KernelInfo = KernelInfo::traced("primary_gbuffer", &BINDINGS, &[], "all");

    fn scene(&self) -> Option<&SceneArgs> {
        Some(&self.scene)
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let n = texels(self.camera.width, self.camera.height);
        a.scene(&self.scene)?
            .params("camera", &self.camera)?
            .gbuffer(&self.gbuffer, n)?;
        Ok(Some(n))
    }
}
