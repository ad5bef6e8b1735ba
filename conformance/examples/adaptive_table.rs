//! Wyman 2009's Table 1 in its own setting: photons traced per level and in total by the
//! dense light view plane and by AdaptiveCaustics' two metrics on `spot-glass` (the plane
//! over the spot's whole cone), with each caustic map's error against a denser reference,
//! and the ratio against CausticMap's default caster-fitted plane on every built-in scene.
//!
//! `cargo run --release -p caustica-conformance --example adaptive_table -- [BACKEND]
//! [TOP] [REFERENCE]`: budgets 256^2 .. TOP^2 (default 2048), reference a dense grid of
//! REFERENCE^2 photons (default 2 x TOP) on the same backend (default cpu). Prints
//! Markdown. With `ERROR_TEXELS=1,2,4` (default 1) it adds a table of the error metric at
//! each tolerance (`error_texels`: footprint splats above 1).

use caustica_core::frame::image::Image;
use caustica_core::frame::output::Output;
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica_core::scene::Scene;
use caustica_core::techniques::adaptive_caustics::AdaptiveStats;
use caustica_core::techniques::adaptive_caustics::{
    AdaptiveCaustics, AdaptiveCausticsSettings, AdaptiveMetric,
};
use caustica_core::techniques::caustic_map::{CausticMap, CausticMapSettings, EmissionPlane};
use caustica_core::{Backend, FrameStats};
use caustica_core::{FrameSettings, PlaneSettings, TraceSettings, TraversalSettings};
use std::time::Instant;

fn map(n: u32, plane: EmissionPlane) -> CausticMapSettings {
    CausticMapSettings {
        frame: FrameSettings {
            photons_w: n,
            photons_h: n,
            ..CausticMapSettings::default().frame
        },
        planes: PlaneSettings {
            emission_plane: plane,
            ..CausticMapSettings::default().planes
        },
        trace: TraceSettings {
            max_photons_per_batch: 1 << 22,
            ..CausticMapSettings::default().trace
        },
        ..CausticMapSettings::default()
    }
}

/// Stats, the gathered atlas and the host time of one frame.
fn run<P: caustica_core::frame::pipeline::Pipeline>(
    b: &mut dyn Backend,
    mut t: caustica_core::frame::pipeline::Hosted<P>,
) -> (FrameStats, Image, f64) {
    let start = Instant::now();
    let s = t.frame(b, &mut |_| {}).expect("frame");
    let ms = start.elapsed().as_secs_f64() * 1e3;
    let atlas = t.read_output(b, Output::CausticAtlas).expect("atlas");
    t.free(b).expect("free");
    (s, atlas, ms)
}

fn adaptive(n: u32, plane: EmissionPlane, metric: AdaptiveMetric) -> AdaptiveCausticsSettings {
    AdaptiveCausticsSettings {
        traversal: TraversalSettings {
            metric,
            max_traversal_bytes: 256 << 20,
            ..AdaptiveCausticsSettings::default().traversal
        },
        ..caustica_conformance::adaptive_over(&map(n, plane))
    }
}

fn rel_mse(a: &Image, r: &Image) -> f64 {
    caustica_conformance::harness::measure::relative_l2(&r.pixels, &a.pixels, None).powi(2)
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let backend = args.get(1).cloned().unwrap_or("cpu".into());
    let top: u32 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(2048);
    let reference: u32 = args.get(3).and_then(|a| a.parse().ok()).unwrap_or(2 * top);
    let mut b = caustica_conformance::backends()
        .into_iter()
        .find(|(n, _)| *n == backend)
        .unwrap_or_else(|| panic!("backend {backend} unavailable"))
        .1;
    let b = b.as_mut();
    let mut scene: Scene = builtin("spot-glass").expect("built-in");
    (scene.camera.width, scene.camera.height) = (64, 36);
    let plane = EmissionPlane::LightCone;
    let t = CausticMap::new(b, &scene, map(reference, plane)).expect("reference");
    let (_, r, _) = run(b, t);
    println!(
        "## spot-glass, plane over the spot's cone ({backend}; reference: dense {reference}^2)\n"
    );
    println!("| equivalent grid | dense photons | level metric | error metric | level / dense | error / dense | map relMSE dense | level | error | ms dense | level | error |");
    println!(
        "| --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    let mut per_level = Vec::new();
    let mut n = 256;
    while n <= top {
        let t = CausticMap::new(b, &scene, map(n, plane)).expect("dense");
        let (ds, da, dms) = run(b, t);
        let mut row = Vec::new();
        for metric in [AdaptiveMetric::Level, AdaptiveMetric::Error] {
            let t = AdaptiveCaustics::new(b, &scene, adaptive(n, plane, metric)).expect("adaptive");
            let (s, a, ms) = run(b, t);
            let st = AdaptiveStats::of(&s).unwrap_or_default();
            per_level.push((n, metric, st.photons_per_level.clone()));
            row.push((st.photons_processed, rel_mse(&a, &r), ms));
        }
        println!(
            "| {n}^2 | {} | {} | {} | {:.3} | {:.3} | {:.3e} | {:.3e} | {:.3e} | {:.0} | {:.0} | {:.0} |",
            ds.photons_emitted,
            row[0].0,
            row[1].0,
            row[0].0 as f64 / ds.photons_emitted as f64,
            row[1].0 as f64 / ds.photons_emitted as f64,
            rel_mse(&da, &r),
            row[0].1,
            row[1].1,
            dms,
            row[0].2,
            row[1].2
        );
        n *= 2;
    }
    let tolerances: Vec<u32> = std::env::var("ERROR_TEXELS")
        .unwrap_or("1".into())
        .split(',')
        .filter_map(|t| t.parse().ok())
        .collect();
    if tolerances.len() > 1 {
        println!("\n### Error metric by tolerance (`error_texels`)\n");
        println!("| equivalent grid | error_texels | photons / dense | map relMSE | ms |");
        println!("| --- | ---: | ---: | ---: | ---: |");
        let mut n = 1024;
        while n <= top {
            let dense = (n as f64).powi(2);
            for &t in &tolerances {
                let settings = AdaptiveCausticsSettings {
                    traversal: TraversalSettings {
                        error_texels: t,
                        ..adaptive(n, plane, AdaptiveMetric::Error).traversal
                    },
                    ..adaptive(n, plane, AdaptiveMetric::Error)
                };
                let tech = AdaptiveCaustics::new(b, &scene, settings).expect("adaptive");
                let (s, a, ms) = run(b, tech);
                let p = AdaptiveStats::of(&s).map_or(0, |a| a.photons_processed) as f64;
                println!(
                    "| {n}^2 | {t} | {:.4} | {:.3e} | {ms:.0} |",
                    p / dense,
                    rel_mse(&a, &r)
                );
            }
            n *= 2;
        }
    }
    println!("\nPhotons traced per level (64^2 start grid first):\n");
    for (n, metric, levels) in per_level {
        println!("- {n}^2, {metric:?}: {levels:?}");
    }
    println!("\n## Every built-in scene, CausticMap's caster-fitted plane, {top}^2 ({backend})\n");
    println!("| scene | dense photons | level metric / dense | error metric / dense |");
    println!("| --- | ---: | ---: | ---: |");
    for name in BUILTIN_SCENES {
        let mut s = builtin(name).expect("built-in");
        (s.camera.width, s.camera.height) = (64, 36);
        let casters = EmissionPlane::Casters;
        let t = CausticMap::new(b, &s, map(top, casters)).expect("dense");
        let (ds, _, _) = run(b, t);
        if ds.photons_emitted == 0 {
            println!("| {name} | 0 | - | - |");
            continue;
        }
        let mut ratios = Vec::new();
        for metric in [AdaptiveMetric::Level, AdaptiveMetric::Error] {
            let t = AdaptiveCaustics::new(b, &s, adaptive(top, casters, metric)).expect("adaptive");
            let (st, _, _) = run(b, t);
            let p = AdaptiveStats::of(&st).map_or(0, |a| a.photons_processed);
            ratios.push(p as f64 / ds.photons_emitted as f64);
        }
        println!(
            "| {name} | {} | {:.3} | {:.3} |",
            ds.photons_emitted, ratios[0], ratios[1]
        );
    }
}
