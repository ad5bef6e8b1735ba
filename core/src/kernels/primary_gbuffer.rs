//! `primary_gbuffer`: primary visibility.

use super::{
    bind, bytes, texels, with_scene, Args, Binding, BindingKind::*, KernelDecl, KernelInfo,
};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, SceneArgs};
use crate::device::layout::{GBufferTexel, GpuCamera};

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
    pub gbuffer: Buf<GBufferTexel>,
}

const BINDINGS: [Binding; 8] = with_scene([bind("camera", Params), bind("gbuffer", ReadWrite)]);

impl KernelDecl for PrimaryGbuffer {
    const INFO: KernelInfo = KernelInfo::traced("primary_gbuffer", &BINDINGS, &[], "all");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let n = texels(self.camera.width, self.camera.height);
        a.scene(&self.scene)?.params("camera", &self.camera)?.buf(
            "gbuffer",
            self.gbuffer,
            n * bytes::GBUFFER_TEXEL,
        )?;
        Ok(Some(n))
    }
}
