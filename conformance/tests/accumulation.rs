//! Progressive accumulation (`accumulate`): N frames of M photons estimate as one frame of
//! N x M photons (Sspm's raw caustics within the noise: the frames' jitters are the strata
//! of one low-discrepancy sequence per grid cell). Measured on the CPU backend against a reference of 16 times the
//! largest photon count: the relative L2 error of the accumulated estimate is that of one
//! frame of all its photons, and the raw estimate's error falls as 1/sqrt(frames) over 1
//! to 64 frames; a moved camera starts the accumulation again.
//!
//! Tolerances. The relative L2 error is a mean over the caustic mask's pixels (a few
//! hundred at 96x54), each an independent photon count, so two estimates of one error
//! differ by about 1/sqrt(2 pixels) ~ 5%; 0.8..1.25 is four such deviations. The
//! reference's own noise (a quarter of the largest test count's, its photons 16 times
//! theirs) is removed in quadrature before the slope is taken; the slope of four points
//! over a factor 64 in photons carries the same 5% per point, 0.06 in the exponent: -0.5
//! within 0.1.

use caustica_core::frame::image::Image;
use caustica_core::frame::metrics::compare;
use caustica_core::frame::output::Output;
use caustica_core::scene::builtin::builtin;
use caustica_core::scene::Scene;
use caustica_core::techniques::create;
use caustica_core::Backend;

fn scene() -> Scene {
    let mut s = builtin("sphere").expect("built-in");
    (s.camera.width, s.camera.height) = (96, 54);
    s
}

/// `output` after `frames` frames of `technique` with `side`^2 photons, accumulating.
fn estimate(
    b: &mut dyn Backend,
    technique: &str,
    side: u32,
    frames: u32,
    output: Output,
    extra: serde_json::Value,
) -> Image {
    let mut settings = serde_json::json!({
        "photons_w": side, "photons_h": side, "accumulate": frames > 1,
    });
    if let (Some(s), Some(e)) = (settings.as_object_mut(), extra.as_object()) {
        s.extend(e.clone());
    }
    let mut t = create(technique, b, &scene(), &settings).expect("create");
    let mut last = None;
    for _ in 0..frames {
        last = Some(t.frame(b, &mut |_| {}).expect("frame"));
    }
    let stats = last.expect("a frame");
    assert_eq!(
        stats.accumulated_frames,
        if frames > 1 { frames } else { 0 },
        "{technique}: the frames the estimate holds"
    );
    let img = t.read_output(b, output).expect("read");
    t.free(b).expect("free");
    img
}

fn rel_l2(x: &Image, r: &Image) -> f64 {
    compare(x, r).relative_mse.sqrt()
}

/// N frames of M photons against one frame of N x M photons, and the raw error's slope.
fn check(technique: &str, output: Output, extra: serde_json::Value, slope: bool) {
    check_from(64, technique, output, extra, (slope, false))
}

/// [`check`] from `base`^2 photons a frame; `stratified`: the accumulation must also not
/// fall behind one frame of all its photons beyond the noise.
fn check_from(
    base: u32,
    technique: &str,
    output: Output,
    extra: serde_json::Value,
    (slope, stratified): (bool, bool),
) {
    let (_, mut b) = caustica_conformance::backends()
        .into_iter()
        .next()
        .expect("the cpu backend");
    let b = b.as_mut();
    // 16 times the photons of the largest test, with photons of their own (another seed)
    let mut own = extra.clone();
    if let Some(o) = own.as_object_mut() {
        o.insert("seed".into(), serde_json::json!(0x7e57_5eed_u32));
    }
    let reference = estimate(b, technique, 8 * base, 64, output, own);
    let reference_noise = |e_largest: f64| e_largest / 4.0;
    let mut errors = Vec::new();
    for n in [1u32, 4, 16, 64] {
        let side = base * (n as f64).sqrt() as u32;
        let accumulated = rel_l2(
            &estimate(b, technique, base, n, output, extra.clone()),
            &reference,
        );
        let single = rel_l2(
            &estimate(b, technique, side, 1, output, extra.clone()),
            &reference,
        );
        eprintln!("{technique} {output}: {n} frames of {base}^2: {accumulated:.5}; one frame of {side}^2: {single:.5}");
        // one frame of all the photons is stratified over a finer grid: it can be better,
        // never worse beyond the noise
        assert!(
            accumulated >= 0.8 * single,
            "{technique} {output}: {n} frames of {base}^2 photons have error {accumulated}, \
             below one frame of {side}^2 ({single})"
        );
        if stratified {
            // the frames' photons stratify each grid cell together (the R2 strata): the
            // accumulation is one frame of all its photons within the noise
            assert!(
                accumulated <= 1.25 * single,
                "{technique} {output}: {n} frames of {base}^2 photons have error {accumulated}, \
                 above one frame of {side}^2 ({single}) beyond the noise"
            );
        }
        errors.push(accumulated);
    }
    if slope {
        let r = reference_noise(errors[3]);
        let true_error = |e: f64| (e * e - r * r).max(0.0).sqrt();
        let s = (true_error(errors[3]) / true_error(errors[0])).ln() / 64f64.ln();
        assert!(
            (s + 0.5).abs() <= 0.1,
            "{technique} {output}: error against frames has slope {s}, not -1/2 ({errors:?})"
        );
    }
}

#[test]
fn sspm_accumulates_frames_as_one_frame_of_all_their_photons() {
    let all = serde_json::json!({ "outputs": { "raw_caustics": true, "filtered_caustics": true } });
    check_from(64, "sspm", Output::RawCaustics, all.clone(), (true, true));
    check("sspm", Output::FilteredCaustics, all, false);
}

#[test]
fn caustic_map_accumulates_frames_as_one_frame_of_all_their_photons() {
    let all = serde_json::json!({
        "atlas_size": 256,
        "outputs": { "raw_caustics": true, "filtered_caustics": true }
    });
    check("caustic-map", Output::FilteredCaustics, all, false);
}

/// PhotonGi's indirect light with the raw deposit (an unbiased per-pixel estimate, as
/// the caustic techniques' raw maps): N frames are one frame of all their photons and the
/// error falls as 1/sqrt(frames). (With the splats each frame keeps the splat size its
/// own photon density sets, so the accumulation converges to that blur: not one frame of
/// all the photons, whose splats are smaller.)
#[test]
fn photon_gi_accumulates_frames_as_one_frame_of_all_their_photons() {
    let deposit = serde_json::json!({ "estimator": "deposit", "rsm_size": 64 });
    check_from(32, "photon-gi", Output::RawIndirect, deposit, (true, false));
}

#[test]
fn a_moved_camera_starts_the_screen_accumulation_again() {
    let (_, mut b) = caustica_conformance::backends()
        .into_iter()
        .next()
        .expect("the cpu backend");
    let b = b.as_mut();
    let s = scene();
    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64, "accumulate": true });
    let mut t = create("sspm", b, &s, &settings).expect("create");
    for k in 1..=3 {
        let st = t.frame(b, &mut |_| {}).expect("frame");
        assert_eq!(st.accumulated_frames, k);
    }
    let mut camera = s.camera.clone();
    camera.position += glam::Vec3::new(0.1, 0.0, 0.0);
    t.set_camera(b, &camera).expect("camera");
    let st = t.frame(b, &mut |_| {}).expect("frame");
    assert_eq!(st.accumulated_frames, 1, "the moved camera's first frame");
    // the first frame of an accumulation is a frame without it, bitwise
    let moved = t.read_output(b, Output::Composite).expect("read");
    t.free(b).expect("free");
    let mut fresh_scene = s.clone();
    fresh_scene.camera = camera;
    let plain = serde_json::json!({ "photons_w": 64, "photons_h": 64 });
    let mut f = create("sspm", b, &fresh_scene, &plain).expect("create");
    f.frame(b, &mut |_| {}).expect("frame");
    let want = f.read_output(b, Output::Composite).expect("read");
    f.free(b).expect("free");
    assert!(
        moved.pixels == want.pixels,
        "a restarted accumulation's first frame differs"
    );
}

/// No ghosting: a moved light restarts every technique's accumulation, so the frames after
/// the move are a fresh accumulation's, bitwise (the error of frame k after a move is that
/// of k frames in the new state, with nothing of the old light in it).
#[test]
fn a_moved_light_restarts_every_accumulation_without_ghosting() {
    let (_, mut b) = caustica_conformance::backends()
        .into_iter()
        .next()
        .expect("the cpu backend");
    let b = b.as_mut();
    let s = scene();
    let mut moved = s.clone();
    for l in &mut moved.lights {
        if let caustica_core::scene::Light::Point { position, .. } = l {
            *position += glam::Vec3::new(0.3, 0.0, -0.2);
        }
    }
    let settings = serde_json::json!({ "photons_w": 64, "photons_h": 64, "accumulate": true });
    for technique in ["sspm", "caustic-map", "adaptive-caustics", "photon-gi"] {
        let mut t = create(technique, b, &s, &settings).expect("create");
        for _ in 0..4 {
            t.frame(b, &mut |_| {}).expect("frame");
        }
        t.set_lights(b, &moved.lights).expect("lights");
        let mut f = create(technique, b, &moved, &settings).expect("create");
        for k in 1..=2 {
            let got = t.frame(b, &mut |_| {}).expect("frame");
            let want = f.frame(b, &mut |_| {}).expect("frame");
            assert_eq!(
                got.accumulated_frames, k,
                "{technique}: frame {k} after the move"
            );
            assert_eq!(want.accumulated_frames, k, "{technique}: a fresh frame {k}");
            let (a, c) = (
                t.read_output(b, Output::Composite).expect("read"),
                f.read_output(b, Output::Composite).expect("read"),
            );
            assert!(
                a.pixels == c.pixels,
                "{technique}: frame {k} after the move holds more than the new light's photons"
            );
        }
        t.free(b).expect("free");
        f.free(b).expect("free");
    }
}
