//! The shared temporal and spatial filter passes (seed 003 section 24.4) as recorders,
//! the same for every technique that opts in (Sspm, PhotonGi): the temporal blend over a
//! reprojected ping-pong history and the A-Trous iterations.

use crate::device::handle::{GBufferPlanes, ImageBuf};
use crate::device::layout::{AtrousParams, GpuCamera, TemporalParams};
use crate::frame::temporal::PingPong;
use crate::kernels::{AtrousFilter, TemporalBlend};
use crate::math::irradiance_filter::FilterConstants;
use crate::recording::Recording;

/// The temporal blend's history: blended images and edge texels (ping-pong, swapped after
/// each frame by the technique) and the camera they were rendered with.
#[derive(Clone, Copy, Debug)]
pub struct History<'a> {
    /// Blended images.
    pub image: &'a PingPong<[f32; 4]>,
    /// Edge texels of the frames the images were blended for.
    pub edge: &'a PingPong<[f32; 4]>,
    /// The history's camera (the reprojection target).
    pub previous: GpuCamera,
}

/// Records `temporal_blend` of `input` with `history` into `out` (Eqs. 10-13), seen from
/// `camera`.
pub fn record_temporal_blend(
    rec: &mut Recording,
    camera: GpuCamera,
    gbuffer: GBufferPlanes,
    history: History,
    input: ImageBuf,
    out: ImageBuf,
) {
    let c = FilterConstants::default();
    rec.kernel(TemporalBlend {
        params: TemporalParams {
            camera,
            previous: history.previous,
            alpha_max: c.alpha_max,
            sigma_z: c.sigma_z,
            sigma_n: c.sigma_n,
            epsilon: c.epsilon,
            history_frames: history.image.frames.min(u32::MAX as u64) as u32,
            _pad: [0; 3],
        },
        gbuffer,
        input,
        history: history.image.history(),
        history_edge: history.edge.history(),
        out,
        next_history: history.image.current(),
        next_edge: history.edge.current(),
    });
}

/// The A-Trous iterations' scratch: two images the iterations alternate between and the
/// running sum of clipped detail coefficients (Eq. 18).
#[derive(Clone, Copy, Debug)]
pub struct AtrousScratch {
    /// Iteration images, alternately.
    pub a: ImageBuf,
    /// See `a`.
    pub b: ImageBuf,
    /// Sum of the clipped details.
    pub details: ImageBuf,
}

/// Records `iterations` A-Trous iterations (Eqs. 14-18) from `input`, the last writing
/// `out`, with detail coefficients clipped at `clip_sigmas` standard deviations.
#[allow(clippy::too_many_arguments)]
pub fn record_atrous(
    rec: &mut Recording,
    camera: GpuCamera,
    gbuffer: GBufferPlanes,
    scratch: AtrousScratch,
    iterations: u32,
    clip_sigmas: f32,
    input: ImageBuf,
    out: ImageBuf,
) {
    let c = FilterConstants::default();
    let mut input = input;
    for i in 0..iterations {
        let target = if i + 1 == iterations {
            out
        } else if i % 2 == 0 {
            scratch.a
        } else {
            scratch.b
        };
        rec.kernel(AtrousFilter {
            params: AtrousParams {
                camera,
                iteration: i,
                last: (i + 1 == iterations) as u32,
                sigma_z: c.sigma_z,
                sigma_n: c.sigma_n,
                epsilon: c.epsilon,
                clip_sigmas,
                _pad: [0; 2],
            },
            gbuffer,
            input,
            details: scratch.details,
            out: target,
        });
        input = target;
    }
}
