// Mirror of core::math::photon_clusters (Wyman 2009's photon clusters, AdaptiveCaustics).

// Its constants (NO_TRIANGLE, CLUSTER_*, MAX_ERROR_TEXELS) are in layout.wgsl.

fn cluster_entry(cluster: u32, spread: u32) -> u32 {
    return (cluster & CLUSTER_ID_MASK) | ((clamp(spread, 1u, MAX_ERROR_TEXELS) - 1u) << 30u);
}

fn entry_cluster(entry: u32) -> u32 {
    return entry & CLUSTER_ID_MASK;
}

// core::math::photon_clusters::live_clusters: entries `first ..` of a list of
// `list_length`, at most `bound`.
fn live_clusters(list_length: u32, first: u32, bound: u32) -> u32 {
    if (list_length <= first) {
        return 0u;
    }
    return min(list_length - first, bound);
}

fn entry_spread(entry: u32) -> u32 {
    return (entry >> 30u) + 1u;
}

fn cluster_spread(xs: array<u32, 4>, ys: array<u32, 4>) -> u32 {
    var lo = vec2<u32>(xs[0], ys[0]);
    var hi = lo;
    for (var k = 1u; k < 4u; k++) {
        lo = min(lo, vec2<u32>(xs[k], ys[k]));
        hi = max(hi, vec2<u32>(xs[k], ys[k]));
    }
    return max(hi.x - lo.x, hi.y - lo.y) + 1u;
}

// core::math::photon_clusters::convergence_cell: the convergence cell (per axis) of a
// photon at `offset` (centroid_offset) inside its texel.
fn convergence_cell(offset: vec2<u32>) -> vec2<u32> {
    return offset / (CENTROID_SUBTEXELS / CONVERGENCE_CELLS);
}

// (x0, x1, y0, y1), inclusive
fn footprint_window(x: u32, y: u32, spread: u32, tile: vec4<u32>) -> vec4<u32> {
    let r = spread / 2u;
    let t1 = tile.xy + vec2<u32>(tile.z - 1u, tile.z - 1u);
    return vec4<u32>(max(select(0u, x - r, x >= r), tile.x), min(x + r, t1.x),
                     max(select(0u, y - r, y >= r), tile.y), min(y + r, t1.y));
}

fn footprint_share(units: u32, n: u32, k: u32) -> u32 {
    return units / n + select(0u, 1u, k < units % n);
}

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
