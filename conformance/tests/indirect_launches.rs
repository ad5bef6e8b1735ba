//! Indirect launches: a kernel's size read from the device (`dispatch_args` records and
//! the lengths the kernels bound themselves by), on every backend against the CPU, with
//! proptest-drawn counts from 0 past the recorded bound.

use caustica_conformance::harness::fixture::Fixture;
use caustica_conformance::harness::{self, kernel_cases};
use caustica_conformance::kernels::dispatch_args::check_dispatch_args;
use caustica_conformance::kernels::refine_clusters::check_indirect_refinement;
use caustica_conformance::strategies;
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};
use std::cell::RefCell;

/// Rows `[first, bound, per_item, word]` and the counts they read: counts from 0 to
/// past `first + bound`, bounds up to 2^22 items, 1 to 8 threads an item.
fn rows_and_counts() -> impl Strategy<Value = (Vec<[u32; 4]>, Vec<u32>)> {
    (1usize..4).prop_flat_map(|words| {
        let row = (0u32..1 << 20, 0u32..1 << 22, 1u32..9, 0..words as u32)
            .prop_map(|(first, bound, per, word)| [first, bound, per, word]);
        let count = prop_oneof![Just(0u32), 0u32..64, 0u32..(1 << 23), Just(u32::MAX),];
        (
            proptest::collection::vec(row, 1..6),
            proptest::collection::vec(count, words),
        )
    })
}

#[test]
fn dispatch_records_match_core_for_any_count() {
    harness::check_generated(
        "dispatch_args on generated rows",
        rows_and_counts(),
        |r, c, (rows, counts)| check_dispatch_args(r, c, rows, counts),
    );
}

#[test]
fn indirect_refinement_matches_cpu_for_any_list_length() {
    let test = "refine_clusters launched indirectly";
    let cases = kernel_cases();
    let (case, scene, settings) = cases
        .iter()
        .find(|c| c.0 == "sphere")
        .expect("the sphere case");
    for cand in harness::candidates(test) {
        let name = cand.name.clone();
        let reference = RefCell::new(harness::reference());
        let backend = RefCell::new(cand.backend);
        let fx = Fixture::new(
            case,
            scene,
            settings,
            &mut *reference.borrow_mut(),
            backend.borrow_mut().as_mut(),
        )
        .expect("the fixture");
        let mut runner = TestRunner::new(strategies::config());
        let result = runner.run(&proptest::collection::vec(0u32..300, 1..5), |lengths| {
            let mut r = reference.borrow_mut();
            let mut c = backend.borrow_mut();
            let v = check_indirect_refinement(&fx, &mut *r, c.as_mut(), &lengths)
                .map_err(TestCaseError::fail)?;
            if v.passed() {
                Ok(())
            } else {
                Err(TestCaseError::fail(format!("{v}lengths {lengths:?}")))
            }
        });
        fx.release(&mut *reference.borrow_mut(), backend.borrow_mut().as_mut());
        if let Err(e) = result {
            panic!("{name}: {e}");
        }
        harness::loud(&format!(
            "{test}: {name} agrees with cpu on {} generated cases",
            strategies::config().cases
        ));
    }
}
