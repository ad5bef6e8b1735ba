//! The shared temporal and spatial filter passes (Smal 2019, section 24.4) as recorders,
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

/// The A-Trous iterations' scratch: two images the iterations alternate between, the
/// running sum of clipped detail coefficients (Eq. 18) and the edge texels the first
/// iteration writes for the others.
#[derive(Clone, Copy, Debug)]
pub struct AtrousScratch {
    /// Iteration images, alternately.
    pub a: ImageBuf,
    /// See `a`.
    pub b: ImageBuf,
    /// Sum of the clipped details.
    pub details: ImageBuf,
    /// Edge texels (`AtrousFilter::edge`).
    pub edge: ImageBuf,
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
            edge: scratch.edge,
        });
        input = target;
    }
}

/// The temporal blend's own buffers: blended images and edge texels (ping-pong) and the
/// camera they were rendered with.
#[derive(Clone, Copy, Debug)]
pub struct TemporalHistory {
    /// Blended images.
    pub image: PingPong<[f32; 4]>,
    /// Edge texels.
    pub edge: PingPong<[f32; 4]>,
    /// The history's camera.
    pub previous: GpuCamera,
}

/// A technique's opt-in temporal blend and A-Trous iterations over one camera-space image
/// (Sspm's and CausticMap's caustics): their buffers, the image the technique writes its unfiltered
/// result into, the recording, and the history's bookkeeping between frames.
#[derive(Clone, Copy, Debug)]
pub struct FilterChain {
    /// The temporal blend's history (blended images, edge texels) and its camera.
    pub temporal: Option<TemporalHistory>,
    /// The unfiltered image (the technique's result) when a filter runs.
    pub unfiltered: Option<ImageBuf>,
    /// The A-Trous iterations' input (the blend's output with the temporal blend, else
    /// the unfiltered image) and scratch.
    pub atrous: Option<(ImageBuf, AtrousScratch)>,
}

impl FilterChain {
    /// Records the creation of the buffers for `pixels` pixels seen by `camera`: the
    /// temporal blend's history when `temporal`, the A-Trous scratch when `atrous`.
    pub fn create(
        rec: &mut Recording,
        pixels: u32,
        camera: GpuCamera,
        temporal: bool,
        atrous: bool,
    ) -> FilterChain {
        let unfiltered = (temporal || atrous).then(|| rec.create(pixels, "unfiltered image"));
        FilterChain {
            temporal: temporal.then(|| TemporalHistory {
                image: PingPong::create(rec, pixels, "temporal history image"),
                edge: PingPong::create(rec, pixels, "temporal edge history image"),
                previous: camera,
            }),
            unfiltered,
            atrous: atrous.then(|| {
                (
                    // the blend's output; without the blend the iterations read the
                    // unfiltered image itself
                    match unfiltered {
                        Some(u) if !temporal => u,
                        _ => rec.create(pixels, "A-Trous input image"),
                    },
                    AtrousScratch {
                        a: rec.create(pixels, "A-Trous image a"),
                        b: rec.create(pixels, "A-Trous image b"),
                        details: rec.create(pixels, "A-Trous clipped details image"),
                        edge: rec.create(pixels, "A-Trous edge texels"),
                    },
                )
            }),
        }
    }

    /// The image the technique writes its unfiltered result into when the chain's output
    /// is `out`: `out` itself when no filter runs.
    pub fn input(&self, out: ImageBuf) -> ImageBuf {
        self.unfiltered.unwrap_or(out)
    }

    /// Records the blend (from the unfiltered image) and the iterations, the last pass
    /// writing `out`; nothing when no filter runs.
    pub fn record(
        &self,
        rec: &mut Recording,
        camera: GpuCamera,
        gbuffer: GBufferPlanes,
        (iterations, clip_sigmas): (u32, f32),
        out: ImageBuf,
    ) {
        let Some(unfiltered) = self.unfiltered else {
            return;
        };
        let blended = self.atrous.map_or(out, |(input, _)| input);
        let mut next = unfiltered;
        if let Some(t) = &self.temporal {
            let history = History {
                image: &t.image,
                edge: &t.edge,
                previous: t.previous,
            };
            record_temporal_blend(rec, camera, gbuffer, history, unfiltered, blended);
            next = blended;
        }
        if let Some((_, scratch)) = self.atrous {
            record_atrous(
                rec,
                camera,
                gbuffer,
                scratch,
                iterations,
                clip_sigmas,
                next,
                out,
            );
        }
    }

    /// After a frame seen by `camera`: its blend becomes the next frame's history.
    pub fn end_frame(&mut self, camera: GpuCamera) {
        if let Some(t) = &mut self.temporal {
            t.image.swap();
            t.edge.swap();
            t.previous = camera;
        }
    }

    /// Forgets the history (the next frame is not blended).
    pub fn reset(&mut self) {
        if let Some(t) = &mut self.temporal {
            t.image.reset();
            t.edge.reset();
        }
    }
}
