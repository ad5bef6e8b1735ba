//! `sort_indirect_paths`: integer counts and a key of one subtraction and one product per
//! axis (exact in every port, no contraction possible), so every backend must put the
//! same paths in the same buckets: the buckets' ends **bitwise** the CPU's, the sorted
//! queue a permutation of the input's live paths whose keys (core's
//! [`path_sort_key`]) never decrease. Within a bucket the order is free (a GPU's atomics),
//! so the queue is compared bucket by bucket as multisets. Launched as PhotonGi launches
//! it: the histogram and the scatter from `dispatch_args`' record of the queue's length
//! (drawn from 0 past the queue's capacity by the proptest in
//! `conformance/tests/photon_gi_schedules.rs`).

use crate::harness::fixture::run_and_free;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::launch::DISPATCH_RECORD_WORDS;
use caustica_core::device::layout::{IndirectPath, PathSortParams};
use caustica_core::kernels::{DispatchArgs, DispatchRecord, SortIndirectPaths};
use caustica_core::math::path_sort::{path_sort_key, path_sort_phase, PATH_SORT_BUCKETS};
use caustica_core::recording::Recording;
use glam::Vec3;

/// The sorted queue and the buckets `sort_indirect_paths` leaves on `b` for `paths`
/// (capacity `paths.len()`, length word `length`).
pub fn run_sort(
    b: &mut dyn Backend,
    paths: &[IndirectPath],
    length: u32,
    (origin_min, origin_scale): ([f32; 3], [f32; 3]),
) -> Result<(Vec<IndirectPath>, Vec<u32>), String> {
    let n = paths.len().max(1) as u32;
    let mut rec = Recording::new();
    let paths_in = if paths.is_empty() {
        rec.create(1, "queued paths")
    } else {
        rec.upload(paths, "queued paths")
    };
    let paths_out = rec.create::<IndirectPath>(n, "sorted paths");
    // word 1 holds the length (word 0 another wave's)
    let path_counts = rec.upload(&[7u32, length], "queue lengths");
    let rows = rec.upload(&[[0, n, 1, 1]], "sort launch row");
    let args = rec.create::<u32>(DISPATCH_RECORD_WORDS as u32, "sort launch record");
    let buckets = rec.create::<u32>(PATH_SORT_BUCKETS, "buckets");
    rec.clear(buckets);
    rec.kernel(DispatchArgs {
        table: rows,
        counts: path_counts,
        args,
    });
    for phase in [
        path_sort_phase::HISTOGRAM,
        path_sort_phase::SCAN,
        path_sort_phase::SCATTER,
    ] {
        rec.kernel(SortIndirectPaths {
            params: PathSortParams {
                origin_min,
                phase,
                origin_scale,
                count_word: 1,
            },
            paths_in,
            path_counts,
            paths_out,
            buckets,
            dispatch: Some(DispatchRecord { args, record: 0 }),
        });
    }
    run_and_free(b, "sort_indirect_paths", &rec, |b| {
        Ok((read_buf(b, paths_out)?, read_buf(b, buckets)?))
    })
}

/// `sort_indirect_paths` on the reference `r` and the candidate `c` (see the module doc).
pub fn check_sort_indirect_paths(
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    paths: &[IndirectPath],
    length: u32,
    key_box: ([f32; 3], [f32; 3]),
) -> Result<Verdict, String> {
    let mut v = Verdict::new("sort_indirect_paths");
    let live = (length as usize).min(paths.len());
    let key = |p: &IndirectPath| {
        path_sort_key(
            Vec3::from(p.origin),
            Vec3::from(p.direction),
            Vec3::from(key_box.0),
            Vec3::from(key_box.1),
        )
    };
    let words = |p: &IndirectPath| bytemuck::cast::<IndirectPath, [u32; 12]>(*p);
    let mut input: Vec<(u32, [u32; 12])> =
        paths[..live].iter().map(|p| (key(p), words(p))).collect();
    input.sort_unstable();
    let (qa, ba) = run_sort(r, paths, length, key_box)?;
    let (qb, bb) = run_sort(c, paths, length, key_box)?;
    v.check(ba == bb, || {
        "the buckets' ends differ from the reference's".into()
    });
    for (name, q) in [("reference", &qa), ("candidate", &qb)] {
        let sorted = &q[..live.min(q.len())];
        v.check(sorted.windows(2).all(|w| key(&w[0]) <= key(&w[1])), || {
            format!("{name}: the queue is not in key order")
        });
        let mut got: Vec<(u32, [u32; 12])> = sorted.iter().map(|p| (key(p), words(p))).collect();
        got.sort_unstable();
        v.check(got == input, || {
            format!("{name}: the sorted queue is not a permutation of the live paths")
        });
    }
    v.note(format!("{live} of {} paths", paths.len()));
    Ok(v)
}
