//! OpenCL platforms and devices: discovery without panics (no loader, no platform and no
//! device are typed errors), the choice of device, and one shared context + built
//! program per device, so that a program is compiled once per device and source; the
//! backend's command queue and what it reports of the device; OpenCL errors as typed
//! backend errors (allocation failures become `OutOfMemory`, the rest `Driver` with the
//! call that failed and the status name).

use crate::pipelines;
use crate::OpenClBackend;
use caustica_core::backend::{BackendError, Capabilities, DeviceType};
use opencl3::command_queue::{CommandQueue, CL_QUEUE_PROFILING_ENABLE};
use opencl3::context::Context;
use opencl3::device::{Device, CL_DEVICE_TYPE_ALL, CL_DEVICE_TYPE_CPU, CL_DEVICE_TYPE_GPU};
use opencl3::error_codes::{
    error_text, ClError, CL_MEM_OBJECT_ALLOCATION_FAILURE, CL_OUT_OF_HOST_MEMORY,
    CL_OUT_OF_RESOURCES,
};
use opencl3::kernel::Kernel;
use opencl3::memory::{Buffer, ClMem, CL_MEM_READ_WRITE};
use opencl3::platform::{get_platforms, Platform};
use opencl3::program::Program;
use opencl3::types::cl_context_properties;
use opencl3::types::{cl_int, CL_BLOCKING};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// A device with its shared context and built programs.
pub struct DeviceState {
    /// The device.
    pub device: Device,
    /// The context of this device alone (on its platform).
    pub context: Context,
    /// Every kernel without variants.
    pub program: Arc<Program>,
    /// Programs of kernel variants by label and the relaxed-division program, built on
    /// first use ([`DeviceState::program_for`]).
    pub(crate) variants: Mutex<HashMap<String, Arc<Program>>>,
    /// What the backend reports about the device.
    pub info: DeviceSummary,
}

/// What the backend reports about its device.
#[derive(Clone, Debug)]
pub struct DeviceSummary {
    /// Device name (`CL_DEVICE_NAME`).
    pub name: String,
    /// Platform name (`CL_PLATFORM_NAME`).
    pub platform: String,
    /// OpenCL version the device supports, `major.minor` (from `CL_DEVICE_VERSION`).
    pub version: String,
    /// Whether the device is a GPU.
    pub is_gpu: bool,
    /// GPU (integrated when it shares host memory), or a CPU device (a GPU API in
    /// software, as PoCL's).
    pub device_type: DeviceType,
    /// Device buffers live in host memory (a CPU device such as PoCL's, or a GPU with
    /// `CL_DEVICE_HOST_UNIFIED_MEMORY`).
    pub host_memory: bool,
    /// Largest single buffer, bytes (`CL_DEVICE_MAX_MEM_ALLOC_SIZE`).
    pub max_alloc_bytes: u64,
    /// Device memory, bytes (`CL_DEVICE_GLOBAL_MEM_SIZE`).
    pub global_mem_bytes: u64,
    /// `cl_khr_int64_base_atomics` is offered.
    pub int64_atomics: bool,
    /// `cl_khr_fp64` is offered.
    pub fp64: bool,
}

/// The backend's `Unavailable` error with `reason`.
fn unavailable(reason: impl Into<String>) -> BackendError {
    BackendError::Unavailable {
        backend: "opencl".into(),
        reason: reason.into(),
    }
}

/// Serialises platform and device discovery: PoCL answers concurrent first queries from
/// two threads with CL_DEVICE_NOT_FOUND for one of them (seen in the test harness).
static DISCOVERY: Mutex<()> = Mutex::new(());

/// Opens the OpenCL ICD loader (`libOpenCL.so.1`, or the paths in `OPENCL_DYLIB_PATH`)
/// once per process; a missing loader is `Unavailable` with what to install.
fn open_loader() -> Result<(), BackendError> {
    match cl3::load_library() {
        Ok(_) => Ok(()),
        Err(e) => Err(unavailable(format!(
            "the OpenCL ICD loader (libOpenCL.so.1) was not found or could not be opened \
             ({e}): install ocl-icd-libopencl1 (scripts/install-drivers.sh) or a GPU \
             driver's OpenCL loader, or name the loader's path in OPENCL_DYLIB_PATH"
        ))),
    }
}

/// Every (platform, device) pair, in platform order.
pub fn list_devices() -> Result<Vec<(Platform, Device)>, BackendError> {
    let _guard = DISCOVERY.lock().unwrap_or_else(|e| e.into_inner());
    open_loader()?;
    let platforms = match get_platforms() {
        Ok(p) if !p.is_empty() => p,
        r => {
            let status = match r {
                Err(e) => status_text(e.0),
                Ok(_) => "0 platforms".into(),
            };
            return Err(unavailable(format!(
                "no OpenCL platform (clGetPlatformIDs: {status}); install an ICD such as \
                 pocl-opencl-icd (scripts/install-drivers.sh) or a GPU driver"
            )));
        }
    };
    let mut out = Vec::new();
    for p in platforms {
        // A platform without devices answers CL_DEVICE_NOT_FOUND: skip it.
        if let Ok(devices) = p.get_devices(CL_DEVICE_TYPE_ALL) {
            out.extend(devices.into_iter().map(|d| (p, Device::new(d))));
        }
    }
    if out.is_empty() {
        return Err(unavailable("OpenCL platforms found, but no device"));
    }
    Ok(out)
}

/// The `major.minor` of a `CL_DEVICE_VERSION` string (`OpenCL<space><major.minor><space>
/// <vendor-specific information>`, e.g. `3.0` for PoCL's `OpenCL 3.0 PoCL HSTR: ...`),
/// or the whole string, trimmed, when it does not have that form.
fn opencl_version(s: &str) -> String {
    let mut words = s.split_whitespace();
    if let (Some(w), Some(v)) = (words.next(), words.next()) {
        let numbers = v.split_once('.').filter(|(major, minor)| {
            [major, minor]
                .iter()
                .all(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
        });
        if w.eq_ignore_ascii_case("opencl") && numbers.is_some() {
            return v.to_string();
        }
    }
    s.trim().to_string()
}

/// Queries what [`DeviceSummary`] holds.
fn summary(platform: Platform, device: Device) -> Result<DeviceSummary, BackendError> {
    let info = cl_error("device info");
    let name = device.name().map_err(&info)?;
    let version = opencl_version(&device.version().map_err(&info)?);
    let extensions = device.extensions().map_err(&info)?;
    let is_gpu = device.dev_type().map_err(&info)? & CL_DEVICE_TYPE_GPU != 0;
    let device_type = if is_gpu {
        if device.host_unified_memory().unwrap_or(false) {
            DeviceType::IntegratedGpu
        } else {
            DeviceType::DiscreteGpu
        }
    } else if device.dev_type().map_err(&info)? & CL_DEVICE_TYPE_CPU != 0 {
        DeviceType::SoftwareGpu
    } else {
        DeviceType::Other
    };
    let max_alloc_bytes = device.max_mem_alloc_size().map_err(&info)?;
    let global_mem_bytes = device.global_mem_size().map_err(&info)?;
    let platform_name = platform.name().unwrap_or_default();
    Ok(DeviceSummary {
        name: name.trim().to_string(),
        platform: platform_name.trim().to_string(),
        version,
        is_gpu,
        device_type,
        host_memory: device_type != DeviceType::DiscreteGpu,
        max_alloc_bytes,
        global_mem_bytes,
        int64_atomics: extensions.contains("cl_khr_int64_base_atomics"),
        fp64: extensions.contains("cl_khr_fp64"),
    })
}

/// The device to use: `CAUSTICA_OPENCL_DEVICE=N` picks the N-th device of
/// [`list_devices`]; otherwise the first GPU, else the first device.
pub fn choose_device() -> Result<(Platform, Device), BackendError> {
    let devices = list_devices()?;
    if let Ok(v) = std::env::var("CAUSTICA_OPENCL_DEVICE") {
        let n: usize = v.trim().parse().map_err(|_| {
            unavailable(format!(
                "CAUSTICA_OPENCL_DEVICE='{v}' is not a device number"
            ))
        })?;
        return devices.get(n).copied().ok_or_else(|| {
            unavailable(format!(
                "CAUSTICA_OPENCL_DEVICE={n}, but the devices are numbered 0 to {}",
                devices.len().saturating_sub(1)
            ))
        });
    }
    for &(p, d) in &devices {
        if summary(p, d).map(|s| s.is_gpu).unwrap_or(false) {
            return Ok((p, d));
        }
    }
    Ok(devices[0])
}

/// Device states by device id (as an address), one per device and process.
type Registry = Mutex<HashMap<usize, Arc<DeviceState>>>;

/// The shared state of a device: context and program are created once per process and
/// device (the program cache), then shared by every backend on that device.
pub fn device_state(platform: Platform, device: Device) -> Result<Arc<DeviceState>, BackendError> {
    static REGISTRY: OnceLock<Registry> = OnceLock::new();
    let registry = REGISTRY.get_or_init(Default::default);
    let key = device.id() as usize;
    let mut map = registry.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = map.get(&key) {
        return Ok(Arc::clone(s));
    }
    let info = summary(platform, device)?;
    let props: [cl_context_properties; 3] = [
        cl3::context::CL_CONTEXT_PLATFORM as cl_context_properties,
        platform.id() as cl_context_properties,
        0,
    ];
    let context = Context::from_devices(&[device.id()], &props, None, std::ptr::null_mut())
        .map_err(cl_error("creating the context"))?;
    let program = Arc::new(pipelines::build(&context, device.id())?);
    let state = Arc::new(DeviceState {
        device,
        context,
        program,
        variants: Mutex::new(HashMap::new()),
        info,
    });
    map.insert(key, Arc::clone(&state));
    Ok(state)
}

/// An OpenCL status code as its name and number, e.g. `CL_INVALID_VALUE (-30)`.
pub fn status_text(status: cl_int) -> String {
    format!("{} ({status})", error_text(status))
}

/// Maps the OpenCL error of a call made while doing `what` to a backend error.
pub fn cl_error(what: &'static str) -> impl Fn(ClError) -> BackendError {
    move |e| match e.0 {
        CL_MEM_OBJECT_ALLOCATION_FAILURE | CL_OUT_OF_RESOURCES | CL_OUT_OF_HOST_MEMORY => {
            BackendError::OutOfMemory {
                bytes: 0,
                what: format!("{what} ({})", status_text(e.0)),
            }
        }
        _ => BackendError::Driver(format!("{what}: {}", status_text(e.0))),
    }
}

impl OpenClBackend {
    /// [`OpenClBackend::new`]'s body.
    pub(crate) fn open() -> Result<OpenClBackend, BackendError> {
        let (platform, device) = choose_device()?;
        let state = device_state(platform, device)?;
        // clCreateCommandQueue (OpenCL 1.2): PoCL's and NVIDIA's platforms both have it.
        #[allow(deprecated)]
        let queue = unsafe {
            CommandQueue::create(&state.context, state.device.id(), CL_QUEUE_PROFILING_ENABLE)
        }
        .map_err(cl_error("creating the command queue"))?;
        // sub-buffer origins must be multiples of the base address alignment (bits)
        let param_align = (state
            .device
            .mem_base_addr_align()
            .map_err(cl_error("querying CL_DEVICE_MEM_BASE_ADDR_ALIGN"))?
            as usize
            / 8)
        .max(16);
        Ok(OpenClBackend {
            state,
            queue,
            buffers: Default::default(),
            variants: Default::default(),
            kernels: Default::default(),
            submissions: Default::default(),
            free_slots: Vec::new(),
            param_align,
        })
    }

    /// `sizeof` of every shared struct as the device compiler lays it out, in the order
    /// of the generated `kernels/common/layout.cl`'s `struct_sizes`, which is core's
    /// layout table's (`caustica_core::device::layout_table::structs`; checked against
    /// Rust's `size_of` in tests).
    pub fn device_struct_sizes(&mut self) -> Result<Vec<u32>, BackendError> {
        let n = caustica_core::device::layout_table::structs().len();
        let mem = unsafe {
            Buffer::<u32>::create(
                &self.state.context,
                CL_MEM_READ_WRITE,
                n,
                std::ptr::null_mut(),
            )
        }
        .map_err(cl_error("creating a buffer"))?;
        let kernel = Kernel::create(&self.state.program, "struct_sizes")
            .map_err(cl_error("creating a kernel"))?;
        unsafe { kernel.set_arg(0, &mem.get()) }.map_err(cl_error("setting a kernel argument"))?;
        let mut out = vec![0u32; n];
        let global: [usize; 3] = [1, 1, 1];
        unsafe {
            self.queue
                .enqueue_nd_range_kernel(
                    kernel.get(),
                    1,
                    std::ptr::null(),
                    global.as_ptr(),
                    std::ptr::null(),
                    &[],
                )
                .map_err(cl_error("struct_sizes"))?;
            self.queue
                .enqueue_read_buffer(&mem, CL_BLOCKING, 0, &mut out, &[])
                .map_err(cl_error("reading a buffer"))?;
        }
        Ok(out)
    }

    /// What the device can do ([`caustica_core::backend::Backend::capabilities`]).
    pub(crate) fn describe(&self) -> Capabilities {
        let i = &self.state.info;
        Capabilities {
            device: format!("{} ({}, {})", i.name, i.platform, i.version),
            device_type: i.device_type,
            hardware_ray_tracing: false,
            float_atomics: false,
            int64_atomics: i.int64_atomics,
            timestamps: true,
            max_buffer_bytes: i.max_alloc_bytes,
            max_buffer_limit: "device allocation size (CL_DEVICE_MAX_MEM_ALLOC_SIZE)",
        }
    }
}

#[cfg(test)]
mod tests {
    use super::opencl_version;

    #[test]
    fn device_version_is_major_minor() {
        let pocl = "OpenCL 3.0 PoCL HSTR: pthread-x86_64-pc-linux-gnu-haswell";
        assert_eq!(opencl_version(pocl), "3.0");
        assert_eq!(opencl_version("OpenCL 3.0 CUDA"), "3.0");
        assert_eq!(opencl_version("OpenCL 1.2"), "1.2");
        assert_eq!(opencl_version(" something else "), "something else");
    }
}
