//! OpenCL platforms and devices: discovery without panics (no loader, no platform and no
//! device are typed errors), the choice of device, and one shared context + built
//! program per device, so that a program is compiled once per device and source.

use crate::error::cl_error;
use crate::program;
use caustica_core::backend::BackendError;
use ocl::core::{
    self, ContextProperties, DeviceId, DeviceInfo, DeviceInfoResult, DeviceType, PlatformId,
    PlatformInfo,
};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// A device with its shared context and built programs.
pub struct DeviceState {
    pub device: DeviceId,
    pub context: core::Context,
    /// Every kernel without variants.
    pub program: core::Program,
    /// Programs of kernel variants by label, built on first use.
    variants: Mutex<HashMap<String, core::Program>>,
    pub info: DeviceSummary,
}

impl DeviceState {
    /// The program holding variant `constants` of `kernel` (the base program for a
    /// kernel without switches), building it on first use.
    pub fn program_for(
        &self,
        kernel: &str,
        constants: &[(&'static str, bool)],
    ) -> Result<core::Program, BackendError> {
        if constants.is_empty() {
            return Ok(self.program.clone());
        }
        let label = caustica_core::kernels::variant_label(kernel, constants);
        let mut map = self.variants.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = map.get(&label) {
            return Ok(p.clone());
        }
        let p = program::build_variant(&self.context, self.device, kernel, constants)?;
        map.insert(label, p.clone());
        Ok(p)
    }
}

/// What the backend reports about its device.
#[derive(Clone, Debug)]
pub struct DeviceSummary {
    pub name: String,
    pub platform: String,
    pub version: String,
    pub is_gpu: bool,
    pub max_alloc_bytes: u64,
    pub global_mem_bytes: u64,
    pub int64_atomics: bool,
    pub fp64: bool,
}

fn unavailable(reason: impl Into<String>) -> BackendError {
    BackendError::Unavailable {
        backend: "opencl".into(),
        reason: reason.into(),
    }
}

/// Serialises platform and device discovery: PoCL answers concurrent first queries from
/// two threads with CL_DEVICE_NOT_FOUND for one of them (seen in the test harness).
static DISCOVERY: Mutex<()> = Mutex::new(());

/// Every (platform, device) pair, in platform order.
pub fn list_devices() -> Result<Vec<(PlatformId, DeviceId)>, BackendError> {
    let _guard = DISCOVERY.lock().unwrap_or_else(|e| e.into_inner());
    // Ask the ICD loader first, directly: ocl's `get_platform_ids` sleeps and retries for
    // 10 s when no platform is installed.
    let mut n: ocl::core::ffi::cl_uint = 0;
    let status = unsafe { ocl::core::ffi::clGetPlatformIDs(0, std::ptr::null_mut(), &mut n) };
    if status != 0 || n == 0 {
        return Err(unavailable(format!(
            "no OpenCL platform (clGetPlatformIDs returned {status}, {n} platforms); \
             install an ICD such as pocl-opencl-icd (scripts/install-drivers.sh) or a GPU driver"
        )));
    }
    let platforms = core::get_platform_ids().map_err(|e| unavailable(e.to_string()))?;
    let mut out = Vec::new();
    for p in platforms {
        // A platform without devices answers CL_DEVICE_NOT_FOUND: skip it.
        if let Ok(devices) = core::get_device_ids(p, Some(DeviceType::ALL), None) {
            out.extend(devices.into_iter().map(|d| (p, d)));
        }
    }
    if out.is_empty() {
        return Err(unavailable("OpenCL platforms found, but no device"));
    }
    Ok(out)
}

fn summary(platform: PlatformId, device: DeviceId) -> Result<DeviceSummary, BackendError> {
    let info =
        |what: DeviceInfo| core::get_device_info(device, what).map_err(cl_error("device info"));
    let name = info(DeviceInfo::Name)?.to_string();
    let version = info(DeviceInfo::Version)?.to_string();
    let extensions = info(DeviceInfo::Extensions)?.to_string();
    let is_gpu =
        matches!(info(DeviceInfo::Type)?, DeviceInfoResult::Type(t) if t.contains(DeviceType::GPU));
    let max_alloc_bytes = match info(DeviceInfo::MaxMemAllocSize)? {
        DeviceInfoResult::MaxMemAllocSize(b) => b,
        _ => 0,
    };
    let global_mem_bytes = match info(DeviceInfo::GlobalMemSize)? {
        DeviceInfoResult::GlobalMemSize(b) => b,
        _ => 0,
    };
    let platform_name = core::get_platform_info(platform, PlatformInfo::Name)
        .map(|r| r.to_string())
        .unwrap_or_default();
    Ok(DeviceSummary {
        name: name.trim().to_string(),
        platform: platform_name.trim().to_string(),
        version: version.trim().to_string(),
        is_gpu,
        max_alloc_bytes,
        global_mem_bytes,
        int64_atomics: extensions.contains("cl_khr_int64_base_atomics"),
        fp64: extensions.contains("cl_khr_fp64"),
    })
}

/// The device to use: `CAUSTICA_OPENCL_DEVICE=N` picks the N-th device of
/// [`list_devices`]; otherwise the first GPU, else the first device.
pub fn choose_device() -> Result<(PlatformId, DeviceId), BackendError> {
    let devices = list_devices()?;
    if let Ok(v) = std::env::var("CAUSTICA_OPENCL_DEVICE") {
        let n: usize = v.trim().parse().map_err(|_| {
            unavailable(format!(
                "CAUSTICA_OPENCL_DEVICE='{v}' is not a device number"
            ))
        })?;
        return devices.get(n).copied().ok_or_else(|| {
            unavailable(format!(
                "CAUSTICA_OPENCL_DEVICE={n}, but there are {} devices",
                devices.len()
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

type Registry = Mutex<HashMap<usize, Arc<DeviceState>>>;

/// The shared state of a device: context and program are created once per process and
/// device (the program cache), then shared by every backend on that device.
pub fn device_state(
    platform: PlatformId,
    device: DeviceId,
) -> Result<Arc<DeviceState>, BackendError> {
    static REGISTRY: OnceLock<Registry> = OnceLock::new();
    let registry = REGISTRY.get_or_init(Default::default);
    let key = {
        use ocl::core::ClDeviceIdPtr;
        device.as_ptr() as usize
    };
    let mut map = registry.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(s) = map.get(&key) {
        return Ok(Arc::clone(s));
    }
    let info = summary(platform, device)?;
    let mut props = ContextProperties::new();
    props.set_platform(platform);
    let context = core::create_context(Some(&props), &[device], None, None)
        .map_err(cl_error("creating the context"))?;
    let program = program::build(&context, device)?;
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
