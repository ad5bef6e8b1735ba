//! `tile_hit_distance` (Kim 2019, section 30.3.2): the mean hit distance of the photons in
//! each screen tile, from which `bilateral_gather` takes its blur radius
//! ([`super::bilateral_gather`] has the method).

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{GatherParams, PhotonMapView};
use caustica_core::kernels::TileHitDistance;
use caustica_core::math::fixed_point::join_u64;
use rayon::prelude::*;

/// Runs `tile_hit_distance` on the host ([`super::run`]'s arm): its buffers read from
/// `cpu`, its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &TileHitDistance) -> Result<(), BackendError> {
    let TileHitDistance {
        params,
        photon_map,
        tiles,
    } = k;
    let m = cpu.photon_map(photon_map)?;
    reserve_temporary::<f32>(tiles.len as u64, "the hit-distance tiles")?;
    let t = tile_hit_distance(params, m);
    cpu.put(tiles.id, &t)
}

/// Photon-weighted mean hit distance (scene units) per `tile_size^2` tile, row-major; 0 for
/// tiles without photons.
pub fn tile_hit_distance(p: &GatherParams, map: PhotonMapView) -> Vec<f32> {
    let (w, h, ts) = (p.camera.width, p.camera.height, p.tile_size);
    let (tw, th) = (w.div_ceil(ts), h.div_ceil(ts));
    (0..tw * th)
        .into_par_iter()
        .map(|t| {
            let (tx, ty) = (t % tw, t / tw);
            let (mut sum, mut n) = (0u64, 0u64);
            for y in ty * ts..((ty + 1) * ts).min(h) {
                for x in tx * ts..((tx + 1) * ts).min(w) {
                    let m = &map.load((y * w + x) as usize);
                    sum += join_u64(m.hit_distance);
                    n += join_u64(m.photons);
                }
            }
            if n == 0 {
                0.0
            } else {
                (sum as f64 * p.hit_distance_quantum as f64 / n as f64) as f32
            }
        })
        .collect()
}
