//! `splat_photons`: PhotonGi's ellipsoid splats into the screen (Smal 2019, section 24.3,
//! Eqs. 2-9; `crate::math::photon_splat`).

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes};
use crate::device::layout::{GiPhoton, SplatParams};
use crate::math::gi_photon::screen_tiles;

/// Every stored photon (of `photon_count[0]`) scatters its splat: the kernel of
/// Eqs. 2-8 (ray-length scale, the density scale from its tile's count in
/// `tile_counts`, normal compression, light stretch) around the photon, and every
/// receiver pixel within `params.max_splat_px` of the photon's pixel whose G-buffer
/// point lies inside the ellipsoid and faces the photon's side receives `E = Phi / a`
/// (Eq. 9) times the pixel's surface area, added in flux quanta to the photon map with
/// exact integer atomics (so `resolve_caustics` turns the sum back into `E x albedo /
/// pi`). A splat reaching past `max_splat_px` is clipped there and counted
/// (`counter::SATURATED`); a photon that packs to zero power is skipped. With
/// `params.light_direction` each contribution to a pixel whose shading normal departs from
/// its geometric one ([`crate::math::irradiance_filter::shading_normal_departs`]) also adds
/// its light direction to `direction_map` (Eq. 20's power-weighted `w_i`,
/// [`crate::math::irradiance_filter::light_direction_deposit`]), exactly as the flux;
/// without, `direction_map` (one texel will do) is not touched.
#[derive(Clone, Copy, Debug)]
pub struct SplatPhotons {
    /// Camera, tiles, kernel constants, quanta.
    pub params: SplatParams,
    /// The frame's G-buffer.
    pub gbuffer: GBufferPlanes,
    /// The stored photons (`trace_indirect`'s packed ones).
    pub photons: Buf<GiPhoton>,
    /// `[0]`: stored photons in `photons`.
    pub photon_count: Buf<u32>,
    /// Stored photons per screen tile.
    pub tile_counts: Buf<u32>,
    /// Counters the kernel adds to (`UNDERFLOW`, `SATURATED`, `DEPOSITED`).
    pub counters: Buf<u32>,
    /// The screen photon map the splats add to.
    pub photon_map: PhotonMapPlanes,
    /// The light-direction map (a photon map's layout) the splats add to with
    /// `params.light_direction`.
    pub direction_map: PhotonMapPlanes,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("photons", Read),
    bind("photon_capacity", Count),
    bind("photon_count", Read),
    bind("tile_counts", Read),
    bind("counters", ReadWrite),
    bind("photon_map0", ReadWrite),
    bind("photon_map1", ReadWrite),
    bind("photon_map2", ReadWrite),
    bind("direction_map0", ReadWrite),
    bind("direction_map1", ReadWrite),
    bind("direction_map2", ReadWrite),
];

impl KernelDecl for SplatPhotons {
    const INFO: KernelInfo = KernelInfo::compute("splat_photons", BINDINGS, "PhotonGi");

    /// Its parameters may come partly from the device ([`crate::device::launch::ParamPatch`]).
    fn params_mut(&mut self) -> Option<&mut [u8]> {
        Some(bytemuck::bytes_of_mut(&mut self.params))
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let c = &p.camera;
        let n = texels(c.width, c.height);
        a.params("params", p)?
            .gbuffer(&self.gbuffer, n)?
            .buf(
                "photons",
                self.photons,
                self.photons.len as u64 * bytes::GI_PHOTON,
            )?
            .count("photon_capacity", self.photons.len)?
            .buf("photon_count", self.photon_count, 4)?
            .buf(
                "tile_counts",
                self.tile_counts,
                screen_tiles(c.width, c.height, p.tile_size) as u64 * 4,
            )?
            .buf("counters", self.counters, bytes::COUNTERS)?
            .photon_map(&self.photon_map, n)?
            .named_photon_map(
                super::DIRECTION_MAP_BINDINGS,
                &self.direction_map,
                if p.light_direction != 0 { n } else { 1 },
            )?;
        Ok(Some(self.photons.len as u64))
    }
}
