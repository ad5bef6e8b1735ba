//! The `Backend` trait: small and object-safe, so `Box<dyn Backend>` gives run-time
//! backend choice without generics leaking into user code. A backend owns kernels and
//! resources; core owns algorithms.

pub use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes, ResourceId};
use crate::device::layout::{deposit_from_planes, gbuffer_from_planes, DepositTexel, GBufferTexel};
use crate::recording::Recording;

/// What kind of device a backend runs on (what `auto` chooses by).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize)]
#[serde(rename_all = "snake_case")]
pub enum DeviceType {
    /// A GPU with its own memory.
    DiscreteGpu,
    /// A GPU sharing the host's memory.
    IntegratedGpu,
    /// A GPU exposed through a virtual machine.
    VirtualGpu,
    /// A GPU API implemented in software on the CPU: a software rasteriser such as Mesa's
    /// lavapipe/llvmpipe, or an OpenCL CPU device such as PoCL's.
    SoftwareGpu,
    /// caustica's native CPU backend (rayon + obvhs).
    Cpu,
    /// The driver did not say.
    #[default]
    Other,
}

impl DeviceType {
    /// Whether this is a hardware GPU.
    pub fn is_hardware_gpu(&self) -> bool {
        matches!(
            self,
            DeviceType::DiscreteGpu | DeviceType::IntegratedGpu | DeviceType::VirtualGpu
        )
    }

    /// `auto`'s preference, lower first: hardware GPUs (discrete, integrated, virtual),
    /// then the native CPU backend, then GPU APIs emulated on the CPU (the native CPU
    /// backend was 2-5x faster than Vulkan on llvmpipe on the same cores), then unknown.
    pub fn auto_rank(&self) -> u32 {
        match self {
            DeviceType::DiscreteGpu => 0,
            DeviceType::IntegratedGpu => 1,
            DeviceType::VirtualGpu => 2,
            DeviceType::Cpu => 3,
            DeviceType::SoftwareGpu => 4,
            DeviceType::Other => 5,
        }
    }

    /// A short label (`discrete GPU`, `software GPU on the CPU`, ...).
    pub fn label(&self) -> &'static str {
        match self {
            DeviceType::DiscreteGpu => "discrete GPU",
            DeviceType::IntegratedGpu => "integrated GPU",
            DeviceType::VirtualGpu => "virtual GPU",
            DeviceType::SoftwareGpu => "software GPU on the CPU",
            DeviceType::Cpu => "native CPU",
            DeviceType::Other => "unknown device type",
        }
    }
}

/// What a backend's device can do (queried, not cfg'd).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct Capabilities {
    /// Human-readable device name.
    pub device: String,
    /// What kind of device it is.
    pub device_type: DeviceType,
    /// Rays are traced by the driver's ray-tracing pipeline (Vulkan) rather than by a
    /// software CWBVH traversal in a compute kernel.
    pub hardware_ray_tracing: bool,
    /// Kernels use floating-point atomic adds (the photon map does not need them: it sums
    /// in integer fixed point).
    pub float_atomics: bool,
    /// The device offers 64-bit integer atomics (informational: the GPU kernels add 64-bit
    /// sums as (lo, hi) pairs of `u32` words with a carry, which gives the same result).
    pub int64_atomics: bool,
    /// Kernel times ([`PassTime`]) are device timestamps; otherwise host wall clock.
    pub timestamps: bool,
    /// Largest single buffer a kernel can use (bytes): the smaller of the device's largest
    /// allocation and its largest storage binding.
    pub max_buffer_bytes: u64,
    /// Which limit `max_buffer_bytes` is, in words (e.g. "storage-binding size
    /// (maxStorageBufferRange)"), for error messages.
    pub max_buffer_limit: &'static str,
}

/// Wall or device time of one executed kernel.
#[derive(Clone, Debug, PartialEq)]
pub struct PassTime {
    /// Registry name of the kernel.
    pub kernel: &'static str,
    /// Its time in seconds (device timestamps or host wall clock, see
    /// [`Capabilities::timestamps`]).
    pub seconds: f64,
}

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
/// keeps the two paths from interleaving. Unlike [`driver_entry`], it cannot be turned
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

/// A compute backend.
pub trait Backend {
    /// Short name used on the command line (`cpu`, `opencl`, ...).
    fn name(&self) -> &'static str;
    /// What the device can do, queried from the driver.
    fn capabilities(&self) -> Capabilities;
    /// Executes every step in order and waits for them; returns the time of each kernel
    /// step.
    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError>;
    /// Reads a buffer's bytes back to the host (waits for the work queued before it).
    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError>;

    /// Enqueues every step of `recording` and returns without waiting for the device
    /// (the non-blocking frame). After the last step the buffers in
    /// `readbacks` are copied into host memory, so that their values at that point can be
    /// collected later with [`Backend::poll`] while later submissions change them.
    /// Submissions run in the order they were made; [`Backend::read`] and
    /// [`Backend::execute`] wait for them.
    ///
    /// The default runs the recording at once ([`Backend::execute`], then reads): right
    /// for the CPU backend, whose work is the host's, and for wrappers.
    fn submit(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        let times = self.execute(recording)?;
        let readbacks = readbacks
            .iter()
            .map(|id| self.read(*id))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Submission::finished(Finished { times, readbacks }))
    }

    /// A submission's result once the device has finished it: `Ok(None)` while it still
    /// runs and `wait` is false (never blocks then); with `wait`, blocks until it is done.
    /// The result is handed out once; polling again is an error.
    fn poll(
        &mut self,
        submission: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        let _ = wait;
        submission.take_finished().map(Some)
    }
    /// Labels of the kernel variants this backend has compiled so far (GPU backends:
    /// pipelines/programs built on demand; CPU: the monomorphised variants it has run),
    /// as [`crate::kernels::variant_label`] writes them. Conformance checks that a scene
    /// compiles no variant it does not need.
    fn variants(&self) -> Vec<String>;
}

/// A recording submitted with [`Backend::submit`], not yet collected.
#[derive(Debug)]
pub struct Submission {
    /// The backend's number for it (increasing in submission order).
    pub id: u64,
    state: SubmissionState,
}

#[derive(Debug)]
enum SubmissionState {
    /// On the device; the backend holds what it will give back.
    Pending,
    /// Done when submitted (the default [`Backend::submit`]).
    Finished(Finished),
    /// Its result was handed out.
    Collected,
}

impl Submission {
    /// A submission still on the device, numbered `id` by its backend.
    pub fn pending(id: u64) -> Submission {
        Submission {
            id,
            state: SubmissionState::Pending,
        }
    }

    /// A submission that finished when it was made.
    pub fn finished(result: Finished) -> Submission {
        Submission {
            id: 0,
            state: SubmissionState::Finished(result),
        }
    }

    /// Whether the backend still owes its result.
    pub fn is_pending(&self) -> bool {
        matches!(self.state, SubmissionState::Pending)
    }

    /// Marks the result handed out (a backend's `poll` calls this when it gives it).
    pub fn mark_collected(&mut self) {
        self.state = SubmissionState::Collected;
    }

    /// The result of a submission that finished when it was made; an error if it was
    /// collected already or is still pending (a backend's own `poll` handles those).
    pub fn take_finished(&mut self) -> Result<Finished, BackendError> {
        match std::mem::replace(&mut self.state, SubmissionState::Collected) {
            SubmissionState::Finished(f) => Ok(f),
            SubmissionState::Collected => Err(BackendError::BadArgument(format!(
                "submission {} was collected already",
                self.id
            ))),
            SubmissionState::Pending => {
                self.state = SubmissionState::Pending;
                Err(BackendError::BadArgument(format!(
                    "submission {} belongs to another backend",
                    self.id
                )))
            }
        }
    }
}

/// Most submissions a backend keeps uncollected: beyond it, the oldest is waited for and
/// its result discarded (polling it later is an error), so a host that never asks for
/// its frames' statistics does not grow the backend's memory.
pub const MAX_UNCOLLECTED: usize = 64;

/// What an asynchronous backend keeps of the submissions it finished before they were
/// polled (waited for to free a slot, or to bound its uncollected work), oldest dropped
/// first beyond [`MAX_UNCOLLECTED`]; and the start of every such backend's `poll`.
#[derive(Debug, Default)]
pub struct UncollectedResults {
    results: std::collections::BTreeMap<u64, Result<Finished, BackendError>>,
}

impl UncollectedResults {
    /// Keeps the result of submission `id` until it is polled.
    pub fn keep(&mut self, id: u64, result: Result<Finished, BackendError>) {
        if self.results.len() >= MAX_UNCOLLECTED {
            self.results.pop_first();
        }
        self.results.insert(id, result);
    }

    /// A poll's answer that needs no device: a submission that finished when it was made,
    /// one collected already (an error), or one kept here. `None`: the backend looks at
    /// its work in flight.
    pub fn settle(
        &mut self,
        submission: &mut Submission,
    ) -> Option<Result<Option<Finished>, BackendError>> {
        if !submission.is_pending() {
            return Some(submission.take_finished().map(Some));
        }
        let r = self.results.remove(&submission.id)?;
        submission.mark_collected();
        Some(r.map(Some))
    }

    /// Forgets every kept result.
    pub fn clear(&mut self) {
        self.results.clear();
    }
}

/// The error of polling a submission a backend neither has in flight nor kept.
pub fn unknown_submission(id: u64) -> BackendError {
    BackendError::BadArgument(format!(
        "submission {id} is not one of this backend's, or its result was discarded \
         ({MAX_UNCOLLECTED} newer submissions were left uncollected)"
    ))
}

/// What a finished submission gives back.
#[derive(Clone, Debug, Default)]
pub struct Finished {
    /// Time of each kernel step, in order (see [`Capabilities::timestamps`]).
    pub times: Vec<PassTime>,
    /// The bytes of each buffer asked for in [`Backend::submit`]'s `readbacks`, in that
    /// order, as they were after the submission's last step.
    pub readbacks: Vec<Vec<u8>>,
}

/// Reads a typed buffer back.
pub fn read_buf<T: bytemuck::Pod>(
    backend: &mut dyn Backend,
    buf: Buf<T>,
) -> Result<Vec<T>, BackendError> {
    let bytes = backend.read(buf.id)?;
    if bytes.len() as u64 != buf.bytes() {
        return Err(BackendError::BadArgument(format!(
            "buffer {:?} holds {} bytes, expected {}",
            buf.id,
            bytes.len(),
            buf.bytes()
        )));
    }
    Ok(bytemuck::pod_collect_to_vec(&bytes))
}

/// Reads the G-buffer's planes back and assembles its texels
/// ([`crate::device::layout::gbuffer_from_planes`]).
pub fn read_gbuffer(
    backend: &mut dyn Backend,
    g: &GBufferPlanes,
) -> Result<Vec<GBufferTexel>, BackendError> {
    let [a, b, c, d] = g.planes;
    let (a, b, c, d) = (
        read_buf(backend, a)?,
        read_buf(backend, b)?,
        read_buf(backend, c)?,
        read_buf(backend, d)?,
    );
    Ok(gbuffer_from_planes([&a, &b, &c, &d]))
}

/// Reads the screen photon map's planes back and assembles its texels
/// ([`crate::device::layout::deposit_from_planes`]).
pub fn read_photon_map(
    backend: &mut dyn Backend,
    m: &PhotonMapPlanes,
) -> Result<Vec<DepositTexel>, BackendError> {
    let [a, b, c] = m.planes;
    let (a, b, c) = (
        read_buf(backend, a)?,
        read_buf(backend, b)?,
        read_buf(backend, c)?,
    );
    Ok(deposit_from_planes([&a, &b, &c]))
}
