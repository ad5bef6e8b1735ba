//! `tile_hit_distance`: mean photon hit distance per tile (Kim 2019, section 30.3.2).

use super::{bind, texels, tiles, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, PhotonMapPlanes};
use crate::device::layout::GatherParams;

/// Mean hit distance (scene units) per `params.tile_size^2` tile of the screen-space
/// photon map, photon-weighted; 0 for tiles without photons. The gather's radius follows it.
#[derive(Clone, Copy, Debug)]
pub struct TileHitDistance {
    /// Gather parameters (camera, tile size, hit-distance quantum).
    pub params: GatherParams,
    /// The screen-space photon map.
    pub photon_map: PhotonMapPlanes,
    /// Output: mean hit distance per tile (scene units), row-major.
    pub tiles: Buf<f32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("photon_map0", Read),
    bind("photon_map1", Read),
    bind("photon_map2", Read),
    bind("tiles", ReadWrite),
];

impl KernelDecl for TileHitDistance {
    const INFO: KernelInfo = KernelInfo::compute("tile_hit_distance", BINDINGS, "Sspm");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let c = &self.params.camera;
        let n = texels(c.width, c.height);
        let nt = tiles(c.width, c.height, self.params.tile_size)?;
        a.params("params", &self.params)?
            .photon_map(&self.photon_map, n)?
            .buf("tiles", self.tiles, nt * 4)?;
        Ok(Some(nt))
    }
}
