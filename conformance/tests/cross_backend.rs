//! Cross-backend conformance. Every test is declared once, generic over
//! `&mut dyn Backend`, and runs for every backend of `caustica_conformance::backends()`
//! except cpu, compared with the CPU reference (`CpuBackend::new()`). With only cpu on the
//! machine a fresh 1-thread CPU backend stands in, so that the comparisons still run and
//! assert; each test says loudly (on stderr, past the harness's capture) what it compares.
//!
//! Per kernel, on fixed inputs (every built-in scene at 96x55 plus a few generated scenes):
//! the scene is uploaded to both backends, and every kernel after the first runs on the
//! *CPU's* intermediate buffers uploaded to both, so only the kernel under test differs.
//! Per technique: whole Sspm frames on every built-in scene and on proptest scenes.
//! The checks are in `caustica_conformance::kernels` (one file per kernel) and
//! `caustica_conformance::techniques`, the argument behind every tolerance in
//! `caustica_conformance::harness::tolerance`, the scene strategies in `strategies`.

use caustica_conformance::harness::{self, builtin_small, kernel_cases, Report};
use caustica_conformance::kernels::{
    atrous_filter::check_atrous_filter,
    bilateral_gather::check_gather,
    caustic_map_lookup::check_caustic_map,
    check_kernel_cases,
    composite::check_composite,
    density_gather::check_density_gather,
    deposit_screen::{check_deposit, check_fused_screen_trace},
    direct_light::check_direct,
    place_vertices::check_place_vertices,
    primary_gbuffer::check_gbuffer,
    refine_clusters::{check_adaptive_caustics, check_screen_target},
    shading_normal_correction::check_photon_gi,
    temporal_blend::check_temporal_blend,
    trace_photons::{check_fused_trace, check_trace},
    KernelCheck,
};
use caustica_conformance::techniques::sspm::check_frame;
use caustica_conformance::{small_settings, strategies};
use caustica_core::scene::builtin::BUILTIN_SCENES;
use proptest::test_runner::{TestCaseError, TestRunner};
use std::cell::RefCell;

/// Runs `check` for every candidate backend on every kernel case and reports.
fn kernel_test(test: &str, check: &KernelCheck) {
    let mut report = Report::new(test);
    let mut reference = harness::reference();
    let cases = kernel_cases();
    for mut cand in harness::candidates(test) {
        check_kernel_cases(&mut report, &mut reference, &mut cand, &cases, check);
    }
    report.finish();
}

/// G-buffer texel by texel: materials on >= 99.5% of pixels, positions, depths, normals
/// and uvs within ulp-derived tolerances on >= 99.9% of the rest, copied fields exact.
#[test]
fn primary_gbuffer_matches_cpu() {
    kernel_test("primary_gbuffer", &|fx, _, r, c| check_gbuffer(fx, r, c));
}

/// Stored photons of every light as multisets: counts and every path-end counter within
/// the path-divergence allowance, flux sums, and >= 99% of photons matched within 1e-3
/// of the scene diagonal in both directions.
#[test]
fn trace_photons_matches_cpu_as_multisets() {
    kernel_test("trace_photons", &|fx, _, r, c| check_trace(fx, r, c));
}

/// The CPU's photon list and G-buffer deposited on both: >= 99.9% of photon-map texels
/// bitwise equal, consistent counters, resolved radiance within ~1e-5 where sums agree.
#[test]
fn deposit_screen_and_resolve_match_cpu_on_the_same_photons() {
    kernel_test("deposit_screen + resolve_caustics", &check_deposit);
}

/// Tiles and both gather directions on the CPU's photon map, raw image, G-buffer and
/// tiles: relative 1e-5 per tile and per pixel.
#[test]
fn tile_hit_distance_and_bilateral_gather_match_cpu_on_the_same_inputs() {
    kernel_test("tile_hit_distance + bilateral_gather", &check_gather);
}

/// The density gather on the CPU's photon map, G-buffer, table and intermediate images:
/// the summed-area table bitwise, footprints and both passes within 1e-5 of what each
/// pixel gathers.
#[test]
fn density_gather_matches_cpu_on_the_same_inputs() {
    kernel_test(
        "photon_count_table + gather_footprint + density_gather",
        &check_density_gather,
    );
}

/// Direct light on the CPU's G-buffer: >= 99% of pixels within 1e-4 relative.
#[test]
fn direct_light_matches_cpu_on_the_same_gbuffer() {
    kernel_test("direct_light", &check_direct);
}

/// Composite of the CPU's direct and filtered images: bitwise equal.
/// CausticMap's kernels on the same inputs: the atlas sums bitwise, the gather per texel,
/// the lookup per pixel (`kernels::gather_caustic_map` and `kernels::caustic_map_lookup`
/// argue each bound).
#[test]
fn caustic_map_kernels_match_cpu_on_the_same_inputs() {
    kernel_test("caustic map kernels", &check_caustic_map);
}

/// CausticMap's fused pass (`trace_photons`' `fused_deposit` variant) on each backend:
/// bitwise the CPU's atlas deposit of the photons that backend's own texture-space trace
/// stores (`kernels::trace_photons::check_fused_trace` argues it).
#[test]
fn caustic_map_fused_trace_deposits_what_its_trace_stores() {
    kernel_test("caustic map fused trace", &check_fused_trace);
}

/// Sspm's fused pass (`trace_photons`' `fused_deposit` variant in world space) on each
/// backend: that backend's own `deposit_screen` of the photons its world-space trace
/// stores, within `deposit_screen`'s agreement
/// (`kernels::deposit_screen::check_fused_screen_trace` argues it).
#[test]
fn sspm_fused_trace_deposits_what_its_trace_stores() {
    kernel_test("sspm fused trace", &check_fused_screen_trace);
}

/// AdaptiveCaustics' kernels on the same inputs: the adaptive trace slot by slot within
/// the path-divergence allowance, `refine_clusters` bitwise (`kernels::refine_clusters`
/// argues both).
#[test]
fn adaptive_caustics_kernels_match_cpu_on_the_same_inputs() {
    kernel_test("adaptive caustics kernels", &check_adaptive_caustics);
}

/// AdaptiveCaustics' screen target on the same inputs: the world-space adaptive trace
/// slot by slot, `refine_clusters` with the camera bitwise where nothing is projected and
/// within the pixel-edge allowance of `deposit_screen` where the error metric projects
/// (`kernels::refine_clusters::check_screen_target` argues both).
#[test]
fn adaptive_caustics_screen_target_matches_cpu_on_the_same_inputs() {
    kernel_test("adaptive caustics screen target", &check_screen_target);
}

/// PhotonGi's kernels (`rsm_importance`, `sample_rsm`, `trace_indirect`,
/// `splat_photons`) on the same inputs for every point and spot light (tolerances argued
/// in `kernels::shading_normal_correction` and the files of its kernels).
#[test]
fn photon_gi_kernels_match_cpu_on_the_same_inputs() {
    kernel_test("photon gi kernels", &check_photon_gi);
}

/// The temporal blend on the same inputs, a moved previous camera: within the tolerance of
/// its `exp` and `pow` but at pixel-edge reprojections, the next edge texels bitwise
/// (`kernels::temporal_blend` argues both).
#[test]
fn temporal_blend_matches_cpu_on_the_same_inputs() {
    kernel_test("temporal_blend", &check_temporal_blend);
}

/// One A-Trous iteration (inner and last) on the same inputs: within the tolerance of its
/// weights' `exp` and `pow` (`kernels::atrous_filter` argues it).
#[test]
fn atrous_filter_matches_cpu_on_the_same_inputs() {
    kernel_test("atrous_filter", &check_atrous_filter);
}

/// An instance's vertices placed on the device: every position coordinate within
/// `2 gamma_4` of its terms' magnitudes of the CPU's, normals within the renormalised
/// bound, u, v and every vertex outside the run bitwise (`kernels::place_vertices` argues
/// it), for transforms of any rotation, scales from 0.01 to 100, zeros of both signs and
/// normals of no length, runs from 0 vertices to the whole object at any offset.
#[test]
fn place_vertices_matches_cpu_for_any_run() {
    use caustica_core::device::layout::GpuVertex;
    use caustica_core::device::placement::placement_params;
    use caustica_core::scene::Transform;
    use glam::{Quat, Vec3};
    use proptest::prelude::*;
    let coordinate = || prop_oneof![-2.0f32..2.0, Just(0.0f32), Just(-0.0f32), Just(1.0f32)];
    let v3 = move || [coordinate(), coordinate(), coordinate()];
    let vertex =
        (v3(), v3(), -1.0f32..2.0, -1.0f32..2.0).prop_map(|(position, normal, u, v)| GpuVertex {
            position,
            u,
            normal,
            v,
        });
    let transform = (
        [-50.0f32..50.0, -50.0f32..50.0, -50.0f32..50.0],
        (-3.2f32..3.2, -3.2f32..3.2),
        [0.01f32..100.0, 0.01f32..100.0, 0.01f32..100.0],
    )
        .prop_map(|(t, (a, b), s)| Transform {
            translation: Vec3::from(t),
            rotation: Quat::from_rotation_y(a) * Quat::from_rotation_x(b),
            scale: Vec3::from(s),
        });
    let cases = (
        transform,
        proptest::collection::vec(vertex.clone(), 1..300),
        proptest::collection::vec(vertex, 1..40),
        (
            0usize..8,
            any::<prop::sample::Index>(),
            any::<prop::sample::Index>(),
        ),
    )
        .prop_map(|(t, object, extra, (first, count, world_at))| {
            let first = first.min(object.len() - 1);
            let count = count.index(object.len() - first + 1);
            // the world buffer: the run somewhere among other vertices
            let mut world = extra.clone();
            world.extend(extra.iter().cycle().take(count));
            let world_first = world_at.index(world.len() - count + 1);
            let p = placement_params(&t, first as u32, world_first as u32, count as u32);
            (p, object, world)
        });
    harness::check_generated(
        "place_vertices on generated instances",
        cases,
        |r, c, (p, object, world)| check_place_vertices(r, c, p, object, world),
    );
}

#[test]
fn composite_is_exact() {
    kernel_test("composite", &|_, inputs, r, c| {
        check_composite(inputs, r, c)
    });
}

/// Whole Sspm frames on every built-in scene (96x55, 64x64 photons per light): photon
/// statistics and image errors as `techniques::sspm::compare_frames` argues.
#[test]
fn sspm_matches_cpu_on_every_builtin_scene() {
    let test = "sspm on built-in scenes";
    let mut report = Report::new(test);
    let mut reference = harness::reference();
    for mut cand in harness::candidates(test) {
        for name in BUILTIN_SCENES {
            let scene = builtin_small(name);
            let settings = small_settings(64);
            match check_frame(&mut reference, cand.backend.as_mut(), &scene, &settings) {
                Ok(v) => report.add(&cand.name, name, v),
                Err(e) => report.error(&cand.name, name, e),
            }
        }
    }
    report.finish();
}

/// Whole Sspm frames on generated scenes and settings (`strategies::scene`,
/// `strategies::sspm_settings`; `PROPTEST_CASES`, default 8, and `PROPTEST_RNG_SEED`
/// choose them). A failing case is shrunk and printed as scene JSON, loadable with
/// `caustica render --scene FILE`.
#[test]
fn sspm_matches_cpu_on_random_scenes() {
    let test = "sspm on generated scenes";
    let reference = RefCell::new(harness::reference());
    for cand in harness::candidates(test) {
        let name = cand.name.clone();
        let backend = RefCell::new(cand.backend);
        let mut runner = TestRunner::new(strategies::config());
        let result = runner.run(
            &(strategies::scene(), strategies::sspm_settings()),
            |(scene, settings)| {
                let mut r = reference.borrow_mut();
                let mut c = backend.borrow_mut();
                let v = check_frame(&mut *r, c.as_mut(), &scene, &settings)
                    .map_err(TestCaseError::fail)?;
                if v.passed() {
                    Ok(())
                } else {
                    Err(TestCaseError::fail(format!(
                        "{v}settings: {settings:?}\nscene JSON:\n{}",
                        serde_json::to_string(&scene).unwrap_or_default()
                    )))
                }
            },
        );
        if let Err(e) = result {
            panic!("{name}: {e}");
        }
        harness::loud(&format!(
            "{test}: {name} agrees with cpu on {} generated cases",
            strategies::config().cases
        ));
    }
}
