//! `sort_indirect_paths` (PhotonGi's `sorted_waves` schedule): a counting sort of the
//! queued paths by `caustica_core::math::path_sort::path_sort_key`, one phase a launch as
//! on the GPU; the paths of one bucket keep their queue order here.

use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{IndirectPath, PathSortParams};
use caustica_core::kernels::SortIndirectPaths;
use caustica_core::math::path_sort::{path_sort_key, path_sort_phase, PATH_SORT_BUCKETS};
use glam::Vec3;

/// Runs one phase of `sort_indirect_paths` on the host ([`super::run`]'s arm): its
/// buffers read from `cpu`, its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &SortIndirectPaths) -> Result<(), BackendError> {
    let p = &k.params;
    let counts = cpu
        .get(k.path_counts.id)?
        .as_slice::<u32>(k.path_counts.len)?;
    let n = (counts[p.count_word as usize]).min(k.paths_in.len) as usize;
    let mut buckets = cpu
        .get(k.buckets.id)?
        .as_slice::<u32>(k.buckets.len)?
        .to_vec();
    let paths = cpu
        .get(k.paths_in.id)?
        .as_slice::<IndirectPath>(k.paths_in.len)?[..n]
        .to_vec();
    match p.phase {
        path_sort_phase::HISTOGRAM => {
            path_sort_histogram(p, &paths, &mut buckets);
            #[cfg(feature = "traversal-stats")]
            {
                let keys: Vec<u32> = paths.iter().map(|q| key(p, q) as u32).collect();
                crate::traversal_stats::sort_keys(p.count_word, &keys, PATH_SORT_BUCKETS as usize);
            }
        }
        path_sort_phase::SCAN => path_sort_scan(&mut buckets),
        _ => {
            let mut out = cpu
                .get(k.paths_out.id)?
                .as_slice::<IndirectPath>(k.paths_out.len)?
                .to_vec();
            path_sort_scatter(p, &paths, &mut buckets, &mut out);
            cpu.put(k.paths_out.id, &out)?;
        }
    }
    cpu.put(k.buckets.id, &buckets)
}

/// The key of `path` under `p`'s box and scale.
fn key(p: &PathSortParams, path: &IndirectPath) -> usize {
    path_sort_key(
        Vec3::from(path.origin),
        Vec3::from(path.direction),
        Vec3::from(p.origin_min),
        Vec3::from(p.origin_scale),
    ) as usize
}

/// `HISTOGRAM`: one count per path in its key's bucket (wrapping, as the GPU's atomics).
pub fn path_sort_histogram(p: &PathSortParams, paths: &[IndirectPath], buckets: &mut [u32]) {
    for path in paths {
        let b = &mut buckets[key(p, path)];
        *b = b.wrapping_add(1);
    }
}

/// `SCAN`: the first [`PATH_SORT_BUCKETS`] counts to their exclusive sums.
pub fn path_sort_scan(buckets: &mut [u32]) {
    let mut sum = 0u32;
    for b in &mut buckets[..PATH_SORT_BUCKETS as usize] {
        let count = *b;
        *b = sum;
        sum = sum.wrapping_add(count);
    }
}

/// `SCATTER`: each path to the next slot of its bucket (a slot past `out` is not
/// written).
pub fn path_sort_scatter(
    p: &PathSortParams,
    paths: &[IndirectPath],
    buckets: &mut [u32],
    out: &mut [IndirectPath],
) {
    for path in paths {
        let b = &mut buckets[key(p, path)];
        if let Some(slot) = out.get_mut(*b as usize) {
            *slot = *path;
        }
        *b = b.wrapping_add(1);
    }
}
