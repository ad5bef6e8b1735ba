//! `caustic_map_lookup`: CausticMap's final pass (Vanderstichelen 2021, section 3.3): camera paths
//! through mirrors and glass read the caustic map of the receiver they end on.

use super::{bind, bytes, with_scene, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, ImageBuf, SceneArgs};
use crate::device::layout::{AtlasTexel, AtlasTileTexel, MapLookupParams};

/// Per pixel (one thread each): the camera ray's specular ray tree (both Fresnel
/// branches, mirrors, Beer-Lambert inside glass; weights below `params.min_weight` cut,
/// at most `params.max_specular_depth` specular surfaces; `direct_light`'s walk), and at
/// every diffuse surface it ends on the caustic radiance `weight * albedo / pi * E(uv)`,
/// `E` the caustic map of that surface's receiver tile averaged over the pixel's footprint
/// rectangle ([`crate::math::map_gather::footprint_extent`],
/// [`crate::math::map_gather::sample_caustic_map`], each texel's flux placed by its
/// photons' centroid; bilinear where the footprint is smaller than a texel). Output: radiance W/(sr m^2),
/// alpha 1; black where the ray meets nothing.
#[derive(Clone, Copy, Debug)]
pub struct CausticMapLookup {
    /// The uploaded scene.
    pub scene: SceneArgs,
    /// Camera, atlas width, specular chain limits.
    pub params: MapLookupParams,
    /// Per scene triangle: its receiver's tile, or [`crate::device::layout::NO_TILE`].
    pub triangle_tiles: Buf<u32>,
    /// The atlas tiles.
    pub tiles: Buf<AtlasTileTexel>,
    /// Per atlas texel: world area and tile.
    pub texels: Buf<AtlasTexel>,
    /// The caustic map (irradiance per atlas texel, `gather_caustic_map`).
    pub map: ImageBuf,
    /// The atlas's centroid sums (`trace_photons`' `centroids`): where in each texel its
    /// photons lie.
    pub centroids: Buf<u32>,
    /// Caustic radiance per pixel.
    pub out: ImageBuf,
}

const BINDINGS: [Binding; 13] = with_scene([
    bind("params", Params),
    bind("triangle_tiles", Read),
    bind("tiles", Read),
    bind("texels", Read),
    bind("map", Read),
    bind("out", ReadWrite),
    bind("centroids", Read),
]);

impl KernelDecl for CausticMapLookup {
    const INFO: KernelInfo = KernelInfo::traced("caustic_map_lookup", &BINDINGS, &[], "CausticMap");

    fn scene(&self) -> Option<&SceneArgs> {
        Some(&self.scene)
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let n = super::texels(p.camera.width, p.camera.height);
        if p.max_specular_depth > super::MAX_SPECULAR_DEPTH {
            return Err(BackendError::BadArgument(format!(
                "caustic_map_lookup: max_specular_depth {} over {}",
                p.max_specular_depth,
                super::MAX_SPECULAR_DEPTH
            )));
        }
        a.scene(&self.scene)?
            .params("params", p)?
            .buf(
                "triangle_tiles",
                self.triangle_tiles,
                self.scene.triangles.len as u64 * 4,
            )?
            .buf("tiles", self.tiles, 0)?
            .buf("texels", self.texels, self.map.len as u64 * 8)?
            .buf("map", self.map, 0)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?
            .buf(
                "centroids",
                self.centroids,
                self.map.len as u64 * 4 * crate::math::map_gather::CENTROID_WORDS as u64,
            )?;
        Ok(Some(n))
    }
}
