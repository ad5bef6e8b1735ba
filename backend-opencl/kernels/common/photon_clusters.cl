// Mirror of core::math::photon_clusters (Wyman 2009's photon clusters, AdaptiveCaustics).
// Its constants (NO_TRIANGLE, CLUSTER_*, MAX_ERROR_TEXELS) are in layout.cl.

inline uint cluster_entry(uint cluster, uint spread) {
    return (cluster & CLUSTER_ID_MASK) | ((clamp(spread, 1u, MAX_ERROR_TEXELS) - 1u) << 30u);
}

inline uint entry_cluster(uint entry) { return entry & CLUSTER_ID_MASK; }

// core::math::photon_clusters::convergence_cell: the convergence cell (per axis) of a
// photon at `offset` (centroid_offset) inside its texel.
inline uint2 convergence_cell(uint2 offset) {
    return offset / (CENTROID_SUBTEXELS / CONVERGENCE_CELLS);
}

// core::math::photon_clusters::live_clusters: entries `first ..` of a list of
// `list_length`, at most `bound`.
inline uint live_clusters(uint list_length, uint first, uint bound) {
    return list_length <= first ? 0u : min(list_length - first, bound);
}

inline uint entry_spread(uint entry) { return (entry >> 30u) + 1u; }

inline uint cluster_spread(const uint* xs, const uint* ys) {
    uint lx = xs[0], hx = xs[0], ly = ys[0], hy = ys[0];
    for (uint k = 1u; k < 4u; k++) {
        lx = min(lx, xs[k]); hx = max(hx, xs[k]);
        ly = min(ly, ys[k]); hy = max(hy, ys[k]);
    }
    return max(hx - lx, hy - ly) + 1u;
}

// (x0, x1, y0, y1), inclusive
inline uint4 footprint_window(uint x, uint y, uint spread, uint4 tile) {
    uint r = spread / 2u;
    return (uint4)(max(x >= r ? x - r : 0u, tile.x), min(x + r, tile.x + tile.z - 1u),
                   max(y >= r ? y - r : 0u, tile.y), min(y + r, tile.y + tile.z - 1u));
}

inline uint footprint_share(uint units, uint n, uint k) {
    return units / n + (k < units % n ? 1u : 0u);
}

inline uint cluster_photon_index(uint cluster, uint sub, uint grid_w) {
    uint clusters_w = grid_w / 2u;
    uint cx = cluster % clusters_w;
    uint cy = cluster / clusters_w;
    return (2u * cy + (sub >> 1u)) * grid_w + 2u * cx + (sub & 1u);
}

inline bool photon_met_caster(uint end, uint rays) {
    return !(end == 1u || (end == 2u && rays <= 1u) || (end == 3u && rays == 0u));
}

inline uint cluster_fate(bool any_met_caster, bool converged, uint level, uint finest,
                         uint metric, uint error_from_level) {
    if (!any_met_caster) return CLUSTER_DISCARDED;
    if (level >= finest || (metric == CLUSTER_METRIC_ERROR && level >= error_from_level && converged))
        return CLUSTER_OUTPUT;
    return CLUSTER_REFINED;
}

inline bool slot_stored(const float* flux) {
    return flux[0] > 0.0f || flux[1] > 0.0f || flux[2] > 0.0f;
}

inline bool slot_met_caster(const float* flux, float position_z) {
    return slot_stored(flux) || position_z != 0.0f;
}

inline bool cluster_overlaps_rect(uint cluster, uint grid_w, float4 rect) {
    uint clusters_w = grid_w / 2u;
    uint cx = cluster % clusters_w;
    uint cy = cluster / clusters_w;
    // 2 / grid_w, built from its exponent (exact, and no division to round)
    float step = as_float((128u - (31u - clz(grid_w))) << 23);
    float x0 = (float)(2u * cx) * step - 1.0f;
    float x1 = (float)(2u * cx + 2u) * step - 1.0f;
    float y1 = 1.0f - (float)(2u * cy) * step;
    float y0 = 1.0f - (float)(2u * cy + 2u) * step;
    return x0 <= rect.z && rect.x <= x1 && y0 <= rect.w && rect.y <= y1;
}
