// Shared data layouts: mirrors of core/src/gpu.rs (#[repr(C)] + Pod) and of
// backend-opencl/kernels/types.cl, same names, same field order. Every struct is built
// from 4-byte scalars and vectors of them. Blocks that hold these structs are declared
// `layout(scalar)` (GL_EXT_scalar_block_layout; the device enables scalarBlockLayout):
// every member sits at the next multiple of 4, exactly as in Rust, so `vec3 position;
// float u;` is 16 bytes as `[f32; 3], f32`. The structs are laid out identically under
// std430, and the parameter structs (the uniform blocks) under std140 too: every vec3 is
// followed by a 4-byte scalar, every vec4 and nested struct starts at a multiple of 16,
// and their pad arrays are separate words (DepositTexel's words[10] is storage-only), so
// a block may switch layout without moving a byte (checked on the compiled offsets).
// Byte offsets, checked against gpu.rs and the SPIR-V Offset decorations:
//   GpuVertex     32: position 0, u 12, normal 16, v 28
//   GpuTriangle   16: indices 0, material 12
//   GpuMaterial   48: kind 0, ior 4, cauchy_b 8, _pad 12, color 16, absorption 32
//   GpuLight      64: kind 0, cos_inner 4, cos_outer 8, _pad 12, position 16,
//                     direction 32, intensity 48
//   GpuCamera     64: position 0, tan_half_fov_x 12, forward 16, tan_half_fov_y 28,
//                     right 32, width 44, up 48, height 60
//   GBufferTexel  64: position 0, depth 12, normal 16, geometric_normal 28, albedo 32,
//                     material 44, uv 48, view_distance 56, flags 60
//   Photon        32: position 0, hit_distance 12, flux 16, direction 28
//   DepositTexel  40: words 0 (10 x u32)
//   TraceParams  256: light 0, emission 4, grid_w 8, grid_h 12, first 16, count 20,
//                     seed 24, max_bounces 28, origin 32, axis 48, rect_u 64, rect_v 80,
//                     photon_flux 96, flux_quantum 112, split_budget 116,
//                     fresnel_model 120, caster_sphere_count 124, caster_spheres 128
//   DepositParams 80: camera 0, flux_quantum 64, hit_distance_quantum 68,
//                     depth_tolerance 72, photon_capacity 76
//   GatherParams 128: camera 0, roughness 64, hit_distance_min 68, hit_distance_max 72,
//                     max_radius_px 76, sigma_depth 80, normal_power 84, axis 88,
//                     tile_size 92, hit_distance_quantum 96, knn_photons 100,
//                     flux_quantum 104, table_block 108, target 112, _pad 116..128
//   DirectParams  80: camera 0, light_count 64, max_specular_depth 68, min_weight 72,
//                     fresnel_model 76
// Spaces: world positions and directions; `depth` is view depth; pixel (0, 0) top-left.
//
// Floating point: the OpenCL port compiles with FP_CONTRACT OFF so that every product
// and sum rounds as in Rust. GLSL has no such switch; instead every function that
// computes with floats returns `precise` (and its float out-parameters and the kernels'
// float locals are `precise`), which glslang propagates to every operation that feeds
// the value: each float add, sub, mul and div carries SPIR-V NoContraction, so neither
// spirv-opt nor the driver may fuse a * b + c or reassociate (scripts/compile-shaders.sh
// fails if a float operation of a stage lacks it). glslang folds constant float
// expressions in double precision, so no shader computes with two constants (such an
// expression goes through a variable, see cauchy_ior). Division, sqrt, exp, sin and cos
// remain only as accurate as Vulkan requires (a few ulp), as in the OpenCL and WGSL ports.

struct GpuVertex { vec3 position; float u; vec3 normal; float v; };
struct GpuTriangle { uvec3 indices; uint material; };
struct GpuMaterial {
    uint kind; float ior; float cauchy_b; uint _pad;
    vec4 color; vec4 absorption;
};
struct GpuLight {
    uint kind; float cos_inner; float cos_outer; uint _pad;
    vec4 position; vec4 direction; vec4 intensity;
};
struct GpuCamera {
    vec3 position; float tan_half_fov_x;
    vec3 forward; float tan_half_fov_y;
    vec3 right; uint width;
    vec3 up; uint height;
};
struct GBufferTexel {
    vec3 position; float depth;
    vec3 normal; uint geometric_normal;
    vec3 albedo; uint material;
    vec2 uv; float view_distance; uint flags;
};
struct Photon { vec3 position; float hit_distance; vec3 flux; uint direction; };
// u64 sums as (lo, hi) u32 words: flux r, g, b, hit distance, photon count.
struct DepositTexel { uint words[10]; };
const uint MAX_CASTER_SPHERES = 8u; // core::device::layout::MAX_CASTER_SPHERES
struct TraceParams {
    uint light; uint emission; uint grid_w; uint grid_h;
    uint first; uint count; uint seed; uint max_bounces;
    vec4 origin; vec4 axis; vec4 rect_u; vec4 rect_v; vec4 photon_flux;
    float flux_quantum; uint split_budget; uint fresnel_model; uint caster_sphere_count;
    vec4 caster_spheres[MAX_CASTER_SPHERES];
};
struct DepositParams {
    GpuCamera camera;
    float flux_quantum; float hit_distance_quantum; float depth_tolerance; uint photon_capacity;
};
struct GatherParams {
    GpuCamera camera;
    float roughness; float hit_distance_min; float hit_distance_max; uint max_radius_px;
    float sigma_depth; float normal_power; uint axis; uint tile_size;
    float hit_distance_quantum; uint knn_photons; float flux_quantum; uint table_block;
    uint surface; uint _pad0; uint _pad1; uint _pad2;
};
struct DirectParams {
    GpuCamera camera;
    uint light_count; uint max_specular_depth; float min_weight; uint fresnel_model;
};

struct AtlasParams {
    uint width; uint height; float flux_quantum; float hit_distance_quantum;
    uint photon_capacity; uint gather_width; uint _pad0; uint _pad1;
};

struct MapLookupParams {
    GpuCamera camera;
    uint atlas_width; uint max_specular_depth; float min_weight; uint fresnel_model;
};
struct AtrousParams {
    GpuCamera camera;
    uint iteration; uint last; float sigma_z; float sigma_n;
    float epsilon; float clip_sigmas; uint _pad0; uint _pad1;
};
struct TemporalParams {
    GpuCamera camera;
    GpuCamera previous;
    float alpha_max; float sigma_z; float sigma_n; float epsilon;
    uint history_frames; uint _pad0; uint _pad1; uint _pad2;
};
struct RefineParams {
    uint atlas_width; float flux_quantum; float hit_distance_quantum; uint level;
    uint finest; uint metric; uint error_from_level; uint grid_w;
    uint first; uint count; uint children_capacity; uint relevance;
    uint rect_count; uint deposit_target; uint error_texels; uint _pad0;
    GpuCamera camera;
};

// The closest-hit payload (location 0) shared by the ray generation, closest-hit and miss
// stages: hit distance, triangle index (NO_HIT on a miss) and the barycentrics (u, v) of
// vertices 1 and 2 (vertex 0 weighs 1 - u - v), core's convention.
struct HitPayload { float t; uint triangle; vec2 bary; };
const uint NO_HIT = 0xffffffffu;

// core::gpu constants
const uint MATERIAL_DIFFUSE = 0u;
const uint MATERIAL_MIRROR = 1u;
const uint MATERIAL_DIELECTRIC = 2u;
const uint LIGHT_POINT = 0u;
const uint LIGHT_SPOT = 1u;
const uint LIGHT_DIRECTIONAL = 2u;
const uint EMISSION_CONE = 0u;
const uint EMISSION_RECTANGLE = 1u;
const uint EMISSION_VIEW_PLANE = 2u;
const uint NO_TILE = 0xffffffffu;
const uint GBUFFER_RECEIVER = 1u;
const uint NO_MATERIAL = 0xffffffffu;
// core::gpu::counter word offsets
// PhotonGi (seed 003): core::device::layout::{RsmTexel, RsmPhoton, RsmParams, GiPhoton,
// IndirectTraceParams, SplatParams} (trace_indirect.rgen binds RsmPhoton and
// IndirectTraceParams; the others belong to compute kernels, which Vulkan runs from WGSL).
struct RsmTexel { vec3 position; uint normal; vec3 flux; uint kind; };
struct RsmParams {
    GpuCamera face_camera;
    uint light; uint face; uint side; uint level;
    uint face_count; uint first_sample; uint sample_count; uint seed;
    uint sampling; uint _pad0; uint _pad1; uint _pad2;
};
struct GiPhoton {
    vec3 position; uint power; uint normal; uint direction; float ray_length; uint tile;
};
struct SplatParams {
    GpuCamera camera;
    uint tile_size; float power_scale; float flux_quantum; uint max_splat_px;
    float max_ray_length; float min_length_scale; float density_radius_min; float density_radius_max;
    float photons_per_pixel; float normal_compression; float max_stretch; float tile_constant;
    float min_splat_px; uint light_direction; uint _pad0; uint _pad1;
};
struct CorrectionParams { uint width; uint height; float max_stretch; float epsilon; };
struct RsmPhoton { vec3 origin; uint direction; vec3 flux; uint bounces; };
struct IndirectTraceParams {
    GpuCamera camera;
    uint first; uint count; uint seed; uint max_bounces;
    uint max_segments; uint tile_size; uint store; uint fresnel_model;
    float power_scale; float flux_quantum; uint _pad0; uint _pad1;
};
const uint GI_STORE_PACKED = 0u; // core::math::gi_photon::gi_store
const uint GI_STORE_FLOAT = 1u;

const uint COUNTER_STORED = 0u;
const uint COUNTER_NO_SPECULAR = 1u;
const uint COUNTER_ESCAPED = 2u;
const uint COUNTER_NEGLIGIBLE = 3u;
const uint COUNTER_BOUNCE_LIMIT = 4u;
const uint COUNTER_OFF_SCREEN = 5u;
const uint COUNTER_DEPTH_MISMATCH = 6u;
const uint COUNTER_DEPOSITED = 7u;
const uint COUNTER_UNDERFLOW = 8u;
const uint COUNTER_SATURATED = 9u;
const uint COUNTER_RAYS = 10u;
const uint COUNTER_STORED_FLUX = 12u;
const uint COUNTER_SPLITS = 18u;
const uint MAX_SPLIT_BRANCHES = 32u; // core::device::layout::MAX_SPLIT_BRANCHES
const uint COUNTER_WORDS = 20u;

const uint MAX_SPECULAR_DEPTH = 30u; // core::sspm::MAX_SPECULAR_DEPTH
const float PI_F = 3.14159265358979323846;
const float TAU_F = 6.28318530717958647692;
// Stands for OpenCL's INFINITY as a ray's t_max ("no limit"): traceRayEXT needs finite
// values, and this is f32::MAX.
const float NO_T_MAX = 3.4028235e38;
