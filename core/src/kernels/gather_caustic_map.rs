//! `gather_caustic_map`: the caustic map's flux-keeping N x N gather (Vanderstichelen 2021, section
//! 3.1, "Denoising"), or with N = 1 the raw map, as irradiance.

use super::{bind, bytes, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, ImageBuf, PhotonMapPlanes};
use crate::device::layout::{AtlasParams, AtlasTexel, AtlasTileTexel};

/// Per atlas texel (one thread each): the irradiance (W/m^2 per channel; alpha 1) of the
/// flux-keeping `params.gather_width` gather of the atlas's fixed-point flux inside the
/// texel's tile, over the texel's world area
/// ([`crate::math::map_gather::gather_caustic_texel`]); 0 outside tiles and on texels
/// no UV triangle covers.
#[derive(Clone, Copy, Debug)]
pub struct GatherCausticMap {
    /// Atlas size, flux quantum, gather width.
    pub params: AtlasParams,
    /// Per atlas texel: world area and tile.
    pub texels: Buf<AtlasTexel>,
    /// The atlas tiles.
    pub tiles: Buf<AtlasTileTexel>,
    /// The atlas's fixed-point sums (`trace_photons`' atlas deposit).
    pub atlas: PhotonMapPlanes,
    /// The caustic map: irradiance per atlas texel.
    pub out: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("texels", Read),
    bind("tiles", Read),
    bind("photon_map0", Read),
    bind("photon_map1", Read),
    bind("photon_map2", Read),
    bind("out", ReadWrite),
];

impl KernelDecl for GatherCausticMap {
    const INFO: KernelInfo = KernelInfo::compute("gather_caustic_map", BINDINGS, "CausticMap");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let n = super::texels(p.width, p.height);
        if p.gather_width == 0 || p.gather_width.is_multiple_of(2) {
            return Err(BackendError::BadArgument(format!(
                "gather_caustic_map: gather width {} is not odd",
                p.gather_width
            )));
        }
        a.params("params", p)?
            .buf("texels", self.texels, n * 8)?
            .buf("tiles", self.tiles, 0)?
            .photon_map(&self.atlas, n)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?;
        Ok(Some(n))
    }
}
