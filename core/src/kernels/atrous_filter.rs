//! `atrous_filter`: one iteration of the edge-avoiding A-Trous wavelet filter with
//! variance clipping of its detail coefficients (Smal 2019, section 24.4.2, Eqs. 14-18), a
//! pass any technique with a per-pixel estimate can opt into.

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{GBufferPlanes, ImageBuf};
use crate::device::layout::AtrousParams;

/// Per receiver pixel `P`: `s_(i+1)(P) = sum_Q h(Q) w(P, Q) s_i(Q) / sum_Q h(Q) w(P, Q)` over
/// the 5x5 taps `Q` spaced `2^i` (`math::irradiance_filter::ATROUS_TAPS`; `w = w_z w_n`,
/// non-receivers skipped), its detail coefficient `d_i = s_(i+1) - s_i` clipped to `b_i`
/// (`clip_sigmas` standard deviations of the taps' `s_i`, weighted alike) and summed into
/// `details` (iteration 0 starts the sum). `out` is `s_(i+1)`, or on the last iteration
/// `E_final = s_n - sum_i clamp(d_i, -b_i, b_i)` (Eq. 18). Non-receivers pass `s_i`
/// through. The alpha channel is `s_i`'s. Iteration 0 reads the taps' depths, normals and
/// receiver flags from the G-buffer and writes every pixel's edge texel
/// (`math::density_gather::edge_texel`, the G-buffer's own bits); the later iterations
/// read the edge texels instead, one 16-byte texel a tap for three G-buffer planes.
#[derive(Clone, Copy, Debug)]
pub struct AtrousFilter {
    /// The iteration, its constants and the image size.
    pub params: AtrousParams,
    /// The frame's G-buffer (depth, normal, receiver flag).
    pub gbuffer: GBufferPlanes,
    /// `s_i`.
    pub input: ImageBuf,
    /// The running sum of clipped detail coefficients (rgb).
    pub details: ImageBuf,
    /// `s_(i+1)`, or `E_final` on the last iteration.
    pub out: ImageBuf,
    /// Edge texels: written by iteration 0, read by the later ones.
    pub edge: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer3", Read),
    bind("input", Read),
    bind("details", ReadWrite),
    bind("out", ReadWrite),
    bind("edge", ReadWrite),
];

impl KernelDecl for AtrousFilter {
    const INFO: KernelInfo = KernelInfo::compute("atrous_filter", BINDINGS, "all (opt-in)");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        if self.params.iteration > 12 {
            return Err(BackendError::BadArgument(
                "atrous_filter: at most 13 iterations (taps 2^12 pixels apart)".into(),
            ));
        }
        let n = texels(self.params.camera.width, self.params.camera.height);
        let img = n * bytes::IMAGE_TEXEL;
        a.params("params", &self.params)?
            .gather_gbuffer(&self.gbuffer, n)?
            .buf("input", self.input, img)?
            .buf("details", self.details, img)?
            .buf("out", self.out, img)?
            .buf("edge", self.edge, img)?;
        Ok(Some(n))
    }
}
