//! Helpers the frame benchmarks share.

/// The environment variable `name`, or `default`.
pub fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_string())
}

/// The median of `v` (sorted in place; the upper one of an even count).
pub fn median(v: &mut [f64]) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Milliseconds of frames each measured configuration runs before its timed frames
/// (`CAUSTICA_BENCH_WARMUP_MS`, default 3000). A fresh process on an idle H200 ran its
/// first seconds of frames 3-5x slow (CausticMap setting 0 on Vulkan: 12.6 ms budget
/// first in its process, 2.5-2.7 ms after other work; docs/performance.md, "Method"), so
/// one warm-up frame is not enough.
#[allow(dead_code)] // dynamic_frame times its updates from the first frame on
pub fn warmup_ms() -> u64 {
    env_or("CAUSTICA_BENCH_WARMUP_MS", "3000")
        .parse()
        .unwrap_or(3000)
}

/// Calls `frame` until `warmup_ms()` have passed (at least once); stops at its first error
/// and returns it.
#[allow(dead_code)]
pub fn warm_up<E>(mut frame: impl FnMut() -> Result<(), E>) -> Result<(), E> {
    let (start, ms) = (std::time::Instant::now(), warmup_ms());
    loop {
        frame()?;
        if start.elapsed().as_millis() as u64 >= ms {
            return Ok(());
        }
    }
}

/// The backends named in the comma-separated list `wanted`, each opened as its turn comes
/// (one device at a time); one that does not open is reported ("skipped") and passed over.
#[allow(dead_code)]
pub fn opened_backends(wanted: &str) -> impl Iterator<Item = (&str, Box<dyn caustica::Backend>)> {
    wanted
        .split(',')
        .map(str::trim)
        .filter(|s| !s.is_empty())
        .filter_map(|name| match caustica::open_backend(name) {
            Ok(b) => Some((name, b)),
            Err(e) => {
                println!("{name}: skipped ({e})");
                None
            }
        })
}
