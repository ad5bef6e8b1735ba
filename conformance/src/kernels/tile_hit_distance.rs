//! `tile_hit_distance` on the reference's photon map: every tile within [`TILE_REL`]
//! relative. Checked in the verdict of [`super::bilateral_gather::check_gather`].

use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::tolerance::{within_rel, TILE_REL};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;

/// Runs `tile_hit_distance` on the reference's photon map on both backends and records in
/// `v` a failure unless every tile agrees within [`TILE_REL`].
pub fn compare_tiles(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    v: &mut Verdict,
) -> Result<(), String> {
    let ta = fx.run_tiles(r, &inputs.photon_map)?;
    let tb = fx.run_tiles(c, &inputs.photon_map)?;
    let bad_tiles = ta
        .iter()
        .zip(&tb)
        .filter(|(a, b)| !within_rel(**a, **b, TILE_REL))
        .count();
    v.check(bad_tiles == 0, || {
        format!(
            "tile_hit_distance differs on {bad_tiles} of {} tiles",
            ta.len()
        )
    });
    Ok(())
}
