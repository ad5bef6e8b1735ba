//! The OpenCL program builds on this machine's platform, and the device compiler lays out
//! every shared struct (the generated kernels/common/layout.cl) with Rust's sizes. Fails loudly when no OpenCL platform exists
//! (CI installs PoCL with scripts/install-drivers.sh).

use caustica_core::device::layout_table;
use caustica_opencl::OpenClBackend;

#[test]
fn struct_sizes_match_core() {
    let mut b = OpenClBackend::new().unwrap_or_else(|e| panic!("OpenCL backend unavailable: {e}"));
    eprintln!("OpenCL device: {:?}", b.device());
    let sizes = b.device_struct_sizes().unwrap();
    let structs = layout_table::structs();
    assert_eq!(sizes.len(), structs.len());
    for (s, cl) in structs.iter().zip(&sizes) {
        assert_eq!(
            s.size as u32, *cl,
            "{}: Rust {} bytes, OpenCL {cl}",
            s.name, s.size
        );
    }
}

#[test]
fn build_failure_returns_the_log() {
    let b = OpenClBackend::new().unwrap();
    let err =
        b.build_test_program("__kernel void broken(__global uint* x) { x[0] = undefined_name; }");
    let msg = err.expect_err("a broken kernel does not build").to_string();
    assert!(
        msg.contains("build log") && msg.contains("undefined_name"),
        "{msg}"
    );
}

#[test]
fn oversized_buffer_is_out_of_memory() {
    use caustica_core::backend::{Backend, BackendError};
    use caustica_core::recording::Recording;
    let mut b = OpenClBackend::new().unwrap();
    let max = b.capabilities().max_buffer_bytes;
    let mut rec = Recording::new();
    // More elements of 16 bytes than the device allows in one buffer.
    let n = (max / 16 + 1).min(u32::MAX as u64) as u32;
    let _ = rec.create::<[f32; 4]>(n, "too big");
    if (n as u64) * 16 <= max {
        eprintln!("device allows {max} bytes: a u32-counted buffer cannot exceed it");
        return;
    }
    match b.execute(&rec) {
        Err(BackendError::OutOfMemory { bytes, what }) => {
            assert_eq!(bytes, n as u64 * 16);
            assert!(what.contains("too big"), "{what}");
        }
        other => panic!("expected OutOfMemory, got {other:?}"),
    }
}
