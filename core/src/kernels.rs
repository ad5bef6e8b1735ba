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
