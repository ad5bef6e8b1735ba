//! `shading_normal_correction`: PhotonGi's shading-normal correction (Smal 2019, section
//! 24.4.3, Eq. 20; `crate::math::irradiance_filter::shading_normal_factor`).

use super::{
    bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo,
    DIRECTION_MAP_BINDINGS,
};
use crate::device::error::BackendError;
use crate::device::handle::{GBufferPlanes, ImageBuf, PhotonMapPlanes};
use crate::device::layout::CorrectionParams;

/// Per pixel: the splats' power-weighted mean light direction `w_i` from the direction
/// map (`splat_photons` with `light_direction`;
/// [`crate::math::irradiance_filter::mean_light_direction`]) and Eq. 20's factor
/// `min(max(0, w_i . n_s) / (w_i . n_g + eps), s_max)` with the G-buffer's shading and
/// geometric normals: `out.rgb = input.rgb x factor` (radiance, W/(sr m^2)), `out.a =
/// input.a`. A pixel that is no receiver, got no splat, or whose shading normal does not
/// depart from its geometric one
/// ([`crate::math::irradiance_filter::shading_normal_departs`]) keeps its input.
#[derive(Clone, Copy, Debug)]
pub struct ShadingNormalCorrection {
    /// Image size, `s_max`, `eps`.
    pub params: CorrectionParams,
    /// The frame's G-buffer (receiver flag, shading and geometric normals).
    pub gbuffer: GBufferPlanes,
    /// The splats' light-direction sums (a photon map's layout: flux `w (d + 1) / 2`,
    /// hit distance `w`).
    pub direction_map: PhotonMapPlanes,
    /// The filtered indirect radiance.
    pub input: ImageBuf,
    /// The corrected indirect radiance.
    pub out: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("direction_map0", Read),
    bind("direction_map1", Read),
    bind("direction_map2", Read),
    bind("input", Read),
    bind("out", ReadWrite),
];

impl KernelDecl for ShadingNormalCorrection {
    const INFO: KernelInfo = KernelInfo::compute("shading_normal_correction", BINDINGS, "PhotonGi");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let n = texels(self.params.width, self.params.height);
        a.params("params", &self.params)?
            .gbuffer(&self.gbuffer, n)?
            .named_photon_map(DIRECTION_MAP_BINDINGS, &self.direction_map, n)?
            .buf("input", self.input, n * bytes::IMAGE_TEXEL)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?;
        Ok(Some(n))
    }
}
