//! CausticMap frames per backend at Vanderstichelen 2021's three test settings (its section 4), each
//! with `sphere`'s glass ball tessellated to the setting's triangle count: 20k triangles,
//! 4 bounces, 3x3 gather, 2048^2 map, 1280x720; 70k, 6 bounces, 2048^2, 1920x1080; 100k,
//! 4 bounces, 4096^2, 1920x1080; 2048x2048 photons (light view plane texels) each. "n
//! bounces" is read as n specular interactions: `max_bounces = n + 1` ray segments and
//! `max_specular_depth = n` for the camera's tree.
//!
//! Per setting, Fresnel split (deterministic; stochastic, the default), map gather
//! (density, the default; Vanderstichelen 2021's box) and backend, after warm-up frames
//! (`CAUSTICA_BENCH_WARMUP_MS`, default 3000, then one more): the median over frames that
//! remake the atlas (a new seed each) of every pass and of the budget line emission +
//! trace + splat + gather (`trace_photons`, which deposits into the atlas, and `gather_caustic_map` or
//! the density gather's `photon_count_table`, `gather_footprint`, `density_gather`; target
//! on the H200: <= 2 ms at 2048^2 photons and a 2048^2 map), and the median host wall time
//! of a camera-only frame (the atlas reused: G-buffer, direct light, lookup, composite).
//!
//! `cargo bench -p caustica --bench caustic_map_frame`
//! Environment: `CAUSTICA_BENCH_BACKENDS` (default: every backend that opens here),
//! `CAUSTICA_BENCH_FRAMES=N` (default 5), `CAUSTICA_BENCH_PHOTONS=N` (default 2048),
//! `CAUSTICA_BENCH_SETTINGS=0,1,2` (which of the three settings),
//! `CAUSTICA_BENCH_SPLITS=deterministic,stochastic` (default both),
//! `CAUSTICA_BENCH_GATHERS=density,box` (default density), `CAUSTICA_BENCH_WARMUP_MS=N`.

mod common;
use caustica::scene::builtin::builtin;
use caustica::scene::limits::tessellated_size;
use caustica::scene::{Scene, Shape};
use caustica::techniques::caustic_map::{CausticMap, CausticMapSettings, FresnelSplit, MapGather};
use caustica::BACKEND_NAMES;
use caustica::{AtlasSettings, FrameSettings, PlaneSettings, TraceSettings};
use caustica::{Output, Outputs};
use common::{env_or, median, opened_backends, warm_up, warmup_ms};
use std::collections::BTreeMap;

const BUDGET_PASSES: &[&str] = &[
    "trace_photons",
    "gather_caustic_map",
    "photon_count_table",
    "gather_footprint",
    "density_gather",
];

/// (glass triangles, bounces, atlas side, image size): Vanderstichelen 2021, section 4.
const SETTINGS: [(u64, u32, u32, (u32, u32)); 3] = [
    (20_000, 4, 2048, (1280, 720)),
    (70_000, 6, 2048, (1920, 1080)),
    (100_000, 4, 4096, (1920, 1080)),
];

/// `sphere` with its glass ball tessellated to about `triangles` triangles (the ball's
/// `segments` chosen for the nearest count), and the ball's triangle count.
fn scene_with(triangles: u64, (w, h): (u32, u32)) -> (Scene, u64) {
    let mut scene = builtin("sphere").expect("built-in scene");
    (scene.camera.width, scene.camera.height) = (w, h);
    let ball = scene
        .objects
        .iter()
        .position(|o| matches!(o.shape, Shape::Sphere { .. }))
        .expect("sphere has a ball");
    let (mut best, mut best_n) = (4u32, 0u64);
    for segments in (4..=2048).step_by(2) {
        if let Shape::Sphere { segments: s, .. } = &mut scene.objects[ball].shape {
            *s = segments;
        }
        let n = tessellated_size(&scene.objects[ball].shape).1;
        if n.abs_diff(triangles) < best_n.abs_diff(triangles) {
            (best, best_n) = (segments, n);
        }
        if n > triangles {
            break;
        }
    }
    if let Shape::Sphere { segments: s, .. } = &mut scene.objects[ball].shape {
        *s = best;
    }
    (scene, best_n)
}

fn main() {
    let frames: usize = env_or("CAUSTICA_BENCH_FRAMES", "5")
        .parse()
        .unwrap_or(5)
        .max(1);
    let side: u32 = env_or("CAUSTICA_BENCH_PHOTONS", "2048")
        .parse()
        .unwrap_or(2048);
    let wanted = env_or("CAUSTICA_BENCH_BACKENDS", &BACKEND_NAMES.join(","));
    let picked: Vec<usize> = env_or("CAUSTICA_BENCH_SETTINGS", "0,1,2")
        .split(',')
        .filter_map(|s| s.trim().parse().ok())
        .filter(|&i: &usize| i < SETTINGS.len())
        .collect();
    println!(
        "CausticMap frame, {side}x{side} photons, median of {frames} frames after {} ms of warm-up frames",
        warmup_ms()
    );
    for (name, mut backend) in opened_backends(&wanted) {
        let device = backend.capabilities().device;
        let splits: Vec<FresnelSplit> = env_or("CAUSTICA_BENCH_SPLITS", "deterministic,stochastic")
            .split(',')
            .filter_map(|s| serde_json::from_value(serde_json::Value::String(s.into())).ok())
            .collect();
        let gathers: Vec<MapGather> = env_or("CAUSTICA_BENCH_GATHERS", "density")
            .split(',')
            .filter_map(|s| serde_json::from_value(serde_json::Value::String(s.into())).ok())
            .collect();
        let mut combos: Vec<(usize, FresnelSplit, MapGather)> = Vec::new();
        for &k in &picked {
            for &s in &splits {
                for &g in &gathers {
                    combos.push((k, s, g));
                }
            }
        }
        for &(k, split, gather) in &combos {
            let (tris, bounces, atlas, size) = SETTINGS[k];
            let (scene, total) = scene_with(tris, size);
            let settings = CausticMapSettings {
                frame: FrameSettings {
                    photons_w: side,
                    photons_h: side,
                    max_specular_depth: bounces,
                    outputs: Outputs::of(&[Output::Composite]),
                    ..CausticMapSettings::default().frame
                },
                atlas: AtlasSettings {
                    atlas_size: atlas,
                    gather,
                    ..CausticMapSettings::default().atlas
                },
                trace: TraceSettings {
                    max_bounces: bounces + 1,
                    ..CausticMapSettings::default().trace
                },
                planes: PlaneSettings {
                    fresnel_split: split,
                    ..CausticMapSettings::default().planes
                },
            };
            let mut t = match CausticMap::new(backend.as_mut(), &scene, settings) {
                Ok(t) => t,
                Err(e) => {
                    println!("{name} / setting {k}: {e}");
                    continue;
                }
            };
            if let Err(e) = warm_up(|| t.frame(backend.as_mut(), &mut |_| {}).map(|_| ())) {
                println!("{name} / setting {k}: {e}");
                continue;
            }
            let mut passes: BTreeMap<String, Vec<f64>> = BTreeMap::new();
            let (mut frame_ms, mut budget, mut camera_ms) = (vec![], vec![], vec![]);
            let mut timing = String::new();
            let mut failed = false;
            for i in 0..=frames {
                t.set_seed(1 + i as u32);
                match t.frame(backend.as_mut(), &mut |_| {}) {
                    Ok(st) if i > 0 => {
                        timing = st.timing.clone();
                        frame_ms.push(st.frame_ms);
                        budget.push(
                            BUDGET_PASSES
                                .iter()
                                .filter_map(|p| st.pass_ms.get(*p))
                                .sum(),
                        );
                        for (p, v) in &st.pass_ms {
                            passes.entry(p.clone()).or_default().push(*v);
                        }
                    }
                    Ok(_) => {}
                    Err(e) => {
                        println!("{name} / setting {k}: {e}");
                        failed = true;
                        break;
                    }
                }
            }
            for _ in 0..frames {
                match t.frame(backend.as_mut(), &mut |_| {}) {
                    Ok(st) => camera_ms.push(st.frame_ms),
                    Err(e) => {
                        println!("{name} / setting {k}: {e}");
                        failed = true;
                        break;
                    }
                }
            }
            let _ = t.free(backend.as_mut());
            if failed || frame_ms.is_empty() {
                continue;
            }
            println!(
                "\n{name} on {device} / setting {k} / {split:?} split / {gather:?} gather: glass ball of {total} triangles ({tris} asked), \
                 {bounces} bounces, {atlas}^2 atlas, {}x{} ({timing}): frame {:.3} ms (host wall), \
                 emission + trace + splat + gather {:.3} ms, camera-only frame {:.3} ms (host wall)",
                size.0,
                size.1,
                median(&mut frame_ms),
                median(&mut budget),
                median(&mut camera_ms)
            );
            for (p, mut v) in passes {
                println!("  {p:<20} {:>9.3} ms", median(&mut v));
            }
        }
    }
}
