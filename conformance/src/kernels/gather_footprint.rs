//! `gather_footprint` on the reference's edge texels, photon map and table: radius and
//! normalised flux within [`DENSITY_GATHER_REL`] (the argument is in
//! [`super::density_gather`]), the source index an integer function of the kernel's own
//! output. Part of the density gather's verdict,
//! [`super::density_gather::check_density_gather`].

use super::density_gather::{compare, Alpha};
use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::tolerance::DENSITY_GATHER_REL;
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;

/// The footprints of both backends, compared into `v`.
pub(crate) fn check_footprint(
    v: &mut Verdict,
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<(), String> {
    let (fa, grid_a) = fx.run_footprint(r, &inputs.edge, &inputs.photon_map, &inputs.table)?;
    let (fb, grid_b) = fx.run_footprint(c, &inputs.edge, &inputs.photon_map, &inputs.table)?;
    // the source index is an integer function of the kernel's own output: equal
    for (who, f, grid) in [("reference", &fa, &grid_a), ("candidate", &fb, &grid_b)] {
        let want = fx.source_index_of(fx.empty_source_index(), 0, f);
        v.check(*grid == want, || {
            format!("gather_footprint's source index on the {who} is not its output's")
        });
    }
    // the radius is ~7 ulp from the same integers: compared as a channel
    let radius: Vec<[f32; 4]> = fa.iter().map(|p| [p[3], 0.0, 0.0, 0.0]).collect();
    let radius_b: Vec<[f32; 4]> = fb.iter().map(|p| [p[3], 0.0, 0.0, 0.0]).collect();
    compare(
        v,
        "gather_footprint radius",
        &fx.camera,
        (&radius, &radius_b),
        &|_, _| (DENSITY_GATHER_REL, 0.0, 0.0),
        Alpha::Free,
    );
    compare(
        v,
        "gather_footprint flux",
        &fx.camera,
        (&fa, &fb),
        &|_, _| (DENSITY_GATHER_REL, 0.0, 0.0),
        Alpha::Free,
    );

    Ok(())
}
