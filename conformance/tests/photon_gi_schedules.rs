//! PhotonGi's two schedules of `trace_indirect` on every backend (`backends()`: all four,
//! required in CI): the per-bounce waves trace exactly the single launch's paths (each
//! path's random numbers are keyed by its photon and segment, its state crosses the
//! queue in full precision), so they store the same photons in another order; the splat
//! and the deposit sum in exact fixed point, so every image is the single launch's bit
//! for bit, and so are the photon statistics. Checked on `cornell` and `rooms`, over two
//! frames (the first selects the photon plan on the device and launches the lights from
//! it, the second from the plan read back), with the splat, the raw deposit, one wave
//! per segment and the default waves, the sorted waves, and the waves over queues that
//! hold a fraction of a light's photons (its photons in chunks, the last one partial);
//! and `sort_indirect_paths` against the CPU on proptest-drawn queues.

use caustica_conformance::backends;
use caustica_conformance::harness;
use caustica_conformance::kernels::sort_indirect_paths::{
    bucket_counts, check_sort_indirect_paths,
};
use caustica_core::frame::output::Output;
use caustica_core::frame::stats::FrameStats;
use caustica_core::math::path_sort::{PathKey, PATH_SORT_BUCKETS};
use caustica_core::scene::builtin::builtin;
use caustica_core::scene::Scene;
use caustica_core::techniques::create;
use caustica_core::techniques::photon_gi::{PhotonGiSettings, PhotonGiStats};
use caustica_core::{Backend, DeviceType};
use proptest::prelude::*;

fn scene(name: &str) -> Scene {
    let mut s = builtin(name).expect("built-in");
    (s.camera.width, s.camera.height) = (96, 54);
    s
}

/// Per frame: the outputs' bits, the photon statistics and the waves' times.
type Frames = Vec<(Vec<Vec<u32>>, String, Option<PhotonGiStats>)>;

fn frames(b: &mut dyn Backend, scene: &Scene, settings: &serde_json::Value) -> Frames {
    let mut t = create("photon-gi", b, scene, settings).expect("create");
    let out = (0..2)
        .map(|k| {
            t.set_seed(3 + k);
            let stats = t.frame(b, &mut |_| {}).expect("frame");
            // every wave is launched from the device's count: no wait inside the frame
            assert_eq!(
                stats.host_waits, 0,
                "{settings}: the frame waited on the device"
            );
            check_wave_times(settings, &stats);
            let images = [
                Output::RawIndirect,
                Output::FilteredIndirect,
                Output::Composite,
            ]
            .map(|o| {
                let img = t.read_output(b, o).expect("read").pixels;
                img.iter().flatten().map(|x| x.to_bits()).collect()
            });
            let counts = format!(
                "emitted {} rays {} stored {} discarded {:?}",
                stats.photons_emitted,
                stats.photon_rays_traced,
                stats.photons_stored,
                stats.discarded
            );
            (images.to_vec(), counts, PhotonGiStats::of(&stats))
        })
        .collect();
    t.free(b).expect("free");
    out
}

/// The waves' times in the frame's statistics ([`PhotonGiStats`]): one per wave, adding
/// up with the single launches' to the frame's `trace_indirect` (and
/// `sort_indirect_paths`) pass; none for the single kernel (`auto`, which resolves by
/// device and light, is checked where it ran waves).
fn check_wave_times(settings: &serde_json::Value, stats: &FrameStats) {
    let gi = PhotonGiStats::of(stats);
    let schedule = settings["indirect_schedule"].as_str().unwrap_or("auto");
    let asked = settings["indirect_waves"]
        .as_u64()
        .map_or(PhotonGiSettings::default().indirect_waves, |w| w as u32);
    match schedule {
        "waves" | "sorted_waves" if asked > 1 => {}
        "auto" if gi.is_some() => {}
        "auto" => return,
        _ => {
            assert_eq!(gi, None, "{settings}: wave times for the single kernel");
            return;
        }
    }
    let gi = gi.unwrap_or_else(|| panic!("{settings}: no wave times"));
    assert!(
        gi.waves >= 2 && gi.waves <= asked,
        "{settings}: {} waves",
        gi.waves
    );
    let adds_up = |parts: &[f64], pass: &str, len: usize| {
        let whole = stats.pass_ms.get(pass).copied().unwrap_or(0.0);
        let sum: f64 = parts.iter().sum();
        parts.len() == len && (sum - whole).abs() <= 1e-9 * whole.max(1.0)
    };
    let waves = gi.waves as usize;
    assert!(
        adds_up(
            &[&gi.trace_ms_per_wave[..], &[gi.single_ms]].concat(),
            "trace_indirect",
            waves + 1
        ),
        "{settings}: {gi:?} against {:?}",
        stats.pass_ms
    );
    if schedule == "sorted_waves" {
        assert!(
            adds_up(&gi.sort_ms_per_wave, "sort_indirect_paths", waves)
                && gi.sort_ms_per_wave[0] == 0.0
                && adds_up(&gi.sort_ms_per_phase, "sort_indirect_paths", 2),
            "{settings}: {gi:?} against {:?}",
            stats.pass_ms
        );
    } else {
        assert!(
            gi.sort_ms_per_wave.is_empty() && gi.sort_ms_per_phase.is_empty(),
            "{settings}: {gi:?}"
        );
    }
}

#[test]
fn waves_render_the_single_launchs_images_bitwise() {
    let mut failures = Vec::new();
    for (name, mut b) in backends() {
        for scene_name in ["cornell", "rooms"] {
            let s = scene(scene_name);
            for estimator in ["splat", "deposit"] {
                let base = serde_json::json!({
                    "photons_w": 96, "photons_h": 96, "rsm_size": 64, "estimator": estimator,
                    "indirect_schedule": "single_kernel"
                });
                let single = frames(b.as_mut(), &s, &base);
                // (the 96^2 photons of a light in chunks of 1000 and of 4096; `auto`
                // with a light of at most 1000 photons in one launch)
                for (schedule, waves, queue) in [
                    ("waves", 8, 1 << 20),
                    ("waves", 16, 1 << 20),
                    ("sorted_waves", 8, 1 << 20),
                    ("waves", 8, 1000),
                    ("sorted_waves", 8, 4096),
                    ("auto", 8, 1 << 20),
                ] {
                    let mut w = base.clone();
                    w["indirect_schedule"] = schedule.into();
                    w["indirect_waves"] = waves.into();
                    w["indirect_queue_paths"] = queue.into();
                    w["auto_waves_above_photons"] = 1000.into();
                    let waved = frames(b.as_mut(), &s, &w);
                    // `rooms`' dim light (a few hundred photons) in one launch, the other
                    // in waves, once the plan is read back (the second frame), on a GPU
                    if schedule == "auto"
                        && scene_name == "rooms"
                        && b.capabilities().device_type != DeviceType::Cpu
                    {
                        let gi = waved[1].2.as_ref();
                        if !gi.is_some_and(|g| g.single_ms > 0.0 && g.waves == waves) {
                            failures.push(format!(
                                "{name} {estimator} auto: not a light in one launch and one \
                                 in waves: {gi:?}"
                            ));
                        }
                    }
                    for (k, (a, c)) in single.iter().zip(&waved).enumerate() {
                        let what = format!(
                            "{name} {scene_name} {estimator} {schedule} {waves} queue {queue} \
                             frame {k}"
                        );
                        if a.1 != c.1 {
                            failures.push(format!("{what}: statistics {} vs {}", c.1, a.1));
                        }
                        for (o, (x, y)) in a.0.iter().zip(&c.0).enumerate() {
                            let differ = x.iter().zip(y).filter(|(p, q)| p != q).count();
                            if differ > 0 || x.len() != y.len() {
                                failures.push(format!("{what}: output {o}: {differ} words differ"));
                            }
                        }
                    }
                    eprintln!(
                        "{name} {scene_name} {estimator} {waves} waves: {}",
                        waved[1].1
                    );
                }
            }
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// A queue's (key, rank) pairs as a queuing wave leaves them: keys over every bucket
/// (crowded into a few or spread), each key's ranks a permutation of its count (in queue
/// order, reversed, or interleaved, as a GPU's atomics may hand them out), now and then a
/// key no wave writes (past the buckets); queue lengths from 0 past the queue's capacity.
fn queues() -> impl Strategy<Value = (Vec<PathKey>, u32)> {
    let key = prop_oneof![
        8 => 0u32..PATH_SORT_BUCKETS,
        8 => 0u32..4,
        1 => Just(PATH_SORT_BUCKETS - 1),
        1 => Just(u32::MAX),
    ];
    (
        proptest::collection::vec(key, 0..600),
        0u32..3,
        prop_oneof![Just(0u32), 0u32..700, Just(u32::MAX)],
    )
        .prop_map(|(keys, ranking, length)| {
            let counts = bucket_counts(&keys.iter().map(|&k| [k, 0]).collect::<Vec<_>>());
            let mut seen = vec![0u32; PATH_SORT_BUCKETS as usize];
            let ranked = keys
                .iter()
                .map(|&k| {
                    let Some(s) = seen.get_mut(k as usize) else {
                        return [k, 0];
                    };
                    let (j, n) = (*s, counts[k as usize]);
                    *s += 1;
                    let rank = match ranking {
                        0 => j,
                        1 => n - 1 - j,
                        // evens first, then odds
                        _ => {
                            if j % 2 == 0 {
                                j / 2
                            } else {
                                n.div_ceil(2) + j / 2
                            }
                        }
                    };
                    [k, rank]
                })
                .collect();
            (ranked, length)
        })
}

#[test]
fn sort_indirect_paths_matches_cpu_for_any_queue() {
    harness::check_generated(
        "sort_indirect_paths on generated queues",
        queues(),
        |r, c, (keys, length)| check_sort_indirect_paths(r, c, keys, *length),
    );
}
