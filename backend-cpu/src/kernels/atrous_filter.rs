//! `atrous_filter` (Smal 2019, section 24.4.2): one edge-avoiding A-Trous iteration with
//! variance clipping of its detail coefficient. The weights are core's
//! `math::irradiance_filter`; see core's `AtrousFilter` for the contract.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{gbuffer_flags, AtrousParams, GBufferView};
use caustica_core::kernels::AtrousFilter;
use caustica_core::math::density_gather::{edge_texel, edge_texel_is_receiver};
use caustica_core::math::irradiance_filter::{
    atrous_final, atrous_offset, clipped_detail, depth_gradient, depth_weight, detail_bound,
    normal_weight, FilterConstants, ATROUS_TAPS,
};
use glam::Vec3;
use rayon::prelude::*;

/// Runs `atrous_filter` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &AtrousFilter) -> Result<(), BackendError> {
    let AtrousFilter {
        params,
        gbuffer,
        input,
        details,
        out,
        edge,
    } = k;
    let g = cpu.gbuffer(gbuffer)?;
    let i = cpu.get(input.id)?.as_slice(input.len)?;
    let d = cpu.get(details.id)?.as_slice(details.len)?;
    // iteration 0 writes the edge texels from the G-buffer, the later ones read them
    let edges = if params.iteration == 0 {
        reserve_temporary::<[f32; 4]>(edge.len as u64, "the A-Trous edge texels")?;
        edge_texels(g)
    } else {
        cpu.get(edge.id)?.as_slice::<[f32; 4]>(edge.len)?.to_vec()
    };
    reserve_temporary::<[[f32; 4]; 2]>(out.len as u64, "an A-Trous iteration")?;
    let r = atrous_filter_image(params, i, d, &edges);
    let (img, det): (Vec<[f32; 4]>, Vec<[f32; 4]>) = r.into_iter().unzip();
    if params.iteration == 0 {
        cpu.put(edge.id, &edges)?;
    }
    cpu.put(details.id, &det)?;
    cpu.put(out.id, &img)
}

/// Every pixel's edge texel (`math::density_gather::edge_texel`: depth and normal, the
/// G-buffer's own bits, or the not-a-receiver mark), as iteration 0 writes them.
pub fn edge_texels(gbuffer: GBufferView) -> Vec<[f32; 4]> {
    (0..gbuffer.len())
        .into_par_iter()
        .map(|i| {
            let g = gbuffer.load_gbuffer(i);
            edge_texel(g.flags & gbuffer_flags::RECEIVER != 0, g.depth, g.normal)
        })
        .collect()
}

/// (out, details) per pixel, the taps' depths, normals and receivers read from `edges`
/// ([`edge_texels`]: the same bits as the G-buffer's).
pub fn atrous_filter_image(
    p: &AtrousParams,
    input: &[[f32; 4]],
    details: &[[f32; 4]],
    edges: &[[f32; 4]],
) -> Vec<([f32; 4], [f32; 4])> {
    let (w, h) = (p.camera.width as i64, p.camera.height as i64);
    let c = FilterConstants {
        sigma_z: p.sigma_z,
        sigma_n: p.sigma_n,
        alpha_max: 0.0,
        epsilon: p.epsilon,
    };
    // (depth, normal) of pixel (x, y); None off the image or on a non-receiver
    let texel = |x: i64, y: i64| {
        if x < 0 || y < 0 || x >= w || y >= h {
            return None;
        }
        let t = &edges[(y * w + x) as usize];
        edge_texel_is_receiver(t).then(|| (t[0], Vec3::new(t[1], t[2], t[3])))
    };
    let depth = |x: i64, y: i64| texel(x, y).map_or(0.0, |t| t.0);
    (0..(w * h) as usize)
        .into_par_iter()
        .map(|j| {
            let (x, y) = (j as i64 % w, j as i64 / w);
            let s_i = input[j];
            let Some((z, n)) = texel(x, y) else {
                return (s_i, [0.0; 4]);
            };
            let (gx, gy) = depth_gradient(
                z,
                [
                    depth(x - 1, y),
                    depth(x + 1, y),
                    depth(x, y - 1),
                    depth(x, y + 1),
                ],
            );
            let (mut sum_w, mut sum, mut sum_sq) = (0.0f32, Vec3::ZERO, Vec3::ZERO);
            for ky in 0..5u32 {
                for kx in 0..5u32 {
                    let (dx, dy) = (
                        atrous_offset(kx, p.iteration) as i64,
                        atrous_offset(ky, p.iteration) as i64,
                    );
                    let Some((zq, nq)) = texel(x + dx, y + dy) else {
                        continue;
                    };
                    let step = gx * dx as f32 + gy * dy as f32;
                    let wgt = ATROUS_TAPS[kx as usize]
                        * ATROUS_TAPS[ky as usize]
                        * depth_weight(z, zq, step, &c)
                        * normal_weight(n, nq, &c);
                    let q = input[((y + dy) * w + x + dx) as usize];
                    let v = Vec3::new(q[0], q[1], q[2]);
                    sum_w += wgt;
                    sum += wgt * v;
                    sum_sq += wgt * v * v;
                }
            }
            let mean = sum / sum_w;
            let mean_sq = sum_sq / sum_w;
            let s = Vec3::new(s_i[0], s_i[1], s_i[2]);
            let clipped = clipped_detail(s, mean, detail_bound(mean, mean_sq, p.clip_sigmas));
            let before = if p.iteration == 0 {
                Vec3::ZERO
            } else {
                Vec3::new(details[j][0], details[j][1], details[j][2])
            };
            let d = before + clipped;
            let o = if p.last != 0 {
                atrous_final(mean, d)
            } else {
                mean
            };
            ([o.x, o.y, o.z, s_i[3]], [d.x, d.y, d.z, 0.0])
        })
        .collect()
}
