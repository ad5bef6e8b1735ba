//! PhotonGi frames (Smal 2019) per backend at the chapter's two settings on `rooms` at
//! 1920x1080: "high", 3 million initial photons (1732^2), 3 bounces, 4 A-Trous iterations;
//! "low", 1 million (1024^2), 1 bounce, 4 A-Trous iterations. Both with the temporal
//! blend. After warm-up frames (`CAUSTICA_BENCH_WARMUP_MS`, default 3000), the median over
//! frames (a new seed each) of every pass, of the technique's device time (every pass but `primary_gbuffer` of the camera and
//! `direct_light`, which a renderer has anyway: the RSM faces' own `primary_gbuffer`
//! dispatches are counted by subtracting one camera G-buffer, see below) and of the host
//! wall time of the frame. Target: <= 6 ms at the high setting (docs/performance.md).
//!
//! `cargo bench -p caustica --bench photon_gi_frame`
//! Environment: `CAUSTICA_BENCH_BACKENDS` (default: every backend that opens here),
//! `CAUSTICA_BENCH_FRAMES=N` (default 5), `CAUSTICA_BENCH_SETTINGS=high,low`,
//! `CAUSTICA_BENCH_SIZE=WxH` (default 1920x1080),
//! `CAUSTICA_BENCH_GI_SCHEDULES=auto,single_kernel,waves,sorted_waves` (`trace_indirect`'s
//! schedules, default `auto`, the settings' default; each timed in turn),
//! `CAUSTICA_BENCH_GI_WAVES=N` (waves of the `waves` schedule, default the settings' 4),
//! `CAUSTICA_BENCH_GI_QUEUE=N` (`indirect_queue_paths`, default the settings' 2^22),
//! `CAUSTICA_BENCH_GI_WAVES_ABOVE=N` (`auto_waves_above_photons`, default the settings').
//! With waves, `trace_indirect`'s (and the sort's) median per wave follows the passes,
//! and the sort's per launch (scan, scatter; summed over the waves), and under
//! `auto` the time of the lights of few photons traced in one launch each.
//! Setting `dev` (256^2 photons, 3 bounces) is the high setting's paths at a size a
//! software device traces in seconds.

mod common;
use caustica::scene::builtin::builtin;
use caustica::techniques::photon_gi::{
    IndirectSchedule, PhotonGi, PhotonGiSettings, PhotonGiStats,
};
use caustica::FrameSettings;
use caustica::BACKEND_NAMES;
use common::{env_or, median, opened_backends, warm_up, warmup_ms};
use std::collections::BTreeMap;

fn main() {
    let frames: usize = env_or("CAUSTICA_BENCH_FRAMES", "5")
        .parse()
        .expect("frames");
    let size = env_or("CAUSTICA_BENCH_SIZE", "1920x1080");
    let (w, h) = size
        .split_once('x')
        .map(|(a, b)| (a.parse().expect("width"), b.parse().expect("height")))
        .expect("WxH");
    let wanted = env_or("CAUSTICA_BENCH_BACKENDS", &BACKEND_NAMES.join(","));
    let settings = env_or("CAUSTICA_BENCH_SETTINGS", "high,low");
    let schedules = env_or("CAUSTICA_BENCH_GI_SCHEDULES", "auto");
    let queue: u32 = env_or(
        "CAUSTICA_BENCH_GI_QUEUE",
        &PhotonGiSettings::default().indirect_queue_paths.to_string(),
    )
    .parse()
    .expect("queue paths");
    let waves_above: u32 = env_or(
        "CAUSTICA_BENCH_GI_WAVES_ABOVE",
        &PhotonGiSettings::default()
            .auto_waves_above_photons
            .to_string(),
    )
    .parse()
    .expect("photons");
    let waves: u32 = env_or(
        "CAUSTICA_BENCH_GI_WAVES",
        &PhotonGiSettings::default().indirect_waves.to_string(),
    )
    .parse()
    .expect("waves");
    let mut scene = builtin("rooms").expect("built-in scene");
    (scene.camera.width, scene.camera.height) = (w, h);
    println!(
        "PhotonGi frame, rooms, {w}x{h}, median of {frames} frames after {} ms of warm-up frames",
        warmup_ms()
    );
    for (name, mut backend) in opened_backends(&wanted) {
        let runs = settings.split(',').map(str::trim).flat_map(|setting| {
            schedules
                .split(',')
                .map(str::trim)
                .map(move |schedule| (setting, schedule))
        });
        for (setting, schedule) in runs {
            let (side, bounces) = match setting {
                "high" => (1732, 3),
                "low" => (1024, 1),
                "dev" => (256, 3),
                other => panic!("unknown setting {other}"),
            };
            let indirect_schedule = match schedule {
                "auto" => IndirectSchedule::Auto,
                "single_kernel" => IndirectSchedule::SingleKernel,
                "waves" => IndirectSchedule::Waves,
                "sorted_waves" => IndirectSchedule::SortedWaves,
                other => panic!("unknown schedule {other}"),
            };
            let s = PhotonGiSettings {
                frame: FrameSettings {
                    photons_w: side,
                    photons_h: side,
                    ..PhotonGiSettings::default().frame
                },
                bounces,
                indirect_schedule,
                indirect_waves: waves,
                indirect_queue_paths: queue,
                auto_waves_above_photons: waves_above,
                ..PhotonGiSettings::default()
            };
            let setting = match s.schedule(backend.capabilities().device_type) {
                IndirectSchedule::SingleKernel => format!("{setting}, {schedule}: single_kernel"),
                run => format!(
                    "{setting}, {schedule}: {} ({waves} waves, queues of {queue} paths{})",
                    serde_json::to_value(run)
                        .ok()
                        .and_then(|v| v.as_str().map(str::to_string))
                        .unwrap_or_default(),
                    if schedule == "auto" {
                        format!(", the waves for lights of over {waves_above} photons")
                    } else {
                        String::new()
                    }
                ),
            };
            let mut t = match PhotonGi::new(backend.as_mut(), &scene, s) {
                Ok(t) => t,
                Err(e) => {
                    println!("{name} / {setting}: {e}");
                    continue;
                }
            };
            if let Err(e) = warm_up(|| t.frame(backend.as_mut(), &mut |_| {}).map(|_| ())) {
                println!("{name} / {setting}: {e}");
                continue;
            }
            let mut passes: BTreeMap<String, Vec<f64>> = BTreeMap::new();
            // per wave `trace_indirect`'s and the sort's times, and the sort's per launch
            // (scan, scatter, over the waves): one entry a frame
            let mut wave_trace: Vec<Vec<f64>> = Vec::new();
            let mut wave_sort: Vec<Vec<f64>> = Vec::new();
            let mut sort_phase: Vec<Vec<f64>> = Vec::new();
            // `trace_indirect` in the lights `auto` traces in one launch each
            let mut single: Vec<Vec<f64>> = Vec::new();
            let (mut wall, mut technique) = (Vec::new(), Vec::new());
            let mut timing = String::new();
            let mut stored = 0;
            for i in 0..=frames {
                t.set_seed(i as u32 + 1);
                let st = match t.frame(backend.as_mut(), &mut |_| {}) {
                    Ok(st) => st,
                    Err(e) => {
                        println!("{name} / {setting}: {e}");
                        break;
                    }
                };
                if i == 0 {
                    continue;
                }
                for (p, v) in &st.pass_ms {
                    passes.entry(p.clone()).or_default().push(*v);
                }
                if let Some(gi) = PhotonGiStats::of(&st) {
                    for (parts, ms) in [
                        (&mut wave_trace, &gi.trace_ms_per_wave),
                        (&mut wave_sort, &gi.sort_ms_per_wave),
                        (&mut sort_phase, &gi.sort_ms_per_phase),
                        (&mut single, &vec![gi.single_ms]),
                    ] {
                        parts.resize(ms.len(), Vec::new());
                        parts.iter_mut().zip(ms).for_each(|(v, &m)| v.push(m));
                    }
                }
                // the camera's G-buffer is one of the primary_gbuffer dispatches: its share
                // is the mean dispatch times the one camera dispatch (faces are smaller, so
                // this leaves the faces slightly overcounted in the technique's time)
                let gb = st
                    .passes
                    .iter()
                    .find(|p| p.name == "primary_gbuffer")
                    .map_or(0.0, |p| p.ms / p.dispatches as f64);
                let own: f64 = st
                    .pass_ms
                    .iter()
                    .filter(|(p, _)| p.as_str() != "direct_light")
                    .map(|(_, v)| v)
                    .sum::<f64>()
                    - gb;
                technique.push(own);
                wall.push(st.frame_ms);
                timing = st.timing.clone();
                stored = st.photons_stored;
            }
            if wall.is_empty() {
                continue;
            }
            println!(
                "\n{name} on {} / {setting} ({side}^2 photons, {bounces} bounce(s), {stored} stored) ({timing}): frame {:.3} ms (host wall), PhotonGi passes {:.3} ms",
                backend.capabilities().device,
                median(&mut wall),
                median(&mut technique)
            );
            for (p, mut v) in passes {
                println!("  {p:24} {:.3} ms", median(&mut v));
            }
            for (what, mut parts) in [
                ("trace_indirect per wave", wave_trace),
                ("sort per wave", wave_sort),
                ("sort per launch (scan / scatter)", sort_phase),
                ("trace_indirect in lights of one launch", single),
            ] {
                // (lights in one launch: `auto` with `auto_waves_above_photons` alone)
                if parts.iter().flatten().any(|&ms| ms != 0.0) {
                    let ms: Vec<String> = parts
                        .iter_mut()
                        .map(|v| format!("{:.3}", median(v)))
                        .collect();
                    println!("  {what}, ms: {}", ms.join(" / "));
                }
            }
            t.free(backend.as_mut()).expect("free");
        }
    }
}
