// Shared data layouts: mirrors of core/src/gpu.rs (#[repr(C)] + Pod) and of
// backend-opencl/kernels/types.cl. Every struct matches Rust byte for byte under WGSL's
// layout rules (tests/wgsl_validate.rs compares naga's offsets with `offset_of!`):
// `vec3<f32>` has align 16 and size 12, so `position: vec3<f32>, u: f32` is 16 bytes, as
// `[f32; 3], f32` in Rust; pad arrays are separate u32 words (`_pad: [u32; 3]` becomes
// `_pad0, _pad1, _pad2`), never a vec3. Structs used in the uniform address space nest
// only 16-byte aligned structs (GpuCamera: align 16, size 64).
// Spaces: world positions and directions; `depth` is view depth; pixel (0, 0) top-left.
//
// No binding is declared in a shared file. Shared functions may read module-scope
// variables that the kernel file declares with exactly these names: `vertices`,
// `triangles`, `materials`, `lights`, `nodes` (traversal.wgsl) and `lc`, `counters`
// (fixed_point.wgsl).
//
// Floating point: the OpenCL port compiles with FP_CONTRACT OFF so that every product
// and sum rounds as in Rust. WGSL has no such switch: a driver may fuse a * b + c into
// an fma (naga emits no NoContraction), and WGSL's division, sqrt, exp, pow, sin and cos
// are only accurate to a few ulp. The functions below keep the operation order of the
// Rust and OpenCL code so that they round the same wherever the device does.

struct GpuVertex {
    position: vec3<f32>,
    u: f32,
    normal: vec3<f32>,
    v: f32,
}

struct GpuTriangle {
    indices: vec3<u32>,
    material: u32,
}

struct GpuMaterial {
    kind: u32,
    ior: f32,
    cauchy_b: f32,
    _pad: u32,
    color: vec4<f32>,
    absorption: vec4<f32>,
}

struct GpuLight {
    kind: u32,
    cos_inner: f32,
    cos_outer: f32,
    _pad: u32,
    position: vec4<f32>,
    direction: vec4<f32>,
    intensity: vec4<f32>,
}

struct GpuCamera {
    position: vec3<f32>,
    tan_half_fov_x: f32,
    forward: vec3<f32>,
    tan_half_fov_y: f32,
    right: vec3<f32>,
    width: u32,
    up: vec3<f32>,
    height: u32,
}

struct GBufferTexel {
    position: vec3<f32>,
    depth: f32,
    normal: vec3<f32>,
    geometric_normal: u32,
    albedo: vec3<f32>,
    material: u32,
    uv: vec2<f32>,
    view_distance: f32,
    flags: u32,
}

struct Photon {
    position: vec3<f32>,
    hit_distance: f32,
    flux: vec3<f32>,
    direction: u32,
}

// DepositTexel (core::gpu::DepositTexel) is not a struct here: the photon map is u32
// words, DEPOSIT_TEXEL_WORDS per pixel, five u64 sums as (lo, hi) words, stored in planes
// of at most 4 words a pixel (core's DEPOSIT_PLANES: words 0-3, 4-7, 8-9).
const DEPOSIT_TEXEL_WORDS: u32 = 10u;
const DEPOSIT_FLUX: u32 = 0u; // r, g, b at words 0, 2, 4
const DEPOSIT_HIT_DISTANCE: u32 = 6u;
const DEPOSIT_PHOTONS: u32 = 8u;

// core's deposit_word: (plane, index in the plane) of word `word` of pixel `pixel`.
fn deposit_word(pixel: u32, word: u32) -> vec2<u32> {
    let k = word / 4u;
    let n = select(4u, 2u, k == 2u);
    return vec2<u32>(k, pixel * n + (word - 4u * k));
}

struct TraceParams {
    light: u32,
    emission: u32,
    grid_w: u32,
    grid_h: u32,
    first: u32,
    count: u32,
    seed: u32,
    max_bounces: u32,
    origin: vec4<f32>,
    axis: vec4<f32>,
    rect_u: vec4<f32>,
    rect_v: vec4<f32>,
    photon_flux: vec4<f32>,
    flux_quantum: f32,
    split_budget: u32,
    fresnel_model: u32,
    caster_sphere_count: u32,
    caster_spheres: array<vec4<f32>, MAX_CASTER_SPHERES>,
}

struct DepositParams {
    camera: GpuCamera,
    flux_quantum: f32,
    hit_distance_quantum: f32,
    depth_tolerance: f32,
    photon_capacity: u32,
}

struct GatherParams {
    camera: GpuCamera,
    roughness: f32,
    hit_distance_min: f32,
    hit_distance_max: f32,
    max_radius_px: u32,
    sigma_depth: f32,
    normal_power: f32,
    axis: u32,
    tile_size: u32,
    hit_distance_quantum: f32,
    knn_photons: u32,
    flux_quantum: f32,
    table_block: u32,
    surface: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

struct AtlasParams {
    width: u32,
    height: u32,
    flux_quantum: f32,
    hit_distance_quantum: f32,
    photon_capacity: u32,
    gather_width: u32,
    _pad0: u32,
    _pad1: u32,
}

struct MapLookupParams {
    camera: GpuCamera,
    atlas_width: u32,
    max_specular_depth: u32,
    min_weight: f32,
    fresnel_model: u32,
}

struct RefineParams {
    atlas_width: u32,
    flux_quantum: f32,
    hit_distance_quantum: f32,
    level: u32,
    finest: u32,
    metric: u32,
    error_from_level: u32,
    grid_w: u32,
    first: u32,
    count: u32,
    children_capacity: u32,
    relevance: u32,
    rect_count: u32,
    deposit_target: u32,
    error_texels: u32,
    _pad0: u32,
    camera: GpuCamera,
}

struct AtrousParams {
    camera: GpuCamera,
    iteration: u32,
    last: u32,
    sigma_z: f32,
    sigma_n: f32,
    epsilon: f32,
    clip_sigmas: f32,
    _pad0: u32,
    _pad1: u32,
}

struct TemporalParams {
    camera: GpuCamera,
    previous: GpuCamera,
    alpha_max: f32,
    sigma_z: f32,
    sigma_n: f32,
    epsilon: f32,
    history_frames: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

// PhotonGi (seed 003): core::device::layout::{RsmTexel, RsmPhoton, RsmParams, GiPhoton,
// IndirectTraceParams, SplatParams}.
struct RsmTexel {
    position: vec3<f32>,
    normal: u32,
    flux: vec3<f32>,
    kind: u32,
}

struct RsmPhoton {
    origin: vec3<f32>,
    direction: u32,
    flux: vec3<f32>,
    bounces: u32,
}

struct RsmParams {
    face_camera: GpuCamera,
    light: u32,
    face: u32,
    side: u32,
    level: u32,
    face_count: u32,
    first_sample: u32,
    sample_count: u32,
    seed: u32,
    sampling: u32,
    _pad0: u32,
    _pad1: u32,
    _pad2: u32,
}

const RSM_SAMPLING_UNIFORM: u32 = 1u; // core::math::rsm::rsm_sampling

struct GiPhoton {
    position: vec3<f32>,
    power: u32,
    normal: u32,
    direction: u32,
    ray_length: f32,
    tile: u32,
}

struct IndirectTraceParams {
    camera: GpuCamera,
    first: u32,
    count: u32,
    seed: u32,
    max_bounces: u32,
    max_segments: u32,
    tile_size: u32,
    store: u32,
    fresnel_model: u32,
    power_scale: f32,
    flux_quantum: f32,
    _pad0: u32,
    _pad1: u32,
}

struct SplatParams {
    camera: GpuCamera,
    tile_size: u32,
    power_scale: f32,
    flux_quantum: f32,
    max_splat_px: u32,
    max_ray_length: f32,
    min_length_scale: f32,
    density_radius_min: f32,
    density_radius_max: f32,
    photons_per_pixel: f32,
    normal_compression: f32,
    max_stretch: f32,
    tile_constant: f32,
    min_splat_px: f32,
    light_direction: u32,
    _pad0: u32,
    _pad1: u32,
}

struct CorrectionParams {
    width: u32,
    height: u32,
    max_stretch: f32,
    epsilon: f32,
}

const RSM_TEXEL_NONE: u32 = 0u; // core::math::rsm::rsm_texel_kind
const RSM_TEXEL_DIFFUSE: u32 = 1u;
const RSM_TEXEL_SPECULAR: u32 = 2u;
const GI_STORE_PACKED: u32 = 0u; // core::math::gi_photon::gi_store
const GI_STORE_FLOAT: u32 = 1u;

struct DirectParams {
    camera: GpuCamera,
    light_count: u32,
    max_specular_depth: u32,
    min_weight: f32,
    fresnel_model: u32,
}

// core::gpu constants
const MATERIAL_DIFFUSE: u32 = 0u;
const MATERIAL_MIRROR: u32 = 1u;
const MATERIAL_DIELECTRIC: u32 = 2u;
const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_DIRECTIONAL: u32 = 2u;
const EMISSION_CONE: u32 = 0u;
const EMISSION_RECTANGLE: u32 = 1u;
const EMISSION_VIEW_PLANE: u32 = 2u;
const NO_TILE: u32 = 0xffffffffu;
const GATHER_SURFACE_ATLAS: u32 = 1u; // core::device::layout::gather_surface::ATLAS
const GBUFFER_RECEIVER: u32 = 1u;
const NO_MATERIAL: u32 = 0xffffffffu;
// core::gpu::counter word offsets
const COUNTER_STORED: u32 = 0u;
const COUNTER_NO_SPECULAR: u32 = 1u;
const COUNTER_ESCAPED: u32 = 2u;
const COUNTER_NEGLIGIBLE: u32 = 3u;
const COUNTER_BOUNCE_LIMIT: u32 = 4u;
const COUNTER_OFF_SCREEN: u32 = 5u;
const COUNTER_DEPTH_MISMATCH: u32 = 6u;
const COUNTER_DEPOSITED: u32 = 7u;
const COUNTER_UNDERFLOW: u32 = 8u;
const COUNTER_SATURATED: u32 = 9u;
const COUNTER_RAYS: u32 = 10u;
const COUNTER_STORED_FLUX: u32 = 12u;
const COUNTER_SPLITS: u32 = 18u;
const MAX_SPLIT_BRANCHES: u32 = 32u; // core::device::layout::MAX_SPLIT_BRANCHES
const MAX_CASTER_SPHERES: u32 = 8u; // core::device::layout::MAX_CASTER_SPHERES
const COUNTER_WORDS: u32 = 20u;

const MAX_SPECULAR_DEPTH: u32 = 30u; // core::sspm::MAX_SPECULAR_DEPTH
// f32 literals carry the `f` suffix so that naga parses them straight to f32, as Rust
// does (an unsuffixed literal would round through f64 first).
const PI_F: f32 = 3.14159265358979323846f;
const TAU_F: f32 = 6.28318530717958647692f;

// Invocations per workgroup: every kernel is `@workgroup_size(64)`.
const WORKGROUP_SIZE: u32 = 64u;

// WGSL has no infinity literal (and a runtime infinity is allowed to be indeterminate), so
// "no t_max" (Rust's f32::INFINITY, OpenCL's INFINITY) is f32::MAX. The only difference:
// a hit at exactly t = f32::MAX, or a box entered at t = +inf, counts on the CPU and not
// here; neither occurs with finite scenes.
const NO_T_MAX: f32 = 3.4028235e38f;
