// GENERATED FILE, do not edit: the structs of core/src/device/layout.rs (through
// core/src/device/layout_table.rs) and the constants of
// core/src/device/shader_constants.rs, written by core/src/device/shader_layouts.rs.
// core/tests/shader_layouts.rs fails while this file differs; regenerate with
//   CAUSTICA_BLESS=1 cargo test -p caustica-core --test shader_layouts
// The numbers after the struct members are their byte offsets (Rust's offset_of!).

// core::device::layout::material_kind
#define MATERIAL_DIFFUSE 0u
#define MATERIAL_MIRROR 1u
#define MATERIAL_DIELECTRIC 2u

// core::device::layout::light_kind
#define LIGHT_POINT 0u
#define LIGHT_SPOT 1u
#define LIGHT_DIRECTIONAL 2u

// core::device::layout::emission_kind
#define EMISSION_CONE 0u
#define EMISSION_RECTANGLE 1u
#define EMISSION_VIEW_PLANE 2u

// core::device::layout::gbuffer_flags
#define GBUFFER_RECEIVER 1u

// core::device::layout::gather_surface
#define GATHER_SURFACE_SCREEN 0u
#define GATHER_SURFACE_ATLAS 1u

// core::device::layout::counter (word offsets into the counter buffer)
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
#define COUNTER_WORDS 20

// core::device::layout::cluster_count (words of refine_clusters' counts)
#define CLUSTER_COUNT_CHILDREN 0
#define CLUSTER_COUNT_OUTPUT 1
#define CLUSTER_COUNT_DISCARDED 2
#define CLUSTER_COUNT_OUTPUT_PHOTONS 3
#define CLUSTER_COUNT_CONVERGED 4
#define CLUSTER_COUNT_OVERFLOW 5
#define CLUSTER_COUNT_WORDS 8

// core::device::layout::DepositTexel (its u32 words: flux r, g, b at 0, 2, 4)
#define DEPOSIT_TEXEL_WORDS 10
#define DEPOSIT_FLUX 0
#define DEPOSIT_HIT_DISTANCE 6
#define DEPOSIT_PHOTONS 8

// core::device::layout
#define NO_MATERIAL 0xffffffffu
#define NO_TILE 0xffffffffu
#define MAX_SPLIT_BRANCHES 32
#define MAX_CASTER_SPHERES 8
#define MAX_SPECULAR_DEPTH 30
#define VISIBLE_TOLERANCE (-0.01f)

// core::device::launch::DEFAULT_WORKGROUP_SIZE (every kernel's invocations per workgroup)
#define WORKGROUP_SIZE 64

// core::device::launch (dispatch records of indirect launches)
#define DISPATCH_RECORD_WORDS 8
#define DISPATCH_MAX_GROUPS_X 65535u
#define DISPATCH_TRACE_WIDTH 8u

// core::device::launch::dispatch_word (words of a dispatch record)
#define DISPATCH_GROUPS_X 0
#define DISPATCH_GROUPS_Y 1
#define DISPATCH_GROUPS_Z 2
#define DISPATCH_WIDTH 3
#define DISPATCH_HEIGHT 4
#define DISPATCH_DEPTH 5
#define DISPATCH_THREADS 6
#define DISPATCH_ITEMS 7

// core::device::layout::photon_plan_word (PhotonGi's photon plan on the device)
#define PLAN_MASK 0
#define PLAN_ROW 1
#define PLAN_POWER_SCALE 1
#define PLAN_FLUX_QUANTUM 2
#define PLAN_RESOLVE_QUANTUM 3
#define PLAN_COUNTS 4

// core::device::layout::NO_PLAN_BIT
#define NO_PLAN_BIT 0xffffffffu

// core::math::photon_plan
#define RSM_SEEN_MIN_TOP 1.1754944e-38f

// core::device::acceleration::instance_flags
#define INSTANCE_IDENTITY 1u

// core::device::acceleration
#define SINGLE_LEVEL_MARK 0x7fc05e1fu
#define SINGLE_LEVEL_SLOT 1u
#define CULLING_MIN_COMPONENT 5.421011e-20f

// core::math::optics
#define FRESNEL_EXACT 0u
#define FRESNEL_SCHLICK 1u
#define REFERENCE_WAVELENGTH_UM 0.55f
#define RADIANCE_MAX 3.4028235e38f
#define KHR_DISPERSION_B_UM2 0.523655f
#define KHR_DISPERSION_D_TERM 1.5168f

// core::math::optics::ior_model
#define IOR_MODEL_CAUCHY 0u
#define IOR_MODEL_ABBE 1u

// core::math::spectrum
#define SPECTRUM_MIN_UM 0.38f
#define SPECTRUM_WIDTH_UM 0.4f
#define SPECTRUM_MAX_UM 0.78f
#define WAVELENGTH_STEP 0x9e3779b9u
#define ONE_THIRD 0.33333334f
#define DISPERSION_SPECTRAL 0u
#define DISPERSION_THREE_BANDS 1u

// core::math::spectrum::CIE_X_LOBES, CIE_Y_LOBES, CIE_Z_LOBES (Wyman 2013's fit: weight, mean in nm, 1/sigma below and from the mean)
#define CIE_X0_WEIGHT 0.362f
#define CIE_X0_MEAN_NM 442.0f
#define CIE_X0_INV_SIGMA_BELOW 0.0624f
#define CIE_X0_INV_SIGMA_ABOVE 0.0374f
#define CIE_X1_WEIGHT 1.056f
#define CIE_X1_MEAN_NM 599.8f
#define CIE_X1_INV_SIGMA_BELOW 0.0264f
#define CIE_X1_INV_SIGMA_ABOVE 0.0323f
#define CIE_X2_WEIGHT (-0.065f)
#define CIE_X2_MEAN_NM 501.1f
#define CIE_X2_INV_SIGMA_BELOW 0.049f
#define CIE_X2_INV_SIGMA_ABOVE 0.0382f
#define CIE_Y0_WEIGHT 0.821f
#define CIE_Y0_MEAN_NM 568.8f
#define CIE_Y0_INV_SIGMA_BELOW 0.0213f
#define CIE_Y0_INV_SIGMA_ABOVE 0.0247f
#define CIE_Y1_WEIGHT 0.286f
#define CIE_Y1_MEAN_NM 530.9f
#define CIE_Y1_INV_SIGMA_BELOW 0.0613f
#define CIE_Y1_INV_SIGMA_ABOVE 0.0322f
#define CIE_Z0_WEIGHT 1.217f
#define CIE_Z0_MEAN_NM 437.0f
#define CIE_Z0_INV_SIGMA_BELOW 0.0845f
#define CIE_Z0_INV_SIGMA_ABOVE 0.0278f
#define CIE_Z1_WEIGHT 0.681f
#define CIE_Z1_MEAN_NM 459.0f
#define CIE_Z1_INV_SIGMA_BELOW 0.0385f
#define CIE_Z1_INV_SIGMA_ABOVE 0.0725f

// core::math::spectrum::XYZ_TO_LINEAR_SRGB (row, column) and SPECTRAL_RGB_SCALE
#define XYZ_TO_SRGB_00 3.2406f
#define XYZ_TO_SRGB_01 (-1.5372f)
#define XYZ_TO_SRGB_02 (-0.4986f)
#define XYZ_TO_SRGB_10 (-0.9689f)
#define XYZ_TO_SRGB_11 1.8758f
#define XYZ_TO_SRGB_12 0.0415f
#define XYZ_TO_SRGB_20 0.0557f
#define XYZ_TO_SRGB_21 (-0.204f)
#define XYZ_TO_SRGB_22 1.057f
#define SPECTRAL_RGB_SCALE_R 2.2722244f
#define SPECTRAL_RGB_SCALE_G 3.4646618f
#define SPECTRAL_RGB_SCALE_B 3.660385f

// core::math::geometry
#define OFFSET_REL 3.0517578e-5f
#define OFFSET_MIN_SCALE 7.888609e-31f
#define SPHERE_TEST_SLACK 1.5258789e-5f

// core::math::footprint
#define MIN_COSINE 0.0001f

// core::math::sampling
#define PHOTON_TILE 8u
#define NARROW_CONE 0.0009765625f

// core::math::rng::R2_STEP (the R2 sequence's steps, 0.32 fixed point)
#define R2_STEP_X 0xc13fa9a9u
#define R2_STEP_Y 0x91e10da5u

// core::math::density_gather
#define MIN_WINDOW_HALF_WIDTH 1
#define COUNT_CLAMP_PER_K 9u
#define SCAN_THREADS 64u
#define COLUMN_CHUNKS 8u
#define SCAN_COLUMNS 8u
#define EDGE_TEXEL_NOT_RECEIVER (-1.0f)
#define COLUMN_PASS_TILE 8u
#define REACH_TILE 8

// core::math::map_gather
#define TILE_FULLY_COVERED 0x80000000u
#define MAX_FOOTPRINT_TEXELS 32.0f
#define CENTROID_WORDS 3
#define CENTROID_SUBTEXELS 256u
#define CENTROID_MAX_PHOTONS 0x1000000u

// core::math::photon_clusters
#define NO_TRIANGLE 0xffffffffu
#define CLUSTER_METRIC_LEVEL 0u
#define CLUSTER_METRIC_ERROR 1u
#define CLUSTER_DISCARDED 0u
#define CLUSTER_OUTPUT 1u
#define CLUSTER_REFINED 2u
#define CLUSTER_RELEVANCE_PHOTONS 0u
#define CLUSTER_RELEVANCE_BOUNDS 1u
#define CLUSTER_TARGET_ATLAS 0u
#define CLUSTER_TARGET_SCREEN 1u
#define MAX_ERROR_TEXELS 4u
#define CLUSTER_ID_MASK 0x3fffffffu
#define CONVERGENCE_CELLS 16u
#define SEED_TILE 4u

// core::math::rsm
#define RSM_TEXEL_NONE 0u
#define RSM_TEXEL_DIFFUSE 1u
#define RSM_TEXEL_SPECULAR 2u
#define RSM_SAMPLING_IMPORTANCE 0u
#define RSM_SAMPLING_UNIFORM 1u

// core::math::gi_photon::gi_store
#define GI_STORE_PACKED 0u
#define GI_STORE_FLOAT 1u

// core::math::path_sort
#define PATH_SORT_BITS 3u
#define PATH_SORT_BUCKETS 4096
#define PATH_SORT_SCAN 0u
#define PATH_SORT_SCATTER 1u

// core::device::layout::GpuVertex, 32 bytes
typedef struct {
    float position[3]; // 0
    float u; // 12
    float normal[3]; // 16
    float v; // 28
} GpuVertex;

// core::device::layout::GpuTriangle, 16 bytes
typedef struct {
    uint indices[3]; // 0
    uint material; // 12
} GpuTriangle;

// core::device::layout::GpuMaterial, 48 bytes
typedef struct {
    uint kind; // 0
    float ior; // 4
    float dispersion; // 8
    uint ior_model; // 12
    float color[4]; // 16
    float absorption[4]; // 32
} GpuMaterial;

// core::device::layout::GpuLight, 64 bytes
typedef struct {
    uint kind; // 0
    float cos_inner; // 4
    float cos_outer; // 8
    float one_minus_cos_outer; // 12
    float position[4]; // 16
    float direction[4]; // 32
    float intensity[4]; // 48
} GpuLight;

// core::device::layout::GpuCamera, 64 bytes
typedef struct {
    float position[3]; // 0
    float tan_half_fov_x; // 12
    float forward[3]; // 16
    float tan_half_fov_y; // 28
    float right[3]; // 32
    uint width; // 44
    float up[3]; // 48
    uint height; // 60
} GpuCamera;

// core::device::layout::GBufferTexel, 64 bytes
typedef struct {
    float position[3]; // 0
    float depth; // 12
    float normal[3]; // 16
    uint geometric_normal; // 28
    float albedo[3]; // 32
    uint material; // 44
    float uv[2]; // 48
    float view_distance; // 56
    uint flags; // 60
} GBufferTexel;

// core::device::layout::Photon, 32 bytes
typedef struct {
    float position[3]; // 0
    float hit_distance; // 12
    float flux[3]; // 16
    uint direction; // 28
} Photon;

// core::device::layout::DepositTexel, 40 bytes
typedef struct {
    uint flux[3][2]; // 0
    uint hit_distance[2]; // 24
    uint photons[2]; // 32
} DepositTexel;

// core::device::layout::TraceParams, 272 bytes
typedef struct {
    uint light; // 0
    uint emission; // 4
    uint grid_w; // 8
    uint grid_h; // 12
    uint first; // 16
    uint count; // 20
    uint seed; // 24
    uint max_bounces; // 28
    float origin[4]; // 32
    float axis[4]; // 48
    float rect_u[4]; // 64
    float rect_v[4]; // 80
    float photon_flux[4]; // 96
    float flux_quantum; // 112
    uint split_budget; // 116
    uint fresnel_model; // 120
    uint caster_sphere_count; // 124
    uint jitter_seed; // 128
    uint stratum; // 132
    uint dispersion_mode; // 136
    uint _pad; // 140
    float caster_spheres[MAX_CASTER_SPHERES][4]; // 144
} TraceParams;

// core::device::layout::DepositParams, 80 bytes
typedef struct {
    GpuCamera camera; // 0
    float flux_quantum; // 64
    float hit_distance_quantum; // 68
    float depth_tolerance; // 72
    uint photon_capacity; // 76
} DepositParams;

// core::device::layout::GatherParams, 128 bytes
typedef struct {
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
} GatherParams;

// core::device::layout::DirectParams, 80 bytes
typedef struct {
    GpuCamera camera; // 0
    uint light_count; // 64
    uint max_specular_depth; // 68
    float min_weight; // 72
    uint fresnel_model; // 76
} DirectParams;

// core::device::layout::AtlasParams, 32 bytes
typedef struct {
    uint width; // 0
    uint height; // 4
    float flux_quantum; // 8
    float hit_distance_quantum; // 12
    uint photon_capacity; // 16
    uint gather_width; // 20
    uint _pad0; // 24
    uint _pad1; // 28
} AtlasParams;

// core::device::layout::MapLookupParams, 80 bytes
typedef struct {
    GpuCamera camera; // 0
    uint atlas_width; // 64
    uint max_specular_depth; // 68
    float min_weight; // 72
    uint fresnel_model; // 76
} MapLookupParams;

// core::device::layout::AtrousParams, 96 bytes
typedef struct {
    GpuCamera camera; // 0
    uint iteration; // 64
    uint last; // 68
    float sigma_z; // 72
    float sigma_n; // 76
    float epsilon; // 80
    float clip_sigmas; // 84
    uint _pad0; // 88
    uint _pad1; // 92
} AtrousParams;

// core::device::layout::TemporalParams, 160 bytes
typedef struct {
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
} TemporalParams;

// core::device::layout::RsmTexel, 32 bytes
typedef struct {
    float position[3]; // 0
    uint normal; // 12
    float flux[3]; // 16
    uint kind; // 28
} RsmTexel;

// core::device::layout::RsmPhoton, 32 bytes
typedef struct {
    float origin[3]; // 0
    uint direction; // 12
    float flux[3]; // 16
    uint bounces; // 28
} RsmPhoton;

// core::device::layout::RsmParams, 112 bytes
typedef struct {
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
} RsmParams;

// core::device::layout::GiPhoton, 32 bytes
typedef struct {
    float position[3]; // 0
    uint power; // 12
    uint normal; // 16
    uint direction; // 20
    float ray_length; // 24
    uint tile; // 28
} GiPhoton;

// core::device::layout::IndirectTraceParams, 160 bytes
typedef struct {
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
    float key_origin_min[3]; // 128
    uint queue_order; // 140
    float key_origin_scale[3]; // 144
    uint _pad; // 156
} IndirectTraceParams;

// core::device::layout::IndirectPath, 48 bytes
typedef struct {
    float origin[3]; // 0
    uint index; // 12
    float direction[3]; // 16
    uint bounces; // 28
    float flux[3]; // 32
    float wavelength; // 44
} IndirectPath;

// core::device::layout::PathSortParams, 16 bytes
typedef struct {
    uint phase; // 0
    uint count_word; // 4
    uint _pad0; // 8
    uint _pad1; // 12
} PathSortParams;

// core::device::layout::SplatParams, 128 bytes
typedef struct {
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
} SplatParams;

// core::device::layout::PlacementParams, 128 bytes
typedef struct {
    float axis_x[4]; // 0
    float axis_y[4]; // 16
    float axis_z[4]; // 32
    float translation[4]; // 48
    float normal_x[4]; // 64
    float normal_y[4]; // 80
    float normal_z[4]; // 96
    uint object_first; // 112
    uint world_first; // 116
    uint count; // 120
    uint _pad; // 124
} PlacementParams;

// core::device::layout::CorrectionParams, 16 bytes
typedef struct {
    uint width; // 0
    uint height; // 4
    float max_stretch; // 8
    float epsilon; // 12
} CorrectionParams;

// core::device::layout::PlanParams, 32 bytes
typedef struct {
    uint side; // 0
    uint faces; // 4
    uint bit; // 8
    uint row_words; // 12
    uint table_words; // 16
    uint _pad0; // 20
    uint _pad1; // 24
    uint _pad2; // 28
} PlanParams;

// core::device::layout::RefineParams, 128 bytes
typedef struct {
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
} RefineParams;

// core::device::layout::SeedParams, 32 bytes
typedef struct {
    uint grid_w; // 0
    uint first_x; // 4
    uint first_y; // 8
    uint window_w; // 12
    uint window_h; // 16
    uint rect_count; // 20
    uint capacity; // 24
    uint _pad; // 28
} SeedParams;

// sizeof of every struct above, in this order (the OpenCL backend's
// device_struct_sizes; its test compares them with Rust's size_of)
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
    out[12] = sizeof(AtlasParams);
    out[13] = sizeof(MapLookupParams);
    out[14] = sizeof(AtrousParams);
    out[15] = sizeof(TemporalParams);
    out[16] = sizeof(RsmTexel);
    out[17] = sizeof(RsmPhoton);
    out[18] = sizeof(RsmParams);
    out[19] = sizeof(GiPhoton);
    out[20] = sizeof(IndirectTraceParams);
    out[21] = sizeof(IndirectPath);
    out[22] = sizeof(PathSortParams);
    out[23] = sizeof(SplatParams);
    out[24] = sizeof(PlacementParams);
    out[25] = sizeof(CorrectionParams);
    out[26] = sizeof(PlanParams);
    out[27] = sizeof(RefineParams);
    out[28] = sizeof(SeedParams);
}
