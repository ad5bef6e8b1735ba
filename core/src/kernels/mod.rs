//! The one list of kernels. Each kernel is declared once, in its own file
//! (`kernels/<name>.rs`): a struct of typed arguments whose doc comment is the kernel's
//! contract (what it reads and writes, units, spaces), and a [`KernelDecl`] impl giving
//! its name, its bindings in launch order with their access, its workgroup size, its
//! compiled switches and its lowering (argument checks, buffer sizes, thread count).
//!
//! From the list in [`with_kernels!`](crate::with_kernels) everything else is derived:
//! the [`Kernel`] enum a [`crate::recording::Recording`] carries, the registry
//! [`KERNELS`], the lowering of a recorded kernel to a [`Launch`] (checked binding by
//! binding against the declaration), the Vulkan descriptor types
//! ([`KernelInfo::descriptor_bindings`]) and the WGSL binding table the shader crate's
//! validation test expects ([`KernelInfo::wgsl_bindings`]). The CPU backend generates its
//! kernel modules and their dispatch from the same list, so a new kernel without its CPU
//! file (a `run` function) does not compile.
//!
//! Adding a kernel: a file here, one line in `with_kernels!` and its name in
//! [`with_shader_kernels!`](crate::with_shader_kernels) (the WGSL and OpenCL kernel tables),
//! then its CPU function, WGSL, OpenCL C (and GLSL stage if traced) and conformance check,
//! each in a file named as the kernel; see CONTRIBUTING.md.

mod atrous_filter;
mod bilateral_gather;
mod caustic_map_lookup;
mod composite;
mod density_gather;
mod deposit_screen;
mod direct_light;
mod dispatch_args;
mod gather_caustic_map;
mod gather_footprint;
mod photon_count_table;
mod place_vertices;
mod prepare_scene;
mod primary_gbuffer;
mod refine_clusters;
mod resolve_caustics;
mod rsm_importance;
mod sample_rsm;
mod seed_clusters;
mod select_photon_plan;
mod shading_normal_correction;
mod sort_indirect_paths;
mod splat_photons;
mod temporal_blend;
mod tile_hit_distance;
mod trace_indirect;
mod trace_photons;

pub use atrous_filter::AtrousFilter;
pub use bilateral_gather::BilateralGather;
pub use caustic_map_lookup::CausticMapLookup;
pub use composite::Composite;
pub use density_gather::DensityGather;
pub use deposit_screen::DepositScreen;
pub use direct_light::DirectLight;
pub use dispatch_args::{dispatch_record, DispatchArgs, DispatchRecord};
pub use gather_caustic_map::GatherCausticMap;
pub use gather_footprint::GatherFootprint;
pub use photon_count_table::PhotonCountTable;
pub use place_vertices::PlaceVertices;
pub use prepare_scene::PrepareScene;
pub use primary_gbuffer::PrimaryGbuffer;
pub use refine_clusters::RefineClusters;
pub use resolve_caustics::ResolveCaustics;
pub use rsm_importance::RsmImportance;
pub use sample_rsm::SampleRsm;
pub use seed_clusters::SeedClusters;
pub use select_photon_plan::SelectPhotonPlan;
pub use shading_normal_correction::ShadingNormalCorrection;
pub use sort_indirect_paths::SortIndirectPaths;
pub use splat_photons::SplatPhotons;
pub use temporal_blend::TemporalBlend;
pub use tile_hit_distance::TileHitDistance;
pub use trace_indirect::{IndirectWave, TraceIndirect, WaveKeys, TRACE_INDIRECT_SWITCHES};
pub use trace_photons::{
    AtlasDeposit, ClusterBatch, FusedDeposit, ScreenDeposit, TracePhotons, TraceVariant,
};

use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes, SceneArgs};
pub use crate::device::launch::{variant_label, variant_labels, DEFAULT_WORKGROUP_SIZE};
use crate::device::launch::{Launch, LaunchArg};
pub use crate::device::layout::{MAX_SPECULAR_DEPTH, VISIBLE_TOLERANCE};

/// How a kernel binds one of its launch arguments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    /// A `#[repr(C)]` parameter block: a uniform buffer in WGSL and Vulkan, a small
    /// read-only buffer in OpenCL, a struct on the CPU.
    Params,
    /// A device buffer the kernel only reads.
    Read,
    /// A device buffer the kernel writes (or reads and writes, atomics included).
    ReadWrite,
    /// An element count passed as a scalar to OpenCL C; WGSL and GLSL derive it from the
    /// length of the buffer before it, so they bind nothing for it.
    Count,
}

/// One launch argument of a kernel, in the order of its OpenCL C signature.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    /// Name of the argument: its OpenCL C parameter and WGSL binding.
    pub name: &'static str,
    /// How it is bound.
    pub kind: BindingKind,
}

/// A binding (shorthand for the declarations).
pub const fn bind(name: &'static str, kind: BindingKind) -> Binding {
    Binding { name, kind }
}

/// The scene's buffers as every traced kernel binds them first: vertices, triangles,
/// materials, lights, the CWBVH nodes and their count. Vulkan replaces `nodes` (and
/// its count) with the driver-built acceleration structure at binding 0.
pub const SCENE_BINDINGS: [Binding; 6] = [
    bind("vertices", BindingKind::Read),
    bind("triangles", BindingKind::Read),
    bind("materials", BindingKind::Read),
    bind("lights", BindingKind::Read),
    bind("nodes", BindingKind::Read),
    bind("bvh_node_count", BindingKind::Count),
];

/// [`SCENE_BINDINGS`] followed by `rest`: the bindings of a traced kernel. `N` must be
/// `6 + M` (checked when the constant is evaluated, i.e. at compile time).
pub const fn with_scene<const M: usize, const N: usize>(rest: [Binding; M]) -> [Binding; N] {
    assert!(N == SCENE_BINDINGS.len() + M, "with_scene: N must be 6 + M");
    let mut out = [bind("", BindingKind::Count); N];
    let mut i = 0;
    while i < SCENE_BINDINGS.len() {
        out[i] = SCENE_BINDINGS[i];
        i += 1;
    }
    let mut j = 0;
    while j < M {
        out[SCENE_BINDINGS.len() + j] = rest[j];
        j += 1;
    }
    out
}

/// A kernel's declaration: everything a backend needs to know about it but its code.
#[derive(Clone, Copy, Debug)]
pub struct KernelInfo {
    /// Registry name; also the stem of the kernel's shader files.
    pub name: &'static str,
    /// Launch arguments in order (the OpenCL C signature; WGSL and GLSL skip counts).
    pub bindings: &'static [Binding],
    /// Threads per workgroup on GPU backends (1-D); compute shaders declare the same.
    pub workgroup_size: u32,
    /// Traces rays against the scene: a ray-tracing pipeline on Vulkan, a software CWBVH
    /// traversal elsewhere.
    pub traced: bool,
    /// Compiled switches (variants are compiled, not branched), in
    /// specialization-constant id order.
    pub switches: &'static [&'static str],
    /// Techniques that use it.
    pub used_by: &'static str,
}

impl KernelInfo {
    /// A compute kernel (no ray tracing, no switches) of [`DEFAULT_WORKGROUP_SIZE`].
    pub const fn compute(
        name: &'static str,
        bindings: &'static [Binding],
        used_by: &'static str,
    ) -> KernelInfo {
        KernelInfo {
            name,
            bindings,
            workgroup_size: DEFAULT_WORKGROUP_SIZE,
            traced: false,
            switches: &[],
            used_by,
        }
    }

    /// A kernel that traces rays against the scene (bindings from [`with_scene`]), of
    /// [`DEFAULT_WORKGROUP_SIZE`], with compiled `switches`.
    pub const fn traced(
        name: &'static str,
        bindings: &'static [Binding],
        switches: &'static [&'static str],
        used_by: &'static str,
    ) -> KernelInfo {
        KernelInfo {
            name,
            bindings,
            workgroup_size: DEFAULT_WORKGROUP_SIZE,
            traced: true,
            switches,
            used_by,
        }
    }
}

/// A binding as the GPU shading languages see it (counts dropped).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ShaderBinding {
    /// The scene's acceleration structure (Vulkan ray-tracing kernels, binding 0).
    AccelerationStructure,
    /// A uniform buffer: the kernel's parameter block.
    Uniform,
    /// A read-only storage buffer.
    StorageRead,
    /// A read-write storage buffer.
    StorageReadWrite,
}

impl KernelInfo {
    /// The bindings of the WGSL module (`@group(0) @binding(i)` in order): every launch
    /// argument but counts.
    pub fn wgsl_bindings(&self) -> Vec<(&'static str, ShaderBinding)> {
        self.bindings
            .iter()
            .filter_map(|b| shader_binding(b.kind).map(|k| (b.name, k)))
            .collect()
    }

    /// The descriptor bindings of the kernel's Vulkan pipeline: ray-traced kernels bind
    /// the acceleration structure at 0 in place of the CWBVH nodes; compute kernels (the
    /// WGSL through naga) bind exactly [`KernelInfo::wgsl_bindings`].
    pub fn descriptor_bindings(&self) -> Vec<ShaderBinding> {
        let mut out = Vec::new();
        if self.traced {
            out.push(ShaderBinding::AccelerationStructure);
        }
        for b in self.bindings {
            if self.traced && b.name == "nodes" {
                continue;
            }
            if let Some(k) = shader_binding(b.kind) {
                out.push(k);
            }
        }
        out
    }
}

fn shader_binding(kind: BindingKind) -> Option<ShaderBinding> {
    match kind {
        BindingKind::Params => Some(ShaderBinding::Uniform),
        BindingKind::Read => Some(ShaderBinding::StorageRead),
        BindingKind::ReadWrite => Some(ShaderBinding::StorageReadWrite),
        BindingKind::Count => None,
    }
}

/// Implemented by each kernel's argument struct, in its own file.
pub trait KernelDecl {
    /// The kernel's declaration.
    const INFO: KernelInfo;

    /// Pushes the launch arguments in declaration order onto `args` (each push is checked
    /// against [`KernelInfo::bindings`]) and returns the number of threads, or `None` for
    /// a kernel that launches nothing on GPU-style backends (`prepare_scene`).
    fn lower(&self, args: &mut Args) -> Result<Option<u64>, BackendError>;

    /// Values of [`KernelInfo::switches`], in order (small enumerations; 0/1 for flags).
    fn switch_values(&self) -> Vec<u32> {
        Vec::new()
    }

    /// The scene a traced kernel traces against (`None` for compute kernels; every
    /// traced kernel overrides it, as a test checks).
    fn scene(&self) -> Option<&SceneArgs> {
        None
    }

    /// The bytes of the kernel's parameter block, for kernels whose parameters may come
    /// partly from the device ([`crate::device::launch::ParamPatch`]; `None`: they may
    /// not).
    fn params_mut(&mut self) -> Option<&mut [u8]> {
        None
    }
}

/// The launch arguments of one kernel under construction, checked against its declaration:
/// a push whose name or kind differs from the next declared binding is an error, so a
/// declaration and its lowering cannot drift apart.
pub struct Args {
    info: &'static KernelInfo,
    args: Vec<LaunchArg>,
    indirect: Option<crate::device::launch::Indirect>,
}

fn bad(why: String) -> BackendError {
    BackendError::BadArgument(why)
}

impl Args {
    fn expect(&mut self, name: &'static str, kind: BindingKind) -> Result<(), BackendError> {
        let i = self.args.len();
        match self.info.bindings.get(i) {
            Some(b) if b.name == name && b.kind == kind => Ok(()),
            other => Err(bad(format!(
                "{}: argument {i} lowered as {name} ({kind:?}), declared as {other:?}",
                self.info.name
            ))),
        }
    }

    /// A device buffer that the launch reads or writes up to `need` bytes of (at least its
    /// whole logical size).
    pub fn buf<T>(
        &mut self,
        name: &'static str,
        b: Buf<T>,
        need: u64,
    ) -> Result<&mut Self, BackendError> {
        let kind = self
            .info
            .bindings
            .get(self.args.len())
            .map(|b| b.kind)
            .filter(|k| matches!(k, BindingKind::Read | BindingKind::ReadWrite))
            .unwrap_or(BindingKind::Read);
        self.expect(name, kind)?;
        self.args.push(LaunchArg::Buffer {
            id: b.id,
            bytes: b.bytes(),
            need: need.max(b.bytes()),
            what: name,
        });
        Ok(self)
    }

    /// A parameter block.
    pub fn params<T: bytemuck::Pod>(
        &mut self,
        name: &'static str,
        p: &T,
    ) -> Result<&mut Self, BackendError> {
        self.expect(name, BindingKind::Params)?;
        self.args
            .push(LaunchArg::Params(bytemuck::bytes_of(p).to_vec()));
        Ok(self)
    }

    /// An element count.
    pub fn count(&mut self, name: &'static str, n: u32) -> Result<&mut Self, BackendError> {
        self.expect(name, BindingKind::Count)?;
        self.args.push(LaunchArg::Count(n));
        Ok(self)
    }

    /// The scene's [`SCENE_BINDINGS`].
    pub fn scene(&mut self, s: &SceneArgs) -> Result<&mut Self, BackendError> {
        if !s.bvh_nodes.len.is_multiple_of(5) {
            return Err(bad(
                "BVH node buffer is not a whole number of 80-byte nodes".into(),
            ));
        }
        self.buf("vertices", s.vertices, 0)?
            .buf("triangles", s.triangles, 0)?
            .buf("materials", s.materials, 0)?
            .buf("lights", s.lights, 0)?
            .buf("nodes", s.bvh_nodes, 0)?
            .count("bvh_node_count", s.bvh_nodes.len / 5)
    }
}

/// Binding names of the G-buffer's planes, in launch order.
pub const GBUFFER_BINDINGS: [&str; 4] = ["gbuffer0", "gbuffer1", "gbuffer2", "gbuffer3"];

/// Binding names of the screen photon map's planes, in launch order.
pub const PHOTON_MAP_BINDINGS: [&str; 3] = ["photon_map0", "photon_map1", "photon_map2"];

/// The binding names of PhotonGi's light-direction map's planes (a photon map's layout).
pub const DIRECTION_MAP_BINDINGS: [&str; 3] =
    ["direction_map0", "direction_map1", "direction_map2"];

impl Args {
    /// The G-buffer's planes ([`GBUFFER_BINDINGS`]), each holding `pixels` texels.
    pub fn gbuffer(&mut self, g: &GBufferPlanes, pixels: u64) -> Result<&mut Self, BackendError> {
        for (name, p) in GBUFFER_BINDINGS.into_iter().zip(g.planes) {
            self.buf(name, p, pixels * bytes::GBUFFER_PLANE_TEXEL)?;
        }
        Ok(self)
    }

    /// The G-buffer planes a gather reads of its neighbours (0: depth, 1: normal, 3:
    /// flags), each holding `pixels` texels.
    pub fn gather_gbuffer(
        &mut self,
        g: &GBufferPlanes,
        pixels: u64,
    ) -> Result<&mut Self, BackendError> {
        for k in [0, 1, 3] {
            self.buf(
                GBUFFER_BINDINGS[k],
                g.planes[k],
                pixels * bytes::GBUFFER_PLANE_TEXEL,
            )?;
        }
        Ok(self)
    }

    /// The screen photon map's planes ([`PHOTON_MAP_BINDINGS`]), each holding `pixels`
    /// texels.
    pub fn photon_map(
        &mut self,
        m: &PhotonMapPlanes,
        pixels: u64,
    ) -> Result<&mut Self, BackendError> {
        self.named_photon_map(PHOTON_MAP_BINDINGS, m, pixels)
    }

    /// [`Args::photon_map`] under the binding names `names`.
    pub fn named_photon_map(
        &mut self,
        names: [&'static str; 3],
        m: &PhotonMapPlanes,
        pixels: u64,
    ) -> Result<&mut Self, BackendError> {
        for (k, (name, p)) in names.into_iter().zip(m.planes).enumerate() {
            let words = crate::device::layout::DEPOSIT_PLANE_WORDS[k] as u64;
            self.buf(name, p, pixels * words * 4)?;
        }
        Ok(self)
    }
}

/// Texels of a `w x h` image.
pub(crate) fn texels(w: u32, h: u32) -> u64 {
    w as u64 * h as u64
}

/// Tiles of `tile_size^2` pixels covering a `w x h` image.
pub(crate) fn tiles(w: u32, h: u32, tile_size: u32) -> Result<u64, BackendError> {
    if tile_size == 0 {
        return Err(bad("tile_size is 0".into()));
    }
    Ok(texels(w.div_ceil(tile_size), h.div_ceil(tile_size)))
}

/// Element sizes the lowerings size buffers with (bytes).
pub(crate) mod bytes {
    use crate::device::layout::{counter, GBufferPlaneTexel, Photon};
    use std::mem::size_of;
    pub const GBUFFER_PLANE_TEXEL: u64 = size_of::<GBufferPlaneTexel>() as u64;
    pub const IMAGE_TEXEL: u64 = 16;
    pub const PHOTON: u64 = size_of::<Photon>() as u64;
    pub const COUNTERS: u64 = 4 * counter::WORDS as u64;
    pub const LIGHT: u64 = size_of::<crate::device::layout::GpuLight>() as u64;
    pub const RSM_TEXEL: u64 = size_of::<crate::device::layout::RsmTexel>() as u64;
    pub const RSM_PHOTON: u64 = size_of::<crate::device::layout::RsmPhoton>() as u64;
    pub const GI_PHOTON: u64 = size_of::<crate::device::layout::GiPhoton>() as u64;
    pub const INDIRECT_PATH: u64 = size_of::<crate::device::layout::IndirectPath>() as u64;
}

/// Called with the one list ([`with_kernels!`](crate::with_kernels)): generates
/// [`Kernel`], [`KERNELS`], `From<...>` for each argument struct, and the lowering
/// dispatch.
macro_rules! kernel_list {
    ($($variant:ident => $module:ident),* $(,)?) => {
        /// One kernel dispatch with its typed arguments (see each struct for its contract).
        // A recording holds a few dispatches a frame: the size of the largest (the trace
        // with its fused deposit's parameters) costs nothing worth a box.
        #[allow(clippy::large_enum_variant)]
        #[derive(Clone, Debug)]
        pub enum Kernel {
            $(
                #[doc = concat!("The `", stringify!($module), "` kernel with its arguments ([`", stringify!($variant), "`]).")]
                $variant($variant),
            )*
        }

        /// Every kernel of the library, in list order.
        pub const KERNELS: &[KernelInfo] = &[$(<$variant as KernelDecl>::INFO,)*];

        $(impl From<$variant> for Kernel {
            fn from(k: $variant) -> Kernel {
                Kernel::$variant(k)
            }
        })*

        impl Kernel {
            /// The declaration of this kernel.
            pub fn info(&self) -> &'static KernelInfo {
                match self {
                    $(Kernel::$variant(_) => &<$variant as KernelDecl>::INFO,)*
                }
            }

            fn lower_into(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
                match self {
                    $(Kernel::$variant(k) => k.lower(a),)*
                }
            }

            fn switch_values(&self) -> Vec<u32> {
                match self {
                    $(Kernel::$variant(k) => k.switch_values(),)*
                }
            }

            /// The scene a traced kernel traces against (`None` for compute kernels).
            pub fn scene(&self) -> Option<&SceneArgs> {
                match self {
                    $(Kernel::$variant(k) => KernelDecl::scene(k),)*
                }
            }

            /// The bytes of the kernel's parameter block where its parameters may come
            /// partly from the device ([`KernelDecl::params_mut`]).
            pub fn params_mut(&mut self) -> Option<&mut [u8]> {
                match self {
                    $(Kernel::$variant(k) => KernelDecl::params_mut(k),)*
                }
            }
        }
    };
}

/// Calls macro `$m` with the one list of kernels, `Variant => module` (the argument
/// struct in [`crate::kernels`] and the stem of the kernel's files), in registry order.
/// [`Kernel`](crate::kernels::Kernel) and [`KERNELS`](crate::kernels::KERNELS) are built
/// from it, and so are the CPU backend's kernel modules and their dispatch.
#[macro_export]
macro_rules! with_kernels {
    ($m:ident) => {
        $m! {
            PrepareScene => prepare_scene,
            PlaceVertices => place_vertices,
            PrimaryGbuffer => primary_gbuffer,
            DirectLight => direct_light,
            TracePhotons => trace_photons,
            DepositScreen => deposit_screen,
            ResolveCaustics => resolve_caustics,
            TileHitDistance => tile_hit_distance,
            BilateralGather => bilateral_gather,
            PhotonCountTable => photon_count_table,
            GatherFootprint => gather_footprint,
            DensityGather => density_gather,
            Composite => composite,
            TemporalBlend => temporal_blend,
            AtrousFilter => atrous_filter,
            GatherCausticMap => gather_caustic_map,
            CausticMapLookup => caustic_map_lookup,
            DispatchArgs => dispatch_args,
            RefineClusters => refine_clusters,
            SeedClusters => seed_clusters,
            RsmImportance => rsm_importance,
            SampleRsm => sample_rsm,
            TraceIndirect => trace_indirect,
            SortIndirectPaths => sort_indirect_paths,
            SplatPhotons => splat_photons,
            ShadingNormalCorrection => shading_normal_correction,
            SelectPhotonPlan => select_photon_plan,
        }
    };
}

crate::with_kernels!(kernel_list);

/// Calls macro `$m` with the registry names of the kernels that have shader code, every
/// kernel of [`with_kernels!`](crate::with_kernels) but `prepare_scene` (which launches
/// nothing on a device), in the order the OpenCL program appends their files.
/// caustica-shaders and caustica-opencl build their kernel tables from it
/// (`wgsl/<name>.wgsl`, `kernels/<name>.cl`, read with `include_str!`, so a missing file
/// fails their build) and caustica-conformance its check modules; a unit test below
/// checks it against [`KERNELS`](crate::kernels::KERNELS).
#[macro_export]
macro_rules! with_shader_kernels {
    ($m:ident) => {
        $m! {
            place_vertices,
            primary_gbuffer,
            direct_light,
            trace_photons,
            deposit_screen,
            resolve_caustics,
            tile_hit_distance,
            bilateral_gather,
            photon_count_table,
            gather_footprint,
            density_gather,
            composite,
            gather_caustic_map,
            caustic_map_lookup,
            dispatch_args,
            refine_clusters,
            seed_clusters,
            temporal_blend,
            atrous_filter,
            shading_normal_correction,
            rsm_importance,
            sample_rsm,
            trace_indirect,
            sort_indirect_paths,
            splat_photons,
            select_photon_plan,
        }
    };
}

impl Kernel {
    /// The registry name of this kernel.
    pub fn name(&self) -> &'static str {
        self.info().name
    }

    /// Lowers the kernel to its launch: arguments in declaration order with the bytes
    /// each buffer must hold, the thread count and the switch values; `None` for
    /// `prepare_scene` (GPU-style backends traverse the uploaded node array as it is;
    /// only its shape is checked). A [`crate::recording::Recording`] lowers each kernel
    /// once, when it is recorded.
    pub fn launch(&self) -> Result<Option<Launch>, BackendError> {
        let info = self.info();
        let mut a = Args {
            info,
            args: Vec::new(),
            indirect: None,
        };
        let Some(threads) = self.lower_into(&mut a)? else {
            return Ok(None);
        };
        if a.args.len() != info.bindings.len() {
            return Err(bad(format!(
                "{}: lowered {} arguments, declared {}",
                info.name,
                a.args.len(),
                info.bindings.len()
            )));
        }
        let values = self.switch_values();
        if values.len() != info.switches.len() {
            return Err(bad(format!(
                "{}: {} switch values for {} switches",
                info.name,
                values.len(),
                info.switches.len()
            )));
        }
        Ok(Some(Launch {
            kernel: info.name,
            constants: info.switches.iter().copied().zip(values).collect(),
            threads,
            workgroup_size: info.workgroup_size,
            args: a.args,
            indirect: a.indirect,
            patches: Vec::new(),
        }))
    }
}

/// The declaration of kernel `name`.
pub fn kernel_info(name: &str) -> Option<&'static KernelInfo> {
    KERNELS.iter().find(|k| k.name == name)
}

/// Registry kernel names, in list order.
pub fn all_kernel_names() -> Vec<&'static str> {
    KERNELS.iter().map(|k| k.name).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `with_shader_kernels!` names every kernel of the list but `prepare_scene`, once.
    #[test]
    fn shader_kernels_are_the_list_but_prepare_scene() {
        macro_rules! names {
            ($($n:ident),* $(,)?) => {
                [$(stringify!($n)),*]
            };
        }
        let mut shader: Vec<&str> = crate::with_shader_kernels!(names).to_vec();
        let mut list: Vec<&str> = KERNELS
            .iter()
            .map(|k| k.name)
            .filter(|n| *n != "prepare_scene")
            .collect();
        shader.sort_unstable();
        list.sort_unstable();
        assert_eq!(shader, list);
    }

    #[test]
    fn names_are_unique_and_snake_case() {
        let names = all_kernel_names();
        for (i, n) in names.iter().enumerate() {
            assert!(!names[..i].contains(n), "{n} listed twice");
            assert!(n.chars().all(|c| c.is_ascii_lowercase() || c == '_'));
        }
    }

    #[test]
    fn traced_kernels_bind_the_scene_first() {
        for k in KERNELS.iter().filter(|k| k.traced) {
            assert_eq!(&k.bindings[..6], &SCENE_BINDINGS, "{}", k.name);
            assert_eq!(
                k.descriptor_bindings()[0],
                ShaderBinding::AccelerationStructure
            );
        }
    }
}
