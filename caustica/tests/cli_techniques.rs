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
        "--repeats",
        "2",
        "--size",
        "64x36",
        "--reference-frames",
        "4",
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
    let _ = std::fs::remove_dir_all(&dir);
}
