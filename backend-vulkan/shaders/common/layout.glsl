// GENERATED FILE, do not edit: the structs of core/src/device/layout.rs (through
// core/src/device/layout_table.rs) and the constants of
// core/src/device/shader_constants.rs, written by core/src/device/shader_layouts.rs.
// core/tests/shader_layouts.rs fails while this file differs; regenerate with
//   CAUSTICA_BLESS=1 cargo test -p caustica-core --test shader_layouts
// The numbers after the struct members are their byte offsets (Rust's offset_of!).

// core::device::layout::material_kind
const uint MATERIAL_DIFFUSE = 0u;
const uint MATERIAL_MIRROR = 1u;
const uint MATERIAL_DIELECTRIC = 2u;

// core::device::layout::light_kind
const uint LIGHT_POINT = 0u;
const uint LIGHT_SPOT = 1u;
const uint LIGHT_DIRECTIONAL = 2u;

// core::device::layout::emission_kind
const uint EMISSION_CONE = 0u;
const uint EMISSION_RECTANGLE = 1u;
const uint EMISSION_VIEW_PLANE = 2u;

// core::device::layout::gbuffer_flags
const uint GBUFFER_RECEIVER = 1u;

// core::device::layout::gather_surface
const uint GATHER_SURFACE_SCREEN = 0u;
const uint GATHER_SURFACE_ATLAS = 1u;

// core::device::layout::counter (word offsets into the counter buffer)
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
const uint COUNTER_WORDS = 20u;

// core::device::layout::cluster_count (words of refine_clusters' counts)
const uint CLUSTER_COUNT_CHILDREN = 0u;
const uint CLUSTER_COUNT_OUTPUT = 1u;
const uint CLUSTER_COUNT_DISCARDED = 2u;
const uint CLUSTER_COUNT_OUTPUT_PHOTONS = 3u;
const uint CLUSTER_COUNT_CONVERGED = 4u;
const uint CLUSTER_COUNT_OVERFLOW = 5u;
const uint CLUSTER_COUNT_WORDS = 8u;

// core::device::layout::DepositTexel (its u32 words: flux r, g, b at 0, 2, 4)
const uint DEPOSIT_TEXEL_WORDS = 10u;
const uint DEPOSIT_FLUX = 0u;
const uint DEPOSIT_HIT_DISTANCE = 6u;
const uint DEPOSIT_PHOTONS = 8u;

// core::device::layout
const uint NO_MATERIAL = 0xffffffffu;
const uint NO_TILE = 0xffffffffu;
const uint MAX_SPLIT_BRANCHES = 32u;
const uint MAX_CASTER_SPHERES = 8u;
const uint MAX_SPECULAR_DEPTH = 30u;
const float VISIBLE_TOLERANCE = -0.01;

// core::device::launch::DEFAULT_WORKGROUP_SIZE (every kernel's invocations per workgroup)
const uint WORKGROUP_SIZE = 64u;

// core::device::launch (dispatch records of indirect launches)
const uint DISPATCH_RECORD_WORDS = 8u;
const uint DISPATCH_MAX_GROUPS_X = 65535u;
const uint DISPATCH_TRACE_WIDTH = 8u;

// core::device::launch::dispatch_word (words of a dispatch record)
const uint DISPATCH_GROUPS_X = 0u;
const uint DISPATCH_GROUPS_Y = 1u;
const uint DISPATCH_GROUPS_Z = 2u;
const uint DISPATCH_WIDTH = 3u;
const uint DISPATCH_HEIGHT = 4u;
const uint DISPATCH_DEPTH = 5u;
const uint DISPATCH_THREADS = 6u;
const uint DISPATCH_ITEMS = 7u;

// core::device::layout::photon_plan_word (PhotonGi's photon plan on the device)
const uint PLAN_MASK = 0u;
const uint PLAN_ROW = 1u;
const uint PLAN_POWER_SCALE = 1u;
const uint PLAN_FLUX_QUANTUM = 2u;
const uint PLAN_RESOLVE_QUANTUM = 3u;
const uint PLAN_COUNTS = 4u;

// core::device::layout::NO_PLAN_BIT
const uint NO_PLAN_BIT = 0xffffffffu;

// core::math::photon_plan
const float RSM_SEEN_MIN_TOP = 1.1754944e-38;

// core::device::acceleration::instance_flags
const uint INSTANCE_IDENTITY = 1u;

// core::device::acceleration
const uint SINGLE_LEVEL_MARK = 0x7fc05e1fu;
const uint SINGLE_LEVEL_SLOT = 1u;
const float CULLING_MIN_COMPONENT = 5.421011e-20;

// core::math::optics
const uint FRESNEL_EXACT = 0u;
const uint FRESNEL_SCHLICK = 1u;
const float REFERENCE_WAVELENGTH_UM = 0.55;
const float RADIANCE_MAX = 3.4028235e38;
const float KHR_DISPERSION_B_UM2 = 0.523655;
const float KHR_DISPERSION_D_TERM = 1.5168;

// core::math::optics::ior_model
const uint IOR_MODEL_CAUCHY = 0u;
const uint IOR_MODEL_ABBE = 1u;

// core::math::spectrum
const float SPECTRUM_MIN_UM = 0.38;
const float SPECTRUM_WIDTH_UM = 0.4;
const float SPECTRUM_MAX_UM = 0.78;
const uint WAVELENGTH_STEP = 0x9e3779b9u;
const float ONE_THIRD = 0.33333334;
const uint DISPERSION_SPECTRAL = 0u;
const uint DISPERSION_THREE_BANDS = 1u;

// core::math::spectrum::CIE_X_LOBES, CIE_Y_LOBES, CIE_Z_LOBES (Wyman 2013's fit: weight, mean in nm, 1/sigma below and from the mean)
const float CIE_X0_WEIGHT = 0.362;
const float CIE_X0_MEAN_NM = 442.0;
const float CIE_X0_INV_SIGMA_BELOW = 0.0624;
const float CIE_X0_INV_SIGMA_ABOVE = 0.0374;
const float CIE_X1_WEIGHT = 1.056;
const float CIE_X1_MEAN_NM = 599.8;
const float CIE_X1_INV_SIGMA_BELOW = 0.0264;
const float CIE_X1_INV_SIGMA_ABOVE = 0.0323;
const float CIE_X2_WEIGHT = -0.065;
const float CIE_X2_MEAN_NM = 501.1;
const float CIE_X2_INV_SIGMA_BELOW = 0.049;
const float CIE_X2_INV_SIGMA_ABOVE = 0.0382;
const float CIE_Y0_WEIGHT = 0.821;
const float CIE_Y0_MEAN_NM = 568.8;
const float CIE_Y0_INV_SIGMA_BELOW = 0.0213;
const float CIE_Y0_INV_SIGMA_ABOVE = 0.0247;
const float CIE_Y1_WEIGHT = 0.286;
const float CIE_Y1_MEAN_NM = 530.9;
const float CIE_Y1_INV_SIGMA_BELOW = 0.0613;
const float CIE_Y1_INV_SIGMA_ABOVE = 0.0322;
const float CIE_Z0_WEIGHT = 1.217;
const float CIE_Z0_MEAN_NM = 437.0;
const float CIE_Z0_INV_SIGMA_BELOW = 0.0845;
const float CIE_Z0_INV_SIGMA_ABOVE = 0.0278;
const float CIE_Z1_WEIGHT = 0.681;
const float CIE_Z1_MEAN_NM = 459.0;
const float CIE_Z1_INV_SIGMA_BELOW = 0.0385;
const float CIE_Z1_INV_SIGMA_ABOVE = 0.0725;

// core::math::spectrum::XYZ_TO_LINEAR_SRGB (row, column) and SPECTRAL_RGB_SCALE
const float XYZ_TO_SRGB_00 = 3.2406;
const float XYZ_TO_SRGB_01 = -1.5372;
const float XYZ_TO_SRGB_02 = -0.4986;
const float XYZ_TO_SRGB_10 = -0.9689;
const float XYZ_TO_SRGB_11 = 1.8758;
const float XYZ_TO_SRGB_12 = 0.0415;
const float XYZ_TO_SRGB_20 = 0.0557;
const float XYZ_TO_SRGB_21 = -0.204;
const float XYZ_TO_SRGB_22 = 1.057;
const float SPECTRAL_RGB_SCALE_R = 2.2722244;
const float SPECTRAL_RGB_SCALE_G = 3.4646618;
const float SPECTRAL_RGB_SCALE_B = 3.660385;

// core::math::geometry
const float OFFSET_REL = 3.0517578e-5;
const float OFFSET_MIN_SCALE = 7.888609e-31;
const float SPHERE_TEST_SLACK = 1.5258789e-5;

// core::math::footprint
const float MIN_COSINE = 0.0001;

// core::math::sampling
const uint PHOTON_TILE = 8u;
const float NARROW_CONE = 0.0009765625;

// core::math::rng::R2_STEP (the R2 sequence's steps, 0.32 fixed point)
const uint R2_STEP_X = 0xc13fa9a9u;
const uint R2_STEP_Y = 0x91e10da5u;

// core::math::density_gather
const int MIN_WINDOW_HALF_WIDTH = 1;
const uint COUNT_CLAMP_PER_K = 9u;
const uint SCAN_THREADS = 64u;
const uint COLUMN_CHUNKS = 8u;
const uint SCAN_COLUMNS = 8u;
const float EDGE_TEXEL_NOT_RECEIVER = -1.0;
const uint COLUMN_PASS_TILE = 8u;
const int REACH_TILE = 8;

// core::math::map_gather
const uint TILE_FULLY_COVERED = 0x80000000u;
const float MAX_FOOTPRINT_TEXELS = 32.0;
const uint CENTROID_WORDS = 3u;
const uint CENTROID_SUBTEXELS = 256u;
const uint CENTROID_MAX_PHOTONS = 0x1000000u;

// core::math::photon_clusters
const uint NO_TRIANGLE = 0xffffffffu;
const uint CLUSTER_METRIC_LEVEL = 0u;
const uint CLUSTER_METRIC_ERROR = 1u;
const uint CLUSTER_DISCARDED = 0u;
const uint CLUSTER_OUTPUT = 1u;
const uint CLUSTER_REFINED = 2u;
const uint CLUSTER_RELEVANCE_PHOTONS = 0u;
const uint CLUSTER_RELEVANCE_BOUNDS = 1u;
const uint CLUSTER_TARGET_ATLAS = 0u;
const uint CLUSTER_TARGET_SCREEN = 1u;
const uint MAX_ERROR_TEXELS = 4u;
const uint CLUSTER_ID_MASK = 0x3fffffffu;
const uint CONVERGENCE_CELLS = 16u;
const uint SEED_TILE = 4u;

// core::math::rsm
const uint RSM_TEXEL_NONE = 0u;
const uint RSM_TEXEL_DIFFUSE = 1u;
const uint RSM_TEXEL_SPECULAR = 2u;
const uint RSM_SAMPLING_IMPORTANCE = 0u;
const uint RSM_SAMPLING_UNIFORM = 1u;

// core::math::gi_photon::gi_store
const uint GI_STORE_PACKED = 0u;
const uint GI_STORE_FLOAT = 1u;

// core::math::path_sort
const uint PATH_SORT_BITS = 3u;
const uint PATH_SORT_BUCKETS = 4096u;
const uint PATH_SORT_SCAN = 0u;
const uint PATH_SORT_SCATTER = 1u;

// core::device::layout::GpuVertex, 32 bytes
struct GpuVertex {
    vec3 position; // 0
    float u; // 12
    vec3 normal; // 16
    float v; // 28
};

// core::device::layout::GpuTriangle, 16 bytes
struct GpuTriangle {
    uvec3 indices; // 0
    uint material; // 12
};

// core::device::layout::GpuMaterial, 48 bytes
struct GpuMaterial {
    uint kind; // 0
    float ior; // 4
    float dispersion; // 8
    uint ior_model; // 12
    vec4 color; // 16
    vec4 absorption; // 32
};

// core::device::layout::GpuLight, 64 bytes
struct GpuLight {
    uint kind; // 0
    float cos_inner; // 4
    float cos_outer; // 8
    float one_minus_cos_outer; // 12
    vec4 position; // 16
    vec4 direction; // 32
    vec4 intensity; // 48
};

// core::device::layout::GpuCamera, 64 bytes
struct GpuCamera {
    vec3 position; // 0
    float tan_half_fov_x; // 12
    vec3 forward; // 16
    float tan_half_fov_y; // 28
    vec3 right; // 32
    uint width; // 44
    vec3 up; // 48
    uint height; // 60
};

// core::device::layout::GBufferTexel, 64 bytes
struct GBufferTexel {
    vec3 position; // 0
    float depth; // 12
    vec3 normal; // 16
    uint geometric_normal; // 28
    vec3 albedo; // 32
    uint material; // 44
    vec2 uv; // 48
    float view_distance; // 56
    uint flags; // 60
};

// core::device::layout::Photon, 32 bytes
struct Photon {
    vec3 position; // 0
    float hit_distance; // 12
    vec3 flux; // 16
    uint direction; // 28
};

// core::device::layout::DepositTexel, 40 bytes
struct DepositTexel {
    uvec2 flux[3]; // 0
    uvec2 hit_distance; // 24
    uvec2 photons; // 32
};

// core::device::layout::TraceParams, 272 bytes
struct TraceParams {
    uint light; // 0
    uint emission; // 4
    uint grid_w; // 8
    uint grid_h; // 12
    uint first; // 16
    uint count; // 20
    uint seed; // 24
    uint max_bounces; // 28
    vec4 origin; // 32
    vec4 axis; // 48
    vec4 rect_u; // 64
    vec4 rect_v; // 80
    vec4 photon_flux; // 96
    float flux_quantum; // 112
    uint split_budget; // 116
    uint fresnel_model; // 120
    uint caster_sphere_count; // 124
    uint jitter_seed; // 128
    uint stratum; // 132
    uint dispersion_mode; // 136
    uint _pad; // 140
    vec4 caster_spheres[MAX_CASTER_SPHERES]; // 144
};

// core::device::layout::DepositParams, 80 bytes
struct DepositParams {
    GpuCamera camera; // 0
    float flux_quantum; // 64
    float hit_distance_quantum; // 68
    float depth_tolerance; // 72
    uint photon_capacity; // 76
};

// core::device::layout::GatherParams, 128 bytes
struct GatherParams {
    GpuCamera camera; // 0
    float roughness; // 64
    float hit_distance_min; // 68
    float hit_distance_max; // 72
    uint max_radius_px; // 76
    float sigma_depth; // 80
    float normal_power; // 84
    uint axis; // 88
    uint tile_size; // 92
    float hit_distance_quantum; // 96
    uint knn_photons; // 100
    float flux_quantum; // 104
    uint table_block; // 108
    uint surface; // 112
    uint _pad0; // 116
    uint _pad1; // 120
    uint _pad2; // 124
};

// core::device::layout::DirectParams, 80 bytes
struct DirectParams {
    GpuCamera camera; // 0
    uint light_count; // 64
    uint max_specular_depth; // 68
    float min_weight; // 72
    uint fresnel_model; // 76
};

// core::device::layout::AtlasParams, 32 bytes
struct AtlasParams {
    uint width; // 0
    uint height; // 4
    float flux_quantum; // 8
    float hit_distance_quantum; // 12
    uint photon_capacity; // 16
    uint gather_width; // 20
    uint _pad0; // 24
    uint _pad1; // 28
};

// core::device::layout::MapLookupParams, 80 bytes
struct MapLookupParams {
    GpuCamera camera; // 0
    uint atlas_width; // 64
    uint max_specular_depth; // 68
    float min_weight; // 72
    uint fresnel_model; // 76
};

// core::device::layout::AtrousParams, 96 bytes
struct AtrousParams {
    GpuCamera camera; // 0
    uint iteration; // 64
    uint last; // 68
    float sigma_z; // 72
    float sigma_n; // 76
    float epsilon; // 80
    float clip_sigmas; // 84
    uint _pad0; // 88
    uint _pad1; // 92
};

// core::device::layout::TemporalParams, 160 bytes
struct TemporalParams {
    GpuCamera camera; // 0
    GpuCamera previous; // 64
    float alpha_max; // 128
    float sigma_z; // 132
    float sigma_n; // 136
    float epsilon; // 140
    uint history_frames; // 144
    uint _pad0; // 148
    uint _pad1; // 152
    uint _pad2; // 156
};

// core::device::layout::RsmTexel, 32 bytes
struct RsmTexel {
    vec3 position; // 0
    uint normal; // 12
    vec3 flux; // 16
    uint kind; // 28
};

// core::device::layout::RsmPhoton, 32 bytes
struct RsmPhoton {
    vec3 origin; // 0
    uint direction; // 12
    vec3 flux; // 16
    uint bounces; // 28
};

// core::device::layout::RsmParams, 112 bytes
struct RsmParams {
    GpuCamera face_camera; // 0
    uint light; // 64
    uint face; // 68
    uint side; // 72
    uint level; // 76
    uint face_count; // 80
    uint first_sample; // 84
    uint sample_count; // 88
    uint seed; // 92
    uint sampling; // 96
    uint _pad0; // 100
    uint _pad1; // 104
    uint _pad2; // 108
};

// core::device::layout::GiPhoton, 32 bytes
struct GiPhoton {
    vec3 position; // 0
    uint power; // 12
    uint normal; // 16
    uint direction; // 20
    float ray_length; // 24
    uint tile; // 28
};

// core::device::layout::IndirectTraceParams, 160 bytes
struct IndirectTraceParams {
    GpuCamera camera; // 0
    uint first; // 64
    uint count; // 68
    uint seed; // 72
    uint max_bounces; // 76
    uint max_segments; // 80
    uint tile_size; // 84
    uint store; // 88
    uint fresnel_model; // 92
    float power_scale; // 96
    float flux_quantum; // 100
    uint dispersion_mode; // 104
    uint segment_first; // 108
    uint segment_end; // 112
    uint chunk_first; // 116
    uint chunk_size; // 120
    uint queue_keys; // 124
    vec3 key_origin_min; // 128
    uint queue_order; // 140
    vec3 key_origin_scale; // 144
    uint _pad; // 156
};

// core::device::layout::IndirectPath, 48 bytes
struct IndirectPath {
    vec3 origin; // 0
    uint index; // 12
    vec3 direction; // 16
    uint bounces; // 28
    vec3 flux; // 32
    float wavelength; // 44
};

// core::device::layout::PathSortParams, 16 bytes
struct PathSortParams {
    uint phase; // 0
    uint count_word; // 4
    uint _pad0; // 8
    uint _pad1; // 12
};

// core::device::layout::SplatParams, 128 bytes
struct SplatParams {
    GpuCamera camera; // 0
    uint tile_size; // 64
    float power_scale; // 68
    float flux_quantum; // 72
    uint max_splat_px; // 76
    float max_ray_length; // 80
    float min_length_scale; // 84
    float density_radius_min; // 88
    float density_radius_max; // 92
    float photons_per_pixel; // 96
    float normal_compression; // 100
    float max_stretch; // 104
    float tile_constant; // 108
    float min_splat_px; // 112
    uint light_direction; // 116
    float scene_magnitude; // 120
    uint _pad0; // 124
};

// core::device::layout::PlacementParams, 128 bytes
struct PlacementParams {
    vec4 axis_x; // 0
    vec4 axis_y; // 16
    vec4 axis_z; // 32
    vec4 translation; // 48
    vec4 normal_x; // 64
    vec4 normal_y; // 80
    vec4 normal_z; // 96
    uint object_first; // 112
    uint world_first; // 116
    uint count; // 120
    uint _pad; // 124
};

// core::device::layout::CorrectionParams, 16 bytes
struct CorrectionParams {
    uint width; // 0
    uint height; // 4
    float max_stretch; // 8
    float epsilon; // 12
};

// core::device::layout::PlanParams, 32 bytes
struct PlanParams {
    uint side; // 0
    uint faces; // 4
    uint bit; // 8
    uint row_words; // 12
    uint table_words; // 16
    uint _pad0; // 20
    uint _pad1; // 24
    uint _pad2; // 28
};

// core::device::layout::RefineParams, 128 bytes
struct RefineParams {
    uint atlas_width; // 0
    float flux_quantum; // 4
    float hit_distance_quantum; // 8
    uint level; // 12
    uint finest; // 16
    uint metric; // 20
    uint error_from_level; // 24
    uint grid_w; // 28
    uint first; // 32
    uint count; // 36
    uint children_capacity; // 40
    uint relevance; // 44
    uint rect_count; // 48
    uint deposit_target; // 52
    uint error_texels; // 56
    uint _pad; // 60
    GpuCamera camera; // 64
};

// core::device::layout::SeedParams, 32 bytes
struct SeedParams {
    uint grid_w; // 0
    uint first_x; // 4
    uint first_y; // 8
    uint window_w; // 12
    uint window_h; // 16
    uint rect_count; // 20
    uint capacity; // 24
    uint _pad; // 28
};
