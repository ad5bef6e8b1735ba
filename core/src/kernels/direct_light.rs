//! `direct_light`: shadow-ray traced direct lighting.

use super::{
    bind, bytes, texels, with_scene, Args, Binding, BindingKind::*, KernelDecl, KernelInfo,
};
use crate::device::error::BackendError;
use crate::device::handle::{GBufferPlanes, ImageBuf, SceneArgs};
use crate::device::layout::{DirectParams, MAX_SPECULAR_DEPTH};

/// Direct lighting with shadow rays at every diffuse G-buffer texel, and specular chains
/// (mirror reflection, Fresnel-weighted reflection and refraction) from mirror and glass
/// pixels up to `params.max_specular_depth`. Reads: scene, G-buffer. Writes: `out`,
/// radiance in W/(sr m^2) per channel, alpha 1.
#[derive(Clone, Copy, Debug)]
pub struct DirectLight {
    /// The uploaded scene.
    pub scene: SceneArgs,
    /// Camera, light count and specular-chain limits.
    pub params: DirectParams,
    /// The frame's G-buffer.
    pub gbuffer: GBufferPlanes,
    /// Direct radiance (W/(sr m^2) per channel), alpha 1.
    pub out: ImageBuf,
}

const BINDINGS: [Binding; 12] = with_scene([
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("out", ReadWrite),
]);

impl KernelDecl for DirectLight {
    const INFO: KernelInfo = KernelInfo::traced("direct_light", &BINDINGS, &[], "all");

    fn scene(&self) -> Option<&SceneArgs> {
        Some(&self.scene)
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        if p.max_specular_depth > MAX_SPECULAR_DEPTH {
            return Err(BackendError::BadArgument(format!(
                "direct_light: max_specular_depth {} exceeds {MAX_SPECULAR_DEPTH}",
                p.max_specular_depth
            )));
        }
        if p.light_count > self.scene.lights.len {
            return Err(BackendError::BadArgument(
                "direct_light: light_count exceeds the light buffer".into(),
            ));
        }
        let n = texels(p.camera.width, p.camera.height);
        a.scene(&self.scene)?
            .params("params", p)?
            .gbuffer(&self.gbuffer, n)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?;
        Ok(Some(n))
    }
}
