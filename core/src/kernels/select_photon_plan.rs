//! `select_photon_plan`: PhotonGi's photon plan picked on the device (Smal 2019, section
//! 24.2.1; [`crate::math::photon_plan`]), so that a light, instance or material change
//! needs no readback: after each light's RSM the plan notes whether it sees a texel that
//! leaves flux and copies the plan table's row of the lights seen so far; the later
//! `sample_rsm`, `trace_indirect`, splat and resolve launches read their counts and
//! quanta from it ([`crate::device::launch::ParamPatch`]).

use super::{bind, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::Buf;
use crate::device::layout::{photon_plan_word, PlanParams, NO_PLAN_BIT};
use crate::math::rsm::pyramid_len;

/// One thread: `mask = plan[MASK]`; where `params.bit` names a light
/// ([`PlanParams::bit`]), its bit is set if the top of one of the pyramid's faces `0 ..
/// params.faces` is positive ([`crate::math::photon_plan::rsm_sees`],
/// [`crate::math::photon_plan::note_light`]); `plan[MASK] = mask` and `plan[ROW ..
/// ROW + row_words]` = the table's row `mask` ([`crate::math::photon_plan::plan_row`]
/// over the table's first `params.table_words` words; a row past them leaves those words
/// as they were).
#[derive(Clone, Copy, Debug)]
pub struct SelectPhotonPlan {
    /// The light's bit and faces, the RSM side, the row length.
    pub params: PlanParams,
    /// The light's importance pyramids (`rsm_importance`, every level; read only where
    /// `params.bit` names a light).
    pub pyramid: Buf<f32>,
    /// The plan table: row `m` (`params.row_words` words) is the plan where the lights
    /// of mask `m` see something.
    pub table: Buf<u32>,
    /// Input and output: the plan ([`photon_plan_word`]).
    pub plan: Buf<u32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("pyramid", Read),
    bind("table", Read),
    bind("plan", ReadWrite),
];

impl KernelDecl for SelectPhotonPlan {
    const INFO: KernelInfo = KernelInfo::compute("select_photon_plan", BINDINGS, "PhotonGi");

    /// Its parameters may come partly from the device ([`crate::device::launch::ParamPatch`]).
    fn params_mut(&mut self) -> Option<&mut [u8]> {
        Some(bytemuck::bytes_of_mut(&mut self.params))
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let noted = p.bit != NO_PLAN_BIT;
        if !p.side.is_power_of_two() || p.faces > 6 || (noted && (p.faces == 0 || p.bit >= 32)) {
            return Err(BackendError::BadArgument(format!(
                "select_photon_plan: side {} must be a power of two, faces {} in 1..=6, \
                 bit {} below 32 (or NO_PLAN_BIT)",
                p.side, p.faces, p.bit
            )));
        }
        let pyramid = if noted {
            p.faces as u64 * pyramid_len(p.side) as u64 * 4
        } else {
            0
        };
        a.params("params", p)?
            .buf("pyramid", self.pyramid, pyramid)?
            .buf("table", self.table, p.table_words as u64 * 4)?
            .buf(
                "plan",
                self.plan,
                (photon_plan_word::ROW as u64 + p.row_words as u64) * 4,
            )?;
        Ok(Some(1))
    }
}
