// seed_clusters (AdaptiveCaustics' bounds seed): one work-item per cluster of a window of
// one level's grid; a cluster whose footprint overlaps a caster's rectangle is appended
// to the level's list (past the capacity counted, not written). Mirror of
// backend-cpu/src/kernels/seed_clusters.rs and shaders/wgsl/seed_clusters.wgsl; the
// list's order is the atomics'.

// core::math::photon_clusters::seed_cluster: work-item t's cluster, the window in
// SEED_TILE tile order.
inline uint seed_cluster(uint t, uint grid_w, uint first_x, uint first_y, uint window_w,
                         uint window_h) {
    uint i = tiled_index(t, window_w, window_h, SEED_TILE);
    return (first_y + i / window_w) * (grid_w / 2u) + first_x + i % window_w;
}

__kernel void seed_clusters(__global const SeedParams* p, __global const float4* caster_rects,
                            __global uint* list, volatile __global uint* list_length) {
    uint t = get_global_id(0);
    if (t >= p->window_w * p->window_h) return;
    uint cluster = seed_cluster(t, p->grid_w, p->first_x, p->first_y, p->window_w, p->window_h);
    bool overlaps = false;
    for (uint r = 0u; r < p->rect_count; r++)
        overlaps = overlaps || cluster_overlaps_rect(cluster, p->grid_w, caster_rects[r]);
    if (overlaps) {
        uint at = atomic_inc(&list_length[0]);
        if (at < p->capacity) list[at] = cluster;
    }
}
