//! Photon gathering (Kim 2019, section 30.3.2): the separable, edge-aware
//! `bilateral_gather` (the tile hit distances come from [`super::tile_hit_distance`]).
//!
//! The source denoises with a reflection denoiser fed with a constant roughness (0.07) and
//! the photons' last hit distance clamped to [min, max]. Here the blur radius of a pixel
//! is `roughness * clamp(d, min, max)` in world units, converted to pixels with the pixel
//! size at the pixel's depth (Eq. 4) and capped at `max_radius_px`; `d` is the mean hit
//! distance of the photons in the pixel's tile (`min` for empty tiles). Weights: Gaussian in
//! pixels (sigma = radius / 2), depth `exp(-|dz| / (sigma_depth z))`, normal
//! `max(0, n . n')^normal_power`; only RECEIVER pixels take part. Two 1-D passes
//! (horizontal then vertical) approximate the 2-D filter.

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{gbuffer_flags, GBufferTexel, GBufferView, GatherParams};
use caustica_core::kernels::BilateralGather;
use caustica_core::math::footprint::pixel_footprint;
use glam::Vec3;
use rayon::prelude::*;

/// Runs `bilateral_gather` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &BilateralGather) -> Result<(), BackendError> {
    let BilateralGather {
        params,
        gbuffer,
        tiles,
        input,
        out,
    } = k;
    let g = cpu.gbuffer(gbuffer)?;
    let t = cpu.get(tiles.id)?.as_slice(tiles.len)?;
    let i = cpu.get(input.id)?.as_slice(input.len)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "a gathered image")?;
    let img = bilateral_gather(params, g, t, i);
    cpu.put(out.id, &img)
}

/// Gather radius in pixels at a receiver pixel.
pub fn gather_radius_px(p: &GatherParams, g: &GBufferTexel, tile_hit_distance: f32) -> f32 {
    let d = if tile_hit_distance > 0.0 {
        tile_hit_distance
    } else {
        p.hit_distance_min
    };
    let d = d.clamp(p.hit_distance_min, p.hit_distance_max);
    let world = p.roughness * d;
    let c = &p.camera;
    let pixel = pixel_footprint(
        g.depth,
        c.width,
        c.height,
        c.tan_half_fov_x,
        c.tan_half_fov_y,
    )
    .sqrt();
    if !(pixel > 0.0) {
        return 0.0;
    }
    (world / pixel).min(p.max_radius_px as f32)
}

/// One pass (`p.axis`) of the edge-aware gather of `input` (caustic radiance): receiver
/// pixels get the normalised weighted mean of their receiver neighbours, other pixels 0;
/// alpha is copied from `input`.
pub fn bilateral_gather(
    p: &GatherParams,
    gbuffer: GBufferView,
    tiles: &[f32],
    input: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    let (w, h, ts) = (
        p.camera.width as i32,
        p.camera.height as i32,
        p.tile_size as i32,
    );
    let tw = (w + ts - 1) / ts;
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let (x, y) = (i % w, i / w);
            let g = &gbuffer.load_gbuffer(i as usize);
            if g.flags & gbuffer_flags::RECEIVER == 0 {
                return [0.0, 0.0, 0.0, input[i as usize][3]];
            }
            let r = gather_radius_px(p, g, tiles[((y / ts) * tw + x / ts) as usize]);
            let radius = r.ceil() as i32;
            let inv_2s2 = 1.0 / (2.0 * (0.5 * r).max(0.5).powi(2));
            let n = Vec3::from(g.normal);
            let (mut sum, mut wsum) = (Vec3::ZERO, 0.0f32);
            for k in -radius..=radius {
                let (qx, qy) = if p.axis == 0 { (x + k, y) } else { (x, y + k) };
                if qx < 0 || qy < 0 || qx >= w || qy >= h {
                    continue;
                }
                let q = (qy * w + qx) as usize;
                let gq = &gbuffer.load_gbuffer(q);
                if gq.flags & gbuffer_flags::RECEIVER == 0 {
                    continue;
                }
                let ws = (-(k * k) as f32 * inv_2s2).exp();
                let wd = (-(gq.depth - g.depth).abs() / (p.sigma_depth * g.depth)).exp();
                let wn = if p.normal_power > 0.0 {
                    n.dot(Vec3::from(gq.normal)).max(0.0).powf(p.normal_power)
                } else {
                    1.0
                };
                let wgt = ws * wd * wn;
                sum += wgt * Vec3::from_slice(&input[q][..3]);
                wsum += wgt;
            }
            let o = if wsum > 0.0 {
                caustica_core::math::optics::saturate_radiance3(sum / wsum)
            } else {
                Vec3::ZERO
            };
            [o.x, o.y, o.z, input[i as usize][3]]
        })
        .collect()
}
