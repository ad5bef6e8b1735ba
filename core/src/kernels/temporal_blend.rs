//! `temporal_blend`: the temporal accumulation of screen-space estimates (Smal 2019, section
//! 24.4.1, Eqs. 10-13), a pass any technique with a per-pixel estimate can opt into.

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{GBufferPlanes, ImageBuf};
use crate::device::layout::TemporalParams;

/// Per pixel `j` of the frame: the receiver's world point (this frame's G-buffer) is
/// reprojected into `params.previous`'s image, nearest pixel `q`; the history's weight is
/// `alpha = alpha_max w_z w_n` (`math::irradiance_filter::temporal_alpha`), `w_z` comparing
/// the point's depth as the previous camera sees it with the history's depth at `q`
/// (tolerance: half the largest depth step to a neighbouring receiver, the most a
/// nearest-pixel reprojection can be off), `w_n` the two normals; 0 off the previous image,
/// where `q` was no receiver, and without history (`history_frames` 0). `out[j] = (1 -
/// alpha) input[j] + alpha history[q]` (rgb; alpha channel `input`'s) is written to `out`
/// and to `next_history`, and the pixel's edge texel (view depth, normal; depth -1 for a
/// non-receiver) to `next_edge`, for the next frame. `out` may be `input` (each pixel
/// reads only its own input).
#[derive(Clone, Copy, Debug)]
pub struct TemporalBlend {
    /// Cameras and constants.
    pub params: TemporalParams,
    /// This frame's G-buffer.
    pub gbuffer: GBufferPlanes,
    /// This frame's estimate.
    pub input: ImageBuf,
    /// The previous frame's blended estimate.
    pub history: ImageBuf,
    /// The previous frame's edge texels.
    pub history_edge: ImageBuf,
    /// The blended estimate.
    pub out: ImageBuf,
    /// The blended estimate again: the next frame's history.
    pub next_history: ImageBuf,
    /// This frame's edge texels: the next frame's.
    pub next_edge: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("input", Read),
    bind("history", Read),
    bind("history_edge", Read),
    bind("out", ReadWrite),
    bind("next_history", ReadWrite),
    bind("next_edge", ReadWrite),
];

impl KernelDecl for TemporalBlend {
    const INFO: KernelInfo = KernelInfo::compute("temporal_blend", BINDINGS, "all (opt-in)");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let (c, q) = (&self.params.camera, &self.params.previous);
        if (c.width, c.height) != (q.width, q.height) {
            return Err(BackendError::BadArgument(
                "temporal_blend: the history's image size differs (a camera cut resets it)".into(),
            ));
        }
        let n = texels(c.width, c.height);
        let img = n * bytes::IMAGE_TEXEL;
        a.params("params", &self.params)?
            .gbuffer(&self.gbuffer, n)?
            .buf("input", self.input, img)?
            .buf("history", self.history, img)?
            .buf("history_edge", self.history_edge, img)?
            .buf("out", self.out, img)?
            .buf("next_history", self.next_history, img)?
            .buf("next_edge", self.next_edge, img)?;
        Ok(Some(n))
    }
}
