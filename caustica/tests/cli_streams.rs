//! The binary's contract for output it cannot write, on every subcommand, never a panic:
//!
//! - stdout a pipe whose reader has gone (`caustica scenes --export prism | head`): the
//!   program ends quietly with status 0 (the reader had what it wanted), its files
//!   written;
//! - stdout that cannot take the bytes (a full disk behind `> file`): one line naming
//!   stdout, status 1;
//! - stderr a pipe whose reader has gone: the command carries on, its status unchanged;
//! - an `--out` or `--cache` folder that cannot be written (a file there or above it, no
//!   write permission): one line naming the path, status 1, before any work.
//!
//! Each case runs the real `caustica` executable at tiny sizes.

use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

fn caustica(args: &[String]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_caustica"));
    c.args(args);
    c
}

fn strings(args: &[&str]) -> Vec<String> {
    args.iter().map(|a| a.to_string()).collect()
}

/// A fresh, empty folder of this test process.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("caustica-streams-{}-{name}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn render(out: &Path) -> Vec<String> {
    let mut v = strings(&[
        "render",
        "--backend",
        "cpu",
        "--scene",
        "prism",
        "--photons",
        "16x16",
        "--size",
        "32x18",
        "--out",
    ]);
    v.push(out.display().to_string());
    v
}

fn reference(cache: &Path) -> Vec<String> {
    let mut v = strings(&[
        "reference",
        "--scene",
        "sphere",
        "--size",
        "16x9",
        "--photons",
        "4096",
        "--batches",
        "2",
        "--cache",
    ]);
    v.push(cache.display().to_string());
    v
}

fn report(out: &Path, cache: Option<&Path>) -> Vec<String> {
    let mut v = strings(&[
        "report",
        "--scenes",
        "sphere",
        "--techniques",
        "sspm",
        "--backends",
        "cpu",
        "--budgets",
        "16x16",
        "--repeats",
        "1",
        "--size",
        "32x18",
        "--reference-frames",
        "2",
        "--tracer-photons",
        "4096",
        "--tracer-batches",
        "2",
        "--out",
    ]);
    v.push(out.display().to_string());
    if let Some(c) = cache {
        v.push("--cache".into());
        v.push(c.display().to_string());
    }
    v
}

/// Every subcommand (and the help and version texts) with what it writes besides stdout:
/// (arguments, a file that must exist after a successful run).
fn every_command(dir: &Path) -> Vec<(Vec<String>, Option<PathBuf>)> {
    vec![
        (strings(&["scenes"]), None),
        (strings(&["scenes", "--export", "prism"]), None),
        (
            strings(&["scenes", "--export", "prism", "--format", "gltf"]),
            None,
        ),
        (strings(&["backends"]), None),
        (strings(&["techniques"]), None),
        (strings(&["--help"]), None),
        (strings(&["render", "--help"]), None),
        (strings(&["--version"]), None),
        (
            render(&dir.join("render")),
            Some(dir.join("render").join("stats.json")),
        ),
        (reference(&dir.join("references")), None),
        (
            report(&dir.join("report"), None),
            Some(dir.join("report").join("report.json")),
        ),
    ]
}

fn no_panic(args: &[String], out: &Output) {
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_ne!(out.status.code(), Some(101), "{args:?} panicked: {stderr}");
    assert!(!stderr.contains("panicked"), "{args:?} panicked: {stderr}");
}

/// A pipe whose read end is already closed, for a child's stdout or stderr: every write
/// to it fails with a broken pipe, whatever the timing. Its only reader was `true`, which
/// has exited; this process never keeps the read end (the standard library closes its
/// copy once `true` is spawned).
#[cfg(unix)]
fn closed_pipe() -> Stdio {
    let mut reader = Command::new("true")
        .stdin(Stdio::piped())
        .spawn()
        .expect("`true` runs");
    let writer = reader.stdin.take().expect("a pipe to `true`");
    reader.wait().expect("`true` exits");
    Stdio::from(writer)
}

#[cfg(unix)]
#[test]
fn a_closed_stdout_ends_every_command_quietly_with_status_0() {
    let dir = temp_dir("closed-stdout");
    for (args, written) in every_command(&dir) {
        let out = caustica(&args)
            .stdout(closed_pipe())
            .stderr(Stdio::piped())
            .output()
            .expect("the caustica binary runs");
        no_panic(&args, &out);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(0), "{args:?}: {stderr}");
        assert!(
            !stderr.lines().any(|l| l.starts_with("error")),
            "{args:?}: {stderr}"
        );
        if let Some(f) = written {
            assert!(f.exists(), "{args:?} did not write {f:?}: {stderr}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// A closed stderr: nothing can be said, so the command runs on and its status tells how
/// it went (0, or 1 and 2 for failures), never 101.
#[cfg(unix)]
#[test]
fn a_closed_stderr_leaves_the_status_as_it_was() {
    let dir = temp_dir("closed-stderr");
    for (args, written) in every_command(&dir) {
        let out = caustica(&args)
            .stdout(closed_pipe())
            .stderr(closed_pipe())
            .output()
            .expect("the caustica binary runs");
        assert_eq!(out.status.code(), Some(0), "{args:?}");
        if let Some(f) = written {
            assert!(f.exists(), "{args:?} did not write {f:?}");
        }
    }
    for (args, status) in [
        (strings(&["render", "--scene", "no-such-scene"]), 1),
        (strings(&["render", "--photons", "0x5"]), 2),
        (strings(&["no-such-command"]), 2),
        (strings(&[]), 2), // the help on stderr
    ] {
        let out = caustica(&args)
            .stdout(Stdio::piped())
            .stderr(closed_pipe())
            .output()
            .expect("the caustica binary runs");
        assert_eq!(out.status.code(), Some(status), "{args:?}");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// `/dev/full` takes no byte: every command that prints fails with one line naming
/// stdout, status 1; its files are written before it prints.
#[cfg(target_os = "linux")]
#[test]
fn a_full_stdout_is_an_error_naming_stdout() {
    let dir = temp_dir("full-stdout");
    for (args, written) in every_command(&dir) {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full opens");
        let out = caustica(&args)
            .stdout(full)
            .stderr(Stdio::piped())
            .output()
            .expect("the caustica binary runs");
        no_panic(&args, &out);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
        let last = stderr.trim_end().lines().last().unwrap_or("");
        assert!(
            last.starts_with("error: writing to stdout: ") && last.contains("space"),
            "{args:?}: {stderr}"
        );
        if let Some(f) = written {
            assert!(f.exists(), "{args:?} did not write {f:?}: {stderr}");
        }
    }
    let _ = std::fs::remove_dir_all(&dir);
}

/// Asserts a failure with status 1 whose last stderr line is `error: ` followed by a
/// message containing every needle, and that nothing was rendered into `dir`.
fn fails_naming(args: &[String], needles: &[&str]) {
    let out = caustica(args).output().expect("the caustica binary runs");
    no_panic(args, &out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{args:?}: {stderr}");
    let last = stderr.trim_end().lines().last().unwrap_or("");
    assert!(last.starts_with("error: "), "{args:?}: {stderr}");
    for n in needles {
        assert!(last.contains(n), "{args:?}: expected '{n}' in: {stderr}");
    }
}

#[test]
fn an_out_or_cache_at_a_file_fails_naming_the_path() {
    let dir = temp_dir("out-file");
    let file = dir.join("a-file");
    std::fs::write(&file, b"a file, not a folder").unwrap();
    let f = file.display().to_string();
    let under = file.join("sub");
    let u = under.display().to_string();
    fails_naming(
        &render(&file),
        &["--out", &f, "a file is there, not a folder"],
    );
    fails_naming(
        &render(&under),
        &["--out", &u, &format!("{f} is a file, not a folder")],
    );
    fails_naming(
        &report(&file, None),
        &["--out", &f, "a file is there, not a folder"],
    );
    fails_naming(
        &report(&dir.join("report"), Some(&under)),
        &["reference cache", &u, "is a file"],
    );
    fails_naming(
        &reference(&file),
        &["reference cache", &f, "a file is there, not a folder"],
    );
    fails_naming(
        &reference(&under),
        &["reference cache", &u, "is a file, not a folder"],
    );
    // the same through a device file (a character device is no folder either)
    #[cfg(target_os = "linux")]
    fails_naming(
        &render(Path::new("/dev/null")),
        &["--out /dev/null", "a file is there"],
    );
    let _ = std::fs::remove_dir_all(&dir);
}

/// A folder without write permission. A user who may write anywhere (root) cannot be
/// refused by permissions: the case is skipped there, with a line saying so.
#[cfg(unix)]
#[test]
fn a_read_only_out_or_cache_fails_naming_the_path() {
    use std::os::unix::fs::PermissionsExt;
    let dir = temp_dir("read-only");
    let ro = dir.join("read-only");
    std::fs::create_dir_all(&ro).unwrap();
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    if std::fs::write(ro.join("probe"), b"").is_ok() {
        eprintln!("SKIPPING: this user writes into a read-only folder (root)");
        let _ = std::fs::remove_file(ro.join("probe"));
    } else {
        let r = ro.display().to_string();
        let inside = ro.join("out");
        let i = inside.display().to_string();
        fails_naming(&render(&ro), &["--out", &r, "not writable"]);
        // a folder to be made inside it
        fails_naming(&render(&inside), &["--out", &i, "ermission denied"]);
        fails_naming(&report(&ro, None), &["--out", &r, "not writable"]);
        fails_naming(&reference(&ro), &["reference cache", &r, "not writable"]);
        fails_naming(
            &report(&dir.join("report"), Some(&ro)),
            &["reference cache", &r, "not writable"],
        );
        assert!(std::fs::read_dir(&ro).unwrap().next().is_none());
    }
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755)).unwrap();
    let _ = std::fs::remove_dir_all(&dir);
}
