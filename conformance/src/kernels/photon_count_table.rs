//! `photon_count_table` on the reference's photon map and G-buffer: the summed-area table
//! (integer sums of the same counts) and the edge texels (copies of the G-buffer's bits,
//! or the not-a-receiver mark) bitwise equal. Part of the density gather's verdict,
//! [`super::density_gather::check_density_gather`].

use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;

/// The table and edge texels of both backends, compared into `v`.
pub(crate) fn check_count_table(
    v: &mut Verdict,
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<(), String> {
    // integer sums of the same counts: bitwise; the edge texels are copies of the
    // G-buffer's bits (or the not-a-receiver mark): bitwise
    let (ta, ea) = fx.run_count_table(r, &inputs.gbuffer, &inputs.photon_map)?;
    let (tb, eb) = fx.run_count_table(c, &inputs.gbuffer, &inputs.photon_map)?;
    let differ = ta.iter().zip(&tb).filter(|(a, b)| a != b).count();
    v.check(differ == 0, || {
        format!(
            "photon_count_table differs on {differ} of {} entries",
            ta.len()
        )
    });
    let differ = ea
        .iter()
        .zip(&eb)
        .filter(|(a, b)| a.map(f32::to_bits) != b.map(f32::to_bits))
        .count();
    v.check(differ == 0, || {
        format!("photon_count_table's edge texels differ on {differ} pixels")
    });

    Ok(())
}
