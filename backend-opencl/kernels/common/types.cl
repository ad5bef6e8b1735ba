// Shared data layouts: mirrors of core/src/gpu.rs (#[repr(C)] + Pod). Every struct is
// built from 4-byte scalars in the same order, so OpenCL C and Rust agree byte for byte;
// `struct_sizes` (below) lets the host check every size against Rust's `size_of`.
// Spaces: world positions and directions; `depth` is view depth; pixel (0, 0) top-left.

// Strict IEEE single precision: no fused multiply-add, so that every product and sum is
// rounded as in the Rust reference (which never contracts).
#pragma OPENCL FP_CONTRACT OFF

typedef struct { float position[3]; float u; float normal[3]; float v; } GpuVertex;
typedef struct { uint indices[3]; uint material; } GpuTriangle;
typedef struct {
    uint kind; float ior; float cauchy_b; uint _pad;
    float color[4]; float absorption[4];
} GpuMaterial;
typedef struct {
    uint kind; float cos_inner; float cos_outer; uint _pad;
    float position[4]; float direction[4]; float intensity[4];
} GpuLight;
typedef struct {
    float position[3]; float tan_half_fov_x;
    float forward[3]; float tan_half_fov_y;
    float right[3]; uint width;
    float up[3]; uint height;
} GpuCamera;
typedef struct {
    float position[3]; float depth;
    float normal[3]; uint geometric_normal;
    float albedo[3]; uint material;
    float uv[2]; float view_distance; uint flags;
} GBufferTexel;
typedef struct { float position[3]; float hit_distance; float flux[3]; uint direction; } Photon;
// u64 sums as (lo, hi) u32 words: flux r, g, b, hit distance, photon count.
typedef struct { uint words[10]; } DepositTexel;
#define MAX_CASTER_SPHERES 8 // core::device::layout::MAX_CASTER_SPHERES
typedef struct {
    uint light; uint emission; uint grid_w; uint grid_h;
    uint first; uint count; uint seed; uint max_bounces;
    float origin[4]; float axis[4]; float rect_u[4]; float rect_v[4]; float photon_flux[4];
    float flux_quantum; uint split_budget; uint fresnel_model; uint caster_sphere_count;
    float caster_spheres[MAX_CASTER_SPHERES][4];
} TraceParams;
typedef struct {
    GpuCamera camera;
    float flux_quantum; float hit_distance_quantum; float depth_tolerance; uint photon_capacity;
} DepositParams;
typedef struct {
    GpuCamera camera;
    float roughness; float hit_distance_min; float hit_distance_max; uint max_radius_px;
    float sigma_depth; float normal_power; uint axis; uint tile_size;
    float hit_distance_quantum; uint knn_photons; float flux_quantum; uint table_block;
    uint surface; uint _pad0; uint _pad1; uint _pad2;
} GatherParams;
typedef struct {
    GpuCamera camera;
    uint light_count; uint max_specular_depth; float min_weight; uint fresnel_model;
} DirectParams;
typedef struct {
    uint width; uint height; float flux_quantum; float hit_distance_quantum;
    uint photon_capacity; uint gather_width; uint _pad0; uint _pad1;
} AtlasParams;
typedef struct {
    GpuCamera camera;
    uint atlas_width; uint max_specular_depth; float min_weight; uint fresnel_model;
} MapLookupParams;
typedef struct {
    uint atlas_width; float flux_quantum; float hit_distance_quantum; uint level;
    uint finest; uint metric; uint error_from_level; uint grid_w;
    uint first; uint count; uint children_capacity; uint relevance;
    uint rect_count; uint deposit_target; uint error_texels; uint _pad0;
    GpuCamera camera;
} RefineParams;
typedef struct {
    GpuCamera camera;
    GpuCamera previous;
    float alpha_max; float sigma_z; float sigma_n; float epsilon;
    uint history_frames; uint _pad0; uint _pad1; uint _pad2;
} TemporalParams;
typedef struct {
    GpuCamera camera;
    uint iteration; uint last; float sigma_z; float sigma_n;
    float epsilon; float clip_sigmas; uint _pad0; uint _pad1;
} AtrousParams;

// PhotonGi (seed 003): core::device::layout::{RsmTexel, RsmPhoton, RsmParams, GiPhoton,
// IndirectTraceParams, SplatParams}.
typedef struct { float position[3]; uint normal; float flux[3]; uint kind; } RsmTexel;
typedef struct { float origin[3]; uint direction; float flux[3]; uint bounces; } RsmPhoton;
typedef struct {
    GpuCamera face_camera;
    uint light; uint face; uint side; uint level;
    uint face_count; uint first_sample; uint sample_count; uint seed;
    uint sampling; uint _pad0; uint _pad1; uint _pad2;
} RsmParams;
#define RSM_SAMPLING_UNIFORM 1u // core::math::rsm::rsm_sampling
typedef struct {
    float position[3]; uint power; uint normal; uint direction; float ray_length; uint tile;
} GiPhoton;
typedef struct {
    GpuCamera camera;
    uint first; uint count; uint seed; uint max_bounces;
    uint max_segments; uint tile_size; uint store; uint fresnel_model;
    float power_scale; float flux_quantum; uint _pad0; uint _pad1;
} IndirectTraceParams;
typedef struct {
    GpuCamera camera;
    uint tile_size; float power_scale; float flux_quantum; uint max_splat_px;
    float max_ray_length; float min_length_scale; float density_radius_min; float density_radius_max;
    float photons_per_pixel; float normal_compression; float max_stretch; float tile_constant;
    float min_splat_px; uint light_direction; uint _pad0; uint _pad1;
} SplatParams;
typedef struct { uint width; uint height; float max_stretch; float epsilon; } CorrectionParams;
#define RSM_TEXEL_NONE 0u // core::math::rsm::rsm_texel_kind
#define RSM_TEXEL_DIFFUSE 1u
#define RSM_TEXEL_SPECULAR 2u
#define GI_STORE_PACKED 0u // core::math::gi_photon::gi_store
#define GI_STORE_FLOAT 1u

// core::gpu constants
#define MATERIAL_DIFFUSE 0u
#define MATERIAL_MIRROR 1u
#define MATERIAL_DIELECTRIC 2u
#define LIGHT_POINT 0u
#define LIGHT_SPOT 1u
#define LIGHT_DIRECTIONAL 2u
#define EMISSION_CONE 0u
#define EMISSION_RECTANGLE 1u
#define EMISSION_VIEW_PLANE 2u
#define NO_TILE 0xffffffffu
#define GATHER_SURFACE_ATLAS 1u // core::device::layout::gather_surface::ATLAS
#define GBUFFER_RECEIVER 1u
#define NO_MATERIAL 0xffffffffu
// core::gpu::counter word offsets
#define COUNTER_STORED 0
#define COUNTER_NO_SPECULAR 1
#define COUNTER_ESCAPED 2
#define COUNTER_NEGLIGIBLE 3
#define COUNTER_BOUNCE_LIMIT 4
#define COUNTER_OFF_SCREEN 5
#define COUNTER_DEPTH_MISMATCH 6
#define COUNTER_DEPOSITED 7
#define COUNTER_UNDERFLOW 8
#define COUNTER_SATURATED 9
#define COUNTER_RAYS 10
#define COUNTER_STORED_FLUX 12
#define COUNTER_SPLITS 18
#define MAX_SPLIT_BRANCHES 32 // core::device::layout::MAX_SPLIT_BRANCHES
#define COUNTER_WORDS 20

#define MAX_SPECULAR_DEPTH 30 // core::sspm::MAX_SPECULAR_DEPTH
#define PI_F 3.14159265358979323846f
#define TAU_F 6.28318530717958647692f

__kernel void struct_sizes(__global uint* out) {
    out[0] = sizeof(GpuVertex);
    out[1] = sizeof(GpuTriangle);
    out[2] = sizeof(GpuMaterial);
    out[3] = sizeof(GpuLight);
    out[4] = sizeof(GpuCamera);
    out[5] = sizeof(GBufferTexel);
    out[6] = sizeof(Photon);
    out[7] = sizeof(DepositTexel);
    out[8] = sizeof(TraceParams);
    out[9] = sizeof(DepositParams);
    out[10] = sizeof(GatherParams);
    out[11] = sizeof(DirectParams);
}
