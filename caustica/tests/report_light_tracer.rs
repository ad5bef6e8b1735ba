//! `caustica report` measures the caustic techniques against the independent light
//! tracer (`caustica::reference::light_tracer`) beside their own converged estimate, and
//! PhotonGi against its own deposit only.
//!
//! `sphere` at 64x36 with 64^2 photons per frame on the CPU backend: every caustic
//! technique's record carries finite, non-negative errors against the tracer, and the
//! tracer's noise (2^17 photons in 4 batches) is below the errors' scale, its square (what
//! it adds to a relative MSE) under each relative MSE. A few seconds in release.

use caustica::reference::light_tracer::{LightTracerSpec, SilhouetteDefinition};
use caustica::reference::ReferenceSpec;
use caustica::report::{run, table, ReportPlan};
use caustica::scene::builtin::builtin;

#[test]
fn the_report_measures_caustic_techniques_against_the_light_tracer() {
    let plan = ReportPlan {
        scenes: vec![builtin("sphere").expect("built-in")],
        techniques: vec![
            "sspm".into(),
            "caustic-map".into(),
            "adaptive-caustics".into(),
            "photon-gi".into(),
        ],
        backends: vec!["cpu".into()],
        budgets: vec![(64, 64)],
        frames: vec![1],
        filters: vec!["density".into()],
        settings: serde_json::Map::new(),
        repeats: 2,
        reference: ReferenceSpec {
            width: 64,
            height: 36,
            photons_side: 128,
            target_noise: 0.0,
            max_frames: 4,
            ..ReferenceSpec::default()
        },
        tracer: LightTracerSpec {
            photons: 1 << 17,
            batches: 4,
            ..LightTracerSpec::default()
        },
    };
    let cache = std::env::temp_dir().join(format!("caustica-report-tracer-{}", std::process::id()));
    let records = run(&plan, &cache, &mut |line| eprintln!("{line}")).expect("the report runs");
    assert_eq!(records.len(), 4);
    for r in &records {
        let finite = |v: f64| v.is_finite() && v >= 0.0;
        assert!(
            finite(r.relative_mse) && finite(r.raw_relative_mse),
            "{r:?}"
        );
        if r.technique == "photon-gi" {
            assert!(
                r.tracer.is_none(),
                "the tracer does not cover indirect light"
            );
            continue;
        }
        let t = r
            .tracer
            .as_ref()
            .expect("a caustic technique has tracer errors");
        assert!(
            finite(t.relative_mse) && finite(t.raw_relative_mse),
            "{r:?}"
        );
        assert!(t.noise.is_finite() && t.noise > 0.0, "{r:?}");
        assert_eq!(t.silhouette, SilhouetteDefinition::CentreSurface);
        assert_eq!((t.batches, t.photons), (4, 4 << 17));
        // the reference's own noise is below the errors it measures
        let noise2 = t.noise * t.noise;
        assert!(
            noise2 < t.relative_mse && noise2 < t.raw_relative_mse,
            "{}: tracer noise^2 {noise2:.2e} against relMSE {:.2e} (raw {:.2e})",
            r.technique,
            t.relative_mse,
            t.raw_relative_mse
        );
        eprintln!(
            "{}: relMSE vs tracer {:.4} (raw {:.4}), vs own {:.4} (raw {:.4}), tracer noise {:.4}",
            r.technique,
            t.relative_mse,
            t.raw_relative_mse,
            r.relative_mse,
            r.raw_relative_mse,
            t.noise
        );
    }
    // the table names the silhouette definition and leaves PhotonGi's tracer cells empty
    let text = table(&records);
    assert!(text.contains("silhouette pixels centre-surface"), "{text}");
    assert!(text.contains("relMSE vs tracer") && text.contains("relMSE vs own"));
    let gi = text
        .lines()
        .find(|l| l.contains("| photon-gi "))
        .expect("a photon-gi row");
    assert_eq!(gi.split('|').nth(7).map(str::trim), Some("-"), "{gi}");
    let _ = std::fs::remove_dir_all(&cache);
}

#[test]
fn silhouette_definitions_parse_from_their_names() {
    for d in SilhouetteDefinition::ALL {
        assert_eq!(d.name().parse::<SilhouetteDefinition>(), Ok(d));
    }
    assert_eq!(
        SilhouetteDefinition::default(),
        SilhouetteDefinition::CentreSurface
    );
    let e = "edge".parse::<SilhouetteDefinition>().unwrap_err();
    assert!(
        e.to_string().contains("centre-surface or eye-visible"),
        "{e}"
    );
}
