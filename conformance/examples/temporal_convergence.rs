//! Measures how a technique's temporal blend converges on `sphere` (64x36, 96^2 photons,
//! the seed changing every frame) against the prediction for independent frames, on the
//! CPU: `cargo run --release -p caustica-conformance --example temporal_convergence --
//! [TECHNIQUE] [RUNS]` (default `caustic-map`, 16 runs of 48 frames).
//!
//! It prints what the error of one run can be trusted to: over 64 single frames of other
//! seeds (their mean is the reference), the spread of a frame's squared error and the
//! degrees of freedom it implies (`2 / spread^2`), the variance's participation ratio
//! (how many channel-pixels carry it) and the correlation of successive seeds'
//! deviations; then, after `n` frames, each run's error ratio and their root mean square
//! against `sqrt((f(n) + 1/K) / (1 - 1/K))` (`f(n)`: the moving average's variance for
//! alpha 0.95 from an empty history, `K` = 64 reference frames).

use caustica_core::frame::output::Output;
use caustica_core::scene::builtin::builtin;
use caustica_core::techniques::create;
use caustica_core::Backend;

const K: usize = 64;
const NS: [usize; 7] = [1, 2, 4, 8, 16, 32, 48];

fn frames(
    b: &mut dyn Backend,
    technique: &str,
    temporal: bool,
    seeds: std::ops::Range<u32>,
) -> Vec<Vec<f64>> {
    let mut scene = builtin("sphere").expect("built-in");
    (scene.camera.width, scene.camera.height) = (64, 36);
    let mut settings =
        serde_json::json!({ "photons_w": 96, "photons_h": 96, "temporal": temporal });
    if technique == "caustic-map" || technique == "adaptive-caustics" {
        settings["atlas_size"] = 128.into();
    }
    let mut t = create(technique, b, &scene, &settings).expect("create");
    let out = seeds
        .map(|k| {
            t.set_seed(k);
            t.frame(b, &mut |_| {}).expect("frame");
            t.read_output(b, Output::FilteredCaustics)
                .expect("read")
                .pixels
                .iter()
                .flat_map(|p| [p[0] as f64, p[1] as f64, p[2] as f64])
                .collect()
        })
        .collect();
    t.free(b).expect("free");
    out
}

fn main() {
    let mut args = std::env::args().skip(1);
    let technique = args.next().unwrap_or_else(|| "caustic-map".into());
    let runs: u32 = args.next().and_then(|a| a.parse().ok()).unwrap_or(16);
    let mut cpu = caustica_cpu::CpuBackend::new().expect("cpu backend");
    let b: &mut dyn Backend = &mut cpu;

    let singles = frames(b, &technique, false, 100_000..100_000 + K as u32);
    let len = singles[0].len();
    let reference: Vec<f64> = (0..len)
        .map(|i| singles.iter().map(|s| s[i]).sum::<f64>() / K as f64)
        .collect();
    // the channel-pixels the blend runs on: run 1's frame 8 differs from its seed's frame
    let first = frames(b, &technique, true, 1000..1000 + NS[6] as u32);
    let own = frames(b, &technique, false, 1007..1008).remove(0);
    let blended: Vec<bool> = first[7]
        .iter()
        .zip(&own)
        .map(|(x, y)| x.to_bits() != y.to_bits())
        .collect();
    let energy: f64 = reference
        .iter()
        .zip(&blended)
        .filter(|(_, m)| **m)
        .map(|(r, _)| r * r)
        .sum();
    let deviation = |img: &[f64]| -> Vec<f64> {
        img.iter()
            .zip(&reference)
            .zip(&blended)
            .filter(|(_, m)| **m)
            .map(|((x, r), _)| x - r)
            .collect()
    };
    let sq = |img: &[f64]| deviation(img).iter().map(|d| d * d).sum::<f64>() / energy;

    let single: Vec<f64> = singles.iter().map(|s| sq(s)).collect();
    let single_ms = single.iter().sum::<f64>() / K as f64;
    let spread = (single.iter().map(|x| (x - single_ms).powi(2)).sum::<f64>() / (K - 1) as f64)
        .sqrt()
        / single_ms;
    let variance: Vec<f64> = (0..len)
        .filter(|i| blended[*i])
        .map(|i| {
            singles
                .iter()
                .map(|s| (s[i] - reference[i]).powi(2))
                .sum::<f64>()
                / (K - 1) as f64
        })
        .collect();
    let (v1, v2) = (
        variance.iter().sum::<f64>(),
        variance.iter().map(|v| v * v).sum::<f64>(),
    );
    let mut sorted = variance.clone();
    sorted.sort_by(|a, b| b.total_cmp(a));
    let top10 = sorted.iter().take(10).sum::<f64>() / v1;
    let correlation = (0..K - 1)
        .map(|k| {
            let (x, y) = (deviation(&singles[k]), deviation(&singles[k + 1]));
            let xy: f64 = x.iter().zip(&y).map(|(a, b)| a * b).sum();
            let xx: f64 = x.iter().map(|a| a * a).sum();
            let yy: f64 = y.iter().map(|a| a * a).sum();
            xy / (xx * yy).sqrt()
        })
        .sum::<f64>()
        / (K - 1) as f64;
    println!(
        "{technique} on sphere 64x36, 96^2 photons: {} blended pixels; single frame rel L2 \
         {:.4}",
        blended.iter().filter(|m| **m).count() / 3,
        single_ms.sqrt()
    );
    println!(
        "a frame's squared error spreads by {spread:.2} of its mean over {K} seeds: {:.1} \
         degrees of freedom; the variance sits on {:.1} channel-pixels (participation \
         ratio), the 10 largest carry {top10:.2}; successive seeds' deviations correlate \
         by {correlation:.3}",
        2.0 / (spread * spread),
        v1 * v1 / v2
    );

    let mut mean_sq = [0.0f64; NS.len()];
    for r in 1..=runs {
        let run = if r == 1 {
            first.clone()
        } else {
            frames(b, &technique, true, r * 1000..r * 1000 + NS[6] as u32)
        };
        let mut line = format!("run {r:2}:");
        for (i, n) in NS.iter().enumerate() {
            let e = sq(&run[n - 1]);
            mean_sq[i] += e / runs as f64;
            line += &format!(" {:.3}", (e / single_ms).sqrt());
        }
        println!("{line}");
    }
    let alpha = 0.95f64;
    println!("frames | blend / single (root mean square over {runs} runs) | independent frames");
    for (i, &n) in NS.iter().enumerate() {
        let f = alpha.powi(2 * (n as i32 - 1))
            + (2..=n)
                .map(|k| ((1.0 - alpha) * alpha.powi((n - k) as i32)).powi(2))
                .sum::<f64>();
        let k = K as f64;
        println!(
            "{n:6} | {:.3} | {:.3}",
            (mean_sq[i] / single_ms).sqrt(),
            ((f + 1.0 / k) / (1.0 - 1.0 / k)).sqrt()
        );
    }
}
