//! The catalogue of stiff and extreme cases (`caustica_conformance::stiff`) on
//! every backend of `caustica_conformance::backends()` (`CAUSTICA_REQUIRE_BACKENDS` makes a
//! missing backend fail). A failure names the case and the backend.
//!
//! Cases that the quirk table (`caustica_conformance::harness::quirks`) holds back on a
//! backend are not run there by the default test, and are all that the ignored test
//! `heavy_cases_on_every_backend` runs. Today these are the two heavy cases (an 8192x8192
//! image, 2^26 photons) on every backend but cpu (lavapipe and PoCL take minutes and ~10 GiB
//! of host memory for them), to be run on the GPU machine:
//! `cargo test --release -p caustica-conformance --test stiff_cases -- --ignored`.
//!
//! `CAUSTICA_STIFF_CASES=a,b` runs only the cases whose id (`group/name`) contains one of
//! the comma-separated parts (while working on one case; CI runs them all).

use caustica_conformance::harness::{loud, quirk, Quirk, Report};
use caustica_conformance::stiff::catalogue;

/// Runs every case for which `pick` says yes, given the quirk that holds it back on the
/// backend's device, if any.
fn run(test: &str, pick: impl Fn(Option<&Quirk>) -> bool) {
    let mut report = Report::new(test);
    let only: Option<Vec<String>> = std::env::var("CAUSTICA_STIFF_CASES")
        .ok()
        .map(|v| v.split(',').map(str::to_owned).collect());
    let cases: Vec<_> = catalogue()
        .into_iter()
        .filter(|c| {
            only.as_ref()
                .is_none_or(|o| o.iter().any(|part| c.id().contains(part.as_str())))
        })
        .collect();
    if let Some(o) = &only {
        loud(&format!(
            "{test}: only the cases matching {o:?} ({} cases)",
            cases.len()
        ));
    }
    let mut ran = 0;
    for (name, mut backend) in caustica_conformance::backends() {
        let device = backend.capabilities().device;
        for case in &cases {
            let id = case.id();
            let held = quirk(name, &device, &id);
            if !pick(held) {
                if let Some(q) = held {
                    loud(&format!("{test}: {name} / {id} not run: {}", q.reason));
                }
                continue;
            }
            ran += 1;
            match (case.run)(backend.as_mut()) {
                Ok(o) => {
                    let mut v = o.verdict;
                    v.note(format!("key: {}", o.key));
                    report.add(name, &id, v);
                }
                Err(e) => report.error(name, &id, e),
            }
        }
    }
    assert!(ran > 0, "{test}: no case ran");
    report.finish();
}

/// Every case on every backend, except those the quirk table holds back there (the heavy
/// ones, on every backend but cpu).
#[test]
fn stiff_cases_on_every_backend() {
    run("stiff cases", |held| held.is_none());
}

/// The cases the quirk table holds back (the heavy ones on every backend but cpu: GPU
/// machine).
#[test]
#[ignore = "8192x8192 and 2^26 photons take minutes on lavapipe/PoCL; run on the GPU machine"]
fn heavy_cases_on_every_backend() {
    run("heavy stiff cases", |held| held.is_some());
}
