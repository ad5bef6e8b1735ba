//! `gather_footprint`: each source pixel's gather footprint (the density-adaptive,
//! scatter-normalised caustic gather's k-NN radius and normaliser) and the row pass's
//! source index (method and sources in `caustica_core::math::density_gather`).

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{gather_surface, GatherParams, PhotonMapView};
use caustica_core::kernels::GatherFootprint;
use caustica_core::math::density_gather::{
    accumulate_source_index, edge_texel_is_receiver, edge_weight, footprint_radius,
    footprint_weight, inherited_flux, join_u64_wide,
};
use rayon::prelude::*;

/// Runs `gather_footprint` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &GatherFootprint) -> Result<(), BackendError> {
    let GatherFootprint {
        params,
        photon_map,
        table,
        edge,
        out,
        source_index,
    } = k;
    let m = cpu.photon_map(photon_map)?;
    let t = cpu.get(table.id)?.as_slice(table.len)?;
    let e = cpu.get(edge.id)?.as_slice(edge.len)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "the gather footprints")?;
    let img = gather_footprint(params, e, m, t);
    let sources = cpu.get(source_index.id)?.as_slice(source_index.len)?;
    let sources = self::source_index(params, 0, sources, &img);
    cpu.put(out.id, &img)?;
    cpu.put(source_index.id, &sources)
}

/// Normaliser of a source at `i` with radius `r`: the sum of its weights over the
/// receivers of its row (`axis` 0) or column (1) inside the image (itself included).
pub(crate) fn normaliser(p: &GatherParams, edge: &[[f32; 4]], i: i32, r: f32, axis: u32) -> f32 {
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
pub(crate) fn edge_weight_of(p: &GatherParams, a: &[f32; 4], b: &[f32; 4]) -> f32 {
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
