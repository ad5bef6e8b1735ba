//! PhotonGi's photon plan picked on the device (Smal 2019, section 24.2.1: photons
//! allocated to the lights by power): the host tables one plan row (power unit, flux
//! quanta, per-light photon counts) for every set of lights whose RSM sees something,
//! and `select_photon_plan` notes, after each light's RSM, whether it sees a texel that
//! leaves flux ([`rsm_sees`], [`note_light`]) and copies the row of the lights seen so
//! far ([`plan_row`]). The shader ports mirror these functions by name.

/// The least pyramid top that counts as flux: the smallest normal `f32`. A subnormal top
/// counts as zero, as on devices whose shaders flush subnormals to zero (NVIDIA's Vulkan
/// and wgpu pipelines), where `top > 0` would read it as zero and the CPU as flux; the
/// same comparison gives every backend the same plan.
pub const RSM_SEEN_MIN_TOP: f32 = f32::MIN_POSITIVE;

/// Whether a light's RSM sees a texel that leaves flux: the top of some face's importance
/// pyramid (the sum of its level-0 entries, each zero exactly where the texel's flux x
/// albedo is zero, under either sampling) is at least [`RSM_SEEN_MIN_TOP`]. A NaN or
/// subnormal top does not count.
pub fn rsm_sees(tops: &[f32]) -> bool {
    tops.iter().any(|&t| t >= RSM_SEEN_MIN_TOP)
}

/// `mask` with bit `bit` set where `sees` (a bit of 32 or more, such as
/// [`crate::device::layout::NO_PLAN_BIT`], leaves it unchanged).
pub fn note_light(mask: u32, bit: u32, sees: bool) -> u32 {
    if sees && bit < 32 {
        mask | (1u32 << bit)
    } else {
        mask
    }
}

/// Row `mask` of a plan table of `row_words`-word rows, or `None` where the table has no
/// such row (the plan then keeps its last row).
pub fn plan_row(table: &[u32], row_words: u32, mask: u32) -> Option<&[u32]> {
    let start = (mask as usize).checked_mul(row_words as usize)?;
    table.get(start..start.checked_add(row_words as usize)?)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_light_is_seen_where_a_top_is_a_normal_positive_float() {
        assert!(!rsm_sees(&[]));
        assert!(!rsm_sees(&[0.0, -0.0, f32::NAN]));
        assert!(!rsm_sees(&[0.0, f32::MIN_POSITIVE * 0.5]));
        assert!(rsm_sees(&[0.0, f32::MIN_POSITIVE]));
        assert_eq!(note_light(0b100, 0, true), 0b101);
        assert_eq!(note_light(0b100, 0, false), 0b100);
        assert_eq!(note_light(0b100, u32::MAX, true), 0b100);
        assert_eq!(note_light(0, 31, true), 1 << 31);
        assert_eq!(plan_row(&[1, 2, 3, 4, 5, 6], 3, 1), Some(&[4, 5, 6][..]));
        assert_eq!(plan_row(&[1, 2, 3, 4, 5, 6], 3, 2), None);
        assert_eq!(plan_row(&[1, 2, 3], 3, u32::MAX), None);
    }
}
