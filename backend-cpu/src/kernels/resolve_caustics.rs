//! `resolve_caustics` (Kim 2019 Eq. 5): radiance `L = (albedo / pi) * Phi / A`, where `Phi` is the pixel's summed flux
//! and `A` the surface area the pixel covers (Eq. 4 footprint corrected for obliquity,
//! see `caustica_core::math::footprint`). Alpha: mean hit distance of the pixel's photons.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::gbuffer_pixel_area;
use caustica_core::device::layout::{gbuffer_flags, DepositParams, GBufferView, PhotonMapView};
use caustica_core::kernels::ResolveCaustics;
use caustica_core::math::fixed_point::join_u64;
use rayon::prelude::*;

/// Runs `resolve_caustics` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &ResolveCaustics) -> Result<(), BackendError> {
    let ResolveCaustics {
        params,
        gbuffer,
        photon_map,
        out,
    } = k;
    let g = cpu.gbuffer(gbuffer)?;
    let m = cpu.photon_map(photon_map)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "the raw caustics image")?;
    let img = resolve_caustics(params, g, m);
    cpu.put(out.id, &img)
}

/// Caustic radiance per pixel from the photon map (W/(sr m^2) per channel); alpha: the
/// mean hit distance of the pixel's photons (scene units). Zero where the pixel has no
/// photons or sees no diffuse surface.
pub fn resolve_caustics(
    p: &DepositParams,
    gbuffer: GBufferView,
    map: PhotonMapView,
) -> Vec<[f32; 4]> {
    let cam = &p.camera;
    (0..gbuffer.len().min(map.len()))
        .into_par_iter()
        .map(|i| {
            let (g, t) = (&gbuffer.load_gbuffer(i), &map.load(i));
            let n = join_u64(t.photons);
            if n == 0 || g.flags & gbuffer_flags::RECEIVER == 0 {
                return [0.0; 4];
            }
            let area = gbuffer_pixel_area(cam, i as u32, g);
            let scale = saturate_wide(p.flux_quantum as f64 / (std::f64::consts::PI * area as f64));
            let l = |ch: usize| {
                (saturate_wide(join_u64(t.flux[ch]) as f64 * scale) * g.albedo[ch] as f64) as f32
            };
            let hit =
                (join_u64(t.hit_distance) as f64 * p.hit_distance_quantum as f64 / n as f64) as f32;
            [l(0), l(1), l(2), hit]
        })
        .collect()
}

/// `saturate_radiance` in the resolve's wide (f64) arithmetic: at most f32::MAX, so the
/// product with an albedo in [0, 1] and the cast to f32 stay finite.
fn saturate_wide(x: f64) -> f64 {
    x.min(caustica_core::math::optics::RADIANCE_MAX as f64)
}
