//! `sample_rsm`: photons from a light's reflective shadow maps by hierarchical warping
//! (Smal 2019, section 24.2.1, Figure 24-3; `crate::math::rsm::warp_rsm`).

use super::{bind, bytes, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::Buf;
use crate::device::layout::{GpuLight, RsmParams, RsmPhoton, RsmTexel};
use crate::math::rsm::pyramid_len;

/// Sample `i < params.sample_count` of light `params.light`: point `i` of the rotated
/// Hammersley set (`math::rsm::hammersley`, rotation from `params.seed`) is warped to a
/// texel of the light's faces `params.face ..` `+ face_count` with probability `P`; the
/// photon written to slot `params.first_sample + i` leaves that texel's point in a
/// cosine-distributed direction (from the warp's leftover sample) with flux `leaving / (P
/// N)` (`N = sample_count`), or, from a specular texel, starts at the light towards the
/// point with flux `arriving / (P N)`. A light whose maps hold no importance writes
/// photons of zero flux.
#[derive(Clone, Copy, Debug)]
pub struct SampleRsm {
    /// The light, its faces, its samples and the seed.
    pub params: RsmParams,
    /// The lights (the light's position).
    pub lights: Buf<GpuLight>,
    /// Every face's texels (`rsm_importance`).
    pub texels: Buf<RsmTexel>,
    /// Every face's flat pyramid (`rsm_importance`, all levels).
    pub pyramid: Buf<f32>,
    /// Output: the photons, at `params.first_sample ..`.
    pub photons: Buf<RsmPhoton>,
    /// Where the launch's shape is on the device (a `dispatch_args` record of the live
    /// sample count; `params.sample_count` is then the bound and the kernel's count comes
    /// from the device too, [`crate::device::launch::ParamPatch`]); `None`: a direct
    /// launch of `params.sample_count` threads.
    pub dispatch: Option<super::DispatchRecord>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("lights", Read),
    bind("texels", Read),
    bind("pyramid", Read),
    bind("photons", ReadWrite),
];

impl KernelDecl for SampleRsm {
    const INFO: KernelInfo = KernelInfo::compute("sample_rsm", BINDINGS, "PhotonGi");

    /// Its parameters may come partly from the device ([`crate::device::launch::ParamPatch`]).
    fn params_mut(&mut self) -> Option<&mut [u8]> {
        Some(bytemuck::bytes_of_mut(&mut self.params))
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        if !p.side.is_power_of_two() || p.face_count == 0 || p.face_count > 6 {
            return Err(BackendError::BadArgument(format!(
                "sample_rsm: side {} must be a power of two, faces {} in 1..=6",
                p.side, p.face_count
            )));
        }
        let faces = (p.face + p.face_count) as u64;
        let n = p.side as u64 * p.side as u64;
        a.params("params", p)?
            .buf("lights", self.lights, (p.light as u64 + 1) * bytes::LIGHT)?
            .buf("texels", self.texels, faces * n * bytes::RSM_TEXEL)?
            .buf(
                "pyramid",
                self.pyramid,
                faces * pyramid_len(p.side) as u64 * 4,
            )?
            .buf(
                "photons",
                self.photons,
                (p.first_sample as u64 + p.sample_count as u64) * bytes::RSM_PHOTON,
            )?;
        a.indirect(self.dispatch)?;
        Ok(Some(p.sample_count as u64))
    }
}
