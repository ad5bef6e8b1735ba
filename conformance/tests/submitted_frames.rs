//! The non-blocking frame, on every backend and for every technique:
//! a frame recorded whole and submitted without waiting ([`Technique::submit_frame`])
//! renders the images of the blocking [`Technique::frame`], bitwise; several frames can be
//! in flight with updates between them (a new seed, moved instances, moved lights, a moved
//! camera), and each frame's statistics, collected later, are that frame's own (its photon
//! counters were copied at its end, not read after the next one ran); a submission is
//! polled without blocking until it is done, handed out once, and a foreign one is an
//! error, not a panic. Work that needs a readback to go on (CausticMap's stale atlas,
//! AdaptiveCaustics' traversal) runs inside `record_frame`; a camera-only CausticMap
//! frame records everything.

use caustica_conformance::backends;
use caustica_core::backend::Submission;
use caustica_core::frame::stats::FrameStats;
use caustica_core::scene::builtin::builtin;
use caustica_core::scene::{Light, Scene, Transform};
use caustica_core::techniques::create;
use caustica_core::{Backend, Technique};
use glam::{Quat, Vec3};

fn small(name: &str) -> Scene {
    let mut s = builtin(name).expect("built-in scene");
    s.camera.width = 80;
    s.camera.height = 45;
    s
}

/// `sphere` with its glass ball an instance, so that frames can move it.
fn sphere_with_instance() -> Scene {
    let mut s = small("sphere");
    let o = &mut s.objects[1];
    if let caustica_core::scene::Shape::Sphere { center, .. } = &mut o.shape {
        let c = std::mem::replace(center, Vec3::ZERO);
        o.transform = Some(Transform::from_translation(c));
    } else {
        panic!("sphere's object 1 is its glass ball");
    }
    s
}

/// Every technique: Sspm, PhotonGi with its temporal blend (history carried from frame
/// to frame, in flight too) and A-Trous, CausticMap, AdaptiveCaustics' two targets.
fn techniques() -> Vec<(&'static str, serde_json::Value)> {
    vec![
        ("sspm", settings()),
        (
            "photon-gi",
            serde_json::json!({ "photons_w": 64, "photons_h": 64, "rsm_size": 32 }),
        ),
        // CausticMap: its photon pass waits inside record_frame when the atlas is stale,
        // nothing waits for a camera-only frame (the last one below)
        (
            "caustic-map",
            serde_json::json!({ "photons_w": 64, "photons_h": 64, "atlas_size": 128 }),
        ),
        // AdaptiveCaustics, both targets: the traversal waits inside record_frame
        (
            "adaptive-caustics",
            serde_json::json!({
                "photons_w": 128, "photons_h": 128, "atlas_size": 128, "error_from_grid": 64
            }),
        ),
        (
            "adaptive-caustics",
            serde_json::json!({
                "photons_w": 128, "photons_h": 128, "error_from_grid": 64, "deposit": "screen"
            }),
        ),
    ]
}

/// Sspm with four batches per light (so one recording holds several trace/deposit
/// pairs) and every output.
fn settings() -> serde_json::Value {
    serde_json::json!({
        "photons_w": 64, "photons_h": 64, "max_photons_per_batch": 1024,
        "outputs": {
            "composite": true, "direct": true, "raw_caustics": true, "filtered_caustics": true
        }
    })
}

/// What a frame's statistics must agree on between the two modes: the photon accounting
/// from the device counters and the recorded work.
fn accounting(s: &FrameStats) -> String {
    format!(
        "emitted {} stored {} deposited {} rays {} splits {} discarded {:?} flux {:?} \
         batches {} skipped {:?}",
        s.photons_emitted,
        s.photons_stored,
        s.photons_deposited,
        s.photon_rays_traced,
        s.photon_splits,
        s.discarded,
        s.stored_flux,
        s.batches,
        s.skipped.iter().map(|p| &p.name).collect::<Vec<_>>()
    )
}

fn outputs(t: &dyn Technique, b: &mut dyn Backend) -> Vec<(String, Vec<[f32; 4]>)> {
    t.outputs()
        .into_iter()
        .filter(|o| o.requested)
        .map(|o| {
            let img = t.read_output(b, o.output).expect("read");
            assert!(img.all_finite(), "{}: not finite", o.name);
            (o.name.to_string(), img.pixels)
        })
        .collect()
}

/// The updates made before frames 1 to 4 (frame 0 has none): a new seed, a moved
/// instance, a moved light, a moved camera (CausticMap's atlas stays valid then).
fn update(t: &mut dyn Technique, b: &mut dyn Backend, scene: &Scene, frame: usize) {
    match frame {
        1 => t.set_seed(7),
        2 => {
            let tr = scene.objects[1].transform.expect("an instance");
            let to = Transform {
                translation: tr.translation + Vec3::new(0.25, 0.05, -0.1),
                rotation: Quat::from_rotation_y(0.4),
                scale: tr.scale * 0.9,
            };
            t.set_object_transforms(b, &[(1, to)]).expect("move");
        }
        3 => {
            let mut lights = scene.lights.clone();
            if let Light::Point { position, .. } = &mut lights[0] {
                *position += Vec3::new(-0.3, 0.1, 0.2);
            }
            t.set_lights(b, &lights).expect("lights");
        }
        4 => {
            let mut camera = scene.camera.clone();
            camera.position += Vec3::new(0.2, 0.1, 0.0);
            t.set_camera(b, &camera).expect("camera");
        }
        _ => {}
    }
}

#[test]
fn submitted_frames_render_the_blocking_frames_bitwise_with_their_own_stats() {
    const FRAMES: usize = 5;
    for (bname, mut b) in backends() {
        let cases = [
            ("sphere", sphere_with_instance()),
            ("cornell", small("cornell")),
        ];
        for ((sname, scene), (tname, settings)) in cases
            .into_iter()
            .flat_map(|c| techniques().into_iter().map(move |t| (c.clone(), t)))
        {
            let b = b.as_mut();
            // the blocking frames: images after each, and stats
            let mut blocking = create(tname, b, &scene, &settings).expect("create");
            let mut want_images = Vec::new();
            let mut want_stats = Vec::new();
            for f in 0..FRAMES {
                if sname == "sphere" || f != 2 {
                    update(blocking.as_mut(), b, &scene, f);
                }
                let s = blocking.frame(b, &mut |_| {}).expect("frame");
                want_stats.push(s);
                want_images.push(outputs(blocking.as_ref(), b));
            }
            blocking.free(b).expect("free");

            // (a) one submitted frame at a time, its images read back after it
            let mut t = create(tname, b, &scene, &settings).expect("create");
            for f in 0..FRAMES {
                if sname == "sphere" || f != 2 {
                    update(t.as_mut(), b, &scene, f);
                }
                let mut ticket = t.submit_frame(b).expect("submit_frame");
                let got = outputs(t.as_ref(), b);
                assert!(
                    got == want_images[f],
                    "{bname}/{tname}/{sname}: submitted frame {f} differs from the blocking one"
                );
                let stats = ticket.stats(b, true).expect("stats").expect("waited");
                assert_eq!(
                    accounting(&stats),
                    accounting(&want_stats[f]),
                    "{bname}/{tname}/{sname}: frame {f}'s statistics"
                );
                if !stats.passes.is_empty() {
                    let passes = |s: &FrameStats| {
                        s.passes
                            .iter()
                            .map(|p| (p.name.clone(), p.dispatches))
                            .collect::<Vec<_>>()
                    };
                    assert_eq!(
                        passes(&stats),
                        passes(&want_stats[f]),
                        "{bname}/{tname}/{sname}: frame {f}'s timed passes"
                    );
                }
            }
            t.free(b).expect("free");

            // (b) every frame in flight at once, the statistics collected afterwards: each
            // frame's counters are its own
            let mut t = create(tname, b, &scene, &settings).expect("create");
            let mut tickets = Vec::new();
            for f in 0..FRAMES {
                if sname == "sphere" || f != 2 {
                    update(t.as_mut(), b, &scene, f);
                }
                tickets.push(t.submit_frame(b).expect("submit_frame"));
            }
            for (f, ticket) in tickets.iter_mut().enumerate() {
                let stats = ticket.stats(b, true).expect("stats").expect("waited");
                assert_eq!(
                    accounting(&stats),
                    accounting(&want_stats[f]),
                    "{bname}/{tname}/{sname}: frame {f} of {FRAMES} in flight: its statistics"
                );
                // handed out once
                assert!(
                    ticket.stats(b, true).is_err(),
                    "{bname}: a ticket's statistics collected twice"
                );
            }
            let got = outputs(t.as_ref(), b);
            assert!(
                got == want_images[FRAMES - 1],
                "{bname}/{tname}/{sname}: the last of {FRAMES} frames in flight differs"
            );
            t.free(b).expect("free");
            eprintln!(
                "{bname}: {tname} on {sname}: submitted frames equal the blocking ones, bitwise, \
                 {FRAMES} in flight each with its own statistics"
            );
        }
    }
}

#[test]
fn a_submission_is_polled_without_blocking_until_done() {
    for (bname, mut b) in backends() {
        let b = b.as_mut();
        let scene = small("sphere");
        let mut t = create("sspm", b, &scene, &settings()).expect("create");
        let mut ticket = t.submit_frame(b).expect("submit_frame");
        let start = std::time::Instant::now();
        let mut polls = 0u32;
        let stats = loop {
            polls += 1;
            if let Some(s) = ticket.stats(b, false).expect("poll") {
                break s;
            }
            assert!(
                start.elapsed().as_secs() < 120,
                "{bname}: a submitted frame did not finish in 120 s of polling"
            );
            std::thread::sleep(std::time::Duration::from_millis(1));
        };
        assert!(stats.photons_deposited > 0, "{bname}: nothing deposited");
        // a submission of no one's is an error, not a panic
        let mut foreign = Submission::pending(u64::MAX);
        assert!(
            b.poll(&mut foreign, false).is_err(),
            "{bname}: polling a foreign submission"
        );
        t.free(b).expect("free");
        eprintln!("{bname}: a submitted frame finished after {polls} non-blocking polls");
    }
}

#[test]
fn a_camera_only_caustic_map_frame_is_recorded_whole_and_runs_nothing_ahead() {
    let mut b = caustica_cpu::CpuBackend::new().expect("cpu");
    let scene = small("sphere");
    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64, "atlas_size": 128 });
    let mut t = create("caustic-map", &mut b, &scene, &settings).expect("create");
    let mut first = t.submit_frame(&mut b).expect("first frame");
    first.stats(&mut b, true).expect("stats");
    let mut camera = scene.camera.clone();
    camera.position += Vec3::new(0.2, 0.1, 0.0);
    t.set_camera(&mut b, &camera).expect("camera");
    let recorded = t.record_frame(&mut b).expect("record");
    assert!(
        recorded
            .stats
            .skipped
            .iter()
            .any(|p| p.name == "trace_photons" && p.reason.contains("only the camera")),
        "a camera-only frame skips the photon pass: {:?}",
        recorded.stats.skipped
    );
    assert!(
        recorded.recording.steps.iter().any(|s| matches!(
            s,
            caustica_core::recording::Step::Kernel(k) if k.name() == "caustic_map_lookup"
        )),
        "the lookup is recorded"
    );
    let mut ticket = recorded.submit(&mut b).expect("submit");
    ticket.stats(&mut b, true).expect("stats");
    t.free(&mut b).expect("free");
}

/// No technique waits on the device inside `record_frame` or a blocking frame's
/// recording (`FrameStats::host_waits`, which counts every device wait and blocking
/// readback there): Sspm, PhotonGi, CausticMap (its reach mask comes back without a
/// wait) and AdaptiveCaustics on both targets (its traversal reads its counts on the
/// device), with moving lights and objects, on every backend, in frames of several
/// photon batches (a batch of at most 1024 photons) and single ones.
#[test]
fn no_technique_waits_inside_a_frame() {
    let scene = sphere_with_instance();
    for (bname, mut b) in backends() {
        let b = b.as_mut();
        for (tname, mut settings) in techniques() {
            for batches in [false, true] {
                if batches {
                    if let Some(o) = settings.as_object_mut() {
                        o.insert("max_photons_per_batch".into(), 1024.into());
                        if tname == "adaptive-caustics" {
                            // passes of a few hundred clusters, lists capped
                            o.insert("max_traversal_bytes".into(), (96 << 10).into());
                        }
                    }
                }
                let mut t = match create(tname, b, &scene, &settings) {
                    Ok(t) => t,
                    // a technique without the batch setting
                    Err(_) if batches => continue,
                    Err(e) => panic!("{bname}/{tname}: {e}"),
                };
                for f in 0..5 {
                    update(t.as_mut(), b, &scene, f);
                    let recorded = t.record_frame(b).expect("record_frame");
                    let waits = recorded.stats.host_waits;
                    let several = recorded.stats.batches;
                    let mut ticket = recorded.submit(b).unwrap_or_else(|e| {
                        panic!("{bname}/{tname} frame {f} batches {batches}: {e}")
                    });
                    let stats = ticket.stats(b, true).expect("stats").expect("waited");
                    assert_eq!(
                        stats.host_waits, waits,
                        "{bname}/{tname}: frame {f}'s waits"
                    );
                    assert_eq!(
                        waits, 0,
                        "{bname}/{tname}: frame {f} ({several} batches) waited on the device"
                    );
                    let blocking = t.frame(b, &mut |_| {}).expect("frame");
                    assert_eq!(
                        blocking.host_waits, 0,
                        "{bname}/{tname}: a blocking frame waited inside its recording"
                    );
                }
                t.free(b).expect("free");
            }
        }
    }
}

/// Every recorded frame carries the updates before it, so frames run in the order
/// recorded: a frame recorded and dropped unsubmitted, or submitted out of order, makes
/// the technique's next frame an error that says why, instead of a stale image; frames
/// submitted in order (and blocking frames between them) run.
#[test]
fn frames_run_in_the_order_recorded_or_the_next_one_says_why() {
    let mut b = caustica_cpu::CpuBackend::new().expect("cpu");
    let scene = small("sphere");
    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64 });
    let mut t = create("sspm", &mut b, &scene, &settings).expect("create");
    // in order, with a blocking frame between
    let r1 = t.record_frame(&mut b).expect("record");
    let r2 = t.record_frame(&mut b).expect("record");
    r1.submit(&mut b)
        .expect("submit")
        .stats(&mut b, true)
        .expect("stats");
    r2.submit(&mut b)
        .expect("submit")
        .stats(&mut b, true)
        .expect("stats");
    t.frame(&mut b, &mut |_| {})
        .expect("a blocking frame after them");
    // a blocking frame while a recorded one waits: out of order
    let waiting = t.record_frame(&mut b).expect("record");
    let e = t
        .frame(&mut b, &mut |_| {})
        .expect_err("ahead of a recorded frame")
        .to_string();
    assert!(e.contains("still to be submitted"), "{e}");
    drop(waiting);
    t.free(&mut b).expect("free");

    let mut t = create("sspm", &mut b, &scene, &settings).expect("create");
    let mut lights = scene.lights.clone();
    if let caustica_core::scene::Light::Point { position, .. } = &mut lights[0] {
        *position += Vec3::new(0.3, 0.0, 0.0);
    }
    t.set_lights(&mut b, &lights).expect("lights");
    drop(t.record_frame(&mut b).expect("record")); // the host skipped it
    for _ in 0..2 {
        let e = t
            .frame(&mut b, &mut |_| {})
            .expect_err("after a dropped frame")
            .to_string();
        assert!(e.contains("dropped without being submitted"), "{e}");
        let e = t
            .record_frame(&mut b)
            .expect_err("after a dropped frame")
            .to_string();
        assert!(e.contains("make the technique anew"), "{e}");
    }
    t.free(&mut b).expect("free");

    let mut t = create("sspm", &mut b, &scene, &settings).expect("create");
    let r1 = t.record_frame(&mut b).expect("record");
    let r2 = t.record_frame(&mut b).expect("record");
    r2.submit(&mut b)
        .expect("submit")
        .stats(&mut b, true)
        .expect("stats");
    r1.submit(&mut b)
        .expect("submit")
        .stats(&mut b, true)
        .expect("stats");
    let e = t
        .record_frame(&mut b)
        .expect_err("out of order")
        .to_string();
    assert!(e.contains("frame 1 was submitted while frame 0"), "{e}");
    t.free(&mut b).expect("free");
}

/// An update made while a recorded frame waits to be submitted must not run ahead of it:
/// a new light count is queued behind the frame (its old light buffer, which the frame
/// uses, freed after it: the frame renders its one light), and the next frame equals a
/// fresh technique's bitwise; an update that must run on the device at once (making the
/// technique's buffers anew, CausticMap's caustic images at a new size) is refused until
/// the frame is submitted, and goes through afterwards.
#[test]
fn updates_never_run_ahead_of_a_recorded_frame() {
    let mut b = caustica_cpu::CpuBackend::new().expect("cpu");
    let scene = small("sphere");
    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64 });
    let mut t = create("sspm", &mut b, &scene, &settings).expect("create");
    let waiting = t.record_frame(&mut b).expect("record");
    let mut more = scene.clone();
    more.lights.push(Light::Point {
        position: Vec3::new(-0.8, 2.5, 0.4),
        intensity: Vec3::splat(3.0),
    });
    t.set_lights(&mut b, &more.lights)
        .expect("a new light count waits for the recorded frame");
    let other = serde_json::json!({ "photons_w": 32, "photons_h": 32 });
    let e = t
        .set_settings(&mut b, &other)
        .expect_err("buffers the recorded frame uses")
        .to_string();
    assert!(e.contains("submit the recorded frames first"), "{e}");
    let own = waiting
        .submit(&mut b)
        .expect("the recorded frame runs with its own lights")
        .stats(&mut b, true)
        .expect("stats")
        .expect("done");
    let mut one = create("sspm", &mut b, &scene, &settings).expect("one light");
    let one_light = one.frame(&mut b, &mut |_| {}).expect("frame");
    assert_eq!(
        (own.photons_emitted, own.photons_stored),
        (one_light.photons_emitted, one_light.photons_stored),
        "the recorded frame did not render its own light"
    );
    one.free(&mut b).expect("free");
    t.frame(&mut b, &mut |_| {}).expect("frame");
    let mut fresh = create("sspm", &mut b, &more, &settings).expect("fresh");
    fresh.frame(&mut b, &mut |_| {}).expect("fresh frame");
    assert!(
        outputs(t.as_ref(), &mut b) == outputs(fresh.as_ref(), &mut b),
        "two lights after a recorded frame differ from a fresh technique's"
    );
    t.set_settings(&mut b, &other)
        .expect("once the frame is submitted");
    t.frame(&mut b, &mut |_| {}).expect("frame");
    t.free(&mut b).expect("free");
    fresh.free(&mut b).expect("free");

    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64, "atlas_size": 128 });
    let mut cm = create("caustic-map", &mut b, &scene, &settings).expect("create");
    cm.frame(&mut b, &mut |_| {}).expect("frame");
    let waiting = cm.record_frame(&mut b).expect("record");
    let mut wider = scene.camera.clone();
    wider.width = 96;
    wider.height = 54;
    let e = cm
        .set_camera(&mut b, &wider)
        .expect_err("images the recorded frame writes")
        .to_string();
    assert!(e.contains("submit the recorded frames first"), "{e}");
    waiting
        .submit(&mut b)
        .expect("the recorded frame, its images whole")
        .stats(&mut b, true)
        .expect("stats");
    cm.set_camera(&mut b, &wider)
        .expect("once the frame is submitted");
    cm.frame(&mut b, &mut |_| {})
        .expect("frame at the new size");
    cm.free(&mut b).expect("free");
    assert_eq!(b.buffer_count(), 0, "buffers left");
}

/// CausticMap lays its atlas out anew after a receiver moves, with the next frame; made
/// anew before that frame (new settings), it does not run that stale work into buffers
/// it freed (which made them again, never to be freed): the frame equals a fresh
/// technique's over the moved scene, bitwise, and nothing is left once both are freed.
#[test]
fn work_deferred_into_a_freed_technique_is_dropped() {
    let mut b = caustica_cpu::CpuBackend::new().expect("cpu");
    let mut scene = small("sphere");
    scene.objects[0].transform = Some(Transform::IDENTITY);
    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64, "atlas_size": 128 });
    let mut t = create("caustic-map", &mut b, &scene, &settings).expect("create");
    t.frame(&mut b, &mut |_| {}).expect("frame");
    let lifted = Transform::from_translation(Vec3::new(0.0, 0.05, 0.0));
    t.set_object_transforms(&mut b, &[(0, lifted)])
        .expect("the receiver moves");
    let other = serde_json::json!({ "photons_w": 48, "photons_h": 48, "atlas_size": 128 });
    t.set_settings(&mut b, &other).expect("new settings");
    t.frame(&mut b, &mut |_| {})
        .expect("the frame after the technique was made anew");
    let mut moved = scene.clone();
    moved.objects[0].transform = Some(lifted);
    let mut fresh = create("caustic-map", &mut b, &moved, &other).expect("fresh");
    fresh.frame(&mut b, &mut |_| {}).expect("fresh frame");
    assert!(
        outputs(t.as_ref(), &mut b) == outputs(fresh.as_ref(), &mut b),
        "differs from a fresh technique over the moved scene"
    );
    t.free(&mut b).expect("free");
    fresh.free(&mut b).expect("free");
    assert_eq!(b.buffer_count(), 0, "buffers left after both were freed");
}
