//! `dispatch_args`: integer arithmetic only, so every record must be **bitwise** the
//! CPU's and core's [`dispatch_record`] (the specification the shaders mirror), for any
//! counts, first entries, bounds and threads per item (the proptest in
//! `conformance/tests/indirect_launches.rs` draws them, counts from 0 past the bound).

use crate::harness::fixture::run_and_free;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::launch::DISPATCH_RECORD_WORDS;
use caustica_core::kernels::{dispatch_record, DispatchArgs};
use caustica_core::recording::Recording;

/// The records `dispatch_args` writes on `b` for `rows` (`[first, bound, per_item, word]`)
/// over `counts`.
pub fn run_dispatch_args(
    b: &mut dyn Backend,
    rows: &[[u32; 4]],
    counts: &[u32],
) -> Result<Vec<u32>, String> {
    let mut rec = Recording::new();
    let table = rec.upload(rows, "dispatch rows");
    let counts = rec.upload(counts, "counts");
    let args = rec.create(
        (rows.len() * DISPATCH_RECORD_WORDS) as u32,
        "dispatch records",
    );
    rec.kernel(DispatchArgs {
        table,
        counts,
        args,
    });
    run_and_free(b, "dispatch_args", &rec, |b| read_buf(b, args))
}

/// `dispatch_args` on the reference `r` and the candidate `c`: both bitwise equal to
/// [`dispatch_record`] of every row.
pub fn check_dispatch_args(
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    rows: &[[u32; 4]],
    counts: &[u32],
) -> Result<Verdict, String> {
    let mut v = Verdict::new("dispatch_args");
    let expected: Vec<u32> = rows
        .iter()
        .flat_map(|&[first, bound, per_item, word]| {
            dispatch_record(counts[word as usize], first, bound, per_item)
        })
        .collect();
    let a = run_dispatch_args(r, rows, counts)?;
    let b = run_dispatch_args(c, rows, counts)?;
    v.check(a == expected, || {
        format!("reference records {a:?}, core's dispatch_record {expected:?}")
    });
    v.check(b == expected, || {
        format!("candidate records {b:?}, core's dispatch_record {expected:?}")
    });
    v.note(format!("{} rows", rows.len()));
    Ok(v)
}
