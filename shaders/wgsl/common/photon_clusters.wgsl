// Mirror of core::math::photon_clusters (seed 004's photon clusters, AdaptiveCaustics).

const NO_TRIANGLE: u32 = 0xffffffffu;
const CLUSTER_METRIC_ERROR: u32 = 1u;
const CLUSTER_DISCARDED: u32 = 0u;
const CLUSTER_OUTPUT: u32 = 1u;
const CLUSTER_REFINED: u32 = 2u;
// core::device::layout::cluster_count words
const CLUSTER_COUNT_CHILDREN: u32 = 0u;
const CLUSTER_COUNT_OUTPUT: u32 = 1u;
const CLUSTER_COUNT_DISCARDED: u32 = 2u;
const CLUSTER_COUNT_OUTPUT_PHOTONS: u32 = 3u;
const CLUSTER_COUNT_CONVERGED: u32 = 4u;

fn cluster_photon_index(cluster: u32, sub: u32, grid_w: u32) -> u32 {
    let clusters_w = grid_w / 2u;
    let cx = cluster % clusters_w;
    let cy = cluster / clusters_w;
    return (2u * cy + (sub >> 1u)) * grid_w + 2u * cx + (sub & 1u);
}

fn photon_met_caster(end: u32, rays: u32) -> bool {
    return !(end == 1u || (end == 2u && rays <= 1u) || (end == 3u && rays == 0u));
}

fn cluster_fate(any_met_caster: bool, converged: bool, level: u32, finest: u32, metric: u32,
                error_from_level: u32) -> u32 {
    if (!any_met_caster) {
        return CLUSTER_DISCARDED;
    }
    if (level >= finest || (metric == CLUSTER_METRIC_ERROR && level >= error_from_level && converged)) {
        return CLUSTER_OUTPUT;
    }
    return CLUSTER_REFINED;
}

const CLUSTER_RELEVANCE_BOUNDS: u32 = 1u;
const CLUSTER_TARGET_SCREEN: u32 = 1u;

fn slot_stored(flux: vec3<f32>) -> bool {
    return flux.x > 0.0f || flux.y > 0.0f || flux.z > 0.0f;
}

fn slot_met_caster(flux: vec3<f32>, position_z: f32) -> bool {
    return slot_stored(flux) || position_z != 0.0f;
}

fn cluster_overlaps_rect(cluster: u32, grid_w: u32, rect: vec4<f32>) -> bool {
    let clusters_w = grid_w / 2u;
    let cx = cluster % clusters_w;
    let cy = cluster / clusters_w;
    // 2 / grid_w, built from its exponent (exact, and no division to round)
    let step = bitcast<f32>((128u - firstLeadingBit(grid_w)) << 23u);
    let x0 = f32(2u * cx) * step - 1.0f;
    let x1 = f32(2u * cx + 2u) * step - 1.0f;
    let y1 = 1.0f - f32(2u * cy) * step;
    let y0 = 1.0f - f32(2u * cy + 2u) * step;
    return x0 <= rect.z && rect.x <= x1 && y0 <= rect.w && rect.y <= y1;
}
