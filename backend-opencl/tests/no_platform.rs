//! Without any OpenCL platform the backend is `Unavailable` with a reason that says what
//! to install, not a panic and not a retry loop (the `ocl` crate this backend once used
//! slept 10 s). The ICD loader is pointed at an empty vendor directory (ocl-icd's
//! `OCL_ICD_VENDORS`) before its first use, which is why this test has a binary of its
//! own. A missing loader itself is checked by `scripts/check-no-opencl-link.sh`, which
//! hides it in a private mount namespace.

use caustica_core::backend::BackendError;
use caustica_opencl::OpenClBackend;

#[test]
fn no_platform_is_a_typed_error() {
    let empty = std::env::temp_dir().join(format!("caustica-no-icd-{}", std::process::id()));
    std::fs::create_dir_all(&empty).unwrap();
    std::env::set_var("OCL_ICD_VENDORS", &empty);
    let t0 = std::time::Instant::now();
    match OpenClBackend::new() {
        Err(BackendError::Unavailable { backend, reason }) => {
            assert_eq!(backend, "opencl");
            assert!(reason.contains("no OpenCL platform"), "{reason}");
        }
        Err(e) => panic!("expected Unavailable, got {e}"),
        Ok(_) => panic!("an empty vendor directory still gave a platform"),
    }
    assert!(
        t0.elapsed().as_secs() < 5,
        "discovery waited {:?}",
        t0.elapsed()
    );
}
