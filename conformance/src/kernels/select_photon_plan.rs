//! `select_photon_plan`: integer words and a sign test of `f32` pyramid tops (`t > 0`,
//! exact in IEEE arithmetic on every device, NaN false everywhere), so every plan must be
//! **bitwise** the one core's `math::photon_plan` functions give (the specification the
//! shaders mirror), for any tops, mask, bit and table (the proptest in
//! `conformance/tests/photon_plan.rs` draws them). The same launch with its `bit` and
//! `row_words` copied in from a device buffer
//! ([`caustica_core::device::launch::ParamPatch`]) must give the same plan: that checks
//! every backend's parameter patches.

use crate::harness::fixture::run_and_free;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::launch::ParamPatch;
use caustica_core::device::layout::{photon_plan_word, PlanParams, NO_PLAN_BIT};
use caustica_core::kernels::SelectPhotonPlan;
use caustica_core::math::photon_plan::{note_light, plan_row, rsm_sees};
use caustica_core::math::rsm::{level_count, level_offset, pyramid_len};
use caustica_core::recording::Recording;
use std::mem::offset_of;

/// One launch's inputs: the parameters, a pyramid of `params.faces` faces, the table and
/// the plan before.
#[derive(Clone, Debug)]
pub struct PlanCase {
    pub params: PlanParams,
    pub pyramid: Vec<f32>,
    pub table: Vec<u32>,
    pub plan: Vec<u32>,
}

/// The plan core's functions give for `case`.
pub fn expected_plan(case: &PlanCase) -> Vec<u32> {
    let p = &case.params;
    let mut plan = case.plan.clone();
    let mut mask = plan[photon_plan_word::MASK];
    if p.bit != NO_PLAN_BIT {
        let (len, top) = (
            pyramid_len(p.side) as usize,
            level_offset(p.side, level_count(p.side) - 1) as usize,
        );
        let tops: Vec<f32> = (0..p.faces as usize)
            .map(|f| case.pyramid[f * len + top])
            .collect();
        mask = note_light(mask, p.bit, rsm_sees(&tops));
    }
    plan[photon_plan_word::MASK] = mask;
    if let Some(row) = plan_row(&case.table, p.row_words, mask) {
        let at = photon_plan_word::ROW;
        plan[at..at + row.len()].copy_from_slice(row);
    }
    plan
}

/// The plan `select_photon_plan` leaves on `b` for `case`; with `patched`, the launch's
/// `bit` and `row_words` come from a device buffer (its host parameters hold others).
pub fn run_select_photon_plan(
    b: &mut dyn Backend,
    case: &PlanCase,
    patched: bool,
) -> Result<Vec<u32>, String> {
    let mut rec = Recording::new();
    let pyramid = rec.upload(&case.pyramid, "RSM importance pyramid");
    let table = rec.upload(&case.table, "plan table");
    let plan = rec.upload(&case.plan, "photon plan");
    let mut params = case.params;
    if patched {
        // words 1 and 2: bit and row_words, between two words the patch must not touch
        let words = rec.upload(&[7u32, params.bit, params.row_words, 9], "parameter words");
        // host values a launch without the patch would read
        params.bit = NO_PLAN_BIT;
        params.row_words = 0;
        rec.kernel_patched(
            SelectPhotonPlan {
                params,
                pyramid,
                table,
                plan,
            },
            vec![ParamPatch {
                offset: offset_of!(PlanParams, bit) as u32,
                src: words.id,
                src_word: 1,
                words: 2,
            }],
        );
    } else {
        rec.kernel(SelectPhotonPlan {
            params,
            pyramid,
            table,
            plan,
        });
    }
    run_and_free(b, "select_photon_plan", &rec, |b| read_buf(b, plan))
}

/// `select_photon_plan` on the reference `r` and the candidate `c`, with host and with
/// device parameters: all four bitwise equal to [`expected_plan`].
pub fn check_select_photon_plan(
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    case: &PlanCase,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("select_photon_plan");
    let expected = expected_plan(case);
    for patched in [false, true] {
        let how = if patched { "device" } else { "host" };
        let a = run_select_photon_plan(r, case, patched)?;
        let b = run_select_photon_plan(c, case, patched)?;
        v.check(a == expected, || {
            format!("reference plan with {how} parameters {a:?}, core's {expected:?}")
        });
        v.check(b == expected, || {
            format!("candidate plan with {how} parameters {b:?}, core's {expected:?}")
        });
    }
    v.note(format!(
        "bit {}, {} faces, mask {:#x}",
        case.params.bit, case.params.faces, expected[photon_plan_word::MASK]
    ));
    Ok(v)
}
