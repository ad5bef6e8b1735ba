//! `sort_indirect_paths` (PhotonGi's `sorted_waves` schedule): the order in which the next
//! wave takes its queued paths, a counting sort of the (key, rank) pairs the queuing wave
//! wrote (`caustica_core::math::path_sort`), one phase a launch as on the GPU.

use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::kernels::SortIndirectPaths;
use caustica_core::math::path_sort::{path_sort_phase, PathKey, PATH_SORT_BUCKETS};

/// Runs one phase of `sort_indirect_paths` on the host ([`super::run`]'s arm): its
/// buffers read from `cpu`, its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &SortIndirectPaths) -> Result<(), BackendError> {
    let p = &k.params;
    let counts = cpu
        .get(k.path_counts.id)?
        .as_slice::<u32>(k.path_counts.len)?;
    let n = (counts[p.count_word as usize]).min(k.path_keys.len) as usize;
    let mut buckets = cpu
        .get(k.buckets.id)?
        .as_slice::<u32>(k.buckets.len)?
        .to_vec();
    if p.phase == path_sort_phase::SCAN {
        path_sort_scan(&mut buckets);
        return cpu.put(k.buckets.id, &buckets);
    }
    let keys = cpu
        .get(k.path_keys.id)?
        .as_slice::<PathKey>(k.path_keys.len)?[..n]
        .to_vec();
    let mut order = cpu
        .get(k.order.id)?
        .as_slice::<u32>(k.order.len)?
        .to_vec();
    // slots below the queue's capacity, as on the GPU
    path_sort_scatter(&keys, &buckets, &mut order[..k.path_keys.len as usize]);
    cpu.put(k.order.id, &order)
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

/// `SCATTER`: path `i`'s queue slot at `order[first[key] + rank]` for its `keys[i]` =
/// (key, rank); a key past the buckets or a slot past `order` is not written.
pub fn path_sort_scatter(keys: &[PathKey], first: &[u32], order: &mut [u32]) {
    for (i, &[key, rank]) in keys.iter().enumerate() {
        let Some(&f) = first.get(key as usize).filter(|_| key < PATH_SORT_BUCKETS) else {
            continue;
        };
        if let Some(slot) = order.get_mut(f.wrapping_add(rank) as usize) {
            *slot = i as u32;
        }
    }
}
