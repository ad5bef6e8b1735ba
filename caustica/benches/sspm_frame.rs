//! One Sspm frame per backend, side by side: `sphere` and `cornell` at 1920x1080 with
//! 2048x2048 photons (the setting of the performance targets), median per-pass times over
//! repeated frames after warm-up frames (`CAUSTICA_BENCH_WARMUP_MS`, default 3000), and the
//! budget line trace + deposit + gather (resolve and the filter's passes: the density gather's table, footprint and two
//! passes, or the bilateral's tiles and two passes; target on a GPU: <= 2 ms on the
//! fastest backend), once per caustic filter. Device timestamps where the backend has
//! them.
//!
//! Then the same frame as a host's frame loop runs it (docs/embedding.md):
//! `submit_frame` without waiting, at most two frames in flight, statistics collected
//! later: the host's submit time, the wall time per frame in the steady state (first to
//! last collected frame), and the device passes' sum.
//!
//! Then `plain` (no caster): the host wall time of a whole Sspm frame, whose plan
//! runs only the G-buffer and direct light, against a recording of those two kernels
//! alone on the same backend, medians with their min..max spread: the frame plan's
//! overhead must be within that noise.
//!
//! `cargo bench -p caustica --bench sspm_frame`
//! Environment: `CAUSTICA_BENCH_BACKENDS=wgpu,vulkan` (default: every backend that opens
//! here), `CAUSTICA_BENCH_FRAMES=N` (default 5), `CAUSTICA_BENCH_SIZE=WxH`,
//! `CAUSTICA_BENCH_PHOTONS=N` (grid side, default 2048), `CAUSTICA_BENCH_FILTERS=density`
//! (default: density,bilateral), `CAUSTICA_BENCH_SETTINGS='{"max_photons_per_batch":
//! 4194304}'` (more Sspm settings as JSON, merged over those: to measure a lever).

mod common;
use caustica::internals::device::device_scene::DeviceScene;
use caustica::internals::device::layout::GpuCamera;
use caustica::BACKEND_NAMES;
use common::{env_or, median, opened_backends, warm_up, warmup_ms};

use caustica::internals::kernels::{DirectLight, PrimaryGbuffer};
use caustica::internals::recording::Recording;
use caustica::scene::builtin::builtin;
use caustica::scene::Scene;
use caustica::techniques::create;
use caustica::techniques::sspm::FrameConstants;
use caustica::{Backend, SspmSettings};
use std::collections::BTreeMap;
use std::time::Instant;

/// The passes of the "trace + store + gather" budget (target on a GPU: <= 2 ms).
const BUDGET_PASSES: &[&str] = &[
    "trace_photons",
    "deposit_screen",
    "resolve_caustics",
    "photon_count_table",
    "gather_footprint",
    "density_gather",
    "tile_hit_distance",
    "bilateral_gather",
];

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
    let filters: Vec<String> = env_or("CAUSTICA_BENCH_FILTERS", "density,bilateral")
        .split(',')
        .map(|f| f.trim().to_string())
        .filter(|f| !f.is_empty())
        .collect();
    let extra: serde_json::Map<String, serde_json::Value> =
        serde_json::from_str(&env_or("CAUSTICA_BENCH_SETTINGS", "{}"))
            .expect("CAUSTICA_BENCH_SETTINGS: a JSON object of Sspm settings");
    println!(
        "Sspm frame, {w}x{h}, {side}x{side} photons, median of {frames} frames after {} ms of warm-up frames",
        warmup_ms()
    );
    if !extra.is_empty() {
        println!("settings: {}", serde_json::Value::Object(extra.clone()));
    }
    for (name, mut backend) in opened_backends(&wanted) {
        let caps = backend.capabilities();
        for (scene_name, filter) in ["sphere", "cornell"]
            .into_iter()
            .flat_map(|s| filters.iter().map(move |f| (s, f.as_str())))
        {
            let mut scene = builtin(scene_name).expect("built-in scene");
            scene.camera.width = w;
            scene.camera.height = h;
            let mut settings =
                serde_json::json!({ "photons_w": side, "photons_h": side, "filter": filter });
            for (k, v) in &extra {
                settings[k] = v.clone();
            }
            let mut sspm = match create("sspm", backend.as_mut(), &scene, &settings) {
                Ok(s) => s,
                Err(e) => {
                    println!("{name}/{scene_name}: {e}");
                    continue;
                }
            };
            if let Err(e) = warm_up(|| sspm.frame(backend.as_mut(), &mut |_| {}).map(|_| ())) {
                println!("{name}/{scene_name}: {e}");
                continue;
            }
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
                "\n{name} on {} / {scene_name} / {filter} filter ({timing}): frame {:.3} ms \
                 (host wall), trace + deposit + gather {:.3} ms",
                caps.device,
                median(&mut frame_ms),
                median(&mut budget)
            );
            for (k, mut v) in passes {
                println!("  {k:<20} {:>9.3} ms", median(&mut v));
            }
            match pipelined(backend.as_mut(), sspm.as_mut(), 4 * frames) {
                Ok(p) => println!(
                    "  non-blocking ({} frames, at most {IN_FLIGHT} in flight): submit {:.3} ms \
                     host, {:.3} ms per frame on the wall, device passes {:.3} ms (medians); \
                     wall - device {:+.3} ms",
                    4 * frames,
                    p.submit_ms,
                    p.wall_ms,
                    p.device_ms,
                    p.wall_ms - p.device_ms
                ),
                Err(e) => println!("  non-blocking: {e}"),
            }
            let _ = sspm.free(backend.as_mut());
        }
        let mut plain = builtin("plain").expect("built-in scene");
        plain.camera.width = w;
        plain.camera.height = h;
        match plain_against_direct(backend.as_mut(), &plain, frames) {
            Ok(((mut f, fs), (mut d, ds))) => println!(
                "\n{name} / plain: Sspm frame {:.3} ms [{:.3}..{:.3}], G-buffer + direct light \
                 alone {:.3} ms [{:.3}..{:.3}] (host wall, median [min..max] of {frames})",
                median(&mut f),
                fs.0,
                fs.1,
                median(&mut d),
                ds.0,
                ds.1
            ),
            Err(e) => println!("{name} / plain: {e}"),
        }
    }
}

/// Frames a pipelined host keeps on the device before it waits for the oldest.
const IN_FLIGHT: usize = 2;

/// The non-blocking frame loop's costs, medians.
struct Pipelined {
    /// Host time of `submit_frame` (record + submit).
    submit_ms: f64,
    /// Wall time per frame in the steady state: from the first collected frame to the
    /// last, over the frames between (the pipeline's fill and drain left out).
    wall_ms: f64,
    /// Sum of a frame's device passes.
    device_ms: f64,
}

/// `n` frames submitted as a host's frame loop does: submit, keep at most [`IN_FLIGHT`] on
/// the device, collect each frame's statistics when it is the oldest.
fn pipelined(
    backend: &mut dyn Backend,
    sspm: &mut dyn caustica::Technique,
    n: usize,
) -> Result<Pipelined, caustica::Error> {
    let mut tickets = std::collections::VecDeque::new();
    let (mut submit, mut device, mut done) = (Vec::new(), Vec::new(), Vec::new());
    let mut collect = |t: &mut caustica::FrameTicket, b: &mut dyn Backend| {
        t.stats(b, true).map(|s| {
            if let Some(s) = s {
                device.push(s.passes.iter().map(|p| p.ms).sum::<f64>());
                done.push(Instant::now());
            }
        })
    };
    for _ in 0..n {
        let t0 = Instant::now();
        tickets.push_back(sspm.submit_frame(backend)?);
        submit.push(t0.elapsed().as_secs_f64() * 1e3);
        while tickets.len() > IN_FLIGHT {
            let mut t = tickets.pop_front().expect("not empty");
            collect(&mut t, backend)?;
        }
    }
    for mut t in tickets {
        collect(&mut t, backend)?;
    }
    let wall_ms = match (done.first(), done.last()) {
        (Some(a), Some(b)) if done.len() > 1 => {
            (*b - *a).as_secs_f64() * 1e3 / (done.len() - 1) as f64
        }
        _ => 0.0,
    };
    Ok(Pipelined {
        submit_ms: median(&mut submit),
        wall_ms,
        device_ms: median(&mut device),
    })
}

type Times = (Vec<f64>, (f64, f64));

fn spread(v: Vec<f64>) -> Times {
    let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = v.iter().copied().fold(0.0, f64::max);
    (v, (lo, hi))
}

/// Host wall times (ms) of `frames` Sspm frames of `scene` and of as many executions of
/// a recording with only `primary_gbuffer` and `direct_light`, each after a warm-up.
fn plain_against_direct(
    backend: &mut dyn Backend,
    scene: &Scene,
    frames: usize,
) -> Result<(Times, Times), caustica::Error> {
    let settings = SspmSettings::default();
    let mut sspm = create("sspm", backend, scene, &serde_json::json!({}))?;
    let mut frame = Vec::new();
    for i in 0..=frames {
        let ms = sspm.frame(backend, &mut |_| {})?.frame_ms;
        if i > 0 {
            frame.push(ms);
        }
    }
    sspm.free(backend)?;

    let ds = DeviceScene::build(scene, Default::default()).map_err(caustica::Error::from)?;
    let mut setup = Recording::new();
    let args = setup.upload_scene(&ds);
    let camera = GpuCamera::from_camera(&scene.camera);
    let pixels = camera.width * camera.height;
    let gbuffer = setup.create_gbuffer(pixels);
    let out = setup.create(pixels, "direct image");
    backend.execute(&setup)?;
    let mut rec = Recording::new();
    rec.kernel(PrimaryGbuffer {
        scene: args,
        camera,
        gbuffer,
    });
    rec.kernel(DirectLight {
        scene: args,
        params: FrameConstants::direct_params(camera, scene.lights.len() as u32, &settings),
        gbuffer,
        out,
    });
    let mut direct = Vec::new();
    for i in 0..=frames {
        let t0 = Instant::now();
        backend.execute(&rec)?;
        if i > 0 {
            direct.push(t0.elapsed().as_secs_f64() * 1e3);
        }
    }
    let mut free = Recording::new();
    for id in [
        args.vertices.id,
        args.triangles.id,
        args.materials.id,
        args.lights.id,
    ] {
        free.steps
            .push(caustica::internals::recording::Step::Free { id });
    }
    free.free(args.bvh_nodes);
    for p in gbuffer.planes {
        free.free(p);
    }
    free.free(out);
    backend.execute(&free)?;
    Ok((spread(frame), spread(direct)))
}
