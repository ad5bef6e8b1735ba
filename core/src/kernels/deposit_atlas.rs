//! `deposit_atlas`: one photon -> one caustic-atlas texel (seed 001 section 3.2).

use super::{bind, bytes, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, PhotonMapPlanes};
use crate::device::layout::{AtlasParams, AtlasTileTexel, Photon};

/// Adds each of the `photon_count[0]` texture-space photons
/// ([`photon_store::SURFACE`](crate::device::layout::photon_store::SURFACE): uv and
/// triangle) to the atlas texel under its uv on its triangle's receiver tile
/// (`triangle_tiles`, `tiles`; [`crate::math::map_gather::atlas_texel_index`]): flux,
/// hit distance and a count in fixed point (`params.flux_quantum`,
/// `params.hit_distance_quantum`) with the integer atomics of `deposit_screen`, so the
/// sums are exact and order-free. A photon on a triangle without a tile (a receiver the
/// atlas leaves out) is counted as `OFF_SCREEN`; deposited ones as `DEPOSITED`. Every
/// photon, with a tile or not, sets its triangle's bit in `triangle_reach`
/// ([`crate::math::map_gather::triangle_reach_bit`]): CausticMap lays out tiles only for
/// the receivers photons reach.
#[derive(Clone, Copy, Debug)]
pub struct DepositAtlas {
    /// Atlas size, quanta, photon capacity.
    pub params: AtlasParams,
    /// Per scene triangle: its receiver's tile, or [`crate::device::layout::NO_TILE`].
    pub triangle_tiles: Buf<u32>,
    /// The atlas tiles.
    pub tiles: Buf<AtlasTileTexel>,
    /// The batch's stored photons (texture space).
    pub photons: Buf<Photon>,
    /// `[0]`: number of photons in `photons`.
    pub photon_count: Buf<u32>,
    /// Photon counters ([`crate::device::layout::counter`]) the kernel adds to.
    pub counters: Buf<u32>,
    /// One bit per scene triangle ([`crate::math::map_gather::triangle_reach_words`]
    /// words), or-ed with the bits of the photons' triangles.
    pub triangle_reach: Buf<u32>,
    /// The atlas's fixed-point sums, one texel per atlas texel (the planes of a screen
    /// photon map), summed over the frame's batches.
    pub atlas: PhotonMapPlanes,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("triangle_tiles", Read),
    bind("tiles", Read),
    bind("photons", Read),
    bind("photon_capacity", Count),
    bind("photon_count", Read),
    bind("counters", ReadWrite),
    bind("triangle_reach", ReadWrite),
    bind("photon_map0", ReadWrite),
    bind("photon_map1", ReadWrite),
    bind("photon_map2", ReadWrite),
];

impl KernelDecl for DepositAtlas {
    const INFO: KernelInfo = KernelInfo::compute("deposit_atlas", BINDINGS, "CausticMap");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let n = super::texels(self.params.width, self.params.height);
        a.params("params", &self.params)?
            .buf("triangle_tiles", self.triangle_tiles, 0)?
            .buf("tiles", self.tiles, 0)?
            .buf(
                "photons",
                self.photons,
                self.photons.len as u64 * bytes::PHOTON,
            )?
            .count("photon_capacity", self.photons.len)?
            .buf("photon_count", self.photon_count, 4)?
            .buf("counters", self.counters, bytes::COUNTERS)?
            .buf("triangle_reach", self.triangle_reach, 4)?
            .photon_map(&self.atlas, n)?;
        Ok(Some(self.photons.len as u64))
    }
}
