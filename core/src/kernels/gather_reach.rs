//! `gather_reach`: per tile, the largest radius among the pixels that carry flux into a
//! `density_gather` pass (see `crate::math::density_gather`).

use super::{bind, bytes, texels, tiles, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, ImageBuf};
use crate::device::layout::GatherParams;

/// For every `params.tile_size^2` tile: the largest `radius` (pixels) among its pixels
/// whose `input` flux is non-zero in some channel, 0 if none. A `density_gather` pass
/// reads the tiles its taps span and loops only as far as the largest of them reaches:
/// a source farther away has zero weight, a source without flux adds zero, so the pass's
/// sums are bitwise those of the full loop. Row-major tiles.
#[derive(Clone, Copy, Debug)]
pub struct GatherReach {
    /// Gather parameters (camera size, `tile_size`).
    pub params: GatherParams,
    /// Every pixel's radius from `gather_footprint` (pixels).
    pub radius: Buf<f32>,
    /// The pass's input: normalised flux per pixel (W per channel).
    pub input: ImageBuf,
    /// Output: the largest radius of a pixel with flux, per tile (pixels).
    pub tiles: Buf<f32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("radius", Read),
    bind("input", Read),
    bind("tiles", ReadWrite),
];

impl KernelDecl for GatherReach {
    const INFO: KernelInfo = KernelInfo::compute("gather_reach", BINDINGS, "Sspm");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let c = &self.params.camera;
        let n = texels(c.width, c.height);
        let nt = tiles(c.width, c.height, self.params.tile_size)?;
        a.params("params", &self.params)?
            .buf("radius", self.radius, n * 4)?
            .buf("input", self.input, n * bytes::IMAGE_TEXEL)?
            .buf("tiles", self.tiles, nt * 4)?;
        Ok(Some(nt))
    }
}
