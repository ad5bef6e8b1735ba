//! Spectral dispersion on every backend against the CPU, with proptest inputs: the prism's
//! beam through a dispersive flint whose index model and parameters are drawn (Cauchy's
//! B, or KHR_materials_dispersion's Abbe number), at indices from just above 1 (1.0001)
//! to 3.5, under both `frame.dispersion` modes and any seed. Each case runs
//! `trace_photons` on the candidate and the CPU and compares the stored photons as
//! multisets (`kernels::trace_photons::check_trace`: positions, which carry each photon's
//! index through `dispersive_ior`, `abbe_ior` or `cauchy_ior`, and fluxes, which carry
//! its colour through `spectral_sample`, `wavelength_at`, `cie_xyz`, `xyz_to_linear_srgb`
//! and `wavelength_rgb`, within `harness::tolerance::SPECTRAL_FLUX_REL` of the largest
//! channel), then the deterministic split (`split_lane`, the variant's `fresnel_split`)
//! the same way. Every case's photon grid also reaches both ends of the spectrum: the
//! batch's wavelengths come within 0.5 nm of 380 and of 780 nm (checked), so the weights
//! at the ends, where every channel is near zero or clipped, are compared too.

use caustica_conformance::harness::fixture::Fixture;
use caustica_conformance::harness::tolerance::{FluxMatch, PHOTON_MATCH, PHOTON_POSITION_REL};
use caustica_conformance::harness::{self, verdict::Verdict};
use caustica_conformance::kernels::trace_photons::check_trace;
use caustica_conformance::{small_settings, strategies};
use caustica_core::backend::Backend;
use caustica_core::device::layout::Photon;
use caustica_core::math::spectrum::{
    spectral_sample, wavelength_at, SPECTRUM_MAX_UM, SPECTRUM_MIN_UM,
};
use caustica_core::scene::{builtin, IorModel, Material, Scene};
use caustica_core::{Dispersion, SspmSettings};
use proptest::prelude::*;
use proptest::test_runner::{TestCaseError, TestRunner};
use std::cell::RefCell;

/// The flint's index model: Cauchy B (um^2) or the Abbe number, at index `ior`.
fn flint() -> impl Strategy<Value = Material> {
    let ior = prop_oneof![
        1 => Just(1.0001f32),
        4 => 1.2f32..=2.5,
        1 => Just(3.5f32),
    ];
    let model = prop_oneof![
        (0.001f32..=0.05).prop_map(|b| (b, IorModel::Cauchy)),
        (5.0f32..=90.0).prop_map(|abbe_number| (0.0, IorModel::Abbe { abbe_number })),
    ];
    (ior, model).prop_map(|(ior, (cauchy_b, ior_model))| Material::Dielectric {
        ior,
        cauchy_b,
        absorption: glam::Vec3::ZERO,
        ior_model,
    })
}

/// The prism's beam alone (a 64 x 36 camera facing the screen) with `flint`.
fn scene(flint: Material) -> Scene {
    let mut s = builtin::prism();
    s.lights.truncate(1);
    s.camera.width = 64;
    s.camera.height = 36;
    s.materials.insert("flint".into(), flint);
    s
}

/// Photons of `a` without a counterpart in `b` within `tol` and `flux` (brute force: the
/// split batches are small).
fn unmatched(a: &[Photon], b: &[Photon], tol: f32, flux: FluxMatch) -> usize {
    let pos = |p: &Photon| glam::Vec3::from(p.position);
    a.iter()
        .filter(|p| {
            !b.iter()
                .any(|q| pos(p).distance(pos(q)) <= tol && flux.close(p.flux, q.flux))
        })
        .count()
}

/// `trace_photons` with the deterministic split (budget 8) on both backends, compared as
/// multisets as `check_trace` compares the stochastic trace.
fn check_split(fx: &Fixture, r: &mut dyn Backend, c: &mut dyn Backend) -> Result<Verdict, String> {
    let mut v = Verdict::new("trace_photons (deterministic split)");
    let variant = caustica_core::kernels::TraceVariant {
        fresnel_split: true,
        ..fx.trace_variant()
    };
    let tol = PHOTON_POSITION_REL * fx.ds.bounds.diagonal();
    let flux = FluxMatch::of(&fx.scene, fx.settings.frame.dispersion, tol);
    for k in 0..fx.constants.domains.len() {
        let budget = |p: &mut caustica_core::device::layout::TraceParams| p.split_budget = 8;
        let (pa, _) = fx.run_trace_as(r, k, variant, budget)?;
        let (pb, _) = fx.run_trace_as(c, k, variant, budget)?;
        v.check(!pa.is_empty(), || "the split stored no photon".into());
        for (u, len, who) in [
            (unmatched(&pb, &pa, tol, flux), pb.len(), "candidate"),
            (unmatched(&pa, &pb, tol, flux), pa.len(), "cpu"),
        ] {
            let allowed = ((1.0 - PHOTON_MATCH) * len as f64).ceil() as usize + 2;
            v.check(u <= allowed, || {
                format!("{u} of {len} {who} photons have no counterpart (allowed {allowed})")
            });
        }
    }
    Ok(v)
}

#[test]
fn spectral_trace_matches_cpu() {
    let test = "spectral dispersion";
    let reference = RefCell::new(harness::reference());
    let cases = (
        flint(),
        prop_oneof![3 => Just(Dispersion::Spectral), 1 => Just(Dispersion::ThreeBands)],
        any::<u32>(),
    );
    for cand in harness::candidates(test) {
        let name = cand.name.clone();
        let backend = RefCell::new(cand.backend);
        let mut runner = TestRunner::new(strategies::config());
        let result = runner.run(&cases, |(flint, dispersion, seed)| {
            let scene = scene(flint);
            let mut settings: SspmSettings = small_settings(64);
            settings.frame.seed = seed;
            settings.frame.dispersion = dispersion;
            let mut r = reference.borrow_mut();
            let mut c = backend.borrow_mut();
            let fx = Fixture::new("prism", &scene, &settings, &mut *r, c.as_mut())
                .map_err(TestCaseError::fail)?;
            // the batch reaches both ends of the spectrum
            if dispersion == Dispersion::Spectral {
                let p = fx.trace_batch(0);
                let (lo, hi) = (0..p.count).fold((f32::MAX, f32::MIN), |(lo, hi), i| {
                    let l = wavelength_at(spectral_sample(p.seed, i));
                    (lo.min(l), hi.max(l))
                });
                prop_assert!(
                    lo - SPECTRUM_MIN_UM < 5e-4 && SPECTRUM_MAX_UM - hi < 5e-4,
                    "wavelengths {lo}..{hi} um"
                );
            }
            let mut v = check_trace(&fx, &mut *r, c.as_mut()).map_err(TestCaseError::fail)?;
            v.absorb(check_split(&fx, &mut *r, c.as_mut()).map_err(TestCaseError::fail)?);
            fx.release(&mut *r, c.as_mut());
            if v.passed() {
                Ok(())
            } else {
                Err(TestCaseError::fail(format!(
                    "{v}dispersion {dispersion:?}, seed {seed}, scene JSON:\n{}",
                    serde_json::to_string(&scene).unwrap_or_default()
                )))
            }
        });
        if let Err(e) = result {
            panic!("{name}: {e}");
        }
        harness::loud(&format!(
            "{test}: {name} agrees with cpu on {} generated cases",
            strategies::config().cases
        ));
    }
}
