//! Per-kernel checks on fixed inputs (the first level of comparison, see
//! [`crate::harness`]): one file per registry kernel, named as its declaration in
//! `caustica_core::kernels` (`prepare_scene`, which only lays out the scene, has none: the
//! traced kernels' checks run on the prepared scene), each comparing the kernel's outputs
//! on a candidate with the reference's, on the same input buffers
//! ([`crate::harness::fixture`]), with the tolerances of [`crate::harness::tolerance`].
//! The modules are declared from core's list of the kernels with shader code; a check is
//! named by its module's path (`kernels::deposit_screen::check_deposit`).
//!
//! Kernels are checked together where one check covers a chain of them; the chain's
//! check lives in the file of the last kernel it runs, and each kernel's comparison in
//! its own file: `tile_hit_distance` and `bilateral_gather` share one verdict
//! ([`bilateral_gather::check_gather`]), though each compares on the reference's inputs
//! ([`tile_hit_distance`], [`bilateral_gather`]); so do the density gather's
//! `photon_count_table`, `gather_footprint` and `density_gather`
//! ([`density_gather::check_density_gather`]), CausticMap's `gather_caustic_map` and
//! `caustic_map_lookup` ([`caustic_map_lookup::check_caustic_map`]), AdaptiveCaustics'
//! adaptive `trace_photons` and `refine_clusters`
//! ([`refine_clusters::check_adaptive_caustics`],
//! [`refine_clusters::check_screen_target`]) and PhotonGi's five kernels
//! ([`shading_normal_correction::check_photon_gi`]). One chain starts its file instead:
//! `deposit_screen` and `resolve_caustics` run in one recording and the resolved radiance
//! is compared on each backend's *own* photon map, on the texels whose sums agree
//! ([`deposit_screen::check_deposit`]; the two comparisons are in [`deposit_screen`] and
//! [`resolve_caustics`]). `trace_photons`' fused variants are checked against the deposit
//! they fuse: [`trace_photons::check_fused_trace`] (atlas) in [`trace_photons`],
//! [`deposit_screen::check_fused_screen_trace`] in [`deposit_screen`].
//!
//! [`check_kernel_cases`] runs one check for a candidate over the fixed cases
//! ([`crate::harness::kernel_cases`]).

/// Called with core's list of the kernels with shader code
/// ([`caustica_core::with_shader_kernels`], every kernel but `prepare_scene`): one module
/// per kernel.
macro_rules! kernel_modules {
    ($($name:ident),* $(,)?) => {
        $(pub mod $name;)*
    };
}

caustica_core::with_shader_kernels!(kernel_modules);

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
