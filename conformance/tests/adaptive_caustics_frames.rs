//! AdaptiveCaustics' frames on every backend (`backends()`: all four, required in CI):
//!
//! - **The level metric is the dense grid.** With the conservative relevance (casters'
//!   projected bounds) no cluster that holds a photon able to meet a caster is discarded,
//!   and the finest level's photons are the dense grid's (the plane's seed and jitter), so
//!   the atlas, every image and the stored flux are **bitwise** CausticMap's at the same
//!   photon budget, on every built-in scene and backend.
//! - **Any memory limit gives the same frame.** Limits that cut the busiest level into 1,
//!   2 and 16 batches (and the error metric, so that converged clusters are resampled)
//!   give bitwise the same atlas and images: photons are keyed by texel and level, and
//!   the sums are exact integers.
//! - **Probe levels change nothing but the path ends** (see
//!   [`probe_levels_give_the_full_traversals_frame_bitwise`]).
//! - **The error metric keeps the flux.** Its stored flux equals the dense grid's within
//!   four standard deviations of their difference, bounded from the stats (see
//!   [`flux_tolerance`]), with Wyman 2009's one-texel metric and with a 4-texel tolerance whose
//!   converged photons splat over their footprints.
//! - **The screen target deposits the traversal's photons.** With the level metric, Sspm's
//!   screen (`deposit: screen`) receives exactly the photons the atlas target outputs:
//!   the same traversal (cluster counts, photons per level) and bitwise the same stored
//!   flux, every output photon accounted for by `deposit_screen` (deposited, off screen or
//!   depth-mismatched), on every built-in scene and backend; across backends the deposit
//!   outcomes agree within the allowances of what differs (each backend's own paths,
//!   G-buffer and pixel-edge flips: `divergence_allowance`, `GBUFFER_MATERIAL_AGREEMENT`,
//!   `DEPOSIT_PHOTON_CHANGES`), and the error metric keeps the flux as above.

use caustica_conformance::backends;
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica_core::scene::Scene;
use caustica_core::techniques::adaptive_caustics::AdaptiveStats;
use caustica_core::techniques::adaptive_caustics::{
    AdaptiveCaustics, AdaptiveCausticsSettings, AdaptiveMetric, ProbeLevels, MAX_PASSES_PER_LEVEL,
};
use caustica_core::techniques::caustic_map::{CausticMap, CausticMapSettings};
use caustica_core::techniques::sspm::Output;
use caustica_core::{AtlasSettings, FrameSettings, TraversalSettings};
use caustica_core::{Backend, FrameStats};

/// `s` with the screen target.
fn on_screen(s: AdaptiveCausticsSettings) -> AdaptiveCausticsSettings {
    AdaptiveCausticsSettings {
        deposit: caustica_core::techniques::adaptive_caustics::AdaptiveDeposit::Screen,
        ..s
    }
}

const OUTPUTS: [Output; 5] = [
    Output::CausticAtlas,
    Output::RawCaustics,
    Output::FilteredCaustics,
    Output::Composite,
    Output::Direct,
];

fn small(name: &str) -> Scene {
    let mut s = builtin(name).expect("built-in");
    (s.camera.width, s.camera.height) = (64, 36);
    s
}

fn map(photons: u32) -> CausticMapSettings {
    CausticMapSettings {
        frame: FrameSettings {
            photons_w: photons,
            photons_h: photons,
            ..CausticMapSettings::default().frame
        },
        atlas: AtlasSettings {
            atlas_size: 128,
            ..CausticMapSettings::default().atlas
        },
        ..CausticMapSettings::default()
    }
}

/// A frame's stats and outputs, the technique freed.
fn render<P: caustica_core::frame::pipeline::Pipeline>(
    b: &mut dyn Backend,
    mut t: caustica_core::frame::pipeline::Hosted<P>,
) -> (FrameStats, Vec<caustica_core::frame::image::Image>) {
    let stats = t.frame(b, &mut |_| {}).expect("frame");
    let images = OUTPUTS
        .iter()
        .map(|o| t.read_output(b, *o).expect("read"))
        .collect();
    t.free(b).expect("free");
    (stats, images)
}

fn same_bits(
    a: &[caustica_core::frame::image::Image],
    b: &[caustica_core::frame::image::Image],
) -> Option<Output> {
    OUTPUTS
        .iter()
        .zip(a.iter().zip(b))
        .find_map(|(name, (x, y))| {
            let equal = x.pixels.len() == y.pixels.len()
                && x.pixels
                    .iter()
                    .zip(&y.pixels)
                    .all(|(p, q)| p.map(f32::to_bits) == q.map(f32::to_bits));
            (!equal).then_some(*name)
        })
}

#[test]
fn the_level_metric_outputs_exactly_the_dense_grid() {
    for (name, mut b) in backends() {
        for scene_name in BUILTIN_SCENES {
            let scene = small(scene_name);
            // every receiver keeps its tile on both sides: CausticMap by default lays its
            // atlas out for the receivers its photons reach, AdaptiveCaustics never does
            // (its error metric reads the layout); pruning off changes nothing else
            let every_tile = CausticMapSettings {
                frame: FrameSettings {
                    prune: false,
                    ..map(256).frame
                },
                ..map(256)
            };
            let dense = CausticMap::new(b.as_mut(), &scene, every_tile).expect("dense");
            let (ds, di) = render(b.as_mut(), dense);
            let adaptive = AdaptiveCaustics::new(
                b.as_mut(),
                &scene,
                AdaptiveCausticsSettings {
                    traversal: TraversalSettings {
                        metric: AdaptiveMetric::Level,
                        start_grid: 32,
                        ..AdaptiveCausticsSettings::default().traversal
                    },
                    ..caustica_conformance::adaptive_over(&map(256))
                },
            )
            .expect("adaptive");
            let (s, ai) = render(b.as_mut(), adaptive);
            let what = format!("{name} / {scene_name}");
            assert_eq!(ds.stored_flux, s.stored_flux, "{what}: stored flux");
            assert_eq!(
                ds.photons_stored, s.photons_stored,
                "{what}: stored photons"
            );
            if let Some(out) = same_bits(&di, &ai) {
                panic!("{what}: {out} differs from the dense grid's");
            }
            if let Some(a) = &AdaptiveStats::of(&s) {
                assert_eq!(a.dense_equivalent_photons, ds.photons_emitted, "{what}");
                eprintln!(
                    "{what}: {} photons traced against {} dense, {} stored",
                    a.photons_processed, ds.photons_emitted, s.photons_stored
                );
            }
        }
    }
}

#[test]
fn any_memory_limit_gives_the_same_frame_bitwise() {
    let settings = |bytes: u64| AdaptiveCausticsSettings {
        traversal: TraversalSettings {
            metric: AdaptiveMetric::Error,
            start_grid: 32,
            error_from_grid: 64,
            // Wyman 2009's tolerance variant converges on every scene at this size (the
            // default's one convergence cell of a texel leaves `cornell` without any)
            error_texels: 2,
            max_traversal_bytes: bytes,
            ..AdaptiveCausticsSettings::default().traversal
        },
        ..caustica_conformance::adaptive_over(&map(256))
    };
    for (name, mut b) in backends() {
        for scene_name in ["sphere", "cornell"] {
            let scene = small(scene_name);
            let one = AdaptiveCaustics::new(b.as_mut(), &scene, settings(1 << 30)).expect("scene");
            let (s1, i1) = render(b.as_mut(), one);
            let a1 = AdaptiveStats::of(&s1).expect("adaptive stats");
            assert!(
                a1.clusters_converged > 0,
                "{name} / {scene_name}: nothing converged"
            );
            // the busiest level's clusters: one pass at the large limit; the smallest pass
            // the lists allow whole
            let busiest = a1.photons_per_level.iter().max().copied().unwrap_or(0) / 4;
            let t = settings(0).traversal();
            let smallest = t.dense_clusters(3).div_ceil(MAX_PASSES_PER_LEVEL);
            let mut steps = vec![a1.steps];
            for parts in [2u64, 16] {
                let c = busiest.div_ceil(parts).max(smallest);
                let bytes = t.bytes_for_pass(3, false, c);
                let t = AdaptiveCaustics::new(b.as_mut(), &scene, settings(bytes)).expect("scene");
                let (s, i) = render(b.as_mut(), t);
                let what = format!("{name} / {scene_name}, passes of {c} clusters");
                let sizes = settings(bytes).traversal_sizes(b.capabilities().max_buffer_bytes);
                assert!(!sizes.lists_capped, "{what}: {sizes:?}");
                assert_eq!(
                    AdaptiveStats::of(&s)
                        .as_ref()
                        .map(|a| a.clusters_overflowed),
                    Some(0)
                );
                let a = AdaptiveStats::of(&s).expect("adaptive stats");
                assert_eq!(a.photons_processed, a1.photons_processed, "{what}");
                assert_eq!(s.stored_flux, s1.stored_flux, "{what}: stored flux");
                if let Some(out) = same_bits(&i1, &i) {
                    panic!("{what}: {out} differs from one batch's");
                }
                steps.push(a.steps);
            }
            assert!(
                steps[0] < steps[1] && steps[1] <= steps[2],
                "{name} / {scene_name}: the limits did not split the traversal: steps {steps:?}"
            );
            eprintln!("{name} / {scene_name}: passes at 1, 2 and 16 parts {steps:?}");
        }
    }
}

/// An accumulation's passes stratify each cell together in the traversal as in the dense
/// plane (the first pass's jitter seed, each pass's stratum): three accumulated frames of
/// the level metric are bitwise CausticMap's three, on every backend.
#[test]
fn the_level_metric_accumulates_as_the_dense_grid() {
    let accumulate = |f: FrameSettings| FrameSettings {
        accumulate: true,
        prune: false,
        ..f
    };
    for (name, mut b) in backends() {
        let scene = small("sphere");
        let every_tile = CausticMapSettings {
            frame: accumulate(map(128).frame),
            ..map(128)
        };
        let adaptive = AdaptiveCausticsSettings {
            traversal: TraversalSettings {
                metric: AdaptiveMetric::Level,
                start_grid: 32,
                ..AdaptiveCausticsSettings::default().traversal
            },
            ..caustica_conformance::adaptive_over(&map(128))
        };
        let adaptive = AdaptiveCausticsSettings {
            frame: accumulate(adaptive.frame.clone()),
            ..adaptive
        };
        let mut dense = CausticMap::new(b.as_mut(), &scene, every_tile).expect("dense");
        let mut traversal = AdaptiveCaustics::new(b.as_mut(), &scene, adaptive).expect("adaptive");
        for frame in 0..3 {
            let ds = dense.frame(b.as_mut(), &mut |_| {}).expect("frame");
            let s = traversal.frame(b.as_mut(), &mut |_| {}).expect("frame");
            assert_eq!(
                ds.stored_flux, s.stored_flux,
                "{name}: frame {frame}: stored flux"
            );
        }
        let read = |t: &mut dyn FnMut(Output) -> caustica_core::frame::image::Image| {
            OUTPUTS.iter().map(|o| t(*o)).collect::<Vec<_>>()
        };
        let di = read(&mut |o| dense.read_output(b.as_mut(), o).expect("read"));
        let ai = read(&mut |o| traversal.read_output(b.as_mut(), o).expect("read"));
        dense.free(b.as_mut()).expect("free");
        traversal.free(b.as_mut()).expect("free");
        if let Some(out) = same_bits(&di, &ai) {
            panic!("{name}: after three accumulated frames {out} differs from the dense grid's");
        }
    }
}

/// Probe levels (the levels judged only by whether a photon met a caster) change nothing
/// but the path ends and the work: traced to their first surface
/// (`ProbeLevels::FirstSegment`) the same clusters are refined, converged and output;
/// not traced at all (`ProbeLevels::Bounds`, the casters' rectangles seed the first judged
/// level) the same clusters are output, and only clusters the rectangles exclude, which
/// would have been discarded, go untraced. So the atlas and every image are bitwise a
/// traversal's with full traces at every level, under both metrics, on every backend (and
/// the screen target's raw caustics with the seed); the
/// path ends still account for every photon traced (`AdaptiveStats::probes_met_caster`),
/// the probes trace fewer ray segments and the seed fewer photons. The same holds with
/// the seed when the finest level's trace deposits (`fused_finest`), whose every traced
/// cluster counts as output.
#[test]
fn probe_levels_give_the_full_traversals_frame_bitwise() {
    let settings = |metric, (probe_levels, fused_finest)| AdaptiveCausticsSettings {
        traversal: TraversalSettings {
            metric,
            start_grid: 16,
            error_from_grid: 64,
            probe_levels,
            fused_finest,
            ..AdaptiveCausticsSettings::default().traversal
        },
        ..caustica_conformance::adaptive_over(&map(256))
    };
    for (name, mut b) in backends() {
        // `sphere-sun`: an orthographic plane
        for scene_name in ["sphere", "cornell", "sphere-sun"] {
            let scene = small(scene_name);
            for metric in [AdaptiveMetric::Level, AdaptiveMetric::Error] {
                let run = |b: &mut dyn Backend, probes| {
                    let t =
                        AdaptiveCaustics::new(b, &scene, settings(metric, probes)).expect("scene");
                    render(b, t)
                };
                let (sf, full) = run(b.as_mut(), (ProbeLevels::Traced, false));
                let af = AdaptiveStats::of(&sf).expect("adaptive stats");
                assert_eq!(af.probes_met_caster, 0);
                assert_eq!(af.levels_seeded, 0);
                for (probes, fused) in [
                    (ProbeLevels::FirstSegment, false),
                    (ProbeLevels::Bounds, false),
                    (ProbeLevels::Bounds, true),
                ] {
                    let what =
                        format!("{name} / {scene_name} / {metric:?} / {probes:?} / fused {fused}");
                    let (sp, probed) = run(b.as_mut(), (probes, fused));
                    let ap = AdaptiveStats::of(&sp).expect("adaptive stats");
                    // the level metric seeded down to a fused finest level judges nothing
                    // from slots: the plan leaves refine_clusters out and says why
                    let slot_free = fused && metric == AdaptiveMetric::Level;
                    assert_eq!(
                        sp.passes.iter().any(|p| p.name == "refine_clusters"),
                        !slot_free,
                        "{what}: refine_clusters dispatched"
                    );
                    assert_eq!(
                        sp.skipped.iter().any(|p| p.name == "refine_clusters"
                            && p.reason == TraversalSettings::NO_SLOTS_REASON),
                        slot_free,
                        "{what}: the plan's word on refine_clusters"
                    );
                    if let Some(out) = same_bits(&full, &probed) {
                        panic!("{what}: {out} differs from the full traversal's");
                    }
                    assert_eq!(sp.stored_flux, sf.stored_flux, "{what}: stored flux");
                    assert_eq!(sp.photons_stored, sf.photons_stored, "{what}");
                    // the deposit's accounting: the same photons landed in the same texels
                    assert_eq!(sp.photons_deposited, sf.photons_deposited, "{what}");
                    assert_eq!(sp.discarded.off_screen, sf.discarded.off_screen, "{what}");
                    if fused {
                        assert!(ap.clusters_output >= af.clusters_output, "{what}");
                    } else {
                        assert_eq!(ap.clusters_output, af.clusters_output, "{what}");
                    }
                    assert_eq!(ap.clusters_converged, af.clusters_converged, "{what}");
                    let d = &sp.discarded;
                    let ends = ap.photons_traced_stored
                        + ap.probes_met_caster
                        + d.no_specular
                        + d.escaped
                        + d.negligible_power
                        + d.bounce_limit;
                    assert_eq!(
                        ends,
                        sp.photons_emitted + sp.photon_splits,
                        "{what}: path ends"
                    );
                    assert!(
                        sp.photon_rays_traced < sf.photon_rays_traced,
                        "{what}: {} segments, full traces {}",
                        sp.photon_rays_traced,
                        sf.photon_rays_traced
                    );
                    if probes == ProbeLevels::FirstSegment {
                        assert_eq!(ap.photons_per_level, af.photons_per_level, "{what}");
                        assert!(ap.probes_met_caster > 0, "{what}: no probe met a caster");
                    } else {
                        let seeded = ap.levels_seeded as usize;
                        assert!(seeded > 0 && ap.clusters_seeded > 0, "{what}: no seed");
                        assert_eq!(ap.probes_met_caster, 0, "{what}");
                        assert!(ap.photons_per_level[..seeded].iter().all(|&n| n == 0));
                        for (l, (p, f)) in ap
                            .photons_per_level
                            .iter()
                            .zip(&af.photons_per_level)
                            .enumerate()
                        {
                            assert!(p <= f, "{what}: level {l} traced {p}, full traces {f}");
                        }
                        assert!(ap.photons_processed < af.photons_processed, "{what}");
                    }
                    eprintln!(
                        "{what}: {} photons and {} ray segments, full traces {} and {}",
                        sp.photons_emitted,
                        sp.photon_rays_traced,
                        sf.photons_emitted,
                        sf.photon_rays_traced
                    );
                }
            }
        }
        // the screen target (Sspm's photon map) takes the same clusters' photons, deposited
        // by the fused finest level's trace as by `deposit_screen`
        let scene = small("sphere");
        let raw = |b: &mut dyn Backend, probes| {
            let mut t = AdaptiveCaustics::new(
                b,
                &scene,
                on_screen(settings(AdaptiveMetric::Level, probes)),
            )
            .expect("screen target");
            let s = t.frame(b, &mut |_| {}).expect("frame");
            let image = t.read_output(b, Output::RawCaustics).expect("raw caustics");
            t.free(b).expect("free");
            (s, image)
        };
        let (sf, full) = raw(b.as_mut(), (ProbeLevels::Traced, false));
        let (ss, seeded) = raw(b.as_mut(), (ProbeLevels::Bounds, true));
        assert!(AdaptiveStats::of(&ss).is_some_and(|a| a.levels_seeded > 0));
        assert_eq!(
            ss.stored_flux, sf.stored_flux,
            "{name} / screen: stored flux"
        );
        for (fused, full, what) in [
            (ss.photons_stored, sf.photons_stored, "stored"),
            (ss.photons_deposited, sf.photons_deposited, "deposited"),
            (
                ss.discarded.off_screen,
                sf.discarded.off_screen,
                "off screen",
            ),
            (
                ss.discarded.depth_mismatch,
                sf.discarded.depth_mismatch,
                "depth mismatch",
            ),
        ] {
            assert_eq!(fused, full, "{name} / screen: {what} photons");
        }
        assert!(
            same_bits(&[full], &[seeded]).is_none(),
            "{name} / screen: raw caustics differ from the full traversal's"
        );
    }
}

/// A limit below whole lists caps them: the clusters whose children do not fit are
/// output at their level from fresh photons and counted, so no photon is lost: the stored
/// flux stays within the error metric's tolerance of the whole lists' (the overflowed
/// clusters are output early, as converged ones are), and the image stays finite.
#[test]
fn capped_lists_overflow_counted_and_keep_the_flux() {
    let settings = |bytes: u64| AdaptiveCausticsSettings {
        traversal: TraversalSettings {
            metric: AdaptiveMetric::Level,
            start_grid: 32,
            max_traversal_bytes: bytes,
            ..AdaptiveCausticsSettings::default().traversal
        },
        ..caustica_conformance::adaptive_over(&map(256))
    };
    for (name, mut b) in backends() {
        let scene = small("sphere");
        let whole = AdaptiveCaustics::new(b.as_mut(), &scene, settings(1 << 30)).expect("scene");
        let (sw, _) = render(b.as_mut(), whole);
        let bytes = settings(0).traversal().full_list_bytes(3) / 8;
        let capped = AdaptiveCaustics::new(b.as_mut(), &scene, settings(bytes)).expect("scene");
        let (sc, img) = render(b.as_mut(), capped);
        let a = AdaptiveStats::of(&sc).expect("adaptive stats");
        assert!(settings(bytes).traversal_sizes(u64::MAX).lists_capped);
        assert!(
            a.clusters_overflowed > 0,
            "{name}: nothing overflowed at {bytes} bytes"
        );
        assert!(
            img.iter()
                .flat_map(|i| &i.pixels)
                .flatten()
                .all(|v| v.is_finite()),
            "{name}: NaN or Inf"
        );
        let (x, y): (f64, f64) = (sc.stored_flux.iter().sum(), sw.stored_flux.iter().sum());
        let tol = flux_tolerance(&sc, &sw, false);
        eprintln!(
            "{name}: capped / whole stored flux {:.5} (tolerance {:.5}), {} clusters overflowed",
            x / y,
            tol / y,
            a.clusters_overflowed
        );
        assert!(
            (x - y).abs() <= tol,
            "{name}: capped lists lost flux: {x} vs {y}"
        );
    }
}

/// Four standard deviations of (adaptive - dense) stored flux, bounded from the stats: the
/// two estimates share the photons of every cluster refined to the finest level; they
/// differ by the photons of the clusters the error metric stopped early: `n_l` fresh
/// photons at level `l` against the `4^(F - l) n_l` finest photons of the same texels.
/// Each photon's stored flux is a random variable in `[0, phi]` (`phi` the largest photon
/// flux of its level, 3x with dispersion), so its variance is at most `phi^2 / 4`, and the
/// photons are independent: `var <= sum_l n_l (phi_l^2 + 4^(F - l) phi_F^2) / 4` with
/// `phi_l = 4^(F - l) phi_F`. `phi_F` is bounded by twice the mean finest-texel flux
/// (emitted flux over the dense photons): a texel of a perspective plane of half-angle
/// up to 60 degrees sees at most 1.5 times the mean solid angle near the axis... and less
/// off it; 2 is a margin). Plus the fixed point's rounding: each stored photon's flux is
/// rounded to its run's quantum in each of 3 channels, at most half a quantum each, so the
/// two sums differ by at most `3 (n q + n_dense q_dense) / 2` even where the photons are
/// the same (no cluster converged before the finest level: the variance term is 0).
fn flux_tolerance(s: &FrameStats, dense: &FrameStats, dispersive: bool) -> f64 {
    let rounding = 1.5
        * (s.photons_stored as f64 * s.flux_quantum
            + dense.photons_stored as f64 * dense.flux_quantum);
    rounding + flux_deviation(s, dense, dispersive)
}

/// The four standard deviations of [`flux_tolerance`].
fn flux_deviation(s: &FrameStats, dense: &FrameStats, dispersive: bool) -> f64 {
    let a = &AdaptiveStats::of(s).expect("adaptive stats");
    let finest = a.photons_per_level.len() - 1;
    let emitted: f64 = dense.emitted_flux.iter().sum();
    // the brightest channel a photon can carry past a dispersive surface (spectral: the
    // largest weight of a wavelength, the default `frame.dispersion`)
    let gain = caustica_core::Dispersion::default().flux_gain(dispersive) as f64;
    let phi_f = 2.0 * gain * emitted / dense.photons_emitted.max(1) as f64;
    let mut var = 0.0;
    for (l, &n) in a.photons_output_per_level.iter().enumerate().take(finest) {
        let k = 4f64.powi((finest - l) as i32);
        var += n as f64 * ((k * phi_f).powi(2) + k * phi_f * phi_f) / 4.0;
    }
    4.0 * var.sqrt()
}

#[test]
fn the_error_metric_keeps_the_dense_grids_flux() {
    for (name, mut b) in backends() {
        for scene_name in BUILTIN_SCENES {
            let scene = small(scene_name);
            let dense = CausticMap::new(b.as_mut(), &scene, map(512)).expect("dense");
            let (ds, _) = render(b.as_mut(), dense);
            // Wyman 2009's one-texel metric, and its tolerance variant with footprint splats
            for error_texels in [1, 4] {
                let adaptive = AdaptiveCaustics::new(
                    b.as_mut(),
                    &scene,
                    AdaptiveCausticsSettings {
                        traversal: TraversalSettings {
                            metric: AdaptiveMetric::Error,
                            error_from_grid: 128,
                            error_texels,
                            ..AdaptiveCausticsSettings::default().traversal
                        },
                        ..caustica_conformance::adaptive_over(&map(512))
                    },
                )
                .expect("adaptive");
                let (s, _) = render(b.as_mut(), adaptive);
                let dispersive = scene.materials.values().any(|m| m.is_dispersive());
                let (x, y): (f64, f64) = (s.stored_flux.iter().sum(), ds.stored_flux.iter().sum());
                let what = format!("{name} / {scene_name} / error_texels {error_texels}");
                if y == 0.0 {
                    assert_eq!(x, 0.0, "{what}: light where the dense grid has none");
                    continue;
                }
                let tol = flux_tolerance(&s, &ds, dispersive);
                eprintln!(
                    "{what}: error metric / dense {:.5} (tolerance {:.5}), {} of {} photons",
                    x / y,
                    tol / y,
                    s.photons_emitted,
                    ds.photons_emitted
                );
                assert!(
                    (x - y).abs() <= tol,
                    "{what}: stored flux {x:.6} vs dense {y:.6}, over 4 sigma = {tol:.6}"
                );
            }
        }
    }
}

#[test]
fn the_screen_target_deposits_the_traversals_photons() {
    use caustica_conformance::harness::tolerance::{
        divergence_allowance, DEPOSIT_PHOTON_CHANGES, GBUFFER_MATERIAL_AGREEMENT,
    };
    let settings = |metric| AdaptiveCausticsSettings {
        traversal: TraversalSettings {
            metric,
            start_grid: 32,
            error_from_grid: 64,
            ..AdaptiveCausticsSettings::default().traversal
        },
        ..caustica_conformance::adaptive_over(&map(256))
    };
    let mut cpu_deposits: std::collections::HashMap<&str, u64> = Default::default();
    for (name, mut b) in backends() {
        for scene_name in BUILTIN_SCENES {
            let scene = small(scene_name);
            let what = format!("{name} / {scene_name}");
            let atlas = AdaptiveCaustics::new(b.as_mut(), &scene, settings(AdaptiveMetric::Level))
                .expect("atlas target");
            let (a, _) = render(b.as_mut(), atlas);
            let mut screen = AdaptiveCaustics::new(
                b.as_mut(),
                &scene,
                on_screen(settings(AdaptiveMetric::Level)),
            )
            .expect("screen target");
            let s = screen.frame(b.as_mut(), &mut |_| {}).expect("frame");
            let raw = screen
                .read_output(b.as_mut(), Output::RawCaustics)
                .expect("raw");
            screen.free(b.as_mut()).expect("free");
            assert_eq!(s.technique, "adaptive-caustics", "{what}");
            // the default traversal judges nothing from slots: the fused finest level
            // deposits into the screen itself
            for pass in ["refine_clusters", "deposit_screen"] {
                assert!(
                    !s.passes.iter().any(|p| p.name == pass),
                    "{what}: {pass} dispatched"
                );
            }
            assert_eq!(a.stored_flux, s.stored_flux, "{what}: stored flux");
            assert_eq!(a.photons_stored, s.photons_stored, "{what}: stored photons");
            let (ta, ts) = (AdaptiveStats::of(&a), AdaptiveStats::of(&s));
            assert_eq!(
                ta.as_ref()
                    .map(|t| (&t.photons_per_level, t.clusters_output, t.clusters_refined)),
                ts.as_ref()
                    .map(|t| (&t.photons_per_level, t.clusters_output, t.clusters_refined)),
                "{what}: the two targets' traversals differ"
            );
            let d = &s.discarded;
            assert_eq!(
                s.photons_deposited + d.off_screen + d.depth_mismatch,
                s.photons_stored,
                "{what}: output photons unaccounted for"
            );
            assert!(
                raw.pixels.iter().all(|p| p.iter().all(|x| x.is_finite())),
                "{what}: raw caustics not finite"
            );
            if s.photons_deposited > 0 {
                assert!(
                    raw.pixels.iter().any(|p| p[0] > 0.0),
                    "{what}: photons deposited, raw image black"
                );
            }
            match cpu_deposits.get(scene_name) {
                None => {
                    cpu_deposits.insert(scene_name, s.photons_deposited);
                }
                Some(&c) => {
                    // each backend traces its own photons (a path may diverge:
                    // divergence_allowance) and deposits them against its own G-buffer
                    // (a pixel's surface may differ on 1 - GBUFFER_MATERIAL_AGREEMENT of
                    // the pixels), besides deposit_screen's own pixel-edge flips
                    let n = s.photons_stored as f64;
                    let allow = divergence_allowance(s.photons_stored)
                        + ((1.0 - GBUFFER_MATERIAL_AGREEMENT + DEPOSIT_PHOTON_CHANGES) * n).ceil()
                            as u64;
                    assert!(
                        c.abs_diff(s.photons_deposited) <= allow,
                        "{what}: {} photons deposited, the cpu {c} (allowance {allow})",
                        s.photons_deposited
                    );
                }
            }
            // the error metric through the screen: the level metric's flux within the bound
            let mut e = AdaptiveCaustics::new(
                b.as_mut(),
                &scene,
                on_screen(settings(AdaptiveMetric::Error)),
            )
            .expect("screen target, error metric");
            let es = e.frame(b.as_mut(), &mut |_| {}).expect("frame");
            e.free(b.as_mut()).expect("free");
            let dispersive = scene.materials.values().any(|m| m.is_dispersive());
            let (x, y): (f64, f64) = (es.stored_flux.iter().sum(), s.stored_flux.iter().sum());
            if AdaptiveStats::of(&es).is_none() {
                // no light reaches a caster: no photon pass runs on either
                assert_eq!((x, y), (0.0, 0.0), "{what}: flux without a traversal");
                continue;
            }
            // the bound takes the finest photon's flux from the dense-equivalent count
            let mut dense = a.clone();
            dense.photons_emitted = ta.as_ref().map_or(0, |t| t.dense_equivalent_photons);
            let tol = flux_tolerance(&es, &dense, dispersive);
            assert!(
                (x - y).abs() <= tol + 1e-9 * y,
                "{what}: error metric on the screen stores {x}, the level metric {y} (bound {tol})"
            );
        }
    }
}
