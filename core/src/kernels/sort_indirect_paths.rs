//! `sort_indirect_paths`: PhotonGi's queued indirect paths in key order before the next
//! wave (the `sorted_waves` schedule), a counting sort in three launches.

use super::{bind, bytes, Args, Binding, BindingKind::*, DispatchRecord, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::Buf;
use crate::device::launch::DEFAULT_WORKGROUP_SIZE;
use crate::device::layout::{IndirectPath, PathSortParams};
use crate::math::path_sort::{path_sort_phase, PATH_SORT_BUCKETS};

/// Sorts the first `n = min(path_counts[params.count_word], path_capacity)` paths of
/// `paths_in` into `paths_out` by
/// [`path_sort_key`](crate::math::path_sort::path_sort_key), one phase a launch
/// ([`path_sort_phase`]): `HISTOGRAM` (a thread per path) adds each path to its key's
/// count in `buckets` (the caller clears them first), `SCAN` (one workgroup of
/// [`DEFAULT_WORKGROUP_SIZE`] threads) turns the counts into each bucket's first slot,
/// `SCATTER` (a thread per path) moves each path to the next slot of its bucket, so that
/// `buckets[k]` ends as bucket `k`'s end. The paths of one bucket keep no particular order
/// on a GPU (the CPU keeps theirs): a wave's result does not depend on it.
#[derive(Clone, Copy, Debug)]
pub struct SortIndirectPaths {
    /// The key's box and scale, the phase, the queue length's word.
    pub params: PathSortParams,
    /// The queue as `trace_indirect` appended it.
    pub paths_in: Buf<IndirectPath>,
    /// The queue lengths (`trace_indirect`'s `path_counts`).
    pub path_counts: Buf<u32>,
    /// Output (`SCATTER`): the queue in key order (at least as long as `paths_in`).
    pub paths_out: Buf<IndirectPath>,
    /// [`PATH_SORT_BUCKETS`] words: counts, then first slots, then ends.
    pub buckets: Buf<u32>,
    /// `HISTOGRAM` and `SCATTER`: the launch record of the queue's length (`None`: a
    /// launch of `paths_in.len` threads); `SCAN` launches one workgroup.
    pub dispatch: Option<DispatchRecord>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("paths_in", Read),
    bind("path_capacity", Count),
    bind("path_counts", Read),
    bind("paths_out", ReadWrite),
    bind("buckets", ReadWrite),
];

impl KernelDecl for SortIndirectPaths {
    const INFO: KernelInfo = KernelInfo::compute("sort_indirect_paths", BINDINGS, "PhotonGi");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        if p.phase > path_sort_phase::SCATTER
            || p.count_word >= self.path_counts.len
            || self.paths_out.len < self.paths_in.len
            || self.buckets.len < PATH_SORT_BUCKETS
        {
            return Err(BackendError::BadArgument(format!(
                "sort_indirect_paths: phase {}, count word {} of {}, queues of {} and {} \
                 paths, {} buckets",
                p.phase,
                p.count_word,
                self.path_counts.len,
                self.paths_in.len,
                self.paths_out.len,
                self.buckets.len
            )));
        }
        let paths = self.paths_in.len as u64 * bytes::INDIRECT_PATH;
        a.params("params", p)?
            .buf("paths_in", self.paths_in, paths)?
            .count("path_capacity", self.paths_in.len)?
            .buf(
                "path_counts",
                self.path_counts,
                (p.count_word as u64 + 1) * 4,
            )?
            .buf("paths_out", self.paths_out, paths)?
            .buf("buckets", self.buckets, PATH_SORT_BUCKETS as u64 * 4)?;
        if p.phase == path_sort_phase::SCAN {
            return Ok(Some(DEFAULT_WORKGROUP_SIZE as u64));
        }
        a.indirect(self.dispatch)?;
        Ok(Some(self.paths_in.len as u64))
    }
}
