//! `density_gather`: the density-adaptive, scatter-normalised caustic gather's separable
//! passes over the footprints of `gather_footprint` (method and sources in
//! `caustica_core::math::density_gather`).

use super::gather_footprint::{edge_weight_of, normaliser};

use super::gather_footprint;
use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    gather_surface, gbuffer_pixel_area, GBufferView, GatherParams,
};
use caustica_core::kernels::DensityGather;
use caustica_core::math::density_gather::{
    edge_texel_is_receiver, footprint_weight, for_each_pass_source,
};
use caustica_core::math::optics::{saturate_radiance, saturate_radiance3};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Runs `density_gather` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &DensityGather) -> Result<(), BackendError> {
    let DensityGather {
        params,
        gbuffer,
        edge,
        input,
        out,
        source_index,
    } = k;
    let g = cpu.gbuffer(gbuffer)?;
    let e = cpu.get(edge.id)?.as_slice(edge.len)?;
    let i = cpu.get(input.id)?.as_slice(input.len)?;
    let sources = cpu.get(source_index.id)?.as_slice(source_index.len)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "a gathered image")?;
    let img = density_gather(params, g, e, i, sources);
    if params.axis == 0 {
        // the row pass's output: the column pass's sources
        let sources = gather_footprint::source_index(params, 1, sources, &img);
        cpu.put(source_index.id, &sources)?;
    }
    cpu.put(out.id, &img)
}

/// One pass (`p.axis`) of `density_gather` (see the kernel's contract in
/// `caustica_core::kernels::DensityGather`); `index` is the source index the pass reads.
pub fn density_gather(
    p: &GatherParams,
    g: GBufferView,
    edge: &[[f32; 4]],
    input: &[[f32; 4]],
    index: &[u32],
) -> Vec<[f32; 4]> {
    let (w, h) = (p.camera.width as i32, p.camera.height as i32);
    (0..w * h)
        .into_par_iter()
        .map(|j| {
            let ej = &edge[j as usize];
            if !edge_texel_is_receiver(ej) {
                return [0.0; 4];
            }
            let (x, y) = (j % w, j / w);
            let r = input[j as usize][3];
            let mut sum = Vec3::ZERO;
            // the sources that can have weight here, in increasing offset (the taps left
            // out have no flux or no weight)
            let cap = p.max_radius_px as i32;
            for_each_pass_source(index, w, h, x, y, p.axis, cap, |d| {
                let (qx, qy) = if p.axis == 0 { (x + d, y) } else { (x, y + d) };
                let q = (qy * w + qx) as usize;
                // source q, destination j: a source without flux adds nothing; then the
                // source's radius at offset j - q (non-receivers hold no flux)
                let s = &input[q];
                if s[0] == 0.0 && s[1] == 0.0 && s[2] == 0.0 {
                    return;
                }
                let ws = footprint_weight(-d, s[3]);
                if ws == 0.0 {
                    return;
                }
                let eq = &edge[q];
                if !edge_texel_is_receiver(eq) {
                    return;
                }
                sum += ws * edge_weight_of(p, eq, ej) * Vec3::from_slice(&s[..3]);
            });
            // (flux and weights are >= 0: a sum without a positive channel is 0)
            if !(sum.x > 0.0 || sum.y > 0.0 || sum.z > 0.0) {
                return [0.0, 0.0, 0.0, if p.axis == 0 { r } else { 0.0 }];
            }
            if p.axis == 0 {
                let s = sum / normaliser(p, edge, j, r, 1);
                [s.x, s.y, s.z, r]
            } else if p.surface == gather_surface::ATLAS {
                // irradiance E = Phi / A over the texel's world area (its edge texel's y;
                // > 0 on every receiver texel; the scale saturates first, as below)
                let e = saturate_radiance3(sum * saturate_radiance(1.0 / ej[1]));
                [e.x, e.y, e.z, r]
            } else {
                // Kim 2019, Eq. 5: L = (albedo / pi) Phi / A
                // (the scale saturates first, so that no pixel of area 0 gives 0 / 0)
                let gj = g.load_gbuffer(j as usize);
                let area = gbuffer_pixel_area(&p.camera, j as u32, &gj);
                let scale = saturate_radiance(1.0 / (PI * area));
                let l = saturate_radiance3(sum * scale) * Vec3::from(gj.albedo);
                // alpha: the radius where the filter gave light (0 elsewhere, as the raw
                // image's alpha is 0 without photons)
                [l.x, l.y, l.z, r]
            }
        })
        .collect()
}
