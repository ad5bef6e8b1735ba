//! `select_photon_plan`: PhotonGi's photon plan picked on the device (Smal 2019, section
//! 24.2.1; core's `math::photon_plan`). Mirror of shaders/wgsl/select_photon_plan.wgsl
//! and backend-opencl/kernels/select_photon_plan.cl.

use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{photon_plan_word, PlanParams, NO_PLAN_BIT};
use caustica_core::kernels::SelectPhotonPlan;
use caustica_core::math::photon_plan::{note_light, plan_row, rsm_sees};
use caustica_core::math::rsm::{level_count, level_offset, pyramid_len};

/// Runs `select_photon_plan` on the host ([`super::run`]'s arm): its buffers read from
/// `cpu`, the plan written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &SelectPhotonPlan) -> Result<(), BackendError> {
    let p = &k.params;
    let pyramid: &[f32] = if p.bit == NO_PLAN_BIT {
        &[]
    } else {
        cpu.get(k.pyramid.id)?.as_slice(k.pyramid.len)?
    };
    let table = cpu
        .get(k.table.id)?
        .as_slice::<u32>(p.table_words.min(k.table.len))?;
    let mut plan = cpu.get(k.plan.id)?.as_slice::<u32>(k.plan.len)?.to_vec();
    select_photon_plan(p, pyramid, table, &mut plan);
    cpu.put(k.plan.id, &plan)
}

/// The kernel's one thread: the light's bit noted from its faces' pyramid tops, the
/// mask's row copied into the plan.
pub fn select_photon_plan(p: &PlanParams, pyramid: &[f32], table: &[u32], plan: &mut [u32]) {
    let Some(&old) = plan.get(photon_plan_word::MASK) else {
        return;
    };
    let mut mask = old;
    if p.bit != NO_PLAN_BIT {
        let (len, top) = (
            pyramid_len(p.side) as usize,
            level_offset(p.side, level_count(p.side) - 1) as usize,
        );
        let tops: Vec<f32> = (0..p.faces.min(6) as usize)
            .map(|f| pyramid.get(f * len + top).copied().unwrap_or(0.0))
            .collect();
        mask = note_light(mask, p.bit, rsm_sees(&tops));
    }
    plan[photon_plan_word::MASK] = mask;
    if let Some(row) = plan_row(table, p.row_words, mask) {
        let at = photon_plan_word::ROW;
        if let Some(dst) = plan.get_mut(at..at + row.len()) {
            dst.copy_from_slice(row);
        }
    }
}
