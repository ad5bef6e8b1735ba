//! `dispatch_args`: the launch shapes of kernels whose work count is on the device. The
//! CPU has no launch grid: its indirect kernels read their counts themselves, and this
//! writes the records for any later reader (and the conformance check).

use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::launch::DISPATCH_RECORD_WORDS;
use caustica_core::kernels::{dispatch_record, DispatchArgs};

/// Runs `dispatch_args` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its records written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &DispatchArgs) -> Result<(), BackendError> {
    let table = cpu.get(k.table.id)?.as_slice::<[u32; 4]>(k.table.len)?;
    let counts = cpu.get(k.counts.id)?.as_slice::<u32>(k.counts.len)?;
    let records = dispatch_args(table, counts);
    let mut args = cpu.get(k.args.id)?.as_slice::<u32>(k.args.len)?.to_vec();
    args[..records.len()].copy_from_slice(&records);
    cpu.put(k.args.id, &args)
}

/// One record per row `[first, bound, per_item, word]` of `table`
/// ([`dispatch_record`] of `counts[word]`; a word past `counts` reads 0).
pub fn dispatch_args(table: &[[u32; 4]], counts: &[u32]) -> Vec<u32> {
    let mut out = Vec::with_capacity(table.len() * DISPATCH_RECORD_WORDS);
    for &[first, bound, per_item, word] in table {
        let count = counts.get(word as usize).copied().unwrap_or(0);
        out.extend(dispatch_record(count, first, bound, per_item));
    }
    out
}
