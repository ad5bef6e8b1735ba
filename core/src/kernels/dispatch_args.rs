//! `dispatch_args`: the launch shapes of kernels whose work count is on the device.

use super::{bind, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::Buf;
use crate::device::launch::{
    dispatch_word, DEFAULT_WORKGROUP_SIZE, DISPATCH_MAX_GROUPS_X, DISPATCH_RECORD_WORDS,
    DISPATCH_TRACE_WIDTH,
};

/// Writes one dispatch record per row of `table`: row `k` = `[first, bound, per_item,
/// word]` (a word past `counts` reads 0) takes `items = min(counts[word] - first, bound)` items (0 when the count is at
/// most `first`: [`crate::math::photon_clusters::live_clusters`]) of `per_item` threads
/// each, and record `k` of `args` ([`DISPATCH_RECORD_WORDS`] words,
/// [`dispatch_word`]) gets that launch's workgroups (x, y, z), traced-launch grid (width,
/// height, depth), threads and items ([`dispatch_record`]). One thread per row. A launch
/// that reads record `k` ([`DispatchRecord`]) must come later in the same recording.
#[derive(Clone, Copy, Debug)]
pub struct DispatchArgs {
    /// Rows `[first, bound, per_item, word]` (items, items, threads per item, word index
    /// into `counts`).
    pub table: Buf<[u32; 4]>,
    /// The device counts the rows read (a list length, a cluster count).
    pub counts: Buf<u32>,
    /// Output: one record per row.
    pub args: Buf<u32>,
}

/// Record `record` of a `dispatch_args` output buffer: what an indirect launch reads.
#[derive(Clone, Copy, Debug)]
pub struct DispatchRecord {
    /// The records.
    pub args: Buf<u32>,
    /// Which one.
    pub record: u32,
}

/// The record of a launch of `items = min(count - first, bound)` items of `per_item`
/// threads each (the shaders' `dispatch_record`): workgroups of
/// [`DEFAULT_WORKGROUP_SIZE`] along x up to [`DISPATCH_MAX_GROUPS_X`], then along y;
/// a traced launch [`DISPATCH_TRACE_WIDTH`] wide (fewer for fewer threads). Threads past
/// `threads` in the last group or row leave at once (each indirect kernel bounds itself
/// by its own count). An empty launch is 0 x 1 x 1 groups and a 0 x 1 x 1 grid.
pub fn dispatch_record(count: u32, first: u32, bound: u32, per_item: u32) -> [u32; 8] {
    let items = crate::math::photon_clusters::live_clusters(count, first, bound);
    let threads = items.saturating_mul(per_item);
    let groups = threads.div_ceil(DEFAULT_WORKGROUP_SIZE);
    let gx = groups.min(DISPATCH_MAX_GROUPS_X);
    let gy = if gx == 0 { 1 } else { groups.div_ceil(gx) };
    let w = threads.min(DISPATCH_TRACE_WIDTH);
    let h = if w == 0 { 1 } else { threads.div_ceil(w) };
    let mut r = [0u32; DISPATCH_RECORD_WORDS];
    r[dispatch_word::GROUPS_X] = gx;
    r[dispatch_word::GROUPS_Y] = gy;
    r[dispatch_word::GROUPS_Z] = 1;
    r[dispatch_word::WIDTH] = w;
    r[dispatch_word::HEIGHT] = h;
    r[dispatch_word::DEPTH] = 1;
    r[dispatch_word::THREADS] = threads;
    r[dispatch_word::ITEMS] = items;
    r
}

const BINDINGS: &[Binding] = &[
    bind("rows", Count),
    bind("table", Read),
    bind("count_words", Count),
    bind("counts", Read),
    bind("args", ReadWrite),
];

impl KernelDecl for DispatchArgs {
    const INFO: KernelInfo =
        KernelInfo::compute("dispatch_args", BINDINGS, "AdaptiveCaustics, PhotonGi");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let rows = self.table.len as u64;
        if self.counts.len == 0 || rows * DISPATCH_RECORD_WORDS as u64 > self.args.len as u64 {
            return Err(BackendError::BadArgument(format!(
                "dispatch_args: {rows} rows, {} counts, {} record words",
                self.counts.len, self.args.len
            )));
        }
        a.count("rows", self.table.len)?
            .buf("table", self.table, rows * 16)?
            .count("count_words", self.counts.len)?
            .buf("counts", self.counts, 0)?
            .buf("args", self.args, rows * 4 * DISPATCH_RECORD_WORDS as u64)?;
        Ok(Some(rows))
    }
}

impl Args {
    /// Makes the launch indirect: its shape is `dispatch`'s record (written by an earlier
    /// `dispatch_args`), its recorded thread count the bound. `None`: a direct launch.
    pub fn indirect(
        &mut self,
        dispatch: Option<DispatchRecord>,
    ) -> Result<&mut Self, BackendError> {
        if let Some(d) = dispatch {
            if (d.record as u64 + 1) * DISPATCH_RECORD_WORDS as u64 > d.args.len as u64 {
                return Err(BackendError::BadArgument(format!(
                    "{}: dispatch record {} past a buffer of {} words",
                    self.info.name, d.record, d.args.len
                )));
            }
            self.indirect = Some(crate::device::launch::Indirect {
                args: d.args.id,
                record: d.record,
            });
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn records_cover_the_live_items_and_no_more() {
        assert_eq!(dispatch_record(0, 0, 100, 4), [0, 1, 1, 0, 1, 1, 0, 0]);
        assert_eq!(dispatch_record(10, 20, 100, 4), [0, 1, 1, 0, 1, 1, 0, 0]);
        assert_eq!(dispatch_record(30, 20, 100, 4), [1, 1, 1, 8, 5, 1, 40, 10]);
        assert_eq!(
            dispatch_record(1000, 0, 100, 1),
            [2, 1, 1, 8, 13, 1, 100, 100]
        );
        // more groups than fit along x go along y
        let r = dispatch_record(u32::MAX, 0, 65536 * 64, 1);
        assert_eq!((r[0], r[1]), (65535, 2));
        assert!(r[0] as u64 * r[1] as u64 * 64 >= r[6] as u64);
    }
}
