//! The WGSL sources: shared files under `shaders/common/` (mirrors of core's scalar
//! functions and Pod structs) and one file per registry kernel under `shaders/`. A kernel
//! file's first `// needs:` line names the shared files it uses, in order; its module is
//! those files followed by the kernel file.

/// Shared WGSL files by name.
pub const COMMON: &[(&str, &str)] = &[
    ("types", include_str!("../shaders/common/types.wgsl")),
    ("vector", include_str!("../shaders/common/vector.wgsl")),
    ("rng", include_str!("../shaders/common/rng.wgsl")),
    ("sampling", include_str!("../shaders/common/sampling.wgsl")),
    ("optics", include_str!("../shaders/common/optics.wgsl")),
    ("packing", include_str!("../shaders/common/packing.wgsl")),
    ("geometry", include_str!("../shaders/common/geometry.wgsl")),
    (
        "footprint",
        include_str!("../shaders/common/footprint.wgsl"),
    ),
    (
        "fixed_point",
        include_str!("../shaders/common/fixed_point.wgsl"),
    ),
    (
        "traversal",
        include_str!("../shaders/common/traversal.wgsl"),
    ),
    ("scene", include_str!("../shaders/common/scene.wgsl")),
];

/// Kernel files by registry name.
pub const KERNELS: &[(&str, &str)] = &[
    (
        "primary_gbuffer",
        include_str!("../shaders/primary_gbuffer.wgsl"),
    ),
    ("direct_light", include_str!("../shaders/direct_light.wgsl")),
    (
        "trace_photons",
        include_str!("../shaders/trace_photons.wgsl"),
    ),
    (
        "deposit_screen",
        include_str!("../shaders/deposit_screen.wgsl"),
    ),
    (
        "resolve_caustics",
        include_str!("../shaders/resolve_caustics.wgsl"),
    ),
    (
        "tile_hit_distance",
        include_str!("../shaders/tile_hit_distance.wgsl"),
    ),
    (
        "bilateral_gather",
        include_str!("../shaders/bilateral_gather.wgsl"),
    ),
    ("composite", include_str!("../shaders/composite.wgsl")),
];

/// Kernels with compiled variants (pipeline-overridable constants named as core's
/// `TraceVariant` switches): one pipeline per variant, built when first launched.
pub const VARIANT_KERNELS: &[&str] = &["trace_photons"];

/// The complete module text of kernel `name`, or why it cannot be assembled.
pub fn module_source(name: &str) -> Result<String, String> {
    let (_, kernel) = KERNELS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| format!("no WGSL kernel named {name}"))?;
    assemble(name, kernel)
}

/// Prepends the shared files named by `text`'s `// needs:` line.
pub fn assemble(name: &str, text: &str) -> Result<String, String> {
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
        out.push_str(src);
        out.push('\n');
    }
    out.push_str(&format!("// ---- {name}.wgsl\n"));
    out.push_str(text);
    Ok(out)
}
