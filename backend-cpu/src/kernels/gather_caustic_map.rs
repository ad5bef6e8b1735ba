//! `gather_caustic_map` (Vanderstichelen 2021): the flux-keeping N x N gather of the caustic atlas
//! as irradiance. The math is core's `math::map_gather`; this is a loop over it.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    AtlasParams, AtlasTexel, AtlasTileTexel, PhotonMapView, NO_TILE,
};
use caustica_core::kernels::GatherCausticMap;
use caustica_core::math::map_gather::{gather_caustic_texel, join_u64_f32};
use glam::Vec3;
use rayon::prelude::*;

/// Runs `gather_caustic_map` on the host ([`super::run`]'s arm): its buffers read from
/// `cpu`, its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &GatherCausticMap) -> Result<(), BackendError> {
    let GatherCausticMap {
        params,
        texels,
        tiles,
        atlas,
        out,
    } = k;
    let tx = cpu.get(texels.id)?.as_slice(texels.len)?;
    let tl = cpu.get(tiles.id)?.as_slice(tiles.len)?;
    let m = cpu.photon_map(atlas)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "the caustic map")?;
    let img = gather_caustic_map(params, tx, tl, m);
    cpu.put(out.id, &img)
}

/// The flux (W per channel) of atlas texel `i`'s fixed-point sums.
pub fn atlas_flux(map: &PhotonMapView, i: u32, quantum: f32) -> Vec3 {
    let ch = |c: u32| {
        join_u64_f32(
            map.photon_map_word(i, 2 * c),
            map.photon_map_word(i, 2 * c + 1),
        ) * quantum
    };
    Vec3::new(ch(0), ch(1), ch(2))
}

/// The caustic map: irradiance (W/m^2 per channel, alpha 1) per atlas texel.
pub fn gather_caustic_map(
    p: &AtlasParams,
    texels: &[AtlasTexel],
    tiles: &[AtlasTileTexel],
    map: PhotonMapView,
) -> Vec<[f32; 4]> {
    let n = p.width as usize * p.height as usize;
    (0..n as u32)
        .into_par_iter()
        .map(|t| {
            let tile = texels[t as usize][1];
            if tile == NO_TILE || tile as usize >= tiles.len() {
                return [0.0, 0.0, 0.0, 1.0];
            }
            let e = gather_caustic_texel(
                tiles[tile as usize],
                t % p.width,
                t / p.width,
                p.gather_width,
                p.width,
                |q| atlas_flux(&map, q, p.flux_quantum),
                |q| f32::from_bits(texels[q as usize][0]),
            );
            [e.x, e.y, e.z, 1.0]
        })
        .collect()
}
