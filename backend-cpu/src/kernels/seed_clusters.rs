//! `seed_clusters`: the clusters of a window of one level's grid that overlap a caster's
//! rectangle, appended in window order (a GPU appends them in its atomics' order).

use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::kernels::SeedClusters;
use caustica_core::math::photon_clusters::{cluster_overlaps_rects, seed_cluster};

/// Runs `seed_clusters` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// the list and its length written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &SeedClusters) -> Result<(), BackendError> {
    let p = &k.params;
    let rects = cpu
        .get(k.caster_rects.id)?
        .as_slice::<[f32; 4]>(k.caster_rects.len)?[..p.rect_count as usize]
        .to_vec();
    let mut list = cpu.get(k.list.id)?.as_slice::<u32>(k.list.len)?.to_vec();
    let mut length = cpu
        .get(k.list_length.id)?
        .as_slice::<u32>(k.list_length.len)?
        .to_vec();
    let threads = p.window_w as u64 * p.window_h as u64;
    for t in 0..threads as u32 {
        let cluster = seed_cluster(t, p.grid_w, (p.first_x, p.first_y), (p.window_w, p.window_h));
        if cluster_overlaps_rects(cluster, p.grid_w, &rects) {
            let at = length[0];
            length[0] = at.wrapping_add(1);
            if at < p.capacity {
                list[at as usize] = cluster;
            }
        }
    }
    cpu.put(k.list.id, &list)?;
    cpu.put(k.list_length.id, &length)
}
