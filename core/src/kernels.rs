//! The kernel registry as data (DESIGN 3): every kernel a backend must provide, with what
//! it reads and writes and its preferred workgroup size. A conformance test checks that
//! every backend implements every kernel listed here.

/// One registered kernel.
#[derive(Clone, Copy, Debug)]
pub struct KernelInfo {
    pub name: &'static str,
    pub reads: &'static str,
    pub writes: &'static str,
    /// Threads per workgroup on GPU backends (1-D).
    pub workgroup_size: u32,
    /// Techniques that use it.
    pub used_by: &'static str,
}

/// Every kernel of the library.
pub const KERNELS: &[KernelInfo] = &[
    KernelInfo {
        name: "prepare_scene",
        reads: "vertices, triangles, materials, lights, bvh nodes",
        writes: "acceleration structure",
        workgroup_size: 1,
        used_by: "all",
    },
    KernelInfo {
        name: "primary_gbuffer",
        reads: "scene, camera",
        writes: "G-buffer",
        workgroup_size: 64,
        used_by: "all",
    },
    KernelInfo {
        name: "direct_light",
        reads: "scene, G-buffer",
        writes: "direct radiance image",
        workgroup_size: 64,
        used_by: "all",
    },
    KernelInfo {
        name: "trace_photons",
        reads: "scene, emission parameters",
        writes: "photons, photon count, counters",
        workgroup_size: 64,
        used_by: "Sspm",
    },
    KernelInfo {
        name: "deposit_screen",
        reads: "photons, G-buffer, camera",
        writes: "screen photon map (fixed point), counters",
        workgroup_size: 64,
        used_by: "Sspm",
    },
    KernelInfo {
        name: "resolve_caustics",
        reads: "screen photon map, G-buffer",
        writes: "raw caustic radiance image",
        workgroup_size: 64,
        used_by: "Sspm",
    },
    KernelInfo {
        name: "tile_hit_distance",
        reads: "screen photon map",
        writes: "tile hit distances",
        workgroup_size: 64,
        used_by: "Sspm",
    },
    KernelInfo {
        name: "bilateral_gather",
        reads: "image, G-buffer, tile hit distances",
        writes: "filtered image",
        workgroup_size: 64,
        used_by: "Sspm",
    },
    KernelInfo {
        name: "composite",
        reads: "direct image, caustic image",
        writes: "composite image",
        workgroup_size: 64,
        used_by: "all",
    },
];

/// A compiled variant of `trace_photons` (DESIGN 3: feature variants are compiled, not
/// branched). Each switch removes a material feature from the kernel; the frame plan
/// turns on only what the scene's objects use. Backends compile it as WGSL
/// pipeline-overridable constants, Vulkan specialization constants (ids in
/// [`TraceVariant::constants`] order), OpenCL `-D` defines and CPU const generics, each
/// under the names of [`TraceVariant::constants`].
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct TraceVariant {
    /// Dielectric interfaces (Fresnel reflect/refract, total internal reflection).
    pub dielectric: bool,
    /// Cauchy dispersion (one colour channel per photon after its first dispersive hit).
    pub dispersion: bool,
    /// Beer-Lambert absorption inside dielectrics.
    pub absorption: bool,
}

impl TraceVariant {
    /// Every feature compiled in (what a frame uses with pruning off).
    pub const ALL: TraceVariant = TraceVariant {
        dielectric: true,
        dispersion: true,
        absorption: true,
    };

    /// `(name, value)` of each switch, in specialization-constant id order.
    pub fn constants(&self) -> [(&'static str, bool); 3] {
        [
            ("DIELECTRIC", self.dielectric),
            ("DISPERSION", self.dispersion),
            ("ABSORPTION", self.absorption),
        ]
    }
}

/// The name a backend lists a compiled kernel variant under, e.g.
/// `trace_photons[DIELECTRIC=1,DISPERSION=0,ABSORPTION=0]`; a kernel without switches is
/// its bare name.
pub fn variant_label(kernel: &str, constants: &[(&'static str, bool)]) -> String {
    if constants.is_empty() {
        return kernel.to_string();
    }
    let parts: Vec<String> = constants
        .iter()
        .map(|(n, v)| format!("{n}={}", *v as u32))
        .collect();
    format!("{kernel}[{}]", parts.join(","))
}

/// The labels with switches among a pipeline cache's keys, sorted: what a GPU backend's
/// `Backend::variants` lists.
pub fn variant_labels<'a>(keys: impl IntoIterator<Item = &'a String>) -> Vec<String> {
    let mut v: Vec<String> = keys
        .into_iter()
        .filter(|k| k.contains('['))
        .cloned()
        .collect();
    v.sort();
    v
}
