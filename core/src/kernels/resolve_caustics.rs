//! `resolve_caustics`: fixed-point photon map -> caustic radiance (Kim 2019 Eq. 5).

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{GBufferPlanes, ImageBuf, PhotonMapPlanes};
use crate::device::layout::DepositParams;

/// Converts the fixed-point screen-space photon map to caustic radiance: flux over the
/// pixel's surface area (Kim 2019 Eq. 4-5) times the diffuse BRDF, W/(sr m^2) per
/// channel; `out.a` holds the mean hit distance of the pixel's photons (scene units, 0
/// without photons).
#[derive(Clone, Copy, Debug)]
pub struct ResolveCaustics {
    /// The deposit's parameters (camera, quanta) the photon map was built with.
    pub params: DepositParams,
    /// The frame's G-buffer (receiver flag, depth, normal, albedo).
    pub gbuffer: GBufferPlanes,
    /// The screen-space photon map.
    pub photon_map: PhotonMapPlanes,
    /// Caustic radiance (W/(sr m^2) per channel); alpha: mean hit distance (scene units).
    pub out: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("photon_map0", Read),
    bind("photon_map1", Read),
    bind("photon_map2", Read),
    bind("out", ReadWrite),
];

impl KernelDecl for ResolveCaustics {
    const INFO: KernelInfo = KernelInfo::compute("resolve_caustics", BINDINGS, "Sspm");

    /// Its parameters may come partly from the device ([`crate::device::launch::ParamPatch`]).
    fn params_mut(&mut self) -> Option<&mut [u8]> {
        Some(bytemuck::bytes_of_mut(&mut self.params))
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let n = texels(self.params.camera.width, self.params.camera.height);
        a.params("params", &self.params)?
            .gbuffer(&self.gbuffer, n)?
            .photon_map(&self.photon_map, n)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?;
        Ok(Some(n))
    }
}
