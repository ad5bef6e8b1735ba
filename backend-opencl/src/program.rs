//! The OpenCL C programs: the shared headers (mirrors of core's scalar functions and Pod
//! structs) and one file per registry kernel under `kernels/`. Kernels without variants
//! are compiled together as one program; a kernel with compiled variants
//! ([`VARIANT_KERNELS`], DESIGN 3) gets one program per variant, the headers and its file
//! built with `-D NAME=0/1` for each switch, only when a launch first asks for it.
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

/// Kernels compiled per variant, in programs of their own.
pub const VARIANT_KERNELS: &[&str] = &["trace_photons"];

/// Number of shared header files at the start of [`SOURCES`].
const HEADERS: usize = 11;

fn append(s: &mut String, name: &str, text: &str) {
    s.push_str(&format!("#line 1 \"{name}\"\n"));
    s.push_str(text);
    s.push('\n');
}

/// The text of the program of every kernel without variants, each file introduced by a
/// `#line` so that build logs name it.
pub fn source() -> String {
    let mut s = String::new();
    for (name, text) in SOURCES {
        if !VARIANT_KERNELS
            .iter()
            .any(|k| name.strip_suffix(".cl") == Some(k))
        {
            append(&mut s, name, text);
        }
    }
    s
}

/// The text of the program of one variant kernel: the headers and its file.
pub fn variant_source(kernel: &str) -> Option<String> {
    let file = format!("{kernel}.cl");
    let (name, text) = SOURCES[HEADERS..].iter().find(|(n, _)| *n == file)?;
    let mut s = String::new();
    for (h, t) in &SOURCES[..HEADERS] {
        append(&mut s, h, t);
    }
    append(&mut s, name, text);
    Some(s)
}

/// `-D NAME=0/1` for every switch of a variant.
pub fn defines(constants: &[(&str, bool)]) -> String {
    constants
        .iter()
        .map(|(n, v)| format!(" -D {n}={}", *v as u32))
        .collect()
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

/// Compiles the program of variant `constants` of `kernel` for `device`.
pub fn build_variant(
    context: &core::Context,
    device: DeviceId,
    kernel: &str,
    constants: &[(&str, bool)],
) -> Result<core::Program, BackendError> {
    let src = variant_source(kernel)
        .ok_or_else(|| BackendError::Unsupported(format!("{kernel} has no variants")))?;
    build_with(context, device, &src, &defines(constants))
}

/// Compiles `src` for `device`; a failure returns the driver's build log.
pub fn build_source(
    context: &core::Context,
    device: DeviceId,
    src: &str,
) -> Result<core::Program, BackendError> {
    build_with(context, device, src, "")
}

fn build_with(
    context: &core::Context,
    device: DeviceId,
    src: &str,
    extra_options: &str,
) -> Result<core::Program, BackendError> {
    let text =
        CString::new(src).map_err(|_| BackendError::Driver("NUL in OpenCL source".into()))?;
    let program = core::create_program_with_source(context, &[text])
        .map_err(|e| BackendError::Driver(format!("creating the OpenCL program: {e}")))?;
    let opts = CString::new(options(device) + extra_options)
        .map_err(|_| BackendError::Driver("NUL in OpenCL build options".into()))?;
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
