#![warn(missing_docs)]
//! caustica OpenCL backend: every registry kernel in OpenCL C 1.2 (`kernels/<kernel>.cl`
//! beside the shared files of `kernels/common/`, functions named as core's scalar
//! functions), software traversal of core's flattened CWBVH, the counter-based RNG and the
//! fixed-point deposit with 32-bit atomics. Runs on any OpenCL platform: PoCL on CPUs,
//! NVIDIA's driver on the GPU machine.
//!
//! The OpenCL API comes through `opencl3`/`cl3` with their `dynamic` feature: the ICD
//! loader (`libOpenCL.so.1`, from Debian's `ocl-icd-libopencl1`) is opened with `dlopen`
//! on first use, not linked, so a binary with this backend starts on a machine without
//! OpenCL and this backend reports itself unavailable there (no loader, no platform or no
//! device), with what to install. No development package is needed to build it.
//!
//! Buffers stay on the device between passes and recordings; data comes back only
//! through [`Backend::read`] and a submission's readbacks. Kernel times are device
//! timestamps (profiling events). [`Backend::submit`] only enqueues (writes and readbacks
//! non-blocking, a marker event last, a flush): the host's frame loop does not wait.
//!
//! The crate's files, as in every caustica backend: `lib.rs` (this: the public face and
//! the backend trait's implementation, which delegates), `device.rs` (platforms, devices,
//! the shared context, the queue, capabilities, OpenCL errors), `memory.rs` (buffers and
//! the submissions' pinned staging), [`pipelines`] (the OpenCL C programs and their
//! variants, built once per device), `recording.rs` (the interpreter that enqueues a
//! recording's steps and launches), `submission.rs` (submit, poll, profiling times).
//!
//! [`Backend::read`]: caustica_core::backend::Backend::read
//! [`Backend::submit`]: caustica_core::backend::Backend::submit

mod device;
mod memory;
pub mod pipelines;
mod recording;
mod submission;

use caustica_core::backend::{
    backend_lifecycle, driver_entry, BackendError, ResourceTable, Submissions,
};
use device::DeviceState;
pub use device::{list_devices, DeviceSummary};
use opencl3::command_queue::CommandQueue;
use std::sync::Arc;

/// The OpenCL backend.
pub struct OpenClBackend {
    state: Arc<DeviceState>,
    queue: CommandQueue,
    buffers: ResourceTable<memory::DeviceBuffer>,
    /// Labels of the kernel variants this backend has run (their programs are built once
    /// per device and shared, see `DeviceState::program_for`).
    variants: std::sync::Mutex<std::collections::BTreeSet<String>>,
    /// Kernel objects by program handle and kernel name, created on first launch and kept
    /// for the backend's life: arguments are taken at enqueue, so one object serves every
    /// launch (`recording::run`). Creating one a launch cost the host a driver call, and
    /// releasing one while its launch was queued made NVIDIA's driver wait for it. An
    /// object keeps its last launch's buffers as arguments; OpenCL does not retain them
    /// for it (a driver that did would keep a freed buffer until that kernel's next
    /// launch).
    kernels:
        std::sync::Mutex<std::collections::HashMap<(usize, &'static str), opencl3::kernel::Kernel>>,
    /// Submissions not yet collected (`Backend::submit`), and the results of those retired
    /// before they were polled.
    submissions: Submissions<submission::InFlight>,
    /// Staging slots free for the next submission (`memory.rs`).
    free_slots: Vec<memory::StagingSlot>,
    /// Alignment of parameter sub-buffers (`CL_DEVICE_MEM_BASE_ADDR_ALIGN`, bytes).
    param_align: usize,
}

impl OpenClBackend {
    /// Opens the chosen device (`CAUSTICA_OPENCL_DEVICE=N`, else the first GPU, else the
    /// first device). No loader, platform or device, or a failed kernel build, is an error.
    pub fn new() -> Result<OpenClBackend, BackendError> {
        backend_lifecycle(OpenClBackend::open)
    }

    /// The device in use.
    pub fn device(&self) -> &DeviceSummary {
        &self.state.info
    }
}

/// Waits for the queue, then releases the submissions and staging slots (their pinned
/// memory is unmapped on the queue, which must still exist) before the queue goes.
impl Drop for OpenClBackend {
    fn drop(&mut self) {
        driver_entry(|| {
            let _ = self.queue.finish();
            self.submissions.clear();
            self.free_slots.clear();
            let _ = self.queue.finish();
        })
    }
}

caustica_core::driver_backend!(OpenClBackend, "opencl");

impl OpenClBackend {
    /// The compiled kernel variants, labelled ([`caustica_core::kernels::variant_label`]).
    pub(crate) fn variant_labels(&self) -> Vec<String> {
        let v = self.variants.lock().unwrap_or_else(|e| e.into_inner());
        v.iter().cloned().collect()
    }
}
