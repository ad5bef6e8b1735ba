//! `caustica report` on hostile input: a scene with no caustic is reported as such (no
//! NaN, no "exact" zero noise), a plan that cannot run is refused before any reference
//! is written to the cache, unknown filters and scenes that could not be told apart are
//! refused. Tiny sizes throughout (32x18 images, 16x16 or 64x64 photons, 2 x 1024 tracer
//! photons, 2 reference frames, 1 repeat).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn caustica(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustica"))
        .args(args)
        .output()
        .expect("the caustica binary runs")
}

/// A fresh, absent folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "caustica-report-hostile-{name}-{}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

/// `caustica report` with the tiny defaults of these tests, `extra` (flag, value pairs)
/// replacing a default of the same flag, writing to `out` with its cache in `cache`.
fn report(out: &Path, cache: &Path, extra: &[&str]) -> Output {
    let (out, cache) = (out.to_str().unwrap(), cache.to_str().unwrap());
    let mut flags: Vec<(&str, &str)> = vec![
        ("--scenes", "sphere"),
        ("--techniques", "sspm"),
        ("--backends", "cpu"),
        ("--size", "32x18"),
        ("--budgets", "16x16"),
        ("--repeats", "1"),
        ("--reference-frames", "2"),
        ("--tracer-photons", "1024"),
        ("--tracer-batches", "2"),
        ("--out", out),
        ("--cache", cache),
    ];
    for pair in extra.chunks(2) {
        let (flag, value) = (pair[0], pair.get(1).copied().unwrap_or(""));
        match flags.iter_mut().find(|(f, _)| *f == flag) {
            Some(given) => given.1 = value,
            None => flags.push((flag, value)),
        }
    }
    let mut args = vec!["report"];
    for (f, v) in flags {
        args.extend([f, v]);
    }
    caustica(&args)
}

/// Whether `dir` is absent or holds no file.
fn absent_or_empty(dir: &Path) -> bool {
    std::fs::read_dir(dir).map_or(true, |mut d| d.next().is_none())
}

/// A cornell box whose light has zero intensity, still named `cornell`, written to `dir`.
fn dark_cornell(dir: &Path) -> PathBuf {
    let out = caustica(&["scenes", "--export", "cornell"]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let mut scene: serde_json::Value = serde_json::from_slice(&out.stdout).expect("scene JSON");
    for light in scene["lights"].as_array_mut().expect("lights") {
        light["intensity"] = serde_json::json!([0.0, 0.0, 0.0]);
    }
    assert_eq!(scene["name"], "cornell");
    std::fs::create_dir_all(dir).unwrap();
    let path = dir.join("dark_cornell.json");
    std::fs::write(&path, serde_json::to_string_pretty(&scene).unwrap()).unwrap();
    path
}

#[test]
fn a_scene_without_caustic_is_reported_not_measured() {
    let dir = scratch("empty");
    let dark = dark_cornell(&dir);
    let scenes = format!("plain,{},sphere", dark.display());
    let out = report(
        &dir.join("out"),
        &dir.join("cache"),
        &[
            "--scenes",
            &scenes,
            "--budgets",
            "64x64",
            "--tracer-photons",
            "16384",
        ],
    );
    let (stdout, stderr) = (
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr),
    );
    assert!(out.status.success(), "{stderr}");
    // the table: no NaN anywhere, the empty scenes' rows say so, and the caustic goes on
    assert!(!stdout.to_lowercase().contains("nan"), "{stdout}");
    for scene in ["plain", "cornell"] {
        let row = stdout
            .lines()
            .find(|l| l.starts_with(&format!("| {scene} | sspm")))
            .unwrap_or_else(|| panic!("a {scene} row in {stdout}"));
        assert!(row.contains("| skipped |"), "{row}");
        assert!(
            stdout.contains(&format!(
                "the reference of {scene} holds no caustic: nothing to measure against"
            )),
            "{stdout}"
        );
    }
    let sphere = stdout
        .lines()
        .find(|l| l.starts_with("| sphere | sspm"))
        .expect("a sphere row");
    assert!(!sphere.contains("skipped"), "{sphere}");
    // one repeat has no variance: the last column
    let cells: Vec<&str> = sphere.split('|').map(str::trim).collect();
    assert_eq!(cells[cells.len() - 2], "n/a", "{sphere}");
    // the log says no pixel carries signal, never a noise of 0
    assert!(stderr.contains("no pixel carries signal"), "{stderr}");
    assert!(!stderr.contains("noise 0.0000"), "{stderr}");
    // report.json: no NaN, the left-out combinations with their reason and no numbers
    let json = std::fs::read_to_string(dir.join("out/report.json")).expect("report.json");
    assert!(!json.to_lowercase().contains("nan"), "{json}");
    let records: serde_json::Value = serde_json::from_str(&json).expect("valid JSON");
    let records = records.as_array().expect("an array");
    assert_eq!(records.len(), 3, "{json}");
    for r in &records[..2] {
        let why = r["skipped"].as_str().expect("a reason");
        assert!(why.contains("holds no caustic"), "{r}");
        for field in [
            "relative_mse",
            "raw_relative_mse",
            "reference_noise",
            "relative_variance",
        ] {
            assert!(r[field].is_null(), "{field}: {r}");
        }
    }
    let measured = &records[2];
    assert_eq!(measured["scene"], "sphere");
    assert!(measured.get("skipped").is_none(), "{measured}");
    assert!(
        measured["relative_mse"]
            .as_f64()
            .is_some_and(f64::is_finite),
        "{measured}"
    );
    assert!(measured["relative_variance"].is_null(), "{measured}");
    // no plot for a scene with nothing measured, and the reason why
    assert!(
        stderr.contains("no plot for plain: nothing measured"),
        "{stderr}"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_plan_that_cannot_run_is_refused_before_any_reference_is_written() {
    let dir = scratch("plan");
    std::fs::create_dir_all(&dir).unwrap();
    let settings = dir.join("knn0.json");
    std::fs::write(&settings, r#"{"screen": {"knn_photons": 0}}"#).unwrap();
    let settings = settings.to_str().unwrap();
    let cases: Vec<(Vec<&str>, &str)> = vec![
        (vec!["--techniques", "sspm:foo=1"], "unknown field `foo`"),
        (
            vec!["--techniques", "sspm:depth_tolerance=abc"],
            "technique 'sspm:depth_tolerance=abc' (filter density, budget 16x16)",
        ),
        (
            vec!["--settings", settings],
            "knn_photons must be in 1..=1024",
        ),
        (
            vec!["--techniques", "sspm,adaptive-caustics"],
            "technique 'adaptive-caustics' (filter density, budget 16x16)",
        ),
        (
            vec!["--techniques", "sspm:"],
            "technique 'sspm:': no settings after ':'",
        ),
        (vec!["--reference-frames", "0"], "at least 2 frames"),
        (vec!["--reference-frames", "1"], "at least 2 frames"),
        (
            vec!["--techniques", "sspm,sspm"],
            "technique 'sspm' is listed twice",
        ),
    ];
    for (k, (args, needle)) in cases.iter().enumerate() {
        let cache = dir.join(format!("cache-{k}"));
        let out = report(&dir.join("out"), &cache, args);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{args:?}: {err}");
        assert!(
            err.contains(needle),
            "{args:?}: expected '{needle}' in {err}"
        );
        assert!(!err.contains("light tracer"), "{args:?}: work began: {err}");
        assert!(
            absent_or_empty(&cache),
            "{args:?}: {} was written",
            cache.display()
        );
    }
    // an unusable cache folder: refused before the light tracer's banner
    let out = report(
        &dir.join("out"),
        Path::new("/proc/caustica-report-hostile"),
        &[],
    );
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("reference cache /proc/caustica-report-hostile"),
        "{err}"
    );
    assert!(!err.contains("light tracer"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn an_unknown_filter_is_refused_with_the_valid_ones() {
    let dir = scratch("filter");
    let cache = dir.join("cache");
    let out = report(&dir.join("out"), &cache, &["--filters", "density,foo"]);
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{err}");
    assert!(
        err.contains("unknown filter 'foo'; available: density, bilateral, box"),
        "{err}"
    );
    assert!(absent_or_empty(&cache));
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn scenes_that_could_not_be_told_apart_are_refused() {
    let dir = scratch("dup");
    let dark = dark_cornell(&dir);
    let cache = dir.join("cache");
    let twice = format!("cornell,{}", dark.display());
    for scenes in ["cornell,cornell", twice.as_str()] {
        let out = report(&dir.join("out"), &cache, &["--scenes", scenes]);
        let err = String::from_utf8_lossy(&out.stderr);
        assert!(!out.status.success(), "{scenes}: {err}");
        assert!(
            err.contains("scenes 1 and 2 of the list are both named 'cornell'"),
            "{scenes}: {err}"
        );
        assert!(absent_or_empty(&cache), "{scenes}");
        assert!(!dir.join("out/error_vs_time_cornell.png").exists());
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A cache that cannot be written to is taken where it holds every reference the plan
/// needs: the second report over a read-only cache that the first one filled runs, saying
/// so, and leaves the cache as it was; a plan needing a reference the cache lacks is
/// refused before any work, naming it. A user who may write anywhere (root) cannot be
/// refused by permissions: the read-only half is skipped there, with a line saying so.
#[cfg(unix)]
#[test]
fn a_read_only_cache_serves_the_references_it_holds() {
    use std::os::unix::fs::PermissionsExt;
    /// Gives the folder its write permission back however the test ends.
    struct Writable<'a>(&'a Path);
    impl Drop for Writable<'_> {
        fn drop(&mut self) {
            let _ = std::fs::set_permissions(self.0, std::fs::Permissions::from_mode(0o755));
        }
    }
    let dir = scratch("read-only-cache");
    let cache = dir.join("cache");
    let first = report(&dir.join("first"), &cache, &[]);
    assert!(first.status.success(), "{first:?}");
    let held = std::fs::read_dir(&cache).unwrap().count();
    assert!(held > 0, "the first report cached no reference");
    std::fs::set_permissions(&cache, std::fs::Permissions::from_mode(0o555)).unwrap();
    let guard = Writable(&cache);
    if writes_anyway(&cache) {
        eprintln!("SKIPPING the read-only half: this user writes into a read-only folder (root)");
    } else {
        let second = report(&dir.join("second"), &cache, &[]);
        let err = String::from_utf8_lossy(&second.stderr);
        assert!(second.status.success(), "{second:?}");
        assert!(err.contains("holds every reference"), "{err}");
        assert_eq!(std::fs::read_dir(&cache).unwrap().count(), held);
        // another scene's references are not there: refused at once, each named
        let third = report(&dir.join("third"), &cache, &["--scenes", "sphere,ring"]);
        let err = String::from_utf8_lossy(&third.stderr);
        assert!(!third.status.success(), "{third:?}");
        assert!(
            err.contains("reference cache") && err.contains("it lacks ring-"),
            "{err}"
        );
        assert!(
            err.contains("ring: light tracer") && !err.contains("(sphere"),
            "{err}"
        );
        assert!(!dir.join("third").join("report.json").exists());
    }
    drop(guard);
    let _ = std::fs::remove_dir_all(&dir);
}

/// Whether a file can be made in `dir` whatever its permissions say (root).
#[cfg(unix)]
fn writes_anyway(dir: &Path) -> bool {
    let probe = dir.join("probe");
    let wrote = std::fs::write(&probe, b"").is_ok();
    let _ = std::fs::remove_file(&probe);
    wrote
}
