//! Per-kernel checks on fixed inputs (the first level of comparison, see
//! [`crate::harness`]): one file per kernel, each comparing the
//! kernel's outputs on a candidate with the reference's, on the same input buffers
//! ([`crate::harness::fixture`]), with the tolerances of [`crate::harness::tolerance`].
//!
//! Two kernels are checked together where one check covers both: `deposit_screen` and
//! `resolve_caustics` run in one recording and the resolved radiance is compared on each
//! backend's *own* photon map, on the texels whose sums agree ([`check_deposit`]; the two
//! comparisons are in [`deposit_screen`] and [`resolve_caustics`]); `tile_hit_distance` and
//! `bilateral_gather` share one verdict ([`check_gather`]), though each compares on the
//! reference's inputs ([`tile_hit_distance`], [`bilateral_gather`]); so do the density
//! gather's `photon_count_table`, `gather_footprint` and `density_gather`
//! ([`check_density_gather`]).
//!
//! [`check_kernel_cases`] runs one check for a candidate over the fixed cases
//! ([`crate::harness::kernel_cases`]).

pub mod adaptive_caustics;
pub mod atrous_filter;
pub mod bilateral_gather;
pub mod caustic_map;
pub mod composite;
pub mod density_gather;
pub mod deposit_screen;
pub mod direct_light;
pub mod photon_gi;
pub mod primary_gbuffer;
pub mod resolve_caustics;
pub mod temporal_blend;
pub mod tile_hit_distance;
pub mod trace_photons;

pub use adaptive_caustics::{check_adaptive_caustics, check_screen_target};
pub use atrous_filter::check_atrous_filter;
pub use bilateral_gather::check_gather;
pub use caustic_map::{check_caustic_map, check_fused_trace};
pub use composite::check_composite;
pub use density_gather::check_density_gather;
pub use deposit_screen::{check_deposit, check_fused_screen_trace};
pub use direct_light::check_direct;
pub use photon_gi::check_photon_gi;
pub use primary_gbuffer::{check_gbuffer, compare_gbuffers};
pub use temporal_blend::check_temporal_blend;
pub use trace_photons::check_trace;

use crate::harness::{Candidate, Fixture, ReferenceInputs, Report, Verdict};
use caustica_core::backend::Backend;
use caustica_core::scene::Scene;
use caustica_core::SspmSettings;

/// A per-kernel check on fixed inputs (reference first, candidate second).
pub type KernelCheck = dyn Fn(
    &Fixture,
    &ReferenceInputs,
    &mut dyn Backend,
    &mut dyn Backend,
) -> Result<Verdict, String>;

/// Runs `check` for `candidate` on every case, adding one verdict per case to `report`.
pub fn check_kernel_cases(
    report: &mut Report,
    reference: &mut dyn Backend,
    candidate: &mut Candidate,
    cases: &[(String, Scene, SspmSettings)],
    check: &KernelCheck,
) {
    let c = candidate.backend.as_mut();
    for (name, scene, settings) in cases {
        let fx = match Fixture::new(name, scene, settings, reference, c) {
            Ok(fx) => fx,
            Err(e) => {
                report.error(&candidate.name, name, e);
                continue;
            }
        };
        let result = ReferenceInputs::new(&fx, reference)
            .and_then(|inputs| check(&fx, &inputs, reference, c));
        match result {
            Ok(v) => report.add(&candidate.name, name, v),
            Err(e) => report.error(&candidate.name, name, e),
        }
        fx.release(reference, c);
    }
}
