//! The density-adaptive, scatter-normalised caustic gather: `photon_count_table`,
//! `gather_footprint` and `density_gather` (method and sources in
//! `caustica_core::math::density_gather`).

use caustica_core::device::layout::{
    gather_surface, gbuffer_flags, gbuffer_pixel_area, GBufferTexel, GBufferView, GatherParams,
    PhotonMapView,
};
use caustica_core::math::density_gather::{
    accumulate_source_index, clamped_photon_count, edge_texel, edge_texel_is_receiver, edge_weight,
    footprint_radius, footprint_weight, for_each_pass_source, inherited_flux, join_u64_wide,
};
use caustica_core::math::optics::{saturate_radiance, saturate_radiance3};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Axis 0 of `photon_count_table`: per row and block, the inclusive prefix sums of the
/// clamped photon counts from the block's left edge (wrapping `u32`), row-major.
pub fn photon_count_rows(p: &GatherParams, map: PhotonMapView, table: &mut [u32]) {
    let (w, b) = (p.camera.width as usize, p.table_block as usize);
    table.par_chunks_mut(w).enumerate().for_each(|(y, row)| {
        let mut sum = 0u32;
        for (x, t) in row.iter_mut().enumerate() {
            if x % b == 0 {
                sum = 0;
            }
            let i = (y * w + x) as u32;
            let n = clamped_photon_count(
                map.photon_map_word(i, 8),
                map.photon_map_word(i, 9),
                p.knn_photons,
            );
            sum = sum.wrapping_add(n);
            *t = sum;
        }
    });
}

/// Axis 1 of `photon_count_table`: the row sums become the blocked summed-area table in
/// place (column prefix sums from each block's top edge, wrapping `u32`).
pub fn photon_count_columns(p: &GatherParams, table: &mut [u32]) {
    let (w, b) = (p.camera.width as usize, p.table_block as usize);
    for y in 1..p.camera.height as usize {
        if y % b == 0 {
            continue;
        }
        let (above, row) = table[(y - 1) * w..(y + 1) * w].split_at_mut(w);
        for (t, a) in row.iter_mut().zip(above.iter()) {
            *t = t.wrapping_add(*a);
        }
    }
}

/// The rest of axis 1 of `photon_count_table`: every pixel's edge texel.
pub fn edge_texels(g: GBufferView, pixels: usize) -> Vec<[f32; 4]> {
    (0..pixels)
        .into_par_iter()
        .map(|i| {
            let gi = g.load_gbuffer(i);
            edge_texel(is_receiver(&gi), gi.depth, gi.normal)
        })
        .collect()
}

fn is_receiver(g: &GBufferTexel) -> bool {
    g.flags & gbuffer_flags::RECEIVER != 0
}

/// Normaliser of a source at `i` with radius `r`: the sum of its weights over the
/// receivers of its row (`axis` 0) or column (1) inside the image (itself included).
fn normaliser(p: &GatherParams, edge: &[[f32; 4]], i: i32, r: f32, axis: u32) -> f32 {
    let (w, h) = (p.camera.width as i32, p.camera.height as i32);
    let (x, y) = (i % w, i / w);
    let ei = &edge[i as usize];
    // taps beyond the radius weigh 0: the loop stops there
    let reach = ((r + 0.5).ceil() as i32).min(p.max_radius_px as i32);
    let mut sum = 0.0f32;
    for d in -reach..=reach {
        let (qx, qy) = if axis == 0 { (x + d, y) } else { (x, y + d) };
        if qx < 0 || qy < 0 || qx >= w || qy >= h {
            continue;
        }
        let eq = &edge[(qy * w + qx) as usize];
        if !edge_texel_is_receiver(eq) {
            continue;
        }
        sum += footprint_weight(d, r) * edge_weight_of(p, ei, eq);
    }
    sum
}

/// [`edge_weight`] between two edge texels.
fn edge_weight_of(p: &GatherParams, a: &[f32; 4], b: &[f32; 4]) -> f32 {
    edge_weight(
        a[0],
        [a[1], a[2], a[3]],
        b[0],
        [b[1], b[2], b[3]],
        p.sigma_depth,
        p.normal_power,
    )
}

/// `gather_footprint`: per receiver pixel `(F / W_row, r)` (W per channel, pixels), 0
/// elsewhere.
pub fn gather_footprint(
    p: &GatherParams,
    edge: &[[f32; 4]],
    map: PhotonMapView,
    table: &[u32],
) -> Vec<[f32; 4]> {
    let (w, h) = (p.camera.width as i32, p.camera.height as i32);
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            if !edge_texel_is_receiver(&edge[i as usize]) {
                return [0.0; 4];
            }
            let r = footprint_radius(
                table,
                w,
                h,
                p.table_block as i32,
                i % w,
                i / w,
                p.knn_photons,
                p.max_radius_px,
            );
            let flux = |j: i32| {
                let word = |k: u32| map.photon_map_word(j as u32, k);
                let channel = |c: u32| join_u64_wide(word(2 * c), word(2 * c + 1)) * p.flux_quantum;
                [channel(0), channel(1), channel(2)]
            };
            // on the atlas, the flux of uncovered neighbours whose heir this texel is
            let f = if p.surface == gather_surface::ATLAS {
                inherited_flux(edge, w, h, i % w, i / w, flux)
            } else {
                flux(i)
            };
            if f == [0.0; 3] {
                // no flux to spread: no normaliser to compute
                return [0.0, 0.0, 0.0, r];
            }
            let inv = 1.0 / normaliser(p, edge, i, r, 0);
            [f[0] * inv, f[1] * inv, f[2] * inv, r]
        })
        .collect()
}

/// The source index after a pass that wrote `sources` for pass `axis`
/// (`gather_footprint`: the row pass's part, axis 0; the row pass: the column pass's,
/// axis 1): `index` with the sources entered (the GPU ports' atomic maxima and ors).
pub fn source_index(p: &GatherParams, axis: u32, index: &[u32], sources: &[[f32; 4]]) -> Vec<u32> {
    let mut index = index.to_vec();
    let (w, h) = (p.camera.width, p.camera.height);
    accumulate_source_index(&mut index, sources, w, h, axis, p.max_radius_px as i32);
    index
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
                // 000 Eq. 5: L = (albedo / pi) Phi / A
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
