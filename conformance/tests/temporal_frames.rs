//! The temporal blend (Smal 2019, section 24.4.1) as Sspm's and CausticMap's opt-in pass
//! (`frame.temporal`), on every backend (`backends()`: all four, required in CI).
//!
//! The blend's expectation is a single frame's (an exponential moving average of frames
//! of independent seeds), so the reference is the mean of many single frames at the same
//! camera on the same backend. Measured as the relative L2 error over the pixels where
//! the reference has light:
//!
//! - **A static camera converges.** After 48 frames the blend's error is below 0.3 of a
//!   single frame's. The arithmetic: the moving average with alpha 0.95 started on an empty
//!   history weighs frame 1 by 0.95^47 = 0.09 and frame `k` by 0.05 x 0.95^(48 - k), a
//!   variance of 0.033 of one frame's (an error ratio of 0.18 in L2), plus the reference's
//!   own noise (1/32 of a frame's variance), on both sides (measured: 0.19-0.2).
//! - **A moved camera does not ghost.** Right after a camera move the blend reprojects its
//!   history; where that history is wrong (disocclusions, the depth or normal test
//!   failing) its weight drops. Its error at the new view must stay below a single frame's
//!   there: a history blended in at the wrong place would exceed it.
//! - **CausticMap's blend is the moving average of independent frames.** On its atlas
//!   the blend weighs the history by 0.95 on every pixel it blends, exactly, frames of
//!   successive seeds are uncorrelated, and over 16 runs its error after 8 and 32 frames
//!   is the independent-frames prediction within the noise of an error carried by a few
//!   pixels (the tests' comments give the arithmetic).

use caustica_conformance::backends;
use caustica_core::frame::output::Output;
use caustica_core::scene::builtin::builtin;
use caustica_core::scene::Scene;
use caustica_core::techniques::create;
use caustica_core::Backend;

fn scene() -> Scene {
    let mut s = builtin("sphere").expect("built-in");
    (s.camera.width, s.camera.height) = (64, 36);
    s
}

fn settings(temporal: bool) -> serde_json::Value {
    serde_json::json!({ "photons_w": 96, "photons_h": 96, "temporal": temporal })
}

fn atrous_settings(iterations: u32, clip: f32) -> serde_json::Value {
    serde_json::json!({
        "photons_w": 96, "photons_h": 96, "atrous_iterations": iterations, "atrous_clip_sigmas": clip
    })
}

/// The filtered caustics of frames with seeds `seeds`, one technique, the camera of
/// `scene` (all frames returned, in order).
fn frames(
    b: &mut dyn Backend,
    scene: &Scene,
    temporal: bool,
    seeds: std::ops::Range<u32>,
) -> Vec<Vec<[f32; 4]>> {
    let mut t = create("sspm", b, scene, &settings(temporal)).expect("create");
    let out = seeds
        .map(|k| {
            t.set_seed(k);
            t.frame(b, &mut |_| {}).expect("frame");
            t.read_output(b, Output::FilteredCaustics)
                .expect("read")
                .pixels
        })
        .collect();
    t.free(b).expect("free");
    out
}

fn mean(images: &[Vec<[f32; 4]>]) -> Vec<[f32; 3]> {
    let n = images.len() as f32;
    (0..images[0].len())
        .map(|i| {
            let mut s = [0.0f32; 3];
            for img in images {
                for c in 0..3 {
                    s[c] += img[i][c];
                }
            }
            s.map(|x| x / n)
        })
        .collect()
}

/// Relative L2 error of `img` against `reference` over the reference's lit pixels.
fn rel_l2(img: &[[f32; 4]], reference: &[[f32; 3]]) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (p, r) in img.iter().zip(reference) {
        for c in 0..3 {
            num += ((p[c] - r[c]) as f64).powi(2);
            den += (r[c] as f64).powi(2);
        }
    }
    (num / den.max(f64::MIN_POSITIVE)).sqrt()
}

/// Mean single-frame error of `singles` against `reference`.
fn single_error(singles: &[Vec<[f32; 4]>], reference: &[[f32; 3]]) -> f64 {
    singles.iter().map(|s| rel_l2(s, reference)).sum::<f64>() / singles.len() as f64
}

#[test]
fn a_static_camera_converges_and_a_moved_one_does_not_ghost() {
    for (name, mut b) in backends() {
        let b = b.as_mut();
        let still = scene();
        let mut moved = still.clone();
        moved.camera.position += glam::Vec3::new(0.15, 0.05, 0.0);
        let singles = frames(b, &still, false, 1000..1032);
        let reference = mean(&singles);
        let single = single_error(&singles[..8], &reference);

        let mut t = create("sspm", b, &still, &settings(true)).expect("create");
        let mut last = Vec::new();
        for k in 0..48 {
            t.set_seed(k);
            t.frame(b, &mut |_| {}).expect("frame");
            last = t
                .read_output(b, Output::FilteredCaustics)
                .expect("read")
                .pixels;
        }
        let blended = rel_l2(&last, &reference);
        eprintln!("{name}: static, 48 frames: blend {blended:.4}, single {single:.4}");
        assert!(
            blended < 0.3 * single,
            "{name}: after 48 frames the blend's error {blended} is not below 0.3 x a single frame's {single}"
        );
        assert!(
            last.iter().flatten().all(|x| x.is_finite()),
            "{name}: not finite"
        );

        let singles_moved = frames(b, &moved, false, 2000..2032);
        let reference_moved = mean(&singles_moved);
        let single_moved = single_error(&singles_moved[..8], &reference_moved);
        t.set_camera(b, &moved.camera).expect("move");
        t.set_seed(99);
        t.frame(b, &mut |_| {}).expect("frame");
        let after = t
            .read_output(b, Output::FilteredCaustics)
            .expect("read")
            .pixels;
        t.free(b).expect("free");
        let err = rel_l2(&after, &reference_moved);
        eprintln!("{name}: first frame after the move: blend {err:.4}, single {single_moved:.4}");
        assert!(
            err < single_moved,
            "{name}: after the move the blend's error {err} exceeds a single frame's {single_moved}: ghosting"
        );
    }
}

/// The A-Trous iterations on single frames (no temporal blend): their error against the
/// same reference, and the flux they keep, printed per clip bound (a measurement for the
/// docs); every output finite, and the iterations with every detail kept (a huge clip
/// bound) give back the input within rounding (Eq. 17).
#[test]
fn atrous_iterations_on_single_frames() {
    for (name, mut b) in backends() {
        let b = b.as_mut();
        let still = scene();
        let singles = frames(b, &still, false, 1000..1032);
        let reference = mean(&singles);
        let flux = |img: &[[f32; 4]]| img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>();
        let base_err = single_error(&singles[..8], &reference);
        let base_flux: f64 = singles[..8].iter().map(|s| flux(s)).sum::<f64>();
        for clip in [0.0f32, 1.0, 1e30] {
            let mut t = create("sspm", b, &still, &atrous_settings(4, clip)).expect("create");
            let mut err = 0.0;
            let mut kept = 0.0;
            for (k, single) in singles[..8].iter().enumerate() {
                t.set_seed(1000 + k as u32);
                t.frame(b, &mut |_| {}).expect("frame");
                let img = t
                    .read_output(b, Output::FilteredCaustics)
                    .expect("read")
                    .pixels;
                assert!(
                    img.iter().flatten().all(|x| x.is_finite()),
                    "{name}: not finite"
                );
                if clip > 1e20 {
                    let close = img.iter().zip(single).all(|(p, q)| {
                        (0..3).all(|c| {
                            (p[c] - q[c]).abs() <= 1e-4 * q[c].abs().max(1e-3 * q[c].abs() + 1e-6)
                        })
                    });
                    let worst = img
                        .iter()
                        .zip(single)
                        .map(|(p, q)| (0..3).map(|c| (p[c] - q[c]).abs()).fold(0.0f32, f32::max))
                        .fold(0.0f32, f32::max);
                    assert!(close || worst <= 1e-4 * single.iter().flatten().fold(0.0f32, |m, x| m.max(*x)),
                        "{name}: with every detail kept the iterations must give back the input (worst {worst})");
                }
                err += rel_l2(&img, &reference) / 8.0;
                kept += flux(&img);
            }
            t.free(b).expect("free");
            eprintln!(
                "{name}: A-Trous 4 iterations, clip {clip:e}: error {err:.4} (unfiltered {base_err:.4}), flux {:.4} of the input's",
                kept / base_flux
            );
        }
    }
}

/// CausticMap's settings on `sphere` for the blend's tests, with `extra` over them.
fn caustic_map_settings(extra: serde_json::Value) -> serde_json::Value {
    let mut v = serde_json::json!({ "photons_w": 96, "photons_h": 96, "atlas_size": 128 });
    for (k, x) in extra.as_object().expect("object") {
        v[k] = x.clone();
    }
    v
}

/// The filtered caustics of CausticMap frames with seeds `seeds` (one technique,
/// `settings`), each checked finite; the plan names the temporal blend and the A-Trous
/// iterations.
fn caustic_map_frames(
    b: &mut dyn Backend,
    settings: &serde_json::Value,
    seeds: std::ops::Range<u32>,
) -> Vec<Vec<[f32; 4]>> {
    let mut t = create("caustic-map", b, &scene(), settings).expect("create");
    for name in ["temporal_blend", "atrous_filter"] {
        let p = t.plan().passes.iter().find(|p| p.name == name).cloned();
        assert!(p.is_some(), "the plan does not name {name}");
    }
    let out: Vec<Vec<[f32; 4]>> = seeds
        .map(|k| {
            t.set_seed(k);
            t.frame(b, &mut |_| {}).expect("frame");
            let img = t
                .read_output(b, Output::FilteredCaustics)
                .expect("read")
                .pixels;
            assert!(img.iter().flatten().all(|x| x.is_finite()), "not finite");
            img
        })
        .collect();
    t.free(b).expect("free");
    out
}

/// CausticMap's opt-in temporal blend and A-Trous iterations (the shared passes on the
/// caustics the camera sees through the map), with the seed changing every frame (each
/// frame a new atlas), on every backend:
///
/// - **The blend is the moving average of its frames.** On a static camera every pixel
///   it blends (a receiver the camera sees directly) weighs its reprojected history by
///   alpha = 0.95 (within 1e-3) from the second frame on: frame `n` is `0.05 x` the
///   frame of that seed alone `+ 0.95 x` frame `n - 1`, so no history is lost to the
///   depth and normal weights or the reprojection; the other pixels (the caustic seen
///   through the glass ball) keep their frame.
/// - **After 48 frames** the blend's error on the pixels it blends is below 0.5 of a
///   single frame's: the prediction is 0.25 (see
///   [`caustic_map_temporal_blend_converges_as_independent_frames`]) and one run's error
///   spreads by 0.3 of itself (the error's few degrees of freedom, measured there), so
///   0.5 is three of those deviations above it.
/// - The A-Trous iterations on single frames are measured (error and flux against single
///   frames, printed for the docs) and must stay finite; the plan names both passes.
#[test]
fn caustic_map_opts_into_the_temporal_blend_and_atrous() {
    let cm = caustic_map_settings;
    for (name, mut b) in backends() {
        let b = b.as_mut();
        let singles = caustic_map_frames(b, &cm(serde_json::json!({})), 1000..1032);
        let reference = mean(&singles);
        let single = single_error(&singles[..8], &reference);
        let blended = caustic_map_frames(b, &cm(serde_json::json!({ "temporal": true })), 0..48);
        // the blend's inputs: each seed's frame alone
        let plain = caustic_map_frames(b, &cm(serde_json::json!({})), 0..8);
        // the blend runs on receiver pixels (its edge texels are the camera's first hit);
        // the caustic seen through the glass ball lies on pixels whose first hit is glass,
        // which keep their single frame: those are the pixels whose blend equals the
        // unblended frame of the same seed bit for bit
        let same = |x: &[f32; 4], y: &[f32; 4]| x.map(f32::to_bits) == y.map(f32::to_bits);
        let blended_px: Vec<bool> = blended[7]
            .iter()
            .zip(&plain[7])
            .map(|(x, y)| !same(x, y))
            .collect();
        let alpha = caustica_core::math::irradiance_filter::FilterConstants::default().alpha_max;
        assert_eq!(alpha, 0.95);
        assert!(
            blended[0].iter().zip(&plain[0]).all(|(x, y)| same(x, y)),
            "{name}: the first frame has no history to blend"
        );
        let mut lowest_alpha = f32::INFINITY;
        for n in 1..8 {
            for (j, &m) in blended_px.iter().enumerate() {
                let (out, input, history) = (blended[n][j], plain[n][j], blended[n - 1][j]);
                let ema = |c: usize| (1.0 - alpha) * input[c] + alpha * history[c];
                // the history's weight is 0.95 within 1e-3: the depth weight compares the
                // reprojected depth with the stored one, equal but for a few ulps against
                // Eq. 10's guard of 1e-3 of the depth (w_z >= exp(-1e-3)); plus the
                // rounding of the blend's two products and sum
                for c in 0..3 {
                    let d = history[c] - input[c];
                    if m && d.abs() > 1e-2 * (history[c].abs() + input[c].abs()) {
                        lowest_alpha = lowest_alpha.min((out[c] - input[c]) / d);
                    }
                }
                let close = (0..3).all(|c| {
                    (out[c] - ema(c)).abs()
                        <= 1e-3 * (history[c] - input[c]).abs()
                            + 4.0 * f32::EPSILON * (input[c].abs() + history[c].abs())
                });
                assert!(
                    close || (!m && same(&out, &input)),
                    "{name}: frame {n}, pixel {j}: {out:?} is neither the moving average \
                     {:?} (input {input:?}, history {history:?}) nor its own frame",
                    [ema(0), ema(1), ema(2)]
                );
                assert!(
                    !m || close,
                    "{name}: frame {n}, pixel {j}: a blended pixel lost its history \
                     ({out:?} against the moving average {:?})",
                    [ema(0), ema(1), ema(2)]
                );
            }
        }
        eprintln!(
            "{name}: the blend's history weight on its pixels, frames 2-8: at least {lowest_alpha}"
        );
        let only = |img: &[[f32; 4]]| -> Vec<[f32; 4]> {
            img.iter()
                .zip(&blended_px)
                .map(|(p, &m)| if m { *p } else { [0.0; 4] })
                .collect()
        };
        let reference_blended: Vec<[f32; 3]> = reference
            .iter()
            .zip(&blended_px)
            .map(|(r, &m)| if m { *r } else { [0.0; 3] })
            .collect();
        let single_blended = singles[..8]
            .iter()
            .map(|s| rel_l2(&only(s), &reference_blended))
            .sum::<f64>()
            / 8.0;
        let blend = rel_l2(&only(&blended[47]), &reference_blended);
        let blend_all = rel_l2(&blended[47], &reference);

        let flux = |img: &[[f32; 4]]| img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>();
        let atrous = caustic_map_frames(
            b,
            &cm(serde_json::json!({ "atrous_iterations": 4 })),
            1000..1008,
        );
        // both in a chain (the blend writes the iterations' input): with every detail kept
        // (a huge clip bound) the same as the blend alone (Eq. 17), within rounding
        let chain = caustic_map_frames(
            b,
            &cm(serde_json::json!({
                "temporal": true, "atrous_iterations": 2, "atrous_clip_sigmas": 1e30
            })),
            0..4,
        );
        let same = chain[3]
            .iter()
            .zip(&blended[3])
            .all(|(p, q)| (0..3).all(|c| (p[c] - q[c]).abs() <= 1e-4 * q[c].abs() + 1e-6));
        assert!(
            same,
            "{name}: the chain with every detail kept differs from the blend alone"
        );
        let atrous_err = single_error(&atrous, &reference);
        let kept = atrous.iter().map(|i| flux(i)).sum::<f64>()
            / singles[..8].iter().map(|i| flux(i)).sum::<f64>();
        eprintln!(
            "{name}: caustic-map on sphere: single frame {single:.4}, temporal after 48 \
             frames {blend_all:.4} (on the {} blended pixels: single {single_blended:.4}, \
             blend {blend:.4}); A-Trous x4 single frames {atrous_err:.4}, flux kept {kept:.4}",
            blended_px.iter().filter(|m| **m).count()
        );
        assert!(
            blend < 0.5 * single_blended,
            "{name}: after 48 frames the blend's error {blend} is not below 0.5 x a single \
             frame's {single_blended} on the blended pixels"
        );
        assert!(blend_all < single, "{name}: the blend made the image worse");
    }
}

/// CausticMap's temporal blend converges as the arithmetic of independent frames says.
///
/// The moving average with alpha = 0.95 started on an empty history weighs frame 1 by
/// `0.95^(n - 1)` and frame `k > 1` by `0.05 x 0.95^(n - k)` after `n` frames: a variance
/// of `f(n)` = 0.501 of a single frame's after 8 frames and 0.235 after 16. The
/// reference is the mean of `K` = 64 single frames of other seeds, so the blend's mean
/// squared error against it is `f(n) + 1/K` of a single frame's variance and a single
/// frame's (one of those `K`) is `1 - 1/K` of it: the error ratio is predicted as
/// `sqrt((f(n) + 1/K) / (1 - 1/K))`, 0.72 after 8 frames and 0.50 after 16.
///
/// Noise. The error is carried by the caustic's core: the squared error of a single
/// frame on the blended pixels spreads by 0.57-0.67 of its mean over 64 seeds, the
/// spread of `d` = 4.5-6 independent terms (`sqrt(2 / d)`; printed by the test,
/// docs/caustic-map.md). One run's error ratio therefore scatters by about 0.3 of itself,
/// which is why a single run read 0.34 after 48 frames against the 0.25 predicted, and
/// 0.93 after 8 against 0.71: one draw, the same on every backend because every backend
/// draws the same photons. Here the blend's squared error is the mean over `R` = 32 runs
/// of independent seeds (relative spread `sqrt(2 / (d R))` <= 0.12) and the single
/// frame's over the `K` frames (<= 0.08): the error ratio spreads by at most 0.072 of
/// itself, and it must lie within 0.22 of the prediction in the logarithm (three such
/// deviations; a blend 1.3 times slower than the prediction, as that one draw read, lies
/// 3.7 deviations out). Frames of successive seeds are independent: their deviations
/// from the reference correlate by 0 within 0.15 (a pair's correlation spreads by
/// `1/sqrt(d)`, the mean of 63 pairs by 0.05).
///
/// Measured on the CPU backend only: every backend renders the same frames (the
/// moving-average identity above holds on each), so another backend adds no
/// independent sample.
#[test]
fn caustic_map_temporal_blend_converges_as_independent_frames() {
    const K: usize = 64;
    const R: u32 = 32;
    const N: usize = 16;
    let (_, mut b) = backends().into_iter().next().expect("the cpu backend");
    let b = b.as_mut();
    let cm = caustic_map_settings;
    let singles = caustic_map_frames(b, &cm(serde_json::json!({})), 100_000..100_000 + K as u32);
    let reference = mean(&singles);
    let runs: Vec<Vec<Vec<[f32; 4]>>> = (1..=R)
        .map(|r| {
            caustic_map_frames(
                b,
                &cm(serde_json::json!({ "temporal": true })),
                r * 1000..r * 1000 + N as u32,
            )
        })
        .collect();
    // the pixels the blend runs on (see the test above): run 1's frame 7 (seed 1007)
    // against that seed's frame alone
    let blended_px: Vec<bool> = runs[0][7]
        .iter()
        .zip(&caustic_map_frames(b, &cm(serde_json::json!({})), 1007..1008)[0])
        .map(|(x, y)| x.map(f32::to_bits) != y.map(f32::to_bits))
        .collect();
    let masked = |img: &[[f32; 4]]| -> Vec<f64> {
        img.iter()
            .zip(&reference)
            .zip(&blended_px)
            .filter(|(_, &m)| m)
            .flat_map(|((p, r), _)| (0..3).map(move |c| (p[c] - r[c]) as f64))
            .collect()
    };
    let energy: f64 = reference
        .iter()
        .zip(&blended_px)
        .filter(|(_, &m)| m)
        .map(|(r, _)| r.iter().map(|x| (*x as f64).powi(2)).sum::<f64>())
        .sum();
    let sq = |img: &[[f32; 4]]| masked(img).iter().map(|d| d * d).sum::<f64>() / energy;
    let single: Vec<f64> = singles.iter().map(|s| sq(s)).collect();
    let single_ms = single.iter().sum::<f64>() / K as f64;
    let spread = (single.iter().map(|x| (x - single_ms).powi(2)).sum::<f64>() / (K - 1) as f64)
        .sqrt()
        / single_ms;
    let dof = 2.0 / (spread * spread);
    eprintln!(
        "caustic-map blend: {} blended pixels; a single frame's squared error spreads by \
         {spread:.2} of its mean over {K} seeds: {dof:.1} degrees of freedom",
        blended_px.iter().filter(|m| **m).count()
    );
    // successive seeds' frames are independent
    let correlation = (0..K - 1)
        .map(|k| {
            let (x, y) = (masked(&singles[k]), masked(&singles[k + 1]));
            let xy: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
            let xx: f64 = x.iter().map(|a| a * a).sum();
            let yy: f64 = y.iter().map(|a| a * a).sum();
            xy / (xx * yy).sqrt()
        })
        .sum::<f64>()
        / (K - 1) as f64;
    eprintln!("caustic-map blend: successive seeds' deviations correlate by {correlation:.3}");
    assert!(
        correlation.abs() <= 0.15,
        "frames of successive seeds correlate by {correlation}: not independent"
    );
    let alpha = 0.95f64;
    for n in [8usize, N] {
        let f = alpha.powi(2 * (n as i32 - 1))
            + (2..=n)
                .map(|k| ((1.0 - alpha) * alpha.powi((n - k) as i32)).powi(2))
                .sum::<f64>();
        let k = K as f64;
        let predicted = ((f + 1.0 / k) / (1.0 - 1.0 / k)).sqrt();
        let blend_ms = runs.iter().map(|run| sq(&run[n - 1])).sum::<f64>() / R as f64;
        let ratio = (blend_ms / single_ms).sqrt();
        eprintln!(
            "caustic-map blend after {n} frames: error {ratio:.3} of a single frame's (root \
             mean square over {R} runs), independent frames predict {predicted:.3}"
        );
        assert!(
            (ratio / predicted).ln().abs() <= 0.22,
            "after {n} frames the blend's error is {ratio} of a single frame's, the \
             independent-frames prediction {predicted} ({dof:.1} degrees of freedom a frame)"
        );
    }
}
