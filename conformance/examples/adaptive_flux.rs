//! Prints AdaptiveCaustics' stored flux against CausticMap's (the dense grid) on every
//! built-in scene, both metrics, on the CPU: `cargo run --release -p caustica-conformance
//! --example adaptive_flux -- [PHOTONS]`.

use caustica_core::frame::technique::Technique;
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica_core::techniques::adaptive_caustics::AdaptiveStats;
use caustica_core::techniques::adaptive_caustics::{
    AdaptiveCaustics, AdaptiveCausticsSettings, AdaptiveMetric,
};
use caustica_core::techniques::caustic_map::{CausticMap, CausticMapSettings};
use caustica_core::{AtlasSettings, FrameSettings, TraversalSettings};

fn main() {
    let n: u32 = std::env::args()
        .nth(1)
        .and_then(|a| a.parse().ok())
        .unwrap_or(256);
    let mut b = caustica_cpu::CpuBackend::new().expect("cpu backend");
    let map = CausticMapSettings {
        frame: FrameSettings {
            photons_w: n,
            photons_h: n,
            ..CausticMapSettings::default().frame
        },
        atlas: AtlasSettings {
            atlas_size: 256,
            ..CausticMapSettings::default().atlas
        },
        ..CausticMapSettings::default()
    };
    println!("scene | dense stored W | level / dense | error / dense | photons level | photons error | dense");
    for name in BUILTIN_SCENES {
        let mut scene = builtin(name).unwrap();
        (scene.camera.width, scene.camera.height) = (64, 36);
        let mut d = CausticMap::new(&mut b, &scene, map.clone()).unwrap();
        let ds = d.frame(&mut b, &mut |_| {}).unwrap();
        Box::new(d).free(&mut b).unwrap();
        let mut row = vec![format!(
            "{name} | {:.5}",
            ds.stored_flux.iter().sum::<f64>()
        )];
        let mut counts = Vec::new();
        for metric in [AdaptiveMetric::Level, AdaptiveMetric::Error] {
            let mut a = AdaptiveCaustics::new(
                &mut b,
                &scene,
                AdaptiveCausticsSettings {
                    traversal: TraversalSettings {
                        metric,
                        ..AdaptiveCausticsSettings::default().traversal
                    },
                    ..caustica_conformance::adaptive_over(&map)
                },
            )
            .unwrap();
            let s = a.frame(&mut b, &mut |_| {}).unwrap();
            Box::new(a).free(&mut b).unwrap();
            let total: f64 = ds.stored_flux.iter().sum();
            let ad: f64 = s.stored_flux.iter().sum();
            row.push(format!("{:.5}", if total > 0.0 { ad / total } else { 0.0 }));
            let st = AdaptiveStats::of(&s).unwrap_or_default();
            counts.push(format!(
                "{} ({} out)",
                st.photons_processed, s.photons_stored
            ));
        }
        println!(
            "{} | {} | {} ({} stored)",
            row.join(" | "),
            counts.join(" | "),
            ds.photons_emitted,
            ds.photons_stored
        );
    }
}
