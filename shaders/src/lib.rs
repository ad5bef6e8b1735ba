//! caustica's WGSL kernels, the one shader source of the wgpu backend and of the Vulkan
//! backend's compute kernels (which compile it to SPIR-V with naga).
//!
//! Files: `wgsl/<kernel>.wgsl`, one per registry kernel, and `wgsl/common/<name>.wgsl`,
//! the shared files (mirrors of core's scalar functions, function by function with the
//! same names, and of core's `#[repr(C)]` Pod structs). A kernel file's first
//! `// needs:` line names the shared files it uses, in order; its module is those files
//! followed by the kernel file (see [`assemble`]). Shared files declare no bindings: the
//! kernel file owns its binding list.
//!
//! Every file is compiled into the crate with `include_str!`, so the crate needs nothing
//! at run time. Its tests (`tests/wgsl_validate.rs`) validate every module with naga and
//! compare the WGSL struct layouts with core's `size_of`/`offset_of!`.

/// The shared WGSL files, as (name, text): `name` is the file stem under `wgsl/common/`
/// and the word a kernel's `// needs:` line uses for it.
pub const COMMON: &[(&str, &str)] = &[
    ("types", include_str!("../wgsl/common/types.wgsl")),
    ("vector", include_str!("../wgsl/common/vector.wgsl")),
    ("rng", include_str!("../wgsl/common/rng.wgsl")),
    ("sampling", include_str!("../wgsl/common/sampling.wgsl")),
    ("optics", include_str!("../wgsl/common/optics.wgsl")),
    ("packing", include_str!("../wgsl/common/packing.wgsl")),
    ("geometry", include_str!("../wgsl/common/geometry.wgsl")),
    ("footprint", include_str!("../wgsl/common/footprint.wgsl")),
    (
        "fixed_point",
        include_str!("../wgsl/common/fixed_point.wgsl"),
    ),
    ("traversal", include_str!("../wgsl/common/traversal.wgsl")),
    ("scene", include_str!("../wgsl/common/scene.wgsl")),
    ("gbuffer", include_str!("../wgsl/common/gbuffer.wgsl")),
    ("photon_map", include_str!("../wgsl/common/photon_map.wgsl")),
    (
        "photon_table",
        include_str!("../wgsl/common/photon_table.wgsl"),
    ),
    (
        "density_gather",
        include_str!("../wgsl/common/density_gather.wgsl"),
    ),
    (
        "source_index",
        include_str!("../wgsl/common/source_index.wgsl"),
    ),
    (
        "photon_map_add",
        include_str!("../wgsl/common/photon_map_add.wgsl"),
    ),
    (
        "specular_tree",
        include_str!("../wgsl/common/specular_tree.wgsl"),
    ),
    ("atlas", include_str!("../wgsl/common/atlas.wgsl")),
    (
        "atlas_deposit",
        include_str!("../wgsl/common/atlas_deposit.wgsl"),
    ),
    (
        "screen_deposit",
        include_str!("../wgsl/common/screen_deposit.wgsl"),
    ),
    ("map_gather", include_str!("../wgsl/common/map_gather.wgsl")),
    ("map_lookup", include_str!("../wgsl/common/map_lookup.wgsl")),
    (
        "photon_clusters",
        include_str!("../wgsl/common/photon_clusters.wgsl"),
    ),
    (
        "irradiance_filter",
        include_str!("../wgsl/common/irradiance_filter.wgsl"),
    ),
    ("photon_gi", include_str!("../wgsl/common/photon_gi.wgsl")),
];

/// The kernel files, as (registry kernel name, text of `wgsl/<name>.wgsl`).
pub const KERNELS: &[(&str, &str)] = &[
    (
        "primary_gbuffer",
        include_str!("../wgsl/primary_gbuffer.wgsl"),
    ),
    ("direct_light", include_str!("../wgsl/direct_light.wgsl")),
    ("trace_photons", include_str!("../wgsl/trace_photons.wgsl")),
    (
        "deposit_screen",
        include_str!("../wgsl/deposit_screen.wgsl"),
    ),
    (
        "resolve_caustics",
        include_str!("../wgsl/resolve_caustics.wgsl"),
    ),
    (
        "tile_hit_distance",
        include_str!("../wgsl/tile_hit_distance.wgsl"),
    ),
    (
        "bilateral_gather",
        include_str!("../wgsl/bilateral_gather.wgsl"),
    ),
    (
        "photon_count_table",
        include_str!("../wgsl/photon_count_table.wgsl"),
    ),
    (
        "gather_footprint",
        include_str!("../wgsl/gather_footprint.wgsl"),
    ),
    (
        "density_gather",
        include_str!("../wgsl/density_gather.wgsl"),
    ),
    ("composite", include_str!("../wgsl/composite.wgsl")),
    (
        "gather_caustic_map",
        include_str!("../wgsl/gather_caustic_map.wgsl"),
    ),
    (
        "caustic_map_lookup",
        include_str!("../wgsl/caustic_map_lookup.wgsl"),
    ),
    (
        "refine_clusters",
        include_str!("../wgsl/refine_clusters.wgsl"),
    ),
    (
        "temporal_blend",
        include_str!("../wgsl/temporal_blend.wgsl"),
    ),
    ("atrous_filter", include_str!("../wgsl/atrous_filter.wgsl")),
    (
        "shading_normal_correction",
        include_str!("../wgsl/shading_normal_correction.wgsl"),
    ),
    (
        "rsm_importance",
        include_str!("../wgsl/rsm_importance.wgsl"),
    ),
    ("sample_rsm", include_str!("../wgsl/sample_rsm.wgsl")),
    (
        "trace_indirect",
        include_str!("../wgsl/trace_indirect.wgsl"),
    ),
    ("splat_photons", include_str!("../wgsl/splat_photons.wgsl")),
];

/// The kernels with compiled variants: their modules declare pipeline-overridable
/// constants named as core's `TraceVariant` switches, so the wgpu backend builds one
/// pipeline per variant when that variant is first launched (the others are built when
/// the backend is created). The Vulkan backend does not compile these from WGSL: it runs
/// them as GLSL ray-tracing stages with specialization constants.
pub const VARIANT_KERNELS: &[&str] = &["trace_photons"];

/// The kernels whose every workgroup variable is written before it is read, by their own
/// code: the backends build them without the zero-initialisation of workgroup memory that
/// WGSL otherwise requires (on Vulkan naga's polyfill, invocation 0 storing zeros over all
/// of it before a barrier: 6.06 to 5.40 ms of `splat_photons` at seed 003's high setting
/// on the H200; wgpu's driver-side initialisation cost nothing measurable).
/// `splat_photons`: every invocation writes `setups[li]` and `starts[li + 1]`,
/// invocation 0 writes `starts[0]`, all before the barrier after which they are read;
/// `lc` is cleared by `counters_clear_local` before any use. A kernel added here must
/// carry the same argument.
pub const WORKGROUP_MEMORY_WRITTEN_FIRST: &[&str] = &["splat_photons"];

/// The complete module text of kernel `name` (its `// needs:` files, then the kernel
/// file; see [`assemble`]), or why there is none: no kernel of that name, or a bad
/// `// needs:` line.
pub fn module_source(name: &str) -> Result<String, String> {
    let (_, kernel) = KERNELS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| format!("no WGSL kernel named {name}"))?;
    match std::env::var_os(KERNEL_DIR_VAR) {
        Some(dir) => {
            let dir = std::path::Path::new(&dir);
            let kernel = file_text(dir, &format!("{name}.wgsl"), kernel);
            assemble_with(name, &kernel, |n, built_in| {
                file_text(dir, &format!("common/{n}.wgsl"), built_in)
            })
        }
        None => assemble(name, kernel),
    }
}

/// Developer aid, as the OpenCL backend's `CAUSTICA_OPENCL_KERNEL_DIR`: a folder whose
/// `<kernel>.wgsl` and `common/<name>.wgsl` files replace the built-in ones of the same
/// name in [`module_source`] (on wgpu and on Vulkan's compute kernels alike), so that a
/// kernel variant can be timed on the GPU machine without a rebuild. Files it lacks stay
/// built in; an unreadable file is the built-in one too.
pub const KERNEL_DIR_VAR: &str = "CAUSTICA_WGSL_KERNEL_DIR";

/// `dir/file`'s text where it can be read, else `built_in`.
fn file_text(dir: &std::path::Path, file: &str, built_in: &str) -> String {
    std::fs::read_to_string(dir.join(file)).unwrap_or_else(|_| built_in.to_string())
}

/// The module text of kernel file `text` (named `name` in messages and in the module's
/// section comments): each shared file that the first `// needs:` line of `text` names,
/// in that order, preceded by a `// ---- common/<file>.wgsl` line and followed by a
/// newline, then `// ---- <name>.wgsl` and `text`. Fails when `text` has no `// needs:`
/// line or names a file that is not in [`COMMON`].
pub fn assemble(name: &str, text: &str) -> Result<String, String> {
    assemble_with(name, text, |_, built_in| built_in.to_string())
}

/// [`assemble`] with each shared file's text passed through `common(name, built_in)`.
fn assemble_with(
    name: &str,
    text: &str,
    common: impl Fn(&str, &str) -> String,
) -> Result<String, String> {
    let needs = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("// needs:"))
        .ok_or_else(|| format!("{name}.wgsl has no `// needs:` line"))?;
    let mut out = String::new();
    for n in needs.split_whitespace() {
        let (_, src) = COMMON
            .iter()
            .find(|(c, _)| *c == n)
            .ok_or_else(|| format!("{name}.wgsl needs unknown shared file '{n}'"))?;
        out.push_str(&format!("// ---- common/{n}.wgsl\n"));
        out.push_str(&common(n, src));
        out.push('\n');
    }
    out.push_str(&format!("// ---- {name}.wgsl\n"));
    out.push_str(text);
    Ok(out)
}
