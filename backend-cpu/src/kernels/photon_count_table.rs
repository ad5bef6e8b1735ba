//! `photon_count_table`: the photon counts' summed-area table of the density-adaptive
//! caustic gather (rows, then columns) and, with the column pass, the screen's edge
//! texels (method and sources in `caustica_core::math::density_gather`).

use crate::recording::reserve_temporary;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    gather_surface, gbuffer_flags, GBufferTexel, GBufferView, GatherParams, PhotonMapView,
};
use caustica_core::kernels::PhotonCountTable;
use caustica_core::math::density_gather::{clamped_photon_count, edge_texel};
use rayon::prelude::*;

/// Runs `photon_count_table` on the host ([`super::run`]'s arm): its buffers read from
/// `cpu`, its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &PhotonCountTable) -> Result<(), BackendError> {
    let PhotonCountTable {
        params,
        photon_map,
        table,
        gbuffer,
        edge,
    } = k;
    if params.axis == 0 {
        let rows = {
            let m = cpu.photon_map(photon_map)?;
            reserve_temporary::<u32>(table.len as u64, "the photon count table")?;
            let mut rows = vec![0u32; table.len as usize];
            photon_count_rows(params, m, &mut rows);
            rows
        };
        cpu.put(table.id, &rows)
    } else if params.surface == gather_surface::ATLAS {
        // the atlas's edge texels come with its layout
        let t = cpu.get_mut(table.id)?.as_mut_slice(table.len)?;
        photon_count_columns(params, t);
        Ok(())
    } else {
        let edges = {
            let g = cpu.gbuffer(gbuffer)?;
            reserve_temporary::<[f32; 4]>(edge.len as u64, "the edge texels")?;
            edge_texels(g, edge.len as usize)
        };
        let t = cpu.get_mut(table.id)?.as_mut_slice(table.len)?;
        photon_count_columns(params, t);
        cpu.put(edge.id, &edges)
    }
}

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
