//! PhotonGi's photon plan on the device: `select_photon_plan` on every backend against
//! core's `math::photon_plan` (bitwise: integer words and the sign of `f32` pyramid tops),
//! with host parameters and with parameters copied in from a device buffer, on
//! proptest-drawn pyramids (tops zero, negative, subnormal, the smallest normal, NaN or
//! positive), masks, bits
//! and tables (rows missing past the table's end too).

use caustica_conformance::harness;
use caustica_conformance::kernels::select_photon_plan::{check_select_photon_plan, PlanCase};
use caustica_conformance::strategies;
use caustica_core::device::layout::{photon_plan_word, PlanParams, NO_PLAN_BIT};
use caustica_core::math::rsm::{level_count, level_offset, pyramid_len};
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};
use std::cell::RefCell;

/// A pyramid top: zero (either sign), negative, subnormal (no flux: a device that flushes
/// subnormals reads zero), the smallest normal (flux), NaN or positive.
fn top() -> impl Strategy<Value = f32> {
    prop_oneof![
        Just(0.0f32),
        Just(-0.0f32),
        Just(f32::NAN),
        Just(f32::MIN_POSITIVE * 0.25),
        Just(f32::MIN_POSITIVE),
        -1e3f32..0.0,
        0.0f32..1e3,
    ]
}

fn cases() -> impl Strategy<Value = PlanCase> {
    (
        0u32..4,
        1u32..=6,
        prop_oneof![3 => 0u32..8, 1 => Just(NO_PLAN_BIT), 1 => 8u32..32],
        0usize..4,
        0u32..3,
        proptest::collection::vec(top(), 6),
        any::<u64>(),
    )
        .prop_map(|(log_side, faces, bit, lights, short, tops, seed)| {
            let side = 1u32 << log_side;
            let (len, at) = (
                pyramid_len(side) as usize,
                level_offset(side, level_count(side) - 1) as usize,
            );
            let mut state = seed | 1;
            let mut next = || {
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                state as u32
            };
            let mut pyramid: Vec<f32> = (0..faces as usize * len)
                .map(|_| (next() >> 8) as f32 * (1.0 / 16_777_216.0))
                .collect();
            for f in 0..faces as usize {
                pyramid[f * len + at] = tops[f];
            }
            // rows of [power scale, flux quantum, resolve quantum, counts...]
            let row_words = (photon_plan_word::COUNTS - photon_plan_word::ROW + lights) as u32;
            // every mask of the lights' bits (and of the drawn bit), some rows cut off
            let rows =
                (1usize << (bit.min(8) as usize + 1).max(lights)).saturating_sub(short as usize);
            let table: Vec<u32> = (0..rows * row_words as usize).map(|_| next()).collect();
            let mut plan: Vec<u32> = (0..photon_plan_word::ROW + row_words as usize)
                .map(|_| next())
                .collect();
            plan[photon_plan_word::MASK] = next() % (rows as u32 + 2);
            PlanCase {
                params: PlanParams {
                    side,
                    faces,
                    bit,
                    row_words,
                    table_words: table.len() as u32,
                    _pad: [0; 3],
                },
                pyramid,
                table,
                plan,
            }
        })
}

#[test]
fn select_photon_plan_matches_core_with_host_and_device_parameters() {
    let test = "select_photon_plan on generated pyramids and tables";
    let reference = RefCell::new(harness::reference());
    for cand in harness::candidates(test) {
        let name = cand.name.clone();
        let backend = RefCell::new(cand.backend);
        let mut runner = TestRunner::new(strategies::config());
        // a table shorter than the 64 bytes wgpu binds at least, its mask's row past the
        // end: the row must stay as it was (the kernel reads the table's length from its
        // parameters, never from its binding)
        let short = PlanCase {
            params: PlanParams {
                side: 2,
                faces: 2,
                bit: 0,
                row_words: 3,
                table_words: 3,
                _pad: [0; 3],
            },
            pyramid: vec![0.5; 2 * pyramid_len(2) as usize],
            table: vec![11, 12, 13],
            plan: vec![0, 21, 22, 23],
        };
        {
            let mut r = reference.borrow_mut();
            let mut c = backend.borrow_mut();
            let v = check_select_photon_plan(&mut *r, c.as_mut(), &short)
                .unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(v.passed(), "{name}: a short table: {v}");
        }
        let result = runner.run(&cases(), |case| {
            let mut r = reference.borrow_mut();
            let mut c = backend.borrow_mut();
            let v = check_select_photon_plan(&mut *r, c.as_mut(), &case)
                .map_err(TestCaseError::fail)?;
            if v.passed() {
                Ok(())
            } else {
                Err(TestCaseError::fail(format!("{v}case {case:?}")))
            }
        });
        if let Err(e) = result {
            panic!("{name}: {e}");
        }
        harness::loud(&format!(
            "{test}: {name} agrees with core on {} generated cases",
            strategies::config().cases
        ));
    }
}
