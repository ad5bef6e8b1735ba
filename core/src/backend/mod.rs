//! The `Backend` trait: small and object-safe, so `Box<dyn Backend>` gives run-time
//! backend choice without generics leaking into user code. A backend owns kernels and
//! resources; core owns algorithms.
//!
//! What every backend would otherwise repeat is written once here: the driver locks and
//! the [`Backend`] of every GPU backend ([`DriverBackend`], in `driver.rs`), the table of
//! a backend's buffers and the bounds check of a write ([`ResourceTable`], [`check_write`],
//! in `resources.rs`), and the submissions with the book-keeping of an asynchronous
//! backend ([`Submissions`], in `submission.rs`).

pub use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes, ResourceId};
use crate::device::layout::{deposit_from_planes, gbuffer_from_planes, DepositTexel, GBufferTexel};
use crate::recording::Recording;

mod driver;
mod resources;
mod submission;

pub use driver::{backend_lifecycle, driver_entry, driver_lifecycle, DriverBackend};
pub use resources::{check_write, ResourceTable};
pub use submission::{
    pass_times_from_ticks, unknown_submission, Finished, Submission, Submissions,
    UncollectedResults, MAX_FRAMES_IN_FLIGHT, MAX_UNCOLLECTED,
};

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
