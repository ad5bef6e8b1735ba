//! The frame plan on every backend ("leave out what a scene does not need"): a scene
//! without casters runs no photon pass and allocates no photon buffer; a scene compiles
//! only the `trace_photons` variant its materials need; a light whose frustum misses every
//! caster emits nothing; and pruning changes no result.
//!
//! "No result changes" is checked bitwise: pruning removes only work whose outcome is
//! known exactly. A variant without a feature skips code that would multiply by exactly 1
//! (Beer-Lambert with zero absorption: `exp(-0 t) = 1`) or is never reached (no
//! dielectric / no Cauchy B); a pruned light's photons are all discarded before storage
//! (they cannot meet a caster first) and the flux quantum ignores them; a composite
//! without caustics is `direct + 0 = direct`. Every backend runs both frames with the
//! same kernels otherwise, so there is no rounding to allow for.

use caustica_conformance::backends;
use caustica_core::kernels::variant_label;
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica_core::scene::Light;
use caustica_core::techniques::sspm::{Output, Outputs};
use caustica_core::{Backend, FrameStats, GatherFilter, Scene, Sspm, SspmSettings};
use caustica_core::{FrameSettings, ScreenSettings};
use glam::Vec3;

const W: u32 = 64;
const H: u32 = 36;

fn small(scene: &str) -> Scene {
    let mut s = builtin(scene).expect("built-in scene");
    s.camera.width = W;
    s.camera.height = H;
    s
}

fn settings(prune: bool) -> SspmSettings {
    SspmSettings {
        frame: FrameSettings {
            photons_w: 64,
            photons_h: 64,
            prune,
            ..SspmSettings::default().frame
        },
        ..SspmSettings::default()
    }
}

/// One frame: stats, every requested output, the plan's buffer names, and the kernel
/// variants the backend compiled for it (new labels only).
struct Run {
    stats: FrameStats,
    images: Vec<(Output, Vec<[f32; 4]>)>,
    buffers: Vec<String>,
    had_photon_buffers: bool,
    new_variants: Vec<String>,
}

fn run(b: &mut dyn Backend, scene: &Scene, settings: SspmSettings) -> Run {
    let before = b.variants();
    let mut s = Sspm::new(b, scene, settings.clone())
        .unwrap_or_else(|e| panic!("{}: Sspm::new on {}: {e}", b.name(), scene.name));
    let stats = s
        .frame(b, &mut |_| {})
        .unwrap_or_else(|e| panic!("{}: frame of {}: {e}", b.name(), scene.name));
    let images = s
        .outputs()
        .into_iter()
        .filter(|o| o.requested)
        .map(|o| {
            (
                o.output,
                s.read_output(b, o.output).expect("read output").pixels,
            )
        })
        .collect();
    let buffers = s.plan().buffers.iter().map(|b| b.name.clone()).collect();
    let had_photon_buffers = s.photon_buffers().is_some();
    s.free(b).expect("free");
    let new_variants = b
        .variants()
        .into_iter()
        .filter(|v| !before.contains(v))
        .collect();
    Run {
        stats,
        images,
        buffers,
        had_photon_buffers,
        new_variants,
    }
}

const PHOTON_PASSES: [&str; 8] = [
    "trace_photons",
    "deposit_screen",
    "resolve_caustics",
    "photon_count_table",
    "gather_footprint",
    "density_gather",
    "tile_hit_distance",
    "bilateral_gather",
];

fn ran(stats: &FrameStats, pass: &str) -> bool {
    stats.passes.iter().any(|p| p.name == pass)
}

fn skipped_reason(stats: &FrameStats, pass: &str) -> Option<String> {
    stats
        .skipped
        .iter()
        .find(|p| p.name == pass)
        .map(|p| p.reason.clone())
}

/// `plain` (no mirror, no glass): no photon pass runs, no photon is emitted, no photon,
/// photon-map, counter, tile or caustic buffer exists, no photon-kernel variant is
/// compiled, the composite is the direct image, and the caustic outputs read as zeros.
#[test]
fn plain_scene_runs_no_photon_pass_and_allocates_no_photon_buffer() {
    let scene = small("plain");
    for (name, mut b) in backends() {
        let r = run(b.as_mut(), &scene, settings(true));
        let s = &r.stats;
        for pass in PHOTON_PASSES.into_iter().chain(["composite"]) {
            assert!(!ran(s, pass), "{name}: plain ran {pass}");
            let why = skipped_reason(s, pass)
                .unwrap_or_else(|| panic!("{name}: plain: {pass} neither ran nor was skipped"));
            assert!(!why.is_empty(), "{name}: {pass} skipped without a reason");
        }
        assert!(
            ran(s, "primary_gbuffer") && ran(s, "direct_light"),
            "{name}"
        );
        assert_eq!(s.photons_emitted, 0, "{name}: plain emitted photons");
        assert_eq!(s.batches, 0, "{name}");
        assert!(!r.had_photon_buffers, "{name}: plain has a photon buffer");
        for word in ["photon", "tiles", "caustics", "scratch", "composite"] {
            assert!(
                !r.buffers.iter().any(|b| b.contains(word)),
                "{name}: plain allocated a '{word}' buffer: {:?}",
                r.buffers
            );
        }
        assert!(
            r.new_variants
                .iter()
                .all(|v| !v.starts_with("trace_photons")),
            "{name}: plain compiled {:?}",
            r.new_variants
        );
        assert!(s.variants.is_empty(), "{name}: {:?}", s.variants);
        let img = |o: Output| &r.images.iter().find(|(x, _)| *x == o).unwrap().1;
        assert_eq!(img(Output::Composite), img(Output::Direct), "{name}");
        assert!(
            img(Output::Direct).iter().any(|p| p[0] > 0.0),
            "{name}: black"
        );
        for o in [Output::RawCaustics, Output::FilteredCaustics] {
            assert!(img(o).iter().all(|p| *p == [0.0; 4]), "{name}: {o:?}");
        }
        eprintln!(
            "*** {name}: plain: photon passes skipped, buffers {:?} ***",
            r.buffers
        );
    }
}

/// Each built-in scene compiles exactly the `trace_photons` variant of the material
/// features its objects use: no dispersion variant without a dispersive material, no
/// absorption without an absorbing one, no dielectric code in the mirror-only `ring`.
#[test]
fn each_scene_compiles_only_the_variant_it_needs() {
    for (name, mut b) in backends() {
        for scene_name in BUILTIN_SCENES {
            let scene = small(scene_name);
            let f = caustica_core::frame::plan::SceneFeatures::of(&scene);
            let r = run(b.as_mut(), &scene, settings(true));
            // the scene's features, and Sspm's fused deposit (a setting, on by default)
            let mut variant = f.trace_variant();
            variant.fused_deposit = settings(true).fused_deposit;
            let want = variant_label("trace_photons", &variant.constants());
            if r.stats.photons_emitted == 0 {
                continue; // plain: checked above
            }
            assert_eq!(r.stats.variants, vec![want.clone()], "{name}: {scene_name}");
            // the backend compiled (or had compiled) exactly that label, nothing else
            assert!(
                r.new_variants.iter().all(|v| *v == want),
                "{name}: {scene_name} compiled {:?}, needs {want}",
                r.new_variants
            );
            assert!(b.variants().contains(&want), "{name}: {scene_name}: {want}");
            let dispersive = scene_name == "prism";
            assert_eq!(want.contains("DISPERSION=1"), dispersive, "{name}: {want}");
            assert_eq!(
                want.contains("DIELECTRIC=1"),
                scene_name != "ring",
                "{want}"
            );
        }
        let labels = b.variants();
        eprintln!("*** {name}: variants over the built-in scenes: {labels:?} ***");
        assert!(
            labels.iter().any(|l| l.contains("DISPERSION=0")),
            "{name}: {labels:?}"
        );
    }
}

/// `sphere` with a second light, a spot aimed away from the glass ball: its cone misses
/// the casters' bounding sphere, so it emits nothing (with the reason in the plan), and
/// the frame equals the one with pruning off, where that light emits its whole cone.
#[test]
fn light_whose_frustum_misses_every_caster_emits_nothing() {
    let mut scene = small("sphere");
    scene.lights.push(Light::Spot {
        position: Vec3::new(0.0, 2.0, 0.0),
        direction: Vec3::new(1.0, 0.2, 0.0),
        intensity: Vec3::splat(20.0),
        inner_angle_deg: 10.0,
        outer_angle_deg: 15.0,
    });
    for (name, mut b) in backends() {
        let on = run(b.as_mut(), &scene, settings(true));
        let off = run(b.as_mut(), &scene, settings(false));
        let plan = on.stats.plan.as_ref().expect("plan in stats");
        let spot = plan.lights.iter().find(|l| l.light == 1).expect("light 1");
        assert!(!spot.emits, "{name}: the spot emits: {}", spot.reason);
        assert!(spot.reason.contains("misses"), "{name}: {}", spot.reason);
        assert_eq!(on.stats.photons_emitted, 64 * 64, "{name}");
        assert_eq!(off.stats.photons_emitted, 2 * 64 * 64, "{name}");
        assert_same_frame(name, "sphere + spot", &on, &off);
        eprintln!("*** {name}: a spot that misses every caster emits nothing ***");
    }
}

/// Pruning on and off give bitwise the same images and photon sums on every built-in
/// scene (see the module docs for why no tolerance is needed).
#[test]
fn pruning_on_and_off_give_the_same_frame() {
    for (name, mut b) in backends() {
        for scene_name in BUILTIN_SCENES {
            let scene = small(scene_name);
            let on = run(b.as_mut(), &scene, settings(true));
            let off = run(b.as_mut(), &scene, settings(false));
            // pruning off runs every pass but those of the filter not chosen, the opt-in
            // temporal blend and A-Trous, and the deposit the fused trace does (settings,
            // not pruning)
            assert!(
                off.stats.skipped.iter().all(|p| {
                    p.reason.starts_with("filter is density")
                        || p.name == "temporal_blend"
                        || p.name == "atrous_filter"
                        || (p.name == "deposit_screen" && p.reason.contains("fused_deposit"))
                }),
                "{name}: pruning off skipped {:?}",
                off.stats.skipped
            );
            assert_same_frame(name, scene_name, &on, &off);
        }
        eprintln!("*** {name}: pruning on and off agree bitwise on every built-in scene ***");
    }
}

/// The filter setting picks the passes: the density gather's three kernels by default,
/// Kim 2019's tile and bilateral passes with `filter: bilateral`; the others are skipped
/// with the filter as the reason, and no buffer of theirs exists.
#[test]
fn the_filter_setting_picks_its_passes_and_buffers() {
    let scene = small("sphere");
    let density = ["photon_count_table", "gather_footprint", "density_gather"];
    let bilateral = ["tile_hit_distance", "bilateral_gather"];
    for (name, mut b) in backends() {
        for (filter, runs, skips, buffer, absent) in [
            (
                GatherFilter::Density,
                &density[..],
                &bilateral[..],
                "photon count table",
                "tiles",
            ),
            (
                GatherFilter::Bilateral,
                &bilateral[..],
                &density[..],
                "tiles",
                "photon count table",
            ),
        ] {
            let r = run(
                b.as_mut(),
                &scene,
                SspmSettings {
                    screen: ScreenSettings {
                        filter,
                        ..settings(true).screen
                    },
                    ..settings(true)
                },
            );
            for pass in runs {
                assert!(
                    ran(&r.stats, pass),
                    "{name}: {filter:?}: {pass} did not run"
                );
            }
            for pass in skips {
                assert!(!ran(&r.stats, pass), "{name}: {filter:?}: {pass} ran");
                let why = skipped_reason(&r.stats, pass).unwrap_or_default();
                assert!(why.starts_with("filter is"), "{name}: {pass}: '{why}'");
            }
            assert!(
                r.buffers.iter().any(|x| x.contains(buffer)),
                "{name}: {:?}",
                r.buffers
            );
            assert!(
                !r.buffers.iter().any(|x| x.contains(absent)),
                "{name}: {:?}",
                r.buffers
            );
        }
    }
}

/// Only the filtered caustics asked for (a renderer with its own direct light): no
/// `direct_light` or `composite` pass, no direct or composite buffer, and the same
/// filtered caustics as the full frame.
#[test]
fn caustics_only_output_skips_direct_light_and_composite() {
    let scene = small("sphere");
    for (name, mut b) in backends() {
        let full = run(b.as_mut(), &scene, settings(true));
        let only = run(
            b.as_mut(),
            &scene,
            SspmSettings {
                frame: FrameSettings {
                    outputs: Outputs::CAUSTICS_ONLY,
                    ..settings(true).frame
                },
                ..settings(true)
            },
        );
        for pass in ["direct_light", "composite"] {
            assert!(!ran(&only.stats, pass), "{name}: ran {pass}");
            assert!(
                skipped_reason(&only.stats, pass).is_some(),
                "{name}: {pass}"
            );
        }
        assert!(
            !only
                .buffers
                .iter()
                .any(|b| b.contains("direct") || b.contains("composite")),
            "{name}: {:?}",
            only.buffers
        );
        let filtered = |r: &Run| {
            r.images
                .iter()
                .find(|(o, _)| *o == Output::FilteredCaustics)
                .unwrap()
                .1
                .clone()
        };
        assert_eq!(filtered(&full), filtered(&only), "{name}");
        assert!(
            only.stats.bytes_allocated < full.stats.bytes_allocated,
            "{name}"
        );
    }
}

fn assert_same_frame(backend: &str, scene: &str, a: &Run, b: &Run) {
    let (x, y) = (&a.stats, &b.stats);
    assert_eq!(
        x.photons_stored, y.photons_stored,
        "{backend}: {scene}: stored"
    );
    assert_eq!(
        x.photons_deposited, y.photons_deposited,
        "{backend}: {scene}"
    );
    assert_eq!(
        x.stored_flux, y.stored_flux,
        "{backend}: {scene}: stored flux"
    );
    assert_eq!(
        x.flux_quantum, y.flux_quantum,
        "{backend}: {scene}: quantum"
    );
    assert_eq!(x.fixed_point_saturated, 0, "{backend}: {scene}");
    assert_eq!(y.fixed_point_saturated, 0, "{backend}: {scene}");
    for ((o, p), (_, q)) in a.images.iter().zip(&b.images) {
        let differ = p.iter().zip(q).filter(|(u, v)| u != v).count();
        assert_eq!(
            differ, 0,
            "{backend}: {scene}: {o:?} differs on {differ} pixels with pruning on/off"
        );
        assert!(
            p.iter().flatten().all(|v| v.is_finite()),
            "{backend}: {scene}: {o:?} NaN/Inf"
        );
    }
}

/// A planned buffer larger than the device's largest buffer (or storage binding) is a
/// typed OutOfMemory error from `Sspm::new` naming that buffer, before anything is
/// uploaded: the G-buffer's first plane (16 bytes a pixel, the largest per-pixel buffer
/// with the images and the photon map's planes) at 3840x2160 and over on lavapipe
/// (128 MiB) is the real case (`docs/stability.md`).
#[test]
fn oversized_buffer_is_a_typed_error_before_any_work() {
    // large enough that a G-buffer plane (14.7 MB) is the largest buffer (the scene's
    // largest, of the 384-segment ball, is 8.2 MB)
    let mut scene = small("sphere");
    scene.camera.width = 1280;
    scene.camera.height = 720;
    let gbuffer = 1280 * 720 * 16;
    let mut b = caustica_conformance::harness::WatchedCpu::new(Some(gbuffer - 1));
    match Sspm::new(&mut b, &scene, settings(true)) {
        Err(caustica_core::Error::Backend(caustica_core::BackendError::OutOfMemory {
            bytes,
            what,
        })) => {
            assert_eq!(bytes, gbuffer);
            assert!(
                what.contains("gbuffer") && what.contains("watched-cpu"),
                "{what}"
            );
        }
        Err(e) => panic!("expected OutOfMemory, got {e}"),
        Ok(_) => panic!(
            "a {gbuffer}-byte G-buffer plane passed a {}-byte device",
            gbuffer - 1
        ),
    }
    assert_eq!(b.executed, 0, "work was recorded before the error");
    b.max_buffer_bytes = Some(gbuffer);
    assert!(Sspm::new(&mut b, &scene, settings(true)).is_ok());
}
