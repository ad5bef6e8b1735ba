//! PhotonGi's frames (seed 003) on every backend (`backends()`: all four, required in CI),
//! measured against the quantity they estimate: the raw screen deposit of the same
//! photons (`estimator: deposit`, every stored photon in the one pixel it lands in),
//! averaged over frames of independent seeds.
//!
//! Error measure: relative L2 over the pixels (`rel_l2`), and total radiance (the sum
//! over pixels) against the reference's.

use caustica_conformance::backends;
use caustica_core::scene::builtin::builtin;
use caustica_core::scene::Scene;
use caustica_core::techniques::create;
use caustica_core::Backend;

fn scene(name: &str) -> Scene {
    let mut s = builtin(name).expect("built-in");
    (s.camera.width, s.camera.height) = (96, 54);
    s
}

fn settings(estimator: &str, temporal: bool, atrous: u32) -> serde_json::Value {
    serde_json::json!({
        "photons_w": 128, "photons_h": 128, "rsm_size": 64, "estimator": estimator,
        "temporal": temporal, "atrous_iterations": atrous
    })
}

/// Output `output` of frames with seeds `seeds`.
fn frames(
    b: &mut dyn Backend,
    scene: &Scene,
    settings: &serde_json::Value,
    output: &str,
    seeds: std::ops::Range<u32>,
) -> Vec<Vec<[f32; 4]>> {
    let mut t = create("photon-gi", b, scene, settings).expect("create");
    let out = seeds
        .map(|k| {
            t.set_seed(k);
            t.frame(b, &mut |_| {}).expect("frame");
            let img = t.read_output(b, output).expect("read").pixels;
            assert!(img.iter().flatten().all(|x| x.is_finite()), "not finite");
            img
        })
        .collect();
    t.free(b).expect("free");
    out
}

fn mean(images: &[Vec<[f32; 4]>]) -> Vec<[f32; 4]> {
    let n = images.len() as f32;
    (0..images[0].len())
        .map(|i| {
            let mut s = [0.0f32; 4];
            for img in images {
                for c in 0..3 {
                    s[c] += img[i][c];
                }
            }
            s.map(|x| x / n)
        })
        .collect()
}

fn rel_l2(img: &[[f32; 4]], reference: &[[f32; 4]]) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (p, r) in img.iter().zip(reference) {
        for c in 0..3 {
            num += ((p[c] - r[c]) as f64).powi(2);
            den += (r[c] as f64).powi(2);
        }
    }
    (num / den.max(f64::MIN_POSITIVE)).sqrt()
}

fn total(img: &[[f32; 4]]) -> f64 {
    img.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum()
}

/// On `cornell` (walls lit only by bounces) and `plain` (diffuse objects): the splats
/// estimate the deposit, beat it frame for frame, and the temporal blend with the A-Trous
/// iterations converges towards it as frames accumulate (a static camera).
///
/// - **Energy.** The splat keeps a photon's power on the surface it lands on (the CPU
///   kernel's unit test, within 2-4% by pixel sampling), and loses what spills off that
///   surface (silhouettes, image borders, the clip at `max_splat_px`): the total must lie
///   within 0.8..1.03 of the deposit's (measured: 0.97 on `cornell`, 0.85 on `plain` at
///   96x54, whose small objects shed their kernels' rims).
/// - **Beats the unfiltered deposit.** One frame's splats have a lower error than one
///   frame's deposit (measured 0.22 against 0.43 on `cornell`).
/// - **Converges.** After 32 frames of the temporal blend (and 4 A-Trous iterations) the
///   error on `cornell` is below 0.7 of a single splat frame's (measured 0.14 against
///   0.22); its floor is the kernel's smoothing bias plus the reference's own noise (24
///   deposit frames: 0.43 / sqrt(24) = 0.09). On `plain` the splats' bias at this size is
///   the floor (0.43 against 0.48): the blend must still beat a single frame.
#[test]
fn splats_estimate_the_deposit_and_filters_converge() {
    for (name, mut b) in backends() {
        let b = b.as_mut();
        for scene_name in ["cornell", "plain"] {
            let s = scene(scene_name);
            let deposits = frames(
                b,
                &s,
                &settings("deposit", false, 0),
                "indirect_raw",
                100..124,
            );
            let reference = mean(&deposits);
            let splats = frames(
                b,
                &s,
                &settings("splat", false, 0),
                "indirect_raw",
                100..104,
            );
            let single_deposit = deposits[..4]
                .iter()
                .map(|d| rel_l2(d, &reference))
                .sum::<f64>()
                / 4.0;
            let single_splat = splats.iter().map(|d| rel_l2(d, &reference)).sum::<f64>() / 4.0;
            let temporal = frames(b, &s, &settings("splat", true, 4), "indirect", 200..232);
            let blended = rel_l2(temporal.last().expect("frames"), &reference);
            let ratio = total(&mean(&splats)) / total(&reference);
            eprintln!(
                "{name} / {scene_name}: totals splat/deposit {ratio:.4}; single-frame rel L2: deposit {single_deposit:.3}, splat {single_splat:.3}; temporal + A-Trous after 32 frames {blended:.3}"
            );
            assert!(
                (0.8..1.03).contains(&ratio),
                "{name} / {scene_name}: splats carry {ratio} of the deposit's light"
            );
            assert!(
                single_splat < single_deposit,
                "{name} / {scene_name}: a splat frame ({single_splat}) is not better than a deposit frame ({single_deposit})"
            );
            // `plain`'s floor is the splats' bias at 96x54 (its small objects lose 14% of
            // their light off their rims): the blend must still beat a single frame
            let bound = if scene_name == "cornell" { 0.7 } else { 1.0 };
            assert!(
                blended < bound * single_splat,
                "{name} / {scene_name}: after 32 frames the blend's error {blended} is not below {bound} x a single splat frame's {single_splat}"
            );
        }
    }
}
