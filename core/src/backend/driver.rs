//! The driver locks every GPU backend takes (docs/embedding.md, "Threads"), and
//! [`DriverBackend`]: a GPU backend's body, whose [`Backend`] implementation, written here
//! once for wgpu, OpenCL and Vulkan, runs every driver entry inside [`driver_entry`].

use super::{Backend, BackendError, Capabilities, Finished, PassTime, Submission};
use crate::device::handle::ResourceId;
use crate::recording::Recording;

/// Runs `f` holding `lock`, with `held` marking this thread as the holder (the caller
/// checks it first, so nested calls do not lock again).
fn held_once<T>(
    lock: &std::sync::Mutex<()>,
    held: &'static std::thread::LocalKey<std::cell::Cell<bool>>,
    f: impl FnOnce() -> T,
) -> T {
    let _guard = lock.lock().unwrap_or_else(|e| e.into_inner());
    held.with(|h| h.set(true));
    let out = f();
    held.with(|h| h.set(false));
    out
}

/// Runs `f`, a call into a GPU driver (a backend's creation, `execute`, `read`, drop), one
/// at a time in the process; `CAUSTICA_SERIALIZE_DRIVERS=0` lets them run at once.
///
/// Why (docs/embedding.md, "Threads"): on NVIDIA's driver, the GPU
/// backends used from parallel threads of one process deadlock in the user-mode driver
/// (threads asleep on its priority-inheritance locks, the GPU idle). With every driver
/// entry of the three GPU backends serialised, 6 of 52 parallel conformance runs on the
/// H200 hung, against 22 of 38 without: a mitigation, not a cure. A backend used alone
/// takes an uncontended lock. Calls a host makes on its own device are not covered.
/// Nested calls on one thread do not lock again.
pub fn driver_entry<T>(f: impl FnOnce() -> T) -> T {
    use std::sync::{Mutex, OnceLock};
    static ON: OnceLock<bool> = OnceLock::new();
    static LOCK: Mutex<()> = Mutex::new(());
    thread_local! {
        static HELD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
    // on unless `CAUSTICA_SERIALIZE_DRIVERS=0` (the documented default)
    let on =
        *ON.get_or_init(|| !std::env::var("CAUSTICA_SERIALIZE_DRIVERS").is_ok_and(|v| v == "0"));
    if !on || HELD.with(|h| h.get()) {
        return f();
    }
    held_once(&LOCK, &HELD, f)
}

/// Runs `f`, a creation or destruction of a GPU driver object that reaches below the API
/// (devices, contexts, ray-tracing pipelines, acceleration structures), one at a time in
/// the process, always; nested calls on one thread do not lock again.
///
/// Why (docs/embedding.md, "Threads"): user-space stacks of a hung
/// parallel run on the H200 showed a lock-order inversion inside NVIDIA's driver, between
/// two threads on two different Vulkan devices: `vkDestroyDevice` holds the driver's
/// global lock (`libnvidia-glsi`) and waits for a `libcuda` mutex, while destroying a
/// ray-tracing pipeline enters `libnvidia-rtcore`, takes that `libcuda` mutex and waits
/// for the global lock. Every other thread in the driver then waits on the global lock.
/// Holding one lock around every such creation and destruction, in every GPU backend,
/// keeps the two paths from interleaving (two threads creating Vulkan backends at once
/// also hung NVIDIA's driver, on the H100). Unlike [`driver_entry`], it cannot be turned
/// off.
pub fn driver_lifecycle<T>(f: impl FnOnce() -> T) -> T {
    use std::sync::Mutex;
    static LOCK: Mutex<()> = Mutex::new(());
    thread_local! {
        static HELD: std::cell::Cell<bool> = const { std::cell::Cell::new(false) };
    }
    if HELD.with(|h| h.get()) {
        return f();
    }
    held_once(&LOCK, &HELD, f)
}

/// Runs `f`, the creation or the destruction of a whole GPU backend (its device, queue,
/// context, programs or pipelines), inside both locks: [`driver_entry`], then
/// [`driver_lifecycle`], always in that order.
pub fn backend_lifecycle<T>(f: impl FnOnce() -> T) -> T {
    driver_entry(|| driver_lifecycle(f))
}

/// A backend whose work goes through a GPU driver (wgpu, OpenCL, Vulkan): what
/// [`Backend`] asks of it, without the driver lock. Every `DriverBackend` is a [`Backend`]
/// whose `execute`, `read`, `submit` and `poll` run these bodies inside [`driver_entry`]:
/// the lock is taken here, for every GPU backend, and never by a backend's own entry
/// points (a nested call on the thread that holds it does not lock again).
pub trait DriverBackend {
    /// [`Backend::name`].
    const NAME: &'static str;
    /// [`Backend::capabilities`].
    fn device_capabilities(&self) -> Capabilities;
    /// [`Backend::execute`]'s body.
    fn execute_in_driver(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError>;
    /// [`Backend::read`]'s body.
    fn read_in_driver(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError>;
    /// [`Backend::submit`]'s body.
    fn submit_in_driver(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError>;
    /// [`Backend::poll`]'s body.
    fn poll_in_driver(
        &mut self,
        submission: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError>;
    /// [`Backend::variants`].
    fn compiled_variants(&self) -> Vec<String>;
}

impl<B: DriverBackend> Backend for B {
    fn name(&self) -> &'static str {
        B::NAME
    }

    fn capabilities(&self) -> Capabilities {
        self.device_capabilities()
    }

    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        driver_entry(|| self.execute_in_driver(recording))
    }

    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        driver_entry(|| self.read_in_driver(id))
    }

    fn submit(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        driver_entry(|| self.submit_in_driver(recording, readbacks))
    }

    fn poll(
        &mut self,
        submission: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        driver_entry(|| self.poll_in_driver(submission, wait))
    }

    fn variants(&self) -> Vec<String> {
        self.compiled_variants()
    }
}

/// Implements [`DriverBackend`] for a GPU backend, written once for every backend: the
/// type must have the inherent methods the trait's bodies call (`describe`,
/// `execute_recording`, `read_resource`, `submit_recording`, `poll_submission`,
/// `variant_labels`), each in the backend's file of its concern.
/// `driver_backend!(WgpuBackend, "wgpu");`
#[macro_export]
macro_rules! driver_backend {
    ($backend:ty, $name:literal) => {
        /// `Backend` for it is core's ([`caustica_core::backend::DriverBackend`]): every
        /// body runs inside the driver lock.
        impl $crate::backend::DriverBackend for $backend {
            const NAME: &'static str = $name;

            fn device_capabilities(&self) -> $crate::backend::Capabilities {
                self.describe()
            }

            fn execute_in_driver(
                &mut self,
                recording: &$crate::recording::Recording,
            ) -> Result<Vec<$crate::backend::PassTime>, $crate::backend::BackendError> {
                self.execute_recording(recording)
            }

            fn read_in_driver(
                &mut self,
                id: $crate::device::handle::ResourceId,
            ) -> Result<Vec<u8>, $crate::backend::BackendError> {
                self.read_resource(id)
            }

            fn submit_in_driver(
                &mut self,
                recording: &$crate::recording::Recording,
                readbacks: &[$crate::device::handle::ResourceId],
            ) -> Result<$crate::backend::Submission, $crate::backend::BackendError> {
                self.submit_recording(recording, readbacks)
            }

            fn poll_in_driver(
                &mut self,
                submission: &mut $crate::backend::Submission,
                wait: bool,
            ) -> Result<Option<$crate::backend::Finished>, $crate::backend::BackendError> {
                self.poll_submission(submission, wait)
            }

            fn compiled_variants(&self) -> Vec<String> {
                self.variant_labels()
            }
        }
    };
}
