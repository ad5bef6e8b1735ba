// Shared data layouts: mirrors of core/src/gpu.rs under the scalar block layout
// (GL_EXT_scalar_block_layout: vec3 is 12 bytes aligned to 4), so every struct matches
// Rust's #[repr(C)] byte for byte. Same field names as core.

struct GpuVertex { vec3 position; float u; vec3 normal; float v; };
struct GpuTriangle { uvec3 indices; uint material; };
struct GpuMaterial { uint kind; float ior; float cauchy_b; uint _pad; vec4 color; vec4 absorption; };
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
    vec3 normal; float roughness;
    vec3 albedo; uint material;
    vec2 uv; float view_distance; uint flags;
};
struct Photon { vec3 position; float hit_distance; vec3 flux; uint direction; };
struct TraceParams {
    uint light; uint emission; uint grid_w; uint grid_h;
    uint first; uint count; uint seed; uint max_bounces;
    vec4 origin; vec4 axis; vec4 rect_u; vec4 rect_v; vec4 photon_flux;
    float flux_quantum; uint _pad0; uint _pad1; uint _pad2;
};
struct DirectParams {
    GpuCamera camera;
    uint light_count; uint max_specular_depth; float min_weight; uint _pad;
};

const uint MATERIAL_DIFFUSE = 0u;
const uint MATERIAL_MIRROR = 1u;
const uint MATERIAL_DIELECTRIC = 2u;
const uint LIGHT_POINT = 0u;
const uint LIGHT_SPOT = 1u;
const uint LIGHT_DIRECTIONAL = 2u;
const uint EMISSION_CONE = 0u;
const uint EMISSION_RECTANGLE = 1u;
const uint GBUFFER_RECEIVER = 1u;
const uint NO_MATERIAL = 0xffffffffu;
const uint COUNTER_STORED = 0u;
const uint COUNTER_NO_SPECULAR = 1u;
const uint COUNTER_ESCAPED = 2u;
const uint COUNTER_NEGLIGIBLE = 3u;
const uint COUNTER_BOUNCE_LIMIT = 4u;
const uint COUNTER_RAYS = 10u;
const uint COUNTER_STORED_FLUX = 12u;
const uint COUNTER_WORDS = 20u;
const uint MAX_SPECULAR_DEPTH = 30u; // core::sspm::MAX_SPECULAR_DEPTH
const float PI_F = 3.14159265358979323846;
const float TAU_F = 6.28318530717958647692;
// "no t_max": traceRayEXT needs finite values; f32::MAX
const float NO_T_MAX = 3.4028235e38;
