// GENERATED FILE, do not edit: the structs of core/src/device/layout.rs (through
// core/src/device/layout_table.rs) and the constants of
// core/src/device/shader_constants.rs, written by core/src/device/shader_layouts.rs.
// core/tests/shader_layouts.rs fails while this file differs; regenerate with
//   CAUSTICA_BLESS=1 cargo test -p caustica-core --test shader_layouts
// The numbers after the struct members are their byte offsets (Rust's offset_of!).

// core::device::layout::material_kind
const MATERIAL_DIFFUSE: u32 = 0u;
const MATERIAL_MIRROR: u32 = 1u;
const MATERIAL_DIELECTRIC: u32 = 2u;

// core::device::layout::light_kind
const LIGHT_POINT: u32 = 0u;
const LIGHT_SPOT: u32 = 1u;
const LIGHT_DIRECTIONAL: u32 = 2u;

// core::device::layout::emission_kind
const EMISSION_CONE: u32 = 0u;
const EMISSION_RECTANGLE: u32 = 1u;
const EMISSION_VIEW_PLANE: u32 = 2u;

// core::device::layout::gbuffer_flags
const GBUFFER_RECEIVER: u32 = 1u;

// core::device::layout::gather_surface
const GATHER_SURFACE_SCREEN: u32 = 0u;
const GATHER_SURFACE_ATLAS: u32 = 1u;

// core::device::layout::counter (word offsets into the counter buffer)
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
const COUNTER_WORDS: u32 = 20u;

// core::device::layout::cluster_count (words of refine_clusters' counts)
const CLUSTER_COUNT_CHILDREN: u32 = 0u;
const CLUSTER_COUNT_OUTPUT: u32 = 1u;
const CLUSTER_COUNT_DISCARDED: u32 = 2u;
const CLUSTER_COUNT_OUTPUT_PHOTONS: u32 = 3u;
const CLUSTER_COUNT_CONVERGED: u32 = 4u;
const CLUSTER_COUNT_OVERFLOW: u32 = 5u;
const CLUSTER_COUNT_WORDS: u32 = 8u;

// core::device::layout::DepositTexel (its u32 words: flux r, g, b at 0, 2, 4)
const DEPOSIT_TEXEL_WORDS: u32 = 10u;
const DEPOSIT_FLUX: u32 = 0u;
const DEPOSIT_HIT_DISTANCE: u32 = 6u;
const DEPOSIT_PHOTONS: u32 = 8u;

// core::device::layout
const NO_MATERIAL: u32 = 0xffffffffu;
const NO_TILE: u32 = 0xffffffffu;
const MAX_SPLIT_BRANCHES: u32 = 32u;
const MAX_CASTER_SPHERES: u32 = 8u;
const MAX_SPECULAR_DEPTH: u32 = 30u;
const VISIBLE_TOLERANCE: f32 = -0.01f;

// core::device::launch::DEFAULT_WORKGROUP_SIZE (every kernel's invocations per workgroup)
const WORKGROUP_SIZE: u32 = 64u;

// core::device::launch (dispatch records of indirect launches)
const DISPATCH_RECORD_WORDS: u32 = 8u;
const DISPATCH_MAX_GROUPS_X: u32 = 65535u;
const DISPATCH_TRACE_WIDTH: u32 = 8u;

// core::device::launch::dispatch_word (words of a dispatch record)
const DISPATCH_GROUPS_X: u32 = 0u;
const DISPATCH_GROUPS_Y: u32 = 1u;
const DISPATCH_GROUPS_Z: u32 = 2u;
const DISPATCH_WIDTH: u32 = 3u;
const DISPATCH_HEIGHT: u32 = 4u;
const DISPATCH_DEPTH: u32 = 5u;
const DISPATCH_THREADS: u32 = 6u;
const DISPATCH_ITEMS: u32 = 7u;

// core::device::layout::photon_plan_word (PhotonGi's photon plan on the device)
const PLAN_MASK: u32 = 0u;
const PLAN_ROW: u32 = 1u;
const PLAN_POWER_SCALE: u32 = 1u;
const PLAN_FLUX_QUANTUM: u32 = 2u;
const PLAN_RESOLVE_QUANTUM: u32 = 3u;
const PLAN_COUNTS: u32 = 4u;

// core::device::layout::NO_PLAN_BIT
const NO_PLAN_BIT: u32 = 0xffffffffu;

// core::math::photon_plan
const RSM_SEEN_MIN_TOP: f32 = 1.1754944e-38f;

// core::device::acceleration::instance_flags
const INSTANCE_IDENTITY: u32 = 1u;

// core::device::acceleration
const SINGLE_LEVEL_MARK: u32 = 0x7fc05e1fu;
const SINGLE_LEVEL_SLOT: u32 = 1u;
const CULLING_MIN_COMPONENT: f32 = 5.421011e-20f;

// core::math::optics
const FRESNEL_EXACT: u32 = 0u;
const FRESNEL_SCHLICK: u32 = 1u;
const REFERENCE_WAVELENGTH_UM: f32 = 0.55f;
const RADIANCE_MAX: f32 = 3.4028235e38f;
const KHR_DISPERSION_B_UM2: f32 = 0.523655f;
const KHR_DISPERSION_D_TERM: f32 = 1.5168f;

// core::math::optics::ior_model
const IOR_MODEL_CAUCHY: u32 = 0u;
const IOR_MODEL_ABBE: u32 = 1u;

// core::math::spectrum
const SPECTRUM_MIN_UM: f32 = 0.38f;
const SPECTRUM_WIDTH_UM: f32 = 0.4f;
const SPECTRUM_MAX_UM: f32 = 0.78f;
const WAVELENGTH_STEP: u32 = 0x9e3779b9u;
const ONE_THIRD: f32 = 0.33333334f;
const DISPERSION_SPECTRAL: u32 = 0u;
const DISPERSION_THREE_BANDS: u32 = 1u;

// core::math::spectrum::CIE_X_LOBES, CIE_Y_LOBES, CIE_Z_LOBES (Wyman 2013's fit: weight, mean in nm, 1/sigma below and from the mean)
const CIE_X0_WEIGHT: f32 = 0.362f;
const CIE_X0_MEAN_NM: f32 = 442.0f;
const CIE_X0_INV_SIGMA_BELOW: f32 = 0.0624f;
const CIE_X0_INV_SIGMA_ABOVE: f32 = 0.0374f;
const CIE_X1_WEIGHT: f32 = 1.056f;
const CIE_X1_MEAN_NM: f32 = 599.8f;
const CIE_X1_INV_SIGMA_BELOW: f32 = 0.0264f;
const CIE_X1_INV_SIGMA_ABOVE: f32 = 0.0323f;
const CIE_X2_WEIGHT: f32 = -0.065f;
const CIE_X2_MEAN_NM: f32 = 501.1f;
const CIE_X2_INV_SIGMA_BELOW: f32 = 0.049f;
const CIE_X2_INV_SIGMA_ABOVE: f32 = 0.0382f;
const CIE_Y0_WEIGHT: f32 = 0.821f;
const CIE_Y0_MEAN_NM: f32 = 568.8f;
const CIE_Y0_INV_SIGMA_BELOW: f32 = 0.0213f;
const CIE_Y0_INV_SIGMA_ABOVE: f32 = 0.0247f;
const CIE_Y1_WEIGHT: f32 = 0.286f;
const CIE_Y1_MEAN_NM: f32 = 530.9f;
const CIE_Y1_INV_SIGMA_BELOW: f32 = 0.0613f;
const CIE_Y1_INV_SIGMA_ABOVE: f32 = 0.0322f;
const CIE_Z0_WEIGHT: f32 = 1.217f;
const CIE_Z0_MEAN_NM: f32 = 437.0f;
const CIE_Z0_INV_SIGMA_BELOW: f32 = 0.0845f;
const CIE_Z0_INV_SIGMA_ABOVE: f32 = 0.0278f;
const CIE_Z1_WEIGHT: f32 = 0.681f;
const CIE_Z1_MEAN_NM: f32 = 459.0f;
const CIE_Z1_INV_SIGMA_BELOW: f32 = 0.0385f;
const CIE_Z1_INV_SIGMA_ABOVE: f32 = 0.0725f;

// core::math::spectrum::XYZ_TO_LINEAR_SRGB (row, column) and SPECTRAL_RGB_SCALE
const XYZ_TO_SRGB_00: f32 = 3.2406f;
const XYZ_TO_SRGB_01: f32 = -1.5372f;
const XYZ_TO_SRGB_02: f32 = -0.4986f;
const XYZ_TO_SRGB_10: f32 = -0.9689f;
const XYZ_TO_SRGB_11: f32 = 1.8758f;
const XYZ_TO_SRGB_12: f32 = 0.0415f;
const XYZ_TO_SRGB_20: f32 = 0.0557f;
const XYZ_TO_SRGB_21: f32 = -0.204f;
const XYZ_TO_SRGB_22: f32 = 1.057f;
const SPECTRAL_RGB_SCALE_R: f32 = 2.2722244f;
const SPECTRAL_RGB_SCALE_G: f32 = 3.4646618f;
const SPECTRAL_RGB_SCALE_B: f32 = 3.660385f;

// core::math::geometry
const OFFSET_REL: f32 = 3.0517578e-5f;
const OFFSET_MIN_SCALE: f32 = 7.888609e-31f;
const SPHERE_TEST_SLACK: f32 = 1.5258789e-5f;

// core::math::footprint
const MIN_COSINE: f32 = 0.0001f;

// core::math::sampling
const PHOTON_TILE: u32 = 8u;
const NARROW_CONE: f32 = 0.0009765625f;

// core::math::rng::R2_STEP (the R2 sequence's steps, 0.32 fixed point)
const R2_STEP_X: u32 = 0xc13fa9a9u;
const R2_STEP_Y: u32 = 0x91e10da5u;

// core::math::density_gather
const MIN_WINDOW_HALF_WIDTH: i32 = 1;
const COUNT_CLAMP_PER_K: u32 = 9u;
const SCAN_THREADS: u32 = 64u;
const COLUMN_CHUNKS: u32 = 8u;
const SCAN_COLUMNS: u32 = 8u;
const EDGE_TEXEL_NOT_RECEIVER: f32 = -1.0f;
const COLUMN_PASS_TILE: u32 = 8u;
const REACH_TILE: i32 = 8;

// core::math::map_gather
const TILE_FULLY_COVERED: u32 = 0x80000000u;
const MAX_FOOTPRINT_TEXELS: f32 = 32.0f;
const CENTROID_WORDS: u32 = 3u;
const CENTROID_SUBTEXELS: u32 = 256u;
const CENTROID_MAX_PHOTONS: u32 = 0x1000000u;

// core::math::photon_clusters
const NO_TRIANGLE: u32 = 0xffffffffu;
const CLUSTER_METRIC_LEVEL: u32 = 0u;
const CLUSTER_METRIC_ERROR: u32 = 1u;
const CLUSTER_DISCARDED: u32 = 0u;
const CLUSTER_OUTPUT: u32 = 1u;
const CLUSTER_REFINED: u32 = 2u;
const CLUSTER_RELEVANCE_PHOTONS: u32 = 0u;
const CLUSTER_RELEVANCE_BOUNDS: u32 = 1u;
const CLUSTER_TARGET_ATLAS: u32 = 0u;
const CLUSTER_TARGET_SCREEN: u32 = 1u;
const MAX_ERROR_TEXELS: u32 = 4u;
const CLUSTER_ID_MASK: u32 = 0x3fffffffu;
const CONVERGENCE_CELLS: u32 = 16u;
const SEED_TILE: u32 = 4u;

// core::math::rsm
const RSM_TEXEL_NONE: u32 = 0u;
const RSM_TEXEL_DIFFUSE: u32 = 1u;
const RSM_TEXEL_SPECULAR: u32 = 2u;
const RSM_SAMPLING_IMPORTANCE: u32 = 0u;
const RSM_SAMPLING_UNIFORM: u32 = 1u;

// core::math::gi_photon::gi_store
const GI_STORE_PACKED: u32 = 0u;
const GI_STORE_FLOAT: u32 = 1u;

// core::math::path_sort
const PATH_SORT_BITS: u32 = 3u;
const PATH_SORT_BUCKETS: u32 = 4096u;
const PATH_SORT_SCAN: u32 = 0u;
const PATH_SORT_SCATTER: u32 = 1u;

// core::device::layout::GpuVertex, 32 bytes
struct GpuVertex {
    position: vec3<f32>, // 0
    u: f32, // 12
    normal: vec3<f32>, // 16
    v: f32, // 28
}

// core::device::layout::GpuTriangle, 16 bytes
struct GpuTriangle {
    indices: vec3<u32>, // 0
    material: u32, // 12
}

// core::device::layout::GpuMaterial, 48 bytes
struct GpuMaterial {
    kind: u32, // 0
    ior: f32, // 4
    dispersion: f32, // 8
    ior_model: u32, // 12
    color: vec4<f32>, // 16
    absorption: vec4<f32>, // 32
}

// core::device::layout::GpuLight, 64 bytes
struct GpuLight {
    kind: u32, // 0
    cos_inner: f32, // 4
    cos_outer: f32, // 8
    one_minus_cos_outer: f32, // 12
    position: vec4<f32>, // 16
    direction: vec4<f32>, // 32
    intensity: vec4<f32>, // 48
}

// core::device::layout::GpuCamera, 64 bytes
struct GpuCamera {
    position: vec3<f32>, // 0
    tan_half_fov_x: f32, // 12
    forward: vec3<f32>, // 16
    tan_half_fov_y: f32, // 28
    right: vec3<f32>, // 32
    width: u32, // 44
    up: vec3<f32>, // 48
    height: u32, // 60
}

// core::device::layout::GBufferTexel, 64 bytes
struct GBufferTexel {
    position: vec3<f32>, // 0
    depth: f32, // 12
    normal: vec3<f32>, // 16
    geometric_normal: u32, // 28
    albedo: vec3<f32>, // 32
    material: u32, // 44
    uv: vec2<f32>, // 48
    view_distance: f32, // 56
    flags: u32, // 60
}

// core::device::layout::Photon, 32 bytes
struct Photon {
    position: vec3<f32>, // 0
    hit_distance: f32, // 12
    flux: vec3<f32>, // 16
    direction: u32, // 28
}

// core::device::layout::DepositTexel, 40 bytes
struct DepositTexel {
    flux: array<vec2<u32>, 3>, // 0
    hit_distance: vec2<u32>, // 24
    photons: vec2<u32>, // 32
}

// core::device::layout::TraceParams, 272 bytes
struct TraceParams {
    light: u32, // 0
    emission: u32, // 4
    grid_w: u32, // 8
    grid_h: u32, // 12
    first: u32, // 16
    count: u32, // 20
    seed: u32, // 24
    max_bounces: u32, // 28
    origin: vec4<f32>, // 32
    axis: vec4<f32>, // 48
    rect_u: vec4<f32>, // 64
    rect_v: vec4<f32>, // 80
    photon_flux: vec4<f32>, // 96
    flux_quantum: f32, // 112
    split_budget: u32, // 116
    fresnel_model: u32, // 120
    caster_sphere_count: u32, // 124
    jitter_seed: u32, // 128
    stratum: u32, // 132
    dispersion_mode: u32, // 136
    _pad: u32, // 140
    caster_spheres: array<vec4<f32>, MAX_CASTER_SPHERES>, // 144
}

// core::device::layout::DepositParams, 80 bytes
struct DepositParams {
    camera: GpuCamera, // 0
    flux_quantum: f32, // 64
    hit_distance_quantum: f32, // 68
    depth_tolerance: f32, // 72
    photon_capacity: u32, // 76
}

// core::device::layout::GatherParams, 128 bytes
struct GatherParams {
    camera: GpuCamera, // 0
    roughness: f32, // 64
    hit_distance_min: f32, // 68
    hit_distance_max: f32, // 72
    max_radius_px: u32, // 76
    sigma_depth: f32, // 80
    normal_power: f32, // 84
    axis: u32, // 88
    tile_size: u32, // 92
    hit_distance_quantum: f32, // 96
    knn_photons: u32, // 100
    flux_quantum: f32, // 104
    table_block: u32, // 108
    surface: u32, // 112
    _pad0: u32, // 116
    _pad1: u32, // 120
    _pad2: u32, // 124
}

// core::device::layout::DirectParams, 80 bytes
struct DirectParams {
    camera: GpuCamera, // 0
    light_count: u32, // 64
    max_specular_depth: u32, // 68
    min_weight: f32, // 72
    fresnel_model: u32, // 76
}

// core::device::layout::AtlasParams, 32 bytes
struct AtlasParams {
    width: u32, // 0
    height: u32, // 4
    flux_quantum: f32, // 8
    hit_distance_quantum: f32, // 12
    photon_capacity: u32, // 16
    gather_width: u32, // 20
    _pad0: u32, // 24
    _pad1: u32, // 28
}

// core::device::layout::MapLookupParams, 80 bytes
struct MapLookupParams {
    camera: GpuCamera, // 0
    atlas_width: u32, // 64
    max_specular_depth: u32, // 68
    min_weight: f32, // 72
    fresnel_model: u32, // 76
}

// core::device::layout::AtrousParams, 96 bytes
struct AtrousParams {
    camera: GpuCamera, // 0
    iteration: u32, // 64
    last: u32, // 68
    sigma_z: f32, // 72
    sigma_n: f32, // 76
    epsilon: f32, // 80
    clip_sigmas: f32, // 84
    _pad0: u32, // 88
    _pad1: u32, // 92
}

// core::device::layout::TemporalParams, 160 bytes
struct TemporalParams {
    camera: GpuCamera, // 0
    previous: GpuCamera, // 64
    alpha_max: f32, // 128
    sigma_z: f32, // 132
    sigma_n: f32, // 136
    epsilon: f32, // 140
    history_frames: u32, // 144
    _pad0: u32, // 148
    _pad1: u32, // 152
    _pad2: u32, // 156
}

// core::device::layout::RsmTexel, 32 bytes
struct RsmTexel {
    position: vec3<f32>, // 0
    normal: u32, // 12
    flux: vec3<f32>, // 16
    kind: u32, // 28
}

// core::device::layout::RsmPhoton, 32 bytes
struct RsmPhoton {
    origin: vec3<f32>, // 0
    direction: u32, // 12
    flux: vec3<f32>, // 16
    bounces: u32, // 28
}

// core::device::layout::RsmParams, 112 bytes
struct RsmParams {
    face_camera: GpuCamera, // 0
    light: u32, // 64
    face: u32, // 68
    side: u32, // 72
    level: u32, // 76
    face_count: u32, // 80
    first_sample: u32, // 84
    sample_count: u32, // 88
    seed: u32, // 92
    sampling: u32, // 96
    _pad0: u32, // 100
    _pad1: u32, // 104
    _pad2: u32, // 108
}

// core::device::layout::GiPhoton, 32 bytes
struct GiPhoton {
    position: vec3<f32>, // 0
    power: u32, // 12
    normal: u32, // 16
    direction: u32, // 20
    ray_length: f32, // 24
    tile: u32, // 28
}

// core::device::layout::IndirectTraceParams, 160 bytes
struct IndirectTraceParams {
    camera: GpuCamera, // 0
    first: u32, // 64
    count: u32, // 68
    seed: u32, // 72
    max_bounces: u32, // 76
    max_segments: u32, // 80
    tile_size: u32, // 84
    store: u32, // 88
    fresnel_model: u32, // 92
    power_scale: f32, // 96
    flux_quantum: f32, // 100
    dispersion_mode: u32, // 104
    segment_first: u32, // 108
    segment_end: u32, // 112
    chunk_first: u32, // 116
    chunk_size: u32, // 120
    queue_keys: u32, // 124
    key_origin_min: vec3<f32>, // 128
    queue_order: u32, // 140
    key_origin_scale: vec3<f32>, // 144
    _pad: u32, // 156
}

// core::device::layout::IndirectPath, 48 bytes
struct IndirectPath {
    origin: vec3<f32>, // 0
    index: u32, // 12
    direction: vec3<f32>, // 16
    bounces: u32, // 28
    flux: vec3<f32>, // 32
    wavelength: f32, // 44
}

// core::device::layout::PathSortParams, 16 bytes
struct PathSortParams {
    phase: u32, // 0
    count_word: u32, // 4
    _pad0: u32, // 8
    _pad1: u32, // 12
}

// core::device::layout::SplatParams, 128 bytes
struct SplatParams {
    camera: GpuCamera, // 0
    tile_size: u32, // 64
    power_scale: f32, // 68
    flux_quantum: f32, // 72
    max_splat_px: u32, // 76
    max_ray_length: f32, // 80
    min_length_scale: f32, // 84
    density_radius_min: f32, // 88
    density_radius_max: f32, // 92
    photons_per_pixel: f32, // 96
    normal_compression: f32, // 100
    max_stretch: f32, // 104
    tile_constant: f32, // 108
    min_splat_px: f32, // 112
    light_direction: u32, // 116
    scene_magnitude: f32, // 120
    _pad0: u32, // 124
}

// core::device::layout::PlacementParams, 128 bytes
struct PlacementParams {
    axis_x: vec4<f32>, // 0
    axis_y: vec4<f32>, // 16
    axis_z: vec4<f32>, // 32
    translation: vec4<f32>, // 48
    normal_x: vec4<f32>, // 64
    normal_y: vec4<f32>, // 80
    normal_z: vec4<f32>, // 96
    object_first: u32, // 112
    world_first: u32, // 116
    count: u32, // 120
    _pad: u32, // 124
}

// core::device::layout::CorrectionParams, 16 bytes
struct CorrectionParams {
    width: u32, // 0
    height: u32, // 4
    max_stretch: f32, // 8
    epsilon: f32, // 12
}

// core::device::layout::PlanParams, 32 bytes
struct PlanParams {
    side: u32, // 0
    faces: u32, // 4
    bit: u32, // 8
    row_words: u32, // 12
    table_words: u32, // 16
    _pad0: u32, // 20
    _pad1: u32, // 24
    _pad2: u32, // 28
}

// core::device::layout::RefineParams, 128 bytes
struct RefineParams {
    atlas_width: u32, // 0
    flux_quantum: f32, // 4
    hit_distance_quantum: f32, // 8
    level: u32, // 12
    finest: u32, // 16
    metric: u32, // 20
    error_from_level: u32, // 24
    grid_w: u32, // 28
    first: u32, // 32
    count: u32, // 36
    children_capacity: u32, // 40
    relevance: u32, // 44
    rect_count: u32, // 48
    deposit_target: u32, // 52
    error_texels: u32, // 56
    _pad: u32, // 60
    camera: GpuCamera, // 64
}

// core::device::layout::SeedParams, 32 bytes
struct SeedParams {
    grid_w: u32, // 0
    first_x: u32, // 4
    first_y: u32, // 8
    window_w: u32, // 12
    window_h: u32, // 16
    rect_count: u32, // 20
    capacity: u32, // 24
    _pad: u32, // 28
}
