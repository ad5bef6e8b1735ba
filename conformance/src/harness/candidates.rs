//! The backends under test: every backend this machine can open (one named in
//! `CAUSTICA_REQUIRE_BACKENDS` that cannot be opened is a failure; any other is skipped
//! with a line on stderr saying why), the CPU reference, and the candidates compared with
//! it.

use caustica_core::Backend;
use caustica_cpu::CpuBackend;
use std::io::Write;

/// Name of the reference backend in [`backends`]: the one every other backend is compared
/// with, and the only one that is never a candidate.
pub const REFERENCE_BACKEND: &str = "cpu";

/// Backends found on this machine (name, backend). Panics, loudly, when a backend listed
/// in `CAUSTICA_REQUIRE_BACKENDS` cannot be opened. `CAUSTICA_SKIP_BACKENDS` (a diagnosis
/// aid, e.g. to find which backends hang together; CI never sets it) leaves the named
/// backends unopened, loudly; naming one that is also required is a failure.
pub fn backends() -> Vec<(&'static str, Box<dyn Backend>)> {
    let required = std::env::var("CAUSTICA_REQUIRE_BACKENDS").unwrap_or_default();
    let skip = std::env::var("CAUSTICA_SKIP_BACKENDS").unwrap_or_default();
    let skipped = |name: &str| {
        let s = skip.split(',').map(str::trim).any(|s| s == name);
        if s {
            assert!(
                !required.split(',').map(str::trim).any(|r| r == name),
                "backend '{name}' is both required and skipped"
            );
            loud(&format!("SKIPPING {name} backend: CAUSTICA_SKIP_BACKENDS"));
        }
        s
    };
    let mut out: Vec<(&'static str, Box<dyn Backend>)> = Vec::new();
    match caustica_cpu::CpuBackend::new() {
        Ok(b) => out.push(("cpu", Box::new(b))),
        Err(e) => eprintln!("SKIPPING cpu backend: {e}"),
    }
    match (!skipped("opencl"))
        .then(caustica_opencl::OpenClBackend::new)
        .transpose()
    {
        Ok(None) => {}
        Ok(Some(b)) => {
            eprintln!("opencl backend: {}", b.device().name);
            out.push(("opencl", Box::new(b)));
        }
        Err(e) => eprintln!("SKIPPING opencl backend (set CAUSTICA_REQUIRE_BACKENDS to fail): {e}"),
    }
    match (!skipped("wgpu"))
        .then(caustica_wgpu::WgpuBackend::new)
        .transpose()
    {
        Ok(None) => {}
        Ok(Some(b)) => {
            eprintln!("wgpu backend: {}", b.capabilities().device);
            out.push(("wgpu", Box::new(b)));
        }
        Err(e) => eprintln!("SKIPPING wgpu backend (set CAUSTICA_REQUIRE_BACKENDS to fail): {e}"),
    }
    // The conformance suite runs Vulkan under the Khronos validation layer where it is
    // installed: any validation error fails the step that caused it.
    match (!skipped("vulkan"))
        .then(|| caustica_vulkan::VulkanBackend::with_validation(true))
        .transpose()
    {
        Ok(None) => {}
        Ok(Some(b)) => {
            eprintln!(
                "vulkan backend: {} (validation layer {})",
                b.capabilities().device,
                if b.validation_active() {
                    "on"
                } else {
                    "NOT INSTALLED"
                }
            );
            out.push(("vulkan", Box::new(b)));
        }
        Err(e) => eprintln!("SKIPPING vulkan backend (set CAUSTICA_REQUIRE_BACKENDS to fail): {e}"),
    }
    for name in required.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        assert!(
            out.iter().any(|(n, _)| *n == name),
            "required backend '{name}' is not available on this machine"
        );
    }
    out
}

/// A backend compared against the CPU reference.
pub struct Candidate {
    /// Backend name (`opencl`, ...), or `cpu[1 thread]` when no other backend exists.
    pub name: String,
    pub device: String,
    pub backend: Box<dyn Backend>,
}

/// Prints to the process's stderr even while the test harness captures output.
pub fn loud(msg: &str) {
    let _ = writeln!(std::io::stderr().lock(), "\n*** {msg} ***");
}

/// Every backend of [`backends`] except the reference (`cpu`). With none, a fresh 1-thread
/// [`CpuBackend`] stands in, so that every comparison still runs and asserts something
/// (and the suite itself is tested). Announces, loudly, what is compared with what.
pub fn candidates(test: &str) -> Vec<Candidate> {
    let mut out: Vec<Candidate> = backends()
        .into_iter()
        .filter(|(name, _)| *name != REFERENCE_BACKEND)
        .map(|(name, b)| Candidate {
            name: name.to_string(),
            device: b.capabilities().device,
            backend: b,
        })
        .collect();
    if out.is_empty() {
        let b = CpuBackend::with_threads(1).expect("a 1-thread CPU backend");
        out.push(Candidate {
            name: "cpu[1 thread]".into(),
            device: b.capabilities().device,
            backend: Box::new(b),
        });
        loud(&format!(
            "{test}: NO BACKEND OTHER THAN cpu IS AVAILABLE; comparing a second, 1-thread \
             cpu backend with the cpu reference (this checks the suite, not a backend)"
        ));
    }
    let list: Vec<String> = out
        .iter()
        .map(|c| format!("{} ({})", c.name, c.device))
        .collect();
    loud(&format!(
        "{test}: comparing [{}] against the cpu reference",
        list.join(", ")
    ));
    out
}

/// The reference: the CPU backend on every core.
pub fn reference() -> CpuBackend {
    CpuBackend::new().expect("the CPU reference backend")
}

/// Runs `check` (reference, candidate, input) on [`crate::strategies::config`]'s cases of
/// `inputs` for every candidate against the CPU reference; a failing verdict fails the
/// test naming the candidate, the verdict and the (shrunk) input. For kernel checks whose
/// inputs proptest draws (counts from 0 past a bound, generated grids and queues).
pub fn check_generated<S>(
    test: &str,
    inputs: S,
    check: impl Fn(&mut dyn Backend, &mut dyn Backend, &S::Value) -> Result<super::Verdict, String>,
) where
    S: proptest::strategy::Strategy,
    S::Value: std::fmt::Debug,
{
    use proptest::test_runner::{TestCaseError, TestRunner};
    let config = crate::strategies::config();
    let reference = std::cell::RefCell::new(reference());
    for cand in candidates(test) {
        let backend = std::cell::RefCell::new(cand.backend);
        let mut runner = TestRunner::new(config.clone());
        let result = runner.run(&inputs, |input| {
            let mut r = reference.borrow_mut();
            let mut c = backend.borrow_mut();
            let v = check(&mut *r, c.as_mut(), &input).map_err(TestCaseError::fail)?;
            if v.passed() {
                Ok(())
            } else {
                Err(TestCaseError::fail(format!("{v}input {input:?}")))
            }
        });
        if let Err(e) = result {
            panic!("{}: {e}", cand.name);
        }
        loud(&format!(
            "{test}: {} agrees on {} generated cases",
            cand.name, config.cases
        ));
    }
}
