//! The binary finds techniques through the registry: `caustica techniques` lists them,
//! `render` and `report` take any of them by name and refuse unknown ones, and a small
//! `report` on the CPU writes a record with a finite error for the technique it ran.

use std::process::{Command, Output};

fn caustica(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustica"))
        .args(args)
        .output()
        .expect("the caustica binary runs")
}

#[test]
fn techniques_are_listed_and_unknown_ones_refused() {
    let out = caustica(&["techniques"]);
    assert!(out.status.success());
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(text.lines().any(|l| l.starts_with("sspm")), "{text}");
    for cmd in [
        vec!["render", "--technique", "nope", "--backend", "cpu"],
        vec!["report", "--techniques", "nope", "--backends", "cpu"],
    ] {
        let out = caustica(&cmd);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{cmd:?}");
        assert!(
            err.contains("unknown technique 'nope'") && err.contains("sspm"),
            "{err}"
        );
    }
}

#[test]
fn a_small_report_measures_the_technique_by_name() {
    let dir = std::env::temp_dir().join(format!("caustica-report-{}", std::process::id()));
    let out = caustica(&[
        "report",
        "--scenes",
        "sphere",
        "--techniques",
        "sspm",
        "--backends",
        "cpu",
        "--budgets",
        "64x64",
        "--frames",
        "1,3",
        "--repeats",
        "2",
        "--size",
        "64x36",
        "--reference-frames",
        "4",
        "--tracer-photons",
        "16384",
        "--tracer-batches",
        "2",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let json = std::fs::read_to_string(dir.join("report.json")).expect("report.json");
    let records: serde_json::Value = serde_json::from_str(&json).expect("valid JSON");
    let r = &records[0];
    assert_eq!(r["technique"], "sspm");
    assert_eq!(r["backend"], "cpu");
    let rel = r["relative_mse"].as_f64().expect("a number");
    let raw = r["raw_relative_mse"].as_f64().expect("a number");
    assert!(rel.is_finite() && raw.is_finite() && rel >= 0.0, "{r}");
    // and against the light tracer, whose noise and silhouette definition come with it
    let tracer = &r["tracer"];
    assert!(
        tracer["relative_mse"].as_f64().is_some_and(f64::is_finite),
        "{r}"
    );
    assert!(tracer["noise"].as_f64().is_some_and(f64::is_finite), "{r}");
    assert_eq!(tracer["silhouette"], "centre_surface");
    assert!(String::from_utf8_lossy(&out.stdout).contains("silhouette pixels centre-surface"));
    // the frames axis: a single frame and three accumulated, timed to the last
    assert_eq!(r["frames"], 1);
    let three = &records[1];
    assert_eq!(three["frames"], 3);
    let t3 = three["frame_ms"].as_f64().expect("a number");
    assert!(
        t3 > 0.0
            && three["raw_relative_mse"]
                .as_f64()
                .is_some_and(f64::is_finite)
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn report_arguments_are_checked_before_any_reference_is_rendered() {
    let dir = std::env::temp_dir().join(format!("caustica-report-args-{}", std::process::id()));
    let d = dir.to_str().unwrap();
    for (args, needle) in [
        (vec!["--scenes", ""], "the list of scenes is empty"),
        (vec!["--backends", " , "], "the list of backends is empty"),
        (vec!["--budgets", ""], "the list of budgets is empty"),
        (vec!["--repeats", "0"], "--repeats must be at least 1"),
        (
            vec!["--frames", "0"],
            "--frames: '0' is not a count of at least 1",
        ),
        (vec!["--backends", "bogus"], "unknown backend"),
        (
            vec!["--tracer-batches", "1"],
            "--tracer-batches must be at least 2",
        ),
        (
            vec!["--tracer-spheres", "cube"],
            "invalid value 'cube' for '--tracer-spheres",
        ),
        (vec!["--silhouette", "edge"], "invalid value 'edge'"),
    ] {
        let mut cmd = vec!["report", "--out", d];
        cmd.extend(args.iter().copied());
        let out = caustica(&cmd);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{cmd:?}");
        assert!(err.contains(needle), "{cmd:?}: {err}");
        // failed before the reference cache (and the output folder) were written
        assert!(
            !dir.join("references").exists(),
            "{cmd:?} rendered a reference"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn the_settings_files_photon_grid_is_kept_unless_the_flag_is_given() {
    let dir = std::env::temp_dir().join(format!("caustica-grid-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("settings.json");
    std::fs::write(&settings, r#"{"photons_w": 32, "photons_h": 16}"#).unwrap();
    let stats = |extra: &[&str]| -> serde_json::Value {
        let out_dir = dir.join("out");
        let mut cmd = vec![
            "render",
            "--backend",
            "cpu",
            "--size",
            "16x9",
            "--settings",
            settings.to_str().unwrap(),
            "--out",
            out_dir.to_str().unwrap(),
        ];
        cmd.extend(extra.iter().copied());
        let out = caustica(&cmd);
        assert!(
            out.status.success(),
            "{}",
            String::from_utf8_lossy(&out.stderr)
        );
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("stats.json")).unwrap()).unwrap()
    };
    let s = stats(&[]);
    assert_eq!(
        (
            s["settings"]["frame"]["photons_w"].as_u64(),
            s["settings"]["frame"]["photons_h"].as_u64()
        ),
        (Some(32), Some(16))
    );
    let s = stats(&["--photons", "8x8"]);
    assert_eq!(
        (
            s["settings"]["frame"]["photons_w"].as_u64(),
            s["settings"]["frame"]["photons_h"].as_u64()
        ),
        (Some(8), Some(8))
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// `--filter` sets the filter of the receiver the settings pick: AdaptiveCaustics with
/// `deposit: screen` takes the screen photon map's filters (`screen.filter`), and its
/// atlas's gather (`box`) is refused rather than set where nothing reads it.
#[test]
fn the_filter_flag_follows_adaptive_caustics_deposit() {
    let dir = std::env::temp_dir().join(format!("caustica-filter-deposit-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("settings.json");
    std::fs::write(&settings, r#"{"deposit": "screen"}"#).unwrap();
    let out_dir = dir.join("out");
    let render = |filter: &str| {
        caustica(&[
            "render",
            "--backend",
            "cpu",
            "--technique",
            "adaptive-caustics",
            "--size",
            "32x18",
            "--photons",
            "64x64",
            "--settings",
            settings.to_str().unwrap(),
            "--filter",
            filter,
            "--out",
            out_dir.to_str().unwrap(),
        ])
    };
    let out = render("bilateral");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let s: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(out_dir.join("stats.json")).unwrap())
            .unwrap();
    assert_eq!(
        s["settings"]["screen"]["filter"].as_str(),
        Some("bilateral")
    );
    let out = render("box");
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("filters are density, bilateral"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}
