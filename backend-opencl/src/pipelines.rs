//! The OpenCL C programs: the shared files under `kernels/common/` ([`COMMON`]: the
//! generated `layout.cl` with core's Pod structs and shared constants, then `prelude.cl`
//! and the mirrors of core's scalar functions) and one file per registry kernel directly
//! under `kernels/` ([`KERNELS`]). Kernels without variants are compiled together as one
//! program; a kernel with compiled variants ([`VARIANT_KERNELS`]) gets one
//! program per variant, the common files and its own file built with `-D NAME=0/1` for
//! each switch, only when a launch first asks for it.
//! A failed build is a typed error carrying the driver's build log.

use crate::device::{cl_error, status_text, DeviceState};
use crate::OpenClBackend;
use caustica_core::backend::BackendError;
use opencl3::context::Context;
use opencl3::device::{Device, CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT};
use opencl3::program::Program;
use opencl3::types::cl_device_id;
use std::sync::Arc;

/// The shared files of `kernels/common/`, in dependency order (a file uses only the ones
/// before it): `(file name, text)`.
pub const COMMON: &[(&str, &str)] = &[
    ("layout.cl", include_str!("../kernels/common/layout.cl")),
    ("prelude.cl", include_str!("../kernels/common/prelude.cl")),
    ("vector.cl", include_str!("../kernels/common/vector.cl")),
    ("rng.cl", include_str!("../kernels/common/rng.cl")),
    ("sampling.cl", include_str!("../kernels/common/sampling.cl")),
    ("optics.cl", include_str!("../kernels/common/optics.cl")),
    ("spectrum.cl", include_str!("../kernels/common/spectrum.cl")),
    ("packing.cl", include_str!("../kernels/common/packing.cl")),
    ("geometry.cl", include_str!("../kernels/common/geometry.cl")),
    (
        "footprint.cl",
        include_str!("../kernels/common/footprint.cl"),
    ),
    (
        "fixed_point.cl",
        include_str!("../kernels/common/fixed_point.cl"),
    ),
    (
        "traversal.cl",
        include_str!("../kernels/common/traversal.cl"),
    ),
    ("scene.cl", include_str!("../kernels/common/scene.cl")),
    ("planes.cl", include_str!("../kernels/common/planes.cl")),
    (
        "density_gather.cl",
        include_str!("../kernels/common/density_gather.cl"),
    ),
    (
        "map_gather.cl",
        include_str!("../kernels/common/map_gather.cl"),
    ),
    (
        "specular_tree.cl",
        include_str!("../kernels/common/specular_tree.cl"),
    ),
    (
        "photon_clusters.cl",
        include_str!("../kernels/common/photon_clusters.cl"),
    ),
    (
        "irradiance_filter.cl",
        include_str!("../kernels/common/irradiance_filter.cl"),
    ),
    (
        "photon_gi.cl",
        include_str!("../kernels/common/photon_gi.cl"),
    ),
];

macro_rules! kernel_table {
    ($($name:ident),* $(,)?) => {
        /// The kernel files of `kernels/`, one per registry kernel: `(registry name, text)`, in
        /// the order they are appended to the program text, which is core's
        /// (`caustica_core::with_shader_kernels!`), so a new kernel needs no row here.
        pub const KERNELS: &[(&str, &str)] = &[$((
            stringify!($name),
            include_str!(concat!("../kernels/", stringify!($name), ".cl")),
        ),)*];
    };
}
caustica_core::with_shader_kernels!(kernel_table);

/// Kernels compiled per variant, in programs of their own.
pub const VARIANT_KERNELS: &[&str] = &["trace_photons"];

/// Kernels compiled in a program of their own with OpenCL's default single-precision
/// bounds, 2.5 ulp for `/` and 3 ulp for `sqrt` (OpenCL C 1.2 section 7.4), instead of the
/// correctly rounded ones of [`options`]: the bounds of WGSL and SPIR-V, which the
/// conformance tolerance of these kernels already argues for (`DENSITY_GATHER_REL` in
/// conformance/src/harness/tolerance.rs). The density gather divides five times per tap;
/// measured on the H200 (`cornell`), this program made `density_gather` 0.26 ms against
/// 0.37 with correctly rounded division, and `gather_footprint` 0.13 against 0.17 (an
/// experiment with native division found the cost; docs/performance.md). `splat_photons`
/// divides three times per pixel of a splat's square (`kernel_contains`); its tolerance
/// (`SPLAT_REL`, 40 ulp a contribution, and the containment flips near 1 that
/// `DEPOSIT_TEXEL_AGREEMENT` allows for: conformance/src/kernels/splat_photons.rs) is argued
/// for WGSL's bounds too. At the chapter's high setting on the H200 it took 9.7 ms here
/// against 14.8 in the main program (both with staged G-buffer loads).
pub const RELAXED_DIVISION_KERNELS: &[&str] =
    &["gather_footprint", "density_gather", "splat_photons"];

/// Kernels with compiled switches (each variant a program of its own, [`build_variant`])
/// whose programs are built with OpenCL's default division bounds, as
/// [`RELAXED_DIVISION_KERNELS`]: `trace_photons`, whose conformance
/// (photons matched within a position tolerance, paths allowed to diverge where a
/// rounding sends them the other way) is argued for WGSL's and SPIR-V's bounds too. On the
/// H200 its trace took 2.71 ms against 2.75 on `sphere`, 1.15 against 1.18 on `cornell`
/// and 1.76 against 1.82 at CausticMap's Vanderstichelen 2021 setting 0, with `cross_backend`'s trace,
/// Sspm and CausticMap checks and the stiff catalogue passing against the CPU.
/// `trace_indirect`, whose conformance is argued the same way (stored photons as multisets,
/// diverged paths allowed): on the H100 at Smal 2019's high setting (`rooms`, 8 waves) it
/// took 6.10 against 6.49 ms, with `cross_backend`'s PhotonGi checks (the waves against
/// the single launch exactly, on the same backend) and `photon_gi_schedules` (the waves'
/// images bitwise the single launch's), `photon_gi_frames` and `photon_gi_stiff` passing:
/// both of its variants are built with the same bounds.
pub const RELAXED_DIVISION_VARIANTS: &[&str] = &["trace_photons", "trace_indirect"];

/// Register caps (`-cl-nv-maxrregcount`) for variant kernels' programs on devices that
/// take NVIDIA's compiler options (`cl_nv_compiler_options`): fewer registers a thread,
/// more warps resident to hide the traversal's memory latency. `trace_indirect` (its
/// path queues' waves) uses 96 uncapped; measured on the H200 (Smal 2019's high setting,
/// `scripts/gpu-run.sh experiment`, the option on every program): 7.10 -> 6.80 ms at 80,
/// 6.88 at 72, and 6.08 -> 5.93 with the sorted waves, while `direct_light` in the same
/// run went 0.85 -> 0.95, which is why the cap is the one kernel's.
pub const REGISTER_CAPS: &[(&str, u32)] = &[("trace_indirect", 80)];

/// NVIDIA's extension that takes `-cl-nv-maxrregcount` and the other `-cl-nv-*` options.
pub const NV_COMPILER_OPTIONS: &str = "cl_nv_compiler_options";

/// `kernel`'s register cap option ([`REGISTER_CAPS`]) where the device's `extensions`
/// offer [`NV_COMPILER_OPTIONS`]; empty otherwise.
pub fn register_cap_option(kernel: &str, extensions: &str) -> String {
    let nv = extensions
        .split_whitespace()
        .any(|e| e == NV_COMPILER_OPTIONS);
    match REGISTER_CAPS.iter().find(|(k, _)| *k == kernel) {
        Some((_, cap)) if nv => format!(" -cl-nv-maxrregcount={cap}"),
        _ => String::new(),
    }
}

/// Developer aid: `CAUSTICA_OPENCL_RELAXED=kernel,...` builds these kernels with OpenCL's
/// default division bounds too (one without switches in the relaxed-division program, one
/// with switches in variant programs without `-cl-fp32-correctly-rounded-divide-sqrt`),
/// so that the lever can be timed on a device without a rebuild (`EXP_ENVS` of
/// `scripts/gpu-run.sh experiment`). Not for production: the conformance suite checks the
/// built-in lists ([`RELAXED_DIVISION_KERNELS`], [`RELAXED_DIVISION_VARIANTS`]).
pub const RELAXED_VAR: &str = "CAUSTICA_OPENCL_RELAXED";

/// Whether [`RELAXED_VAR`] names `kernel`.
fn relaxed_by_developer(kernel: &str) -> bool {
    std::env::var(RELAXED_VAR).is_ok_and(|v| names_kernel(&v, kernel))
}

/// Whether the comma-separated `list` names `kernel`.
fn names_kernel(list: &str, kernel: &str) -> bool {
    list.split(',').any(|k| k.trim() == kernel)
}

/// Whether `kernel`, a kernel without switches, is built in the relaxed-division program.
fn in_relaxed_program(kernel: &str) -> bool {
    RELAXED_DIVISION_KERNELS.contains(&kernel)
        || (relaxed_by_developer(kernel)
            && caustica_core::kernels::kernel_info(kernel).is_some_and(|i| i.switches.is_empty()))
}

/// The label [`crate::device::DeviceState::program_for`] keeps the relaxed program under.
pub const RELAXED_DIVISION_PROGRAM: &str = "relaxed division";

/// Developer override: `CAUSTICA_OPENCL_KERNEL_DIR=dir` reads every kernel file from
/// `dir/<kernel>.cl` and `dir/common/<file>.cl` instead of the texts built into the
/// library (a missing file falls back to the built-in text), so that a kernel can be
/// changed and timed on a device without rebuilding. Not for production: the
/// conformance suite checks the built-in texts.
pub const KERNEL_DIR_VAR: &str = "CAUSTICA_OPENCL_KERNEL_DIR";

/// Developer aid: `CAUSTICA_OPENCL_DUMP_DIR=dir` writes every program the backend builds
/// to `dir/<label>.bin` (on NVIDIA the driver's PTX, which `ptxas -v` reads for
/// registers and spills). A write that fails is reported on stderr.
pub const DUMP_DIR_VAR: &str = "CAUSTICA_OPENCL_DUMP_DIR";

/// Developer aid: `CAUSTICA_OPENCL_OPTIONS="..."` appends build options to every program
/// (for example NVIDIA's `-cl-nv-verbose` or `-cl-nv-maxrregcount=N`); with
/// [`DUMP_DIR_VAR`] the build log is written beside the binary.
pub const OPTIONS_VAR: &str = "CAUSTICA_OPENCL_OPTIONS";

/// Developer aid: `CAUSTICA_OPENCL_WORKGROUP_SIZES="kernel=threads,..."` launches the named
/// kernels with that many threads a workgroup instead of core's `workgroup_size`, so that
/// a group size can be timed on a device without a rebuild (`scripts/gpu-run.sh
/// experiment`, `EXP_ENVS`). Only the kernels of [`WORKGROUP_SIZE_FREE`]; the conformance
/// suite checks core's sizes. A malformed entry, or another kernel, is an error at launch.
pub const WORKGROUP_SIZES_VAR: &str = "CAUSTICA_OPENCL_WORKGROUP_SIZES";

/// The kernels whose code and local memory do not depend on their workgroup's size (every
/// other kernel's arrays, strides or `reqd_work_group_size` are written for
/// `WORKGROUP_SIZE`).
pub const WORKGROUP_SIZE_FREE: &[&str] = &["trace_indirect", "trace_photons"];

/// [`WORKGROUP_SIZES_VAR`]'s value, read once per process (a launch does not read the
/// environment).
pub fn workgroup_sizes_env() -> Option<&'static str> {
    static LIST: std::sync::OnceLock<Option<String>> = std::sync::OnceLock::new();
    LIST.get_or_init(|| std::env::var(WORKGROUP_SIZES_VAR).ok())
        .as_deref()
}

/// The workgroup size [`WORKGROUP_SIZES_VAR`] names for `kernel` in `list`, if any; an
/// entry that is not `name=threads` with 1 <= threads <= 1024, or names a kernel not in
/// [`WORKGROUP_SIZE_FREE`], is an error.
pub fn workgroup_size_override(list: &str, kernel: &str) -> Result<Option<u32>, String> {
    for entry in list.split(',').map(str::trim).filter(|e| !e.is_empty()) {
        let parsed = entry
            .split_once('=')
            .and_then(|(name, n)| Some((name.trim(), n.trim().parse::<u32>().ok()?)))
            .filter(|(_, n)| (1..=1024).contains(n));
        let Some((name, threads)) = parsed else {
            return Err(format!(
                "{WORKGROUP_SIZES_VAR}: '{entry}' is not kernel=threads (1 to 1024)"
            ));
        };
        if !WORKGROUP_SIZE_FREE.contains(&name) {
            return Err(format!(
                "{WORKGROUP_SIZES_VAR}: '{name}' is written for its own workgroup size; only \
                 {WORKGROUP_SIZE_FREE:?} take another"
            ));
        }
        if name == kernel {
            return Ok(Some(threads));
        }
    }
    Ok(None)
}

/// The text of kernel file `file` (`common/<name>.cl` or `<kernel>.cl`): the override of
/// [`KERNEL_DIR_VAR`] where one is set and holds the file, else `built_in`.
fn file_text(file: &str, built_in: &str) -> String {
    if let Some(dir) = std::env::var_os(KERNEL_DIR_VAR) {
        if let Ok(text) = std::fs::read_to_string(std::path::Path::new(&dir).join(file)) {
            return text;
        }
    }
    built_in.to_string()
}

/// Appends one file to a program text, introduced by a `#line` naming it so that build
/// logs point at the file and line.
fn append(s: &mut String, file: &str, text: &str) {
    s.push_str(&format!("#line 1 \"{file}\"\n"));
    s.push_str(text);
    s.push('\n');
}

/// Appends every common file, in [`COMMON`] order.
fn append_common(s: &mut String) {
    for (file, text) in COMMON {
        append(s, file, &file_text(&format!("common/{file}"), text));
    }
}

/// The text of the program of every kernel without variants: the common files, then the
/// kernel files in [`KERNELS`] order, each introduced by a `#line` so that build logs
/// name it.
pub fn source() -> String {
    let mut s = String::new();
    append_common(&mut s);
    for (kernel, text) in KERNELS {
        if !VARIANT_KERNELS.contains(kernel) && !RELAXED_DIVISION_KERNELS.contains(kernel) {
            let file = format!("{kernel}.cl");
            append(&mut s, &file, &file_text(&file, text));
        }
    }
    s
}

/// The text of the program of one variant kernel: the common files and its file (`None`
/// for a name without a kernel file).
pub fn variant_source(kernel: &str) -> Option<String> {
    let (name, text) = KERNELS.iter().find(|(n, _)| *n == kernel)?;
    let mut s = String::new();
    append_common(&mut s);
    let file = format!("{name}.cl");
    append(&mut s, &file, &file_text(&file, text));
    Some(s)
}

/// `-D NAME=value` for every switch of a variant (0/1 for flags).
pub fn defines(constants: &[(&str, u32)]) -> String {
    constants
        .iter()
        .map(|(n, v)| format!(" -D {n}={v}"))
        .collect()
}

/// The text of the program of [`RELAXED_DIVISION_KERNELS`]: the common files and theirs.
pub fn relaxed_division_source() -> String {
    let mut s = String::new();
    append_common(&mut s);
    for (kernel, text) in KERNELS {
        if in_relaxed_program(kernel) {
            let file = format!("{kernel}.cl");
            append(&mut s, &file, &file_text(&file, text));
        }
    }
    s
}

/// Compiles [`relaxed_division_source`] for `device` with [`base_options`].
pub fn build_relaxed_division(
    context: &Context,
    device: cl_device_id,
) -> Result<Program, BackendError> {
    let program = build_with(
        context,
        device,
        &relaxed_division_source(),
        base_options(),
        "",
    )?;
    dump_binary(&program, device, RELAXED_DIVISION_PROGRAM);
    Ok(program)
}

/// OpenCL C 1.2, never fast math.
fn base_options() -> String {
    String::from("-cl-std=CL1.2")
}

/// Build options: [`base_options`] with IEEE-exact division and square root where the
/// device offers them (the Rust reference rounds both correctly).
pub fn options(device: cl_device_id) -> String {
    let mut o = base_options();
    if let Ok(c) = Device::new(device).single_fp_config() {
        if c & CL_FP_CORRECTLY_ROUNDED_DIVIDE_SQRT != 0 {
            o.push_str(" -cl-fp32-correctly-rounded-divide-sqrt");
        }
    }
    o
}

/// Compiles [`source`] for `device`.
pub fn build(context: &Context, device: cl_device_id) -> Result<Program, BackendError> {
    let program = build_source(context, device, &source())?;
    dump_binary(&program, device, "kernels");
    Ok(program)
}

/// Compiles the program of variant `constants` of `kernel` for `device`.
pub fn build_variant(
    context: &Context,
    device: cl_device_id,
    kernel: &str,
    constants: &[(&'static str, u32)],
) -> Result<Program, BackendError> {
    let src = variant_source(kernel)
        .ok_or_else(|| BackendError::Unsupported(format!("{kernel} has no variants")))?;
    let opts = if RELAXED_DIVISION_VARIANTS.contains(&kernel) || relaxed_by_developer(kernel) {
        base_options()
    } else {
        options(device)
    };
    let extensions = Device::new(device).extensions().unwrap_or_default();
    let extra = defines(constants) + &register_cap_option(kernel, &extensions);
    let program = build_with(context, device, &src, opts, &extra)?;
    dump_binary(
        &program,
        device,
        &caustica_core::kernels::variant_label(kernel, constants),
    );
    Ok(program)
}

/// Writes `program`'s binary to [`DUMP_DIR_VAR`]'s folder when that is set; a failure
/// to write is only logged (a developer aid must not fail a frame).
fn dump_binary(program: &Program, device: cl_device_id, label: &str) {
    let Some(dir) = std::env::var_os(DUMP_DIR_VAR) else {
        return;
    };
    let name: String = label
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    let path = std::path::Path::new(&dir).join(format!("{name}.bin"));
    let written = program
        .get_binaries()
        .map_err(|e| e.to_string())
        .and_then(|b| {
            let bytes = b.into_iter().next().unwrap_or_default();
            std::fs::write(&path, bytes).map_err(|e| e.to_string())
        });
    let log = program.get_build_log(device).unwrap_or_default();
    let written = written
        .and_then(|()| std::fs::write(path.with_extension("log"), log).map_err(|e| e.to_string()));
    if let Err(e) = written {
        // opted into by the developer's own environment variable: say it where they look
        eprintln!(
            "could not dump the OpenCL program to {}: {e}",
            path.display()
        );
    }
}

/// Compiles `src` for `device`; a failure returns the driver's build log.
pub fn build_source(
    context: &Context,
    device: cl_device_id,
    src: &str,
) -> Result<Program, BackendError> {
    build_with(context, device, src, options(device), "")
}

/// Compiles `src` for `device` with [`options`] followed by `extra_options`.
fn build_with(
    context: &Context,
    device: cl_device_id,
    src: &str,
    options: String,
    extra_options: &str,
) -> Result<Program, BackendError> {
    if src.contains('\0') {
        return Err(BackendError::Driver("NUL in OpenCL source".into()));
    }
    let mut opts = options + extra_options;
    if let Ok(more) = std::env::var(OPTIONS_VAR) {
        opts.push(' ');
        opts.push_str(&more);
    }
    // opencl3's `Program::build` panics on a NUL in the options: refuse it here.
    if opts.contains('\0') {
        return Err(BackendError::Driver("NUL in OpenCL build options".into()));
    }
    let mut program = Program::create_from_source(context, src)
        .map_err(cl_error("creating the OpenCL program"))?;
    if let Err(e) = program.build(&[device], &opts) {
        let log = program.get_build_log(device).unwrap_or_default();
        return Err(BackendError::Driver(format!(
            "OpenCL kernel build failed: {}\n--- build log ---\n{}",
            status_text(e.0),
            log.trim()
        )));
    }
    Ok(program)
}

impl DeviceState {
    /// The program holding variant `constants` of `kernel` (the base program for a
    /// kernel without switches, the relaxed-division program for
    /// [`RELAXED_DIVISION_KERNELS`]), building it on first use.
    pub(crate) fn program_for(
        &self,
        kernel: &str,
        constants: &[(&'static str, u32)],
    ) -> Result<Arc<Program>, BackendError> {
        let relaxed = in_relaxed_program(kernel);
        if constants.is_empty() && !relaxed {
            return Ok(Arc::clone(&self.program));
        }
        let label = if relaxed {
            RELAXED_DIVISION_PROGRAM.to_string()
        } else {
            caustica_core::kernels::variant_label(kernel, constants)
        };
        let mut map = self.variants.lock().unwrap_or_else(|e| e.into_inner());
        if let Some(p) = map.get(&label) {
            return Ok(Arc::clone(p));
        }
        let p = Arc::new(if relaxed {
            build_relaxed_division(&self.context, self.device.id())?
        } else {
            build_variant(&self.context, self.device.id(), kernel, constants)?
        });
        map.insert(label, Arc::clone(&p));
        Ok(p)
    }
}

impl OpenClBackend {
    /// Records that a launch ran variant `label`.
    pub(crate) fn note_variant(&self, label: String) {
        let mut v = self.variants.lock().unwrap_or_else(|e| e.into_inner());
        v.insert(label);
    }

    /// Compiles `src` on this backend's device (diagnostics and tests: the error of a
    /// failed build carries the driver's build log).
    pub fn build_test_program(&self, src: &str) -> Result<(), BackendError> {
        build_source(&self.state.context, self.state.device.id(), src).map(|_| ())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A kernel named in [`RELAXED_DIVISION_VARIANTS`] has switches, so its launches go
    /// through [`build_variant`], where the list is read (a kernel without switches would
    /// be built in the main program and the entry silently ignored).
    #[test]
    fn relaxed_division_variants_have_switches() {
        for k in RELAXED_DIVISION_VARIANTS {
            let info = caustica_core::kernels::kernel_info(k);
            assert!(info.is_some_and(|i| !i.switches.is_empty()), "{k}");
        }
    }

    /// `CAUSTICA_OPENCL_WORKGROUP_SIZES` names kernels whole and refuses what is not a size
    /// or a kernel written for its own workgroup size.
    #[test]
    fn workgroup_size_overrides() {
        let list = "trace_photons=128, trace_indirect = 256";
        assert_eq!(
            workgroup_size_override(list, "trace_indirect"),
            Ok(Some(256))
        );
        assert_eq!(
            workgroup_size_override(list, "trace_photons"),
            Ok(Some(128))
        );
        assert_eq!(workgroup_size_override(list, "trace"), Ok(None));
        assert_eq!(workgroup_size_override("", "trace"), Ok(None));
        for bad in [
            "trace_indirect",
            "trace_indirect=0",
            "trace_indirect=2048",
            "x=y",
            "splat_photons=128",
        ] {
            assert!(
                workgroup_size_override(bad, "trace_indirect").is_err(),
                "{bad}"
            );
        }
    }

    /// `CAUSTICA_OPENCL_RELAXED`'s list names whole kernel names only.
    #[test]
    fn the_relaxed_list_names_whole_kernels() {
        assert!(names_kernel(
            "trace_indirect, atrous_filter",
            "atrous_filter"
        ));
        assert!(names_kernel("trace_indirect", "trace_indirect"));
        assert!(!names_kernel("trace_indirect", "trace"));
        assert!(!names_kernel("", "trace_indirect"));
    }

    /// A register cap is asked for only of NVIDIA's compiler, and only for a variant
    /// kernel (the others share the base program, whose kernels the cap would slow).
    #[test]
    fn register_caps_only_on_nvidia_and_variant_kernels() {
        let nv = "cl_khr_fp64 cl_nv_compiler_options cl_khr_int64_base_atomics";
        assert_eq!(
            register_cap_option("trace_indirect", nv),
            " -cl-nv-maxrregcount=80"
        );
        assert_eq!(register_cap_option("trace_indirect", "cl_khr_fp64"), "");
        assert_eq!(
            register_cap_option("trace_indirect", "cl_nv_compiler_options_x"),
            ""
        );
        assert_eq!(register_cap_option("direct_light", nv), "");
        // a kernel with switches is always launched with their values, so it is built
        // in a program of its own (`program_for`), where the cap touches it alone
        for (k, _) in REGISTER_CAPS {
            let info = caustica_core::kernels::kernel_info(k).expect("a kernel");
            assert!(!info.switches.is_empty(), "{k} shares the base program");
        }
    }

    /// Every registry kernel that launches device code has exactly one kernel file, and
    /// every kernel file is a registry kernel. `prepare_scene` launches nothing here (core
    /// hands it a flattened BVH already in buffers: `Launch` is `None`), so it has no file.
    #[test]
    fn kernel_files_match_the_registry() {
        let mut registry: Vec<&str> = caustica_core::kernels::all_kernel_names()
            .into_iter()
            .filter(|k| *k != "prepare_scene")
            .collect();
        let mut files: Vec<&str> = KERNELS.iter().map(|(n, _)| *n).collect();
        registry.sort_unstable();
        files.sort_unstable();
        assert_eq!(files, registry);
        for k in VARIANT_KERNELS {
            assert!(files.contains(k), "variant kernel {k} has no file");
        }
    }

    /// The common files and kernel files are the files of `kernels/common/` and
    /// `kernels/`, so a new file cannot be forgotten in the tables.
    /// Every kernel is in exactly one of the base, variant and relaxed-division programs
    /// (a relaxed kernel's switches would be ignored: none may have any).
    #[test]
    fn each_kernel_is_in_one_program() {
        let base = source();
        let relaxed = relaxed_division_source();
        for (kernel, _) in KERNELS {
            let marker = format!("void {kernel}(");
            let places = [
                base.contains(&marker),
                VARIANT_KERNELS.contains(kernel),
                relaxed.contains(&marker),
            ];
            assert_eq!(
                places.iter().filter(|&&p| p).count(),
                1,
                "{kernel}: {places:?}"
            );
        }
    }

    #[test]
    fn tables_list_every_file() {
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("kernels");
        let names = |d: &std::path::Path| {
            let mut v: Vec<String> = std::fs::read_dir(d)
                .unwrap()
                .filter_map(|e| e.ok())
                .filter(|e| e.path().is_file())
                .map(|e| e.file_name().to_string_lossy().into_owned())
                .collect();
            v.sort();
            v
        };
        let mut common: Vec<String> = COMMON.iter().map(|(f, _)| f.to_string()).collect();
        common.sort();
        assert_eq!(names(&dir.join("common")), common);
        let mut kernels: Vec<String> = KERNELS.iter().map(|(k, _)| format!("{k}.cl")).collect();
        kernels.sort();
        assert_eq!(names(&dir), kernels);
    }
}
