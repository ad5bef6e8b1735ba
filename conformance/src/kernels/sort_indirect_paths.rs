//! `sort_indirect_paths`: integer sums and integer slots, no atomics and no floating
//! point, so every backend must leave the **bitwise** same buckets (first slots) and the
//! bitwise same order (each queued path's slot at its bucket's first slot plus its rank;
//! a slot no path is placed in keeps what it held). Launched as PhotonGi launches it:
//! the scatter from `dispatch_args`' record of the queue's length (drawn from 0 past the
//! queue's capacity by the proptest in `conformance/tests/photon_gi_schedules.rs`), the
//! keys and the buckets' counts as a queuing wave of `trace_indirect` leaves them (the
//! wave's own keys are checked per kernel with the sorted waves of
//! [`super::trace_indirect`]).

use crate::harness::fixture::run_and_free;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::launch::DISPATCH_RECORD_WORDS;
use caustica_core::device::layout::PathSortParams;
use caustica_core::kernels::{DispatchArgs, DispatchRecord, SortIndirectPaths};
use caustica_core::math::path_sort::{path_sort_phase, PathKey, PATH_SORT_BUCKETS};
use caustica_core::recording::Recording;

/// What an order slot holds before the sort (no path placed there).
pub const UNPLACED: u32 = u32::MAX;

/// The buckets' counts a queuing wave leaves for `keys`: one per key below
/// [`PATH_SORT_BUCKETS`].
pub fn bucket_counts(keys: &[PathKey]) -> Vec<u32> {
    let mut counts = vec![0u32; PATH_SORT_BUCKETS as usize];
    for &[k, _] in keys {
        if let Some(c) = counts.get_mut(k as usize) {
            *c += 1;
        }
    }
    counts
}

/// The order and the buckets `sort_indirect_paths` leaves on `b` for a queue of `keys`
/// (capacity `keys.len()`, length word `length`).
pub fn run_sort(
    b: &mut dyn Backend,
    keys: &[PathKey],
    length: u32,
) -> Result<(Vec<u32>, Vec<u32>), String> {
    let n = keys.len().max(1) as u32;
    let mut rec = Recording::new();
    let path_keys = if keys.is_empty() {
        rec.create(1, "path keys")
    } else {
        rec.upload(keys, "path keys")
    };
    let order = rec.upload(&vec![UNPLACED; n as usize], "path order");
    // word 1 holds the length (word 0 another wave's)
    let path_counts = rec.upload(&[7u32, length], "queue lengths");
    let rows = rec.upload(&[[0, n, 1, 1]], "sort launch row");
    let args = rec.create::<u32>(DISPATCH_RECORD_WORDS as u32, "sort launch record");
    let buckets = rec.upload(&bucket_counts(keys), "buckets");
    rec.kernel(DispatchArgs {
        table: rows,
        counts: path_counts,
        args,
    });
    for phase in [path_sort_phase::SCAN, path_sort_phase::SCATTER] {
        rec.kernel(SortIndirectPaths {
            params: PathSortParams {
                phase,
                count_word: 1,
                _pad: [0; 2],
            },
            path_keys,
            path_counts,
            order,
            buckets,
            dispatch: Some(DispatchRecord { args, record: 0 }),
        });
    }
    run_and_free(b, "sort_indirect_paths", &rec, |b| {
        Ok((read_buf(b, order)?, read_buf(b, buckets)?))
    })
}

/// `sort_indirect_paths` on the reference `r` and the candidate `c` (see the module doc).
pub fn check_sort_indirect_paths(
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    keys: &[PathKey],
    length: u32,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("sort_indirect_paths");
    let live = (length as usize).min(keys.len());
    let (oa, ba) = run_sort(r, keys, length)?;
    let (ob, bb) = run_sort(c, keys, length)?;
    v.check(ba == bb, || {
        "the buckets' first slots differ from the reference's".into()
    });
    v.check(oa == ob, || {
        let first = oa.iter().zip(&ob).position(|(x, y)| x != y);
        format!("the order differs from the reference's (first at slot {first:?})")
    });
    // the reference itself: the first slots the counts' exclusive sums, every live path
    // of a valid key at first + rank, the keys along the order never decreasing
    let first: Vec<u32> = bucket_counts(keys)
        .iter()
        .scan(0u32, |sum, &c| {
            let f = *sum;
            *sum = sum.wrapping_add(c);
            Some(f)
        })
        .collect();
    v.check(ba == first, || "reference: the first slots are not the counts' sums".into());
    let mut want = vec![UNPLACED; keys.len().max(1)];
    for (i, &[k, rank]) in keys[..live].iter().enumerate() {
        if let Some(&f) = first.get(k as usize) {
            if let Some(s) = want.get_mut(f.wrapping_add(rank) as usize) {
                *s = i as u32;
            }
        }
    }
    v.check(oa == want, || {
        "reference: a path not at its bucket's first slot plus its rank".into()
    });
    let placed: Option<Vec<u32>> = oa
        .iter()
        .filter(|&&i| i != UNPLACED)
        .map(|&i| keys.get(i as usize).map(|k| k[0]))
        .collect();
    v.check(
        placed.is_some_and(|p| p.windows(2).all(|w| w[0] <= w[1])),
        || "reference: the order names a path past the queue or is not in key order".into(),
    );
    v.note(format!("{live} of {} paths", keys.len()));
    Ok(v)
}
