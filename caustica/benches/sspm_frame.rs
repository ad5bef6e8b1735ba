//! One Sspm frame per backend, side by side: `sphere` and `cornell` at 1920x1080 with
//! 2048x2048 photons (DESIGN 9), median per-pass times over repeated frames after a
//! warm-up frame, and the DESIGN 9 budget line trace + deposit + gather (resolve, tiles
//! and both bilateral passes). Device timestamps where the backend has them.
//!
//! `cargo bench -p caustica --bench sspm_frame`
//! Environment: `CAUSTICA_BENCH_BACKENDS=wgpu,vulkan` (default: every backend that opens
//! here), `CAUSTICA_BENCH_FRAMES=N` (default 5), `CAUSTICA_BENCH_SIZE=WxH`,
//! `CAUSTICA_BENCH_PHOTONS=N` (grid side, default 2048).

use caustica::{open_backend, BACKEND_NAMES};
use caustica_core::scene::builtin::builtin;
use caustica_core::{Sspm, SspmSettings};
use std::collections::BTreeMap;

/// The passes of DESIGN 9's "trace + store + gather" budget.
const BUDGET_PASSES: &[&str] = &[
    "trace_photons",
    "deposit_screen",
    "resolve_caustics",
    "tile_hit_distance",
    "bilateral_gather",
];

fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    // `cargo bench` passes `--bench`; this harness takes its settings from the environment.
    let frames: usize = env_or("CAUSTICA_BENCH_FRAMES", "5")
        .parse()
        .unwrap_or(5)
        .max(1);
    let side: u32 = env_or("CAUSTICA_BENCH_PHOTONS", "2048")
        .parse()
        .unwrap_or(2048);
    let size = env_or("CAUSTICA_BENCH_SIZE", "1920x1080");
    let (w, h) = size
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .unwrap_or((1920u32, 1080u32));
    let wanted = env_or("CAUSTICA_BENCH_BACKENDS", &BACKEND_NAMES.join(","));
    println!(
        "Sspm frame, {w}x{h}, {side}x{side} photons, median of {frames} frames after one warm-up"
    );
    for name in wanted.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        let mut backend = match open_backend(name) {
            Ok(b) => b,
            Err(e) => {
                println!("{name}: skipped ({e})");
                continue;
            }
        };
        let caps = backend.capabilities();
        for scene_name in ["sphere", "cornell"] {
            let mut scene = builtin(scene_name).expect("built-in scene");
            scene.camera.width = w;
            scene.camera.height = h;
            let settings = SspmSettings {
                photons_w: side,
                photons_h: side,
                ..SspmSettings::default()
            };
            let mut sspm = match Sspm::new(backend.as_mut(), &scene, settings) {
                Ok(s) => s,
                Err(e) => {
                    println!("{name}/{scene_name}: {e}");
                    continue;
                }
            };
            let mut passes: BTreeMap<String, Vec<f64>> = BTreeMap::new();
            let mut frame_ms = Vec::new();
            let mut budget = Vec::new();
            let mut timing = String::new();
            for i in 0..=frames {
                let stats = match sspm.frame(backend.as_mut(), &mut |_| {}) {
                    Ok(s) => s,
                    Err(e) => {
                        println!("{name}/{scene_name}: {e}");
                        break;
                    }
                };
                if i == 0 {
                    continue; // warm-up
                }
                timing = stats.timing.clone();
                frame_ms.push(stats.frame_ms);
                budget.push(
                    BUDGET_PASSES
                        .iter()
                        .filter_map(|p| stats.pass_ms.get(*p))
                        .sum(),
                );
                for (k, v) in &stats.pass_ms {
                    passes.entry(k.clone()).or_default().push(*v);
                }
            }
            if frame_ms.is_empty() {
                continue;
            }
            println!(
                "\n{name} on {} / {scene_name} ({timing}): frame {:.3} ms (host wall), \
                 trace + deposit + gather {:.3} ms",
                caps.device,
                median(&mut frame_ms),
                median(&mut budget)
            );
            for (k, mut v) in passes {
                println!("  {k:<20} {:>9.3} ms", median(&mut v));
            }
            let _ = sspm.free(backend.as_mut());
        }
    }
}
