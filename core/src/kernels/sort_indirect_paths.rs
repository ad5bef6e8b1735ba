//! `sort_indirect_paths`: the order in which the next wave of PhotonGi's `sorted_waves`
//! schedule takes its queued paths, a counting sort of the keys the queuing wave wrote,
//! in two launches.

use super::{bind, Args, Binding, BindingKind::*, DispatchRecord, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::Buf;
use crate::device::launch::DEFAULT_WORKGROUP_SIZE;
use crate::device::layout::PathSortParams;
use crate::math::path_sort::{path_sort_phase, PathKey, PATH_SORT_BUCKETS};

/// Orders the first `n = min(path_counts[params.count_word], path_capacity)` queued paths
/// by their keys, one phase a launch ([`path_sort_phase`]): `SCAN` (one workgroup of
/// [`DEFAULT_WORKGROUP_SIZE`] threads) turns the counts in `buckets` (the queuing wave's,
/// `trace_indirect` with `queue_keys`) into each bucket's first slot; `SCATTER` (a thread
/// per path) writes path `i`'s queue slot at `order[first + rank]` from its `path_keys[i]`
/// = (key, rank). No atomics: the order is the ranks', which the queuing wave's atomics
/// drew on a GPU (the CPU queues in order); a wave's result does not depend on it.
#[derive(Clone, Copy, Debug)]
pub struct SortIndirectPaths {
    /// The phase and the queue length's word.
    pub params: PathSortParams,
    /// Each queued path's (key, rank) (`trace_indirect`'s `path_keys`).
    pub path_keys: Buf<PathKey>,
    /// The queue lengths (`trace_indirect`'s `path_counts`).
    pub path_counts: Buf<u32>,
    /// Output (`SCATTER`): queue slots in key order (as long as `path_keys`).
    pub order: Buf<u32>,
    /// [`PATH_SORT_BUCKETS`] words: counts, then (after `SCAN`) first slots.
    pub buckets: Buf<u32>,
    /// `SCATTER`: the launch record of the queue's length (`None`: a launch of
    /// `path_keys.len` threads); `SCAN` launches one workgroup.
    pub dispatch: Option<DispatchRecord>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("path_keys", Read),
    bind("path_capacity", Count),
    bind("path_counts", Read),
    bind("order", ReadWrite),
    bind("buckets", ReadWrite),
];

impl KernelDecl for SortIndirectPaths {
    const INFO: KernelInfo = KernelInfo::compute("sort_indirect_paths", BINDINGS, "PhotonGi");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        if p.phase > path_sort_phase::SCATTER
            || p.count_word >= self.path_counts.len
            || self.order.len < self.path_keys.len
            || self.buckets.len < PATH_SORT_BUCKETS
        {
            return Err(BackendError::BadArgument(format!(
                "sort_indirect_paths: phase {}, count word {} of {}, {} keys and {} order \
                 slots, {} buckets",
                p.phase,
                p.count_word,
                self.path_counts.len,
                self.path_keys.len,
                self.order.len,
                self.buckets.len
            )));
        }
        a.params("params", p)?
            .buf("path_keys", self.path_keys, self.path_keys.len as u64 * 8)?
            .count("path_capacity", self.path_keys.len)?
            .buf(
                "path_counts",
                self.path_counts,
                (p.count_word as u64 + 1) * 4,
            )?
            .buf("order", self.order, self.path_keys.len as u64 * 4)?
            .buf("buckets", self.buckets, PATH_SORT_BUCKETS as u64 * 4)?;
        if p.phase == path_sort_phase::SCAN {
            return Ok(Some(DEFAULT_WORKGROUP_SIZE as u64));
        }
        a.indirect(self.dispatch)?;
        Ok(Some(self.path_keys.len as u64))
    }
}
