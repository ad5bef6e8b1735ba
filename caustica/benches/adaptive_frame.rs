//! AdaptiveCaustics against the dense light view plane (CausticMap) per backend, at 1024^2,
//! 2048^2 and 4096^2 equivalent photons (Wyman 2009 found adaptive faster from 1024^2 on):
//! `spot-glass` with the plane over the spot's whole cone (Wyman 2009's setting) and `sphere` with
//! CausticMap's caster-fitted plane.
//!
//! Per scene, size and technique (dense; adaptive, level metric; adaptive, error metric),
//! after warm-up frames (`CAUSTICA_BENCH_WARMUP_MS`, default 3000), the median over frames
//! that remake the atlas (a new seed each) of: the photon work (every `trace_photons`, `refine_clusters` and
//! gather pass, device time where the backend has timestamps), the whole frame (host wall
//! time), the photons traced and the traversal's steps; and per level the photons traced
//! and the time of its passes (`dispatch_args`, `trace_photons`, `refine_clusters`, `AdaptiveStats::
//! ms_per_level`).
//!
//! `cargo bench -p caustica --bench adaptive_frame`
//! Environment: `CAUSTICA_BENCH_BACKENDS` (default: every backend that opens here),
//! `CAUSTICA_BENCH_FRAMES=N` (default 5), `CAUSTICA_BENCH_SIZES=1024,2048,4096`,
//! `CAUSTICA_BENCH_SCENES=spot-glass,sphere`, `CAUSTICA_BENCH_START_GRID=64` (the
//! traversal's start grid), `CAUSTICA_BENCH_KERNELS=1` (each level's time by kernel),
//! `CAUSTICA_BENCH_PROBES=bounds` (a list of `traced`, `first_segment`, `bounds`: the
//! adaptive rows under each `TraversalSettings::probe_levels`), `CAUSTICA_BENCH_FUSED=1` (a
//! list of 1 and 0: the finest level's trace deposits, `TraversalSettings::fused_finest`,
//! or writes slots for `refine_clusters`; rows of the latter say "slots").

mod common;
use caustica::scene::builtin::builtin;
use caustica::techniques::adaptive_caustics::AdaptiveStats;
use caustica::techniques::adaptive_caustics::{
    AdaptiveCaustics, AdaptiveCausticsSettings, AdaptiveMetric, ProbeLevels,
};
use caustica::techniques::caustic_map::{CausticMap, CausticMapSettings, EmissionPlane};
use caustica::Technique;
use caustica::BACKEND_NAMES;
use caustica::{FrameSettings, PlaneSettings, TraceSettings, TraversalSettings};
use caustica::{Output, Outputs};
use common::{env_or, median, opened_backends, warm_up, warmup_ms};

const PHOTON_PASSES: &[&str] = &[
    "seed_clusters",
    "dispatch_args",
    "trace_photons",
    "refine_clusters",
    "gather_caustic_map",
    "photon_count_table",
    "gather_footprint",
    "density_gather",
];

fn main() {
    let frames: usize = env_or("CAUSTICA_BENCH_FRAMES", "5")
        .parse()
        .unwrap_or(5)
        .max(1);
    let sizes: Vec<u32> = env_or("CAUSTICA_BENCH_SIZES", "1024,2048,4096")
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .collect();
    let wanted = env_or("CAUSTICA_BENCH_BACKENDS", &BACKEND_NAMES.join(","));
    let scenes = env_or("CAUSTICA_BENCH_SCENES", "spot-glass,sphere");
    let start_grid: u32 = env_or("CAUSTICA_BENCH_START_GRID", "64")
        .parse()
        .unwrap_or(64);
    let by_kernel = env_or("CAUSTICA_BENCH_KERNELS", "0") == "1";
    let probe_settings: Vec<ProbeLevels> = env_or("CAUSTICA_BENCH_PROBES", "bounds")
        .split(',')
        .map(|s| match s.trim() {
            "traced" | "0" => ProbeLevels::Traced,
            "first_segment" | "1" => ProbeLevels::FirstSegment,
            "bounds" => ProbeLevels::Bounds,
            other => {
                panic!("CAUSTICA_BENCH_PROBES: unknown {other:?} (traced, first_segment, bounds)")
            }
        })
        .collect();
    let fused_settings: Vec<bool> = env_or("CAUSTICA_BENCH_FUSED", "1")
        .split(',')
        .map(|s| match s.trim() {
            "1" => true,
            "0" => false,
            other => panic!("CAUSTICA_BENCH_FUSED: unknown {other:?} (1, 0)"),
        })
        .collect();
    println!(
        "AdaptiveCaustics vs the dense plane, median of {frames} frames after {} ms of warm-up frames",
        warmup_ms()
    );
    for (name, mut backend) in opened_backends(&wanted) {
        let device = backend.capabilities().device;
        for (scene_name, plane) in [
            ("spot-glass", EmissionPlane::LightCone),
            ("sphere", EmissionPlane::Casters),
        ] {
            if !scenes.split(',').any(|s| s.trim() == scene_name) {
                continue;
            }
            let mut scene = builtin(scene_name).expect("built-in");
            (scene.camera.width, scene.camera.height) = (1920, 1080);
            for &n in &sizes {
                let map = CausticMapSettings {
                    frame: FrameSettings {
                        photons_w: n,
                        photons_h: n,
                        outputs: Outputs::of(&[Output::Composite]),
                        ..CausticMapSettings::default().frame
                    },
                    planes: PlaneSettings {
                        emission_plane: plane,
                        ..CausticMapSettings::default().planes
                    },
                    trace: TraceSettings {
                        max_photons_per_batch: 1 << 22,
                        ..CausticMapSettings::default().trace
                    },
                    ..CausticMapSettings::default()
                };
                let mut variants = vec![("dense".to_string(), None, ProbeLevels::Bounds, true)];
                for probes in probe_settings.iter().copied() {
                    for &fused in &fused_settings {
                        let (level, error) = match probes {
                            ProbeLevels::Bounds => ("level", "error"),
                            ProbeLevels::FirstSegment => ("level, probes", "error, probes"),
                            ProbeLevels::Traced => ("level, full traces", "error, full traces"),
                        };
                        let slots = if fused { "" } else { ", slots" };
                        for (label, metric) in [
                            (level, AdaptiveMetric::Level),
                            (error, AdaptiveMetric::Error),
                        ] {
                            variants.push((format!("{label}{slots}"), Some(metric), probes, fused));
                        }
                    }
                }
                for (label, metric, probes, fused) in variants {
                    let made = match metric {
                        None => CausticMap::new(backend.as_mut(), &scene, map.clone())
                            .map(|t| Box::new(t) as Box<dyn Technique>),
                        Some(metric) => AdaptiveCaustics::new(
                            backend.as_mut(),
                            &scene,
                            AdaptiveCausticsSettings {
                                traversal: TraversalSettings {
                                    metric,
                                    start_grid,
                                    probe_levels: probes,
                                    fused_finest: fused,
                                    max_traversal_bytes: 256 << 20,
                                    ..AdaptiveCausticsSettings::default().traversal
                                },
                                ..adaptive_over(&map)
                            },
                        )
                        .map(|t| Box::new(t) as Box<dyn Technique>),
                    };
                    let mut t = match made {
                        Ok(t) => t,
                        Err(e) => {
                            println!("{name} / {scene_name} / {n}^2 / {label}: {e}");
                            continue;
                        }
                    };
                    if let Err(e) = warm_up(|| t.frame(backend.as_mut(), &mut |_| {}).map(|_| ())) {
                        println!("{name} / {scene_name} / {n}^2 / {label}: {e}");
                        continue;
                    }
                    let (mut work, mut frame) = (vec![], vec![]);
                    let (mut traced, mut steps, mut levels, mut timing) =
                        (0u64, 0u32, Vec::new(), String::new());
                    let mut level_ms: Vec<Vec<f64>> = Vec::new();
                    let mut kernel_ms: Vec<std::collections::BTreeMap<String, Vec<f64>>> =
                        Vec::new();
                    let mut failed = false;
                    let mut traversal_passes = Vec::new();
                    for i in 0..=frames {
                        t.set_seed(1 + i as u32);
                        match t.frame(backend.as_mut(), &mut |_| {}) {
                            Ok(st) if i > 0 => {
                                timing = st.timing.clone();
                                frame.push(st.frame_ms);
                                traversal_passes.push(
                                    [
                                        "seed_clusters",
                                        "dispatch_args",
                                        "trace_photons",
                                        "refine_clusters",
                                        "deposit_screen",
                                    ]
                                    .iter()
                                    .filter_map(|p| st.pass_ms.get(*p))
                                    .sum::<f64>(),
                                );
                                work.push(
                                    PHOTON_PASSES
                                        .iter()
                                        .filter_map(|p| st.pass_ms.get(*p))
                                        .sum(),
                                );
                                traced = st.photons_emitted;
                                if let Some(a) = &AdaptiveStats::of(&st) {
                                    steps = a.steps;
                                    levels = a.photons_per_level.clone();
                                    level_ms.resize(a.ms_per_level.len(), Vec::new());
                                    for (v, ms) in level_ms.iter_mut().zip(&a.ms_per_level) {
                                        v.push(*ms);
                                    }
                                    kernel_ms
                                        .resize(a.ms_per_level_kernel.len(), Default::default());
                                    for (m, k) in kernel_ms.iter_mut().zip(&a.ms_per_level_kernel) {
                                        for (name, ms) in k {
                                            m.entry(name.clone()).or_default().push(*ms);
                                        }
                                    }
                                }
                            }
                            Ok(_) => {}
                            Err(e) => {
                                println!("{name} / {scene_name} / {n}^2 / {label}: {e}");
                                failed = true;
                                break;
                            }
                        }
                    }
                    let _ = Box::new(t).free(backend.as_mut());
                    if failed || frame.is_empty() {
                        continue;
                    }
                    let per_level: Vec<String> = level_ms
                        .iter_mut()
                        .map(|v| format!("{:.3}", median(v)))
                        .collect();
                    println!(
                        "{name} on {device} / {scene_name} / {n}^2 / {label}: photon work {:.3} ms ({timing}), frame {:.3} ms (host wall), {traced} photons traced, {steps} steps, per level {levels:?}, ms per level (dispatch_args + trace + refine) [{}]",
                        median(&mut work),
                        median(&mut frame),
                        per_level.join(", ")
                    );
                    if by_kernel {
                        println!(
                            "    photon passes (seed_clusters + dispatch_args + trace_photons + refine_clusters + deposit_screen): {:.3} ms",
                            median(&mut traversal_passes)
                        );
                        for (level, m) in kernel_ms.iter_mut().enumerate() {
                            let parts: Vec<String> = m
                                .iter_mut()
                                .map(|(name, v)| format!("{name} {:.4}", median(v)))
                                .collect();
                            println!("    level {level}: {} ms", parts.join(", "));
                        }
                    }
                }
            }
        }
    }
}

/// AdaptiveCaustics with the default traversal over CausticMap's `map` (the same photon
/// grid, trace, view planes and atlas).
fn adaptive_over(map: &CausticMapSettings) -> AdaptiveCausticsSettings {
    AdaptiveCausticsSettings {
        frame: map.frame.clone(),
        trace: map.trace,
        planes: map.planes,
        atlas: map.atlas,
        ..Default::default()
    }
}
