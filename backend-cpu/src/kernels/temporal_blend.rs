//! `temporal_blend` (Smal 2019, section 24.4.1): the temporal accumulation of a screen-space
//! estimate over its reprojected history. The weights are core's
//! `math::irradiance_filter`; see core's `TemporalBlend` for the contract.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{gbuffer_flags, project_to_pixel, GBufferView, TemporalParams};
use caustica_core::kernels::TemporalBlend;
use caustica_core::math::density_gather::edge_texel;
use caustica_core::math::irradiance_filter::{
    blend_with_history, depth_weight, normal_weight, reprojection_depth_step, temporal_alpha,
    FilterConstants,
};
use glam::{Vec3, Vec4};
use rayon::prelude::*;

/// Runs `temporal_blend` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &TemporalBlend) -> Result<(), BackendError> {
    let TemporalBlend {
        params,
        gbuffer,
        input,
        history,
        history_edge,
        out,
        next_history,
        next_edge,
    } = k;
    let g = cpu.gbuffer(gbuffer)?;
    let i = cpu.get(input.id)?.as_slice(input.len)?;
    let hi = cpu.get(history.id)?.as_slice(history.len)?;
    let he = cpu.get(history_edge.id)?.as_slice(history_edge.len)?;
    reserve_temporary::<[[f32; 4]; 2]>(out.len as u64, "the temporal blend")?;
    let r = temporal_blend_image(params, g, i, hi, he);
    let (img, edge): (Vec<[f32; 4]>, Vec<[f32; 4]>) = r.into_iter().unzip();
    cpu.put(out.id, &img)?;
    cpu.put(next_history.id, &img)?;
    cpu.put(next_edge.id, &edge)
}

/// (blended estimate, edge texel) per pixel.
pub fn temporal_blend_image(
    p: &TemporalParams,
    gbuffer: GBufferView,
    input: &[[f32; 4]],
    history: &[[f32; 4]],
    history_edge: &[[f32; 4]],
) -> Vec<([f32; 4], [f32; 4])> {
    let (w, h) = (p.camera.width as i64, p.camera.height as i64);
    let c = FilterConstants {
        sigma_z: p.sigma_z,
        sigma_n: p.sigma_n,
        alpha_max: p.alpha_max,
        epsilon: p.epsilon,
    };
    let depth_at = |x: i64, y: i64| {
        if x < 0 || y < 0 || x >= w || y >= h {
            return 0.0;
        }
        let g = gbuffer.load_gbuffer((y * w + x) as usize);
        if g.flags & gbuffer_flags::RECEIVER != 0 {
            g.depth
        } else {
            0.0
        }
    };
    (0..(w * h) as usize)
        .into_par_iter()
        .map(|j| {
            let g = gbuffer.load_gbuffer(j);
            let cur = input[j];
            let receiver = g.flags & gbuffer_flags::RECEIVER != 0;
            let edge = edge_texel(receiver, g.depth, g.normal);
            if !receiver {
                return (cur, edge);
            }
            let (x, y) = (j as i64 % w, j as i64 / w);
            let mut alpha = 0.0;
            let mut hist = Vec3::ZERO;
            if p.history_frames > 0 {
                if let Some((qx, qy, zq)) = project_to_pixel(&p.previous, Vec3::from(g.position)) {
                    let q = (qy * p.camera.width + qx) as usize;
                    let e = history_edge[q];
                    if e[0] > 0.0 {
                        let n = [
                            depth_at(x - 1, y),
                            depth_at(x + 1, y),
                            depth_at(x, y - 1),
                            depth_at(x, y + 1),
                        ];
                        let step = reprojection_depth_step(g.depth, n);
                        let wz = depth_weight(zq, e[0], step, &c);
                        let wn =
                            normal_weight(Vec3::from(g.normal), Vec3::new(e[1], e[2], e[3]), &c);
                        alpha = temporal_alpha(wz, wn, &c);
                        hist = Vec4::from(history[q]).truncate();
                    }
                }
            }
            let rgb = blend_with_history(Vec4::from(cur).truncate(), hist, alpha);
            ([rgb.x, rgb.y, rgb.z, cur[3]], edge)
        })
        .collect()
}
