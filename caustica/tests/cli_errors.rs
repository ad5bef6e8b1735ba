//! The binary's contract for bad input: one line on stderr, a non-zero exit, no panic.
//! Each case runs the real `caustica` executable.

use std::process::{Command, Output};

fn caustica(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_caustica"))
        .args(args)
        .output()
        .expect("the caustica binary runs")
}

/// Asserts a clean failure whose message contains `needle`.
fn fails_cleanly(args: &[&str], needle: &str) {
    let out = caustica(args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success(), "{args:?} succeeded");
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
    assert!(
        stderr.contains(needle),
        "{args:?}: expected '{needle}' in: {stderr}"
    );
    assert_eq!(
        stderr.trim_end().lines().count(),
        1,
        "{args:?}: error is not one line: {stderr}"
    );
}

fn temp_file(name: &str, text: &str) -> std::path::PathBuf {
    let dir = std::env::temp_dir().join(format!("caustica-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn unknown_scene() {
    fails_cleanly(&["render", "--scene", "no-such-scene"], "no-such-scene");
}

#[test]
fn zero_photon_grid() {
    fails_cleanly(&["render", "--scene", "sphere", "--photons", "0x5"], "0x5");
}

#[test]
fn unknown_backend() {
    fails_cleanly(
        &["render", "--scene", "sphere", "--backend", "quantum"],
        "quantum",
    );
}

#[test]
fn truncated_scene_file() {
    let path = temp_file("truncated.json", "{ \"camera\": { \"position\": [0, 1");
    fails_cleanly(
        &["render", "--scene", path.to_str().unwrap()],
        "truncated.json",
    );
}

#[test]
fn negative_ior_names_its_line() {
    let exported = caustica(&["scenes", "--export", "sphere"]);
    assert!(exported.status.success());
    let text = String::from_utf8(exported.stdout).unwrap();
    let bad = text.replacen("\"ior\": 1.5", "\"ior\": -1.5", 1);
    assert_ne!(
        bad, text,
        "the exported sphere scene has an \"ior\": 1.5 field"
    );
    let line = bad.lines().position(|l| l.contains("-1.5")).unwrap() + 1;
    let path = temp_file("negative_ior.json", &bad);
    fails_cleanly(
        &["render", "--scene", path.to_str().unwrap()],
        &format!("negative_ior.json:{line}:"),
    );
}

#[test]
fn exported_scene_loads_back() {
    let exported = caustica(&["scenes", "--export", "ring"]);
    assert!(exported.status.success());
    let path = temp_file("ring.json", &String::from_utf8(exported.stdout).unwrap());
    let out_dir = path.with_file_name("ring-out");
    let out = caustica(&[
        "render",
        "--scene",
        path.to_str().unwrap(),
        "--photons",
        "32x32",
        "--size",
        "64x36",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(out_dir.join("stats.json").exists());
}

/// `stats.json` of the `plain` scene (no caster) lists the passes that ran and those the
/// frame plan skipped, each with its reason.
#[test]
fn stats_json_lists_passes_run_and_skipped_with_reasons() {
    let out_dir = std::env::temp_dir().join(format!("caustica-plain-{}", std::process::id()));
    let out = caustica(&[
        "render",
        "--scene",
        "plain",
        "--photons",
        "16x16",
        "--size",
        "32x18",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = std::fs::read_to_string(out_dir.join("stats.json")).expect("stats.json");
    let doc: serde_json::Value = serde_json::from_str(&text).expect("valid JSON");
    let stats = &doc["stats"];
    let names = |key: &str| -> Vec<String> {
        stats[key]
            .as_array()
            .unwrap_or_else(|| panic!("stats.{key} is not a list: {text}"))
            .iter()
            .map(|p| p["name"].as_str().unwrap().to_string())
            .collect()
    };
    let ran = names("passes");
    assert!(ran.contains(&"primary_gbuffer".to_string()), "{ran:?}");
    assert!(ran.contains(&"direct_light".to_string()), "{ran:?}");
    assert!(!ran.contains(&"trace_photons".to_string()), "{ran:?}");
    for p in stats["skipped"].as_array().unwrap() {
        assert!(!p["reason"].as_str().unwrap().is_empty(), "{p}");
    }
    assert!(names("skipped").contains(&"trace_photons".to_string()));
    let plan = stats["plan"]["passes"]
        .as_array()
        .expect("stats.plan.passes");
    assert!(plan.len() >= 8, "{plan:?}");
    for p in plan {
        assert!(
            p["runs"].is_boolean() && !p["reason"].as_str().unwrap().is_empty(),
            "{p}"
        );
    }
    // the caustic images of a frame without caustics are still written (zeros)
    assert!(out_dir.join("plain_caustics_filtered.exr").exists());
    let _ = std::fs::remove_dir_all(&out_dir);
}

#[test]
fn size_over_the_camera_bound_names_the_flag() {
    fails_cleanly(
        &["render", "--scene", "sphere", "--size", "100000x100000"],
        "--size",
    );
}

/// PoCL backs every buffer with host memory and aborted the process when it could not
/// (`pocl_util.c: Assertion 'p->mem_ptr != NULL'`). Under an 8 GB address-space limit an
/// 8192x8192 frame of `sphere` (a 4.3 GB G-buffer, a 2.7 GB photon map, 1 GB images) must end in a one-line out-of-memory error.
#[test]
fn opencl_out_of_host_memory_is_an_error_not_an_abort() {
    let probe = caustica(&["backends"]);
    let listing = String::from_utf8_lossy(&probe.stdout).to_string();
    let required = std::env::var("CAUSTICA_REQUIRE_BACKENDS").unwrap_or_default();
    if !listing
        .lines()
        .any(|l| l.starts_with("opencl") && !l.contains("unavailable"))
    {
        assert!(
            !required.contains("opencl"),
            "opencl is required but not available: {listing}"
        );
        eprintln!("SKIPPING: no OpenCL device here: {listing}");
        return;
    }
    let out = Command::new("sh")
        .arg("-c")
        .arg(format!(
            "ulimit -v 8000000 && exec '{}' render --scene sphere --backend opencl \
             --size 8192x8192 --photons 16x16 --out '{}'",
            env!("CARGO_BIN_EXE_caustica"),
            std::env::temp_dir()
                .join(format!("caustica-oom-{}", std::process::id()))
                .display()
        ))
        .output()
        .expect("sh runs");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "not a clean failure: {stderr}");
    assert!(stderr.contains("out of memory"), "{stderr}");
    assert!(stderr.contains("host memory"), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
}

#[test]
fn gltf_scenes_export_render_and_fail_cleanly() {
    // export a built-in scene as glTF, render it on the CPU
    let out = caustica(&["scenes", "--export", "sphere", "--format", "gltf"]);
    assert!(out.status.success());
    let path = temp_file("sphere.gltf", &String::from_utf8(out.stdout).unwrap());
    let dir = path.with_extension("out");
    let r = caustica(&[
        "render",
        "--scene",
        path.to_str().unwrap(),
        "--backend",
        "cpu",
        "--size",
        "64x48",
        "--photons",
        "64x64",
        "--out",
        dir.to_str().unwrap(),
    ]);
    assert!(r.status.success(), "{}", String::from_utf8_lossy(&r.stderr));
    assert!(dir.join("sphere_composite.exr").exists());
    // a broken glTF: one located line
    let bad = temp_file("bad.gltf", "{\"asset\": {\"version\": \"2.0\"},\n oops}");
    fails_cleanly(&["render", "--scene", bad.to_str().unwrap()], "bad.gltf:2:");
    fails_cleanly(
        &["scenes", "--export", "sphere", "--format", "obj"],
        "possible values: json, gltf",
    );
}

/// `--animate` needs a height field and a finite time step, and says so in one line.
#[test]
fn animate_without_a_height_field_or_with_a_bad_step() {
    fails_cleanly(
        &["render", "--scene", "sphere", "--animate", "0.1"],
        "no height field",
    );
    fails_cleanly(&["render", "--scene", "pool", "--animate", "inf"], "finite");
}

/// `render --animate` writes every frame's composite, and the waves move between them.
#[test]
fn animate_writes_every_frame_and_the_waves_move() {
    let out_dir = std::env::temp_dir().join(format!("caustica-waves-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&out_dir);
    let out = caustica(&[
        "render",
        "--scene",
        "pool",
        "--technique",
        "caustic-map",
        "--photons",
        "64x64",
        "--size",
        "48x27",
        "--frames",
        "3",
        "--animate",
        "0.25",
        "--out",
        out_dir.to_str().unwrap(),
    ]);
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let frames: Vec<Vec<u8>> = (0..3)
        .map(|f| std::fs::read(out_dir.join(format!("pool_f{f:03}_composite.png"))).expect("frame"))
        .collect();
    assert!(
        frames[0] != frames[1] && frames[1] != frames[2],
        "the frames are the same"
    );
    // the last frame is also the run's composite
    let last = std::fs::read(out_dir.join("pool_composite.png")).expect("composite");
    assert!(last == frames[2]);
    let _ = std::fs::remove_dir_all(&out_dir);
}

#[test]
fn settings_files_are_read_with_a_limit() {
    // a pipe that never ends is refused after the limit, not after filling memory
    fails_cleanly(
        &["render", "--scene", "cornell", "--settings", "/dev/zero"],
        "larger than the 16 MiB a settings file may have",
    );
}

#[test]
fn negative_numbers_are_values_not_flags() {
    fails_cleanly(
        &["render", "--seed", "-1"],
        "invalid value '-1' for '--seed",
    );
    fails_cleanly(&["render", "--exposure", "-1"], "--exposure");
    fails_cleanly(
        &["render", "--frames", "-2"],
        "invalid value '-2' for '--frames",
    );
}

#[test]
fn light_tracer_bounds_its_photons() {
    let cache = std::env::temp_dir().join(format!("caustica-cli-rc-{}", std::process::id()));
    let cache = cache.to_str().expect("a UTF-8 temporary path");
    fails_cleanly(
        &[
            "reference",
            "--scene",
            "cornell",
            "--size",
            "32x18",
            "--cache",
            cache,
            "--batches",
            "2",
            "--photons",
            "18446744073709551615",
        ],
        "photons per batch must be at most 2^40",
    );
}

#[test]
fn an_animation_past_f32_time_is_refused_and_a_long_one_stays_finite() {
    let pool = [
        "render",
        "--scene",
        "pool",
        "--technique",
        "caustic-map",
        "--size",
        "32x18",
        "--photons",
        "16x16",
        "--animate",
        "3e38",
        "--frames",
    ];
    fails_cleanly(&[&pool[..], &["3"]].concat(), "--animate");
    let dir = std::env::temp_dir().join(format!("caustica-cli-anim-{}", std::process::id()));
    let dir = dir.to_str().expect("a UTF-8 temporary path");
    let out = caustica(&[&pool[..], &["2", "--out", dir]].concat());
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

#[test]
fn a_flag_of_a_few_values_lists_them_and_a_side_too_large_says_so() {
    fails_cleanly(
        &["render", "--filter", "foo"],
        "possible values: density, bilateral, box",
    );
    fails_cleanly(
        &["reference", "--spheres", "foo"],
        "possible values: analytic, mesh",
    );
    fails_cleanly(
        &["render", "--photons", "4294967296x1"],
        "a side must be at most 4294967295",
    );
    // usage errors share clap's status
    assert_eq!(
        caustica(&["reference", "--spheres", "foo"]).status.code(),
        Some(2)
    );
}

#[test]
fn an_obj_file_given_as_a_scene_says_how_to_place_it() {
    let path = temp_file("ball.obj", "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\n");
    fails_cleanly(
        &["render", "--scene", path.to_str().unwrap()],
        "an OBJ file is a mesh, not a scene",
    );
}

/// `render` of `scene` on the CPU backend at 32x18 with 16x16 photons into `out`, then
/// `more` arguments.
fn small_render(scene: &str, out: &std::path::Path, more: &[&str]) -> Vec<String> {
    let out = out.to_str().expect("a UTF-8 temporary path");
    let base = [
        "render",
        "--scene",
        scene,
        "--backend",
        "cpu",
        "--size",
        "32x18",
        "--photons",
        "16x16",
        "--out",
        out,
    ];
    base.iter().chain(more).map(|s| s.to_string()).collect()
}

fn as_strs(args: &[String]) -> Vec<&str> {
    args.iter().map(String::as_str).collect()
}

/// A settings file whose block is not an object is refused, naming the block, also where a
/// flag (`--photons`) sets a field of that block.
#[test]
fn a_settings_block_that_is_not_an_object_is_refused() {
    for (name, text) in [
        ("frame7.json", r#"{"frame": 7}"#),
        ("trace.json", r#"{"trace": [1, 2]}"#),
    ] {
        let path = temp_file(name, text);
        let settings = path.to_str().unwrap();
        let args = small_render(
            "sphere",
            &path.with_extension("out"),
            &["--settings", settings],
        );
        fails_cleanly(&as_strs(&args), "must be a JSON object");
    }
}

/// Outputs another technique has are named in a warning, not dropped in silence; an
/// empty list is refused.
#[test]
fn outputs_a_technique_lacks_are_named() {
    let path = temp_file(
        "outputs.json",
        r#"{"frame": {"outputs": ["composite", "caustic_atlas", "indirect"]}}"#,
    );
    let out_dir = path.with_extension("out");
    let settings = path.to_str().unwrap();
    let args = small_render(
        "sphere",
        &out_dir,
        &["--technique", "sspm", "--settings", settings],
    );
    let out = caustica(&as_strs(&args));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: sspm has no caustic_atlas, indirect output"),
        "{stderr}"
    );
    assert!(out_dir.join("sphere_composite.exr").exists());
    let empty = temp_file("no_outputs.json", r#"{"frame": {"outputs": []}}"#);
    let args = small_render("sphere", &out_dir, &["--settings", empty.to_str().unwrap()]);
    fails_cleanly(&as_strs(&args), "frame.outputs is empty");
}

/// A frame larger than the host's memory fails with an out-of-memory error when its
/// buffers are made, before their pages are touched (the system would otherwise kill the
/// process as the kernels filled them): 16384^2 on the CPU backend needs about 70 GB.
#[test]
fn a_cpu_frame_beyond_host_memory_is_an_error_not_a_kill() {
    let meminfo = std::fs::read_to_string("/proc/meminfo").unwrap_or_default();
    let kib = |key: &str| -> Option<u64> {
        let line = meminfo.lines().find_map(|l| l.strip_prefix(key))?;
        line.trim().strip_suffix("kB")?.trim().parse().ok()
    };
    let Some(available) = kib("MemAvailable:").map(|a| a + kib("SwapFree:").unwrap_or(0)) else {
        eprintln!("SKIPPING: no /proc/meminfo here");
        return;
    };
    if available > 48 << 20 {
        eprintln!("SKIPPING: {available} KiB available: this host could hold the frame");
        return;
    }
    let out_dir = std::env::temp_dir().join(format!("caustica-16k-{}", std::process::id()));
    let mut args = small_render("sphere", &out_dir, &[]);
    args[6] = "16384x16384".into(); // --size
    let out = caustica(&as_strs(&args));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "not a clean failure: {stderr}");
    assert!(
        stderr.contains("out of memory") && stderr.contains("host memory"),
        "{stderr}"
    );
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
}

/// A negative size or grid is named as a bad value, not taken for a flag.
#[test]
fn a_negative_size_is_a_bad_value() {
    fails_cleanly(&["render", "--size", "-64x36"], "'-64x36' is not WxH");
    fails_cleanly(&["render", "--photons", "-1x1"], "'-1x1' is not WxH");
}

/// A scene problem found when the technique is made names the scene file too.
#[test]
fn a_scene_refused_by_the_technique_names_the_file() {
    let out = caustica(&["scenes", "--export", "sphere"]);
    let mut s: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let material = s["materials"]
        .as_object()
        .unwrap()
        .keys()
        .next()
        .unwrap()
        .clone();
    s["objects"].as_array_mut().unwrap().push(serde_json::json!({
        "name": "flat", "material": material,
        "shape": {"type": "mesh", "positions": [[0, 0, 0], [1, 0, 0], [2, 0, 0]], "indices": [[0, 1, 2]]}
    }));
    let path = temp_file("collapsed.json", &s.to_string());
    let arg = path.to_str().unwrap();
    let out = caustica(&as_strs(&small_render(
        arg,
        &path.with_extension("out"),
        &[],
    )));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains(&format!("error: {arg}: invalid scene: objects[2].shape")),
        "{stderr}"
    );
}
