//! `bilateral_gather`: one direction of the separable edge-aware photon gather (Kim 2019
//! section 30.3.2).

use super::{bind, bytes, texels, tiles, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf};
use crate::device::layout::GatherParams;

/// One direction (`params.axis` 0: horizontal, 1: vertical) of the separable edge-aware
/// bilateral gather of caustic radiance: radius from the tile's hit distance
/// (`params.roughness` x clamped distance, in pixels at the texel's depth), depth and
/// normal weights from the G-buffer, normalised. Reads `input`, writes `out` (radiance).
#[derive(Clone, Copy, Debug)]
pub struct BilateralGather {
    /// Gather parameters; `axis` picks the pass direction.
    pub params: GatherParams,
    /// The frame's G-buffer (depth, normal, receiver flag).
    pub gbuffer: GBufferPlanes,
    /// Mean hit distance per tile from `tile_hit_distance` (scene units).
    pub tiles: Buf<f32>,
    /// Caustic radiance to filter (W/(sr m^2) per channel); its alpha is passed through.
    pub input: ImageBuf,
    /// Filtered caustic radiance; alpha copied from `input`.
    pub out: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("tiles", Read),
    bind("input", Read),
    bind("out", ReadWrite),
];

impl KernelDecl for BilateralGather {
    const INFO: KernelInfo = KernelInfo::compute("bilateral_gather", BINDINGS, "Sspm");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let c = &self.params.camera;
        let n = texels(c.width, c.height);
        let nt = tiles(c.width, c.height, self.params.tile_size)?;
        a.params("params", &self.params)?
            .gbuffer(&self.gbuffer, n)?
            .buf("tiles", self.tiles, nt * 4)?
            .buf("input", self.input, n * bytes::IMAGE_TEXEL)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?;
        Ok(Some(n))
    }
}
