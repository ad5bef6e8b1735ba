//! `rsm_importance`: a reflective shadow map's texels and importance pyramid (Smal 2019
//! section 24.2.1; `crate::math::rsm`).

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes};
use crate::device::layout::{GpuLight, RsmParams, RsmTexel};
use crate::math::rsm::{level_count, pyramid_len};

/// Level 0 (`params.level == 0`): from the G-buffer that `primary_gbuffer` rendered with
/// `params.face_camera` (a face of light `params.light`, `side x side`), writes face
/// `params.face`'s RSM texels (`math::rsm::rsm_texel_kind`; leaving flux: arriving flux
/// `I x falloff x dw`, times the albedo on diffuse surfaces) and its importance,
/// `luminance(arriving flux x albedo)`, into level 0 of the face's flat pyramid. Level
/// `k > 0`: the 2x2 sums of level `k - 1` (`math::rsm::pyramid_sum`) of faces `0 ..=
/// params.face` (one launch per level covers every face written so far).
#[derive(Clone, Copy, Debug)]
pub struct RsmImportance {
    /// The face, light, side and level.
    pub params: RsmParams,
    /// The lights (the face's light: intensity, spot falloff).
    pub lights: Buf<GpuLight>,
    /// The face's G-buffer (`side x side`; read at level 0 only, any planes of at least
    /// one texel otherwise).
    pub gbuffer: GBufferPlanes,
    /// Every face's texels, `side^2` per face, face-major.
    pub texels: Buf<RsmTexel>,
    /// Every face's flat pyramid, `pyramid_len(side)` floats per face.
    pub pyramid: Buf<f32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("lights", Read),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("texels", ReadWrite),
    bind("pyramid", ReadWrite),
];

impl KernelDecl for RsmImportance {
    const INFO: KernelInfo = KernelInfo::compute("rsm_importance", BINDINGS, "PhotonGi");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let side = p.side;
        if !side.is_power_of_two() || p.level >= level_count(side) {
            return Err(BackendError::BadArgument(format!(
                "rsm_importance: side {side} must be a power of two and level {} below {}",
                p.level,
                level_count(side)
            )));
        }
        let faces = p.face as u64 + 1;
        let n = texels(side, side);
        let g = if p.level == 0 { n } else { 1 };
        a.params("params", p)?
            .buf("lights", self.lights, (p.light as u64 + 1) * bytes::LIGHT)?
            .gbuffer(&self.gbuffer, g)?
            .buf("texels", self.texels, faces * n * bytes::RSM_TEXEL)?
            .buf(
                "pyramid",
                self.pyramid,
                faces * pyramid_len(side) as u64 * 4,
            )?;
        Ok(Some(if p.level == 0 {
            n
        } else {
            let s = (side >> p.level) as u64;
            faces * s * s
        }))
    }
}
