//! `shading_normal_correction` (PhotonGi, Smal 2019 Eq. 20): the splatted irradiance
//! corrected for smooth shading normals. Method and sources in
//! `caustica_core::math::irradiance_filter` and the kernel's declaration.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{gbuffer_flags, CorrectionParams, GBufferView, PhotonMapView};
use caustica_core::kernels::ShadingNormalCorrection;
use caustica_core::math::irradiance_filter::{
    mean_light_direction, shading_normal_departs, shading_normal_factor,
};
use caustica_core::math::map_gather::join_u64_f32;
use caustica_core::math::packing::unpack_unit_vector;
use glam::Vec3;
use rayon::prelude::*;

/// Runs `shading_normal_correction` on the host ([`super::run`]'s arm): its buffers read
/// from `cpu`, its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &ShadingNormalCorrection) -> Result<(), BackendError> {
    let ShadingNormalCorrection {
        params,
        gbuffer,
        direction_map,
        input,
        out,
    } = k;
    let g = cpu.gbuffer(gbuffer)?;
    let d = cpu.photon_map(direction_map)?;
    let i = cpu.get(input.id)?.as_slice(input.len)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "the shading-normal correction")?;
    let img = shading_normal_correction(params, g, d, i);
    cpu.put(out.id, &img)
}

/// `shading_normal_correction` (Smal 2019, Eq. 20): per receiver pixel with splats, the input
/// times `shading_normal_factor(w_i, n_s, n_g, s_max, eps)` with `w_i` the direction
/// map's mean light direction; other pixels keep the input.
pub fn shading_normal_correction(
    p: &CorrectionParams,
    g: GBufferView,
    directions: PhotonMapView,
    input: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    (0..(p.width as usize * p.height as usize))
        .into_par_iter()
        .map(|i| {
            let v = input[i];
            let t = g.load_gbuffer(i);
            let d = directions.load(i);
            let w = join_u64_f32(d.hit_distance[0], d.hit_distance[1]);
            let (n_s, n_g) = (Vec3::from(t.normal), unpack_unit_vector(t.geometric_normal));
            if t.flags & gbuffer_flags::RECEIVER == 0
                || !(w > 0.0)
                || !shading_normal_departs(n_s, n_g)
            {
                return v;
            }
            let sums = Vec3::new(
                join_u64_f32(d.flux[0][0], d.flux[0][1]),
                join_u64_f32(d.flux[1][0], d.flux[1][1]),
                join_u64_f32(d.flux[2][0], d.flux[2][1]),
            );
            let w_i = mean_light_direction(sums, w);
            if w_i == Vec3::ZERO {
                return v;
            }
            let f = shading_normal_factor(w_i, n_s, n_g, p.max_stretch, p.epsilon);
            [v[0] * f, v[1] * f, v[2] * f, v[3]]
        })
        .collect()
}
