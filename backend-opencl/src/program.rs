//! The OpenCL C program: the shared headers (mirrors of core's scalar functions and Pod
//! structs) and one file per registry kernel under `kernels/`, compiled as one program.
//! A failed build is a typed error carrying the driver's build log.

use caustica_core::backend::BackendError;
use ocl::core::{
    self, DeviceId, DeviceInfo, DeviceInfoResult, ProgramBuildInfo, ProgramBuildInfoResult,
};
use std::ffi::CString;

/// Sources in dependency order: headers first, then one file per kernel.
pub const SOURCES: &[(&str, &str)] = &[
    ("types.cl", include_str!("../kernels/types.cl")),
    ("vector.cl", include_str!("../kernels/vector.cl")),
    ("rng.cl", include_str!("../kernels/rng.cl")),
    ("sampling.cl", include_str!("../kernels/sampling.cl")),
    ("optics.cl", include_str!("../kernels/optics.cl")),
    ("packing.cl", include_str!("../kernels/packing.cl")),
    ("geometry.cl", include_str!("../kernels/geometry.cl")),
    ("footprint.cl", include_str!("../kernels/footprint.cl")),
    ("fixed_point.cl", include_str!("../kernels/fixed_point.cl")),
    ("traversal.cl", include_str!("../kernels/traversal.cl")),
    ("scene.cl", include_str!("../kernels/scene.cl")),
    (
        "primary_gbuffer.cl",
        include_str!("../kernels/primary_gbuffer.cl"),
    ),
    (
        "direct_light.cl",
        include_str!("../kernels/direct_light.cl"),
    ),
    (
        "trace_photons.cl",
        include_str!("../kernels/trace_photons.cl"),
    ),
    (
        "deposit_screen.cl",
        include_str!("../kernels/deposit_screen.cl"),
    ),
    (
        "resolve_caustics.cl",
        include_str!("../kernels/resolve_caustics.cl"),
    ),
    (
        "tile_hit_distance.cl",
        include_str!("../kernels/tile_hit_distance.cl"),
    ),
    (
        "bilateral_gather.cl",
        include_str!("../kernels/bilateral_gather.cl"),
    ),
    ("composite.cl", include_str!("../kernels/composite.cl")),
];

/// The whole program text, each file introduced by a `#line` so that build logs name it.
pub fn source() -> String {
    let mut s = String::new();
    for (name, text) in SOURCES {
        s.push_str(&format!("#line 1 \"{name}\"\n"));
        s.push_str(text);
        s.push('\n');
    }
    s
}

/// Build options: OpenCL C 1.2, IEEE-exact division and square root where the device
/// offers them (the Rust reference rounds both correctly), never fast math.
pub fn options(device: DeviceId) -> String {
    let mut o = String::from("-cl-std=CL1.2");
    if let Ok(DeviceInfoResult::SingleFpConfig(c)) =
        core::get_device_info(device, DeviceInfo::SingleFpConfig)
    {
        if c.contains(core::DeviceFpConfig::CORRECTLY_ROUNDED_DIVIDE_SQRT) {
            o.push_str(" -cl-fp32-correctly-rounded-divide-sqrt");
        }
    }
    o
}

/// Compiles [`source`] for `device`.
pub fn build(context: &core::Context, device: DeviceId) -> Result<core::Program, BackendError> {
    build_source(context, device, &source())
}

/// Compiles `src` for `device`; a failure returns the driver's build log.
pub fn build_source(
    context: &core::Context,
    device: DeviceId,
    src: &str,
) -> Result<core::Program, BackendError> {
    let text =
        CString::new(src).map_err(|_| BackendError::Driver("NUL in OpenCL source".into()))?;
    let program = core::create_program_with_source(context, &[text])
        .map_err(|e| BackendError::Driver(format!("creating the OpenCL program: {e}")))?;
    let opts = CString::new(options(device)).expect("options have no NUL");
    if let Err(e) = core::build_program(&program, Some(&[device]), &opts, None, None) {
        let log = match core::get_program_build_info(&program, device, ProgramBuildInfo::BuildLog) {
            Ok(ProgramBuildInfoResult::BuildLog(l)) => l,
            _ => String::new(),
        };
        return Err(BackendError::Driver(format!(
            "OpenCL kernel build failed: {}\n--- build log ---\n{}",
            e.api_status()
                .map(|s| format!("{s:?}"))
                .unwrap_or_else(|| e.to_string()),
            log.trim()
        )));
    }
    Ok(program)
}
