// seed_clusters (AdaptiveCaustics' bounds seed): one work-item per cluster of a window of
// one level's grid; a cluster whose footprint overlaps a caster's rectangle is appended
// to the level's list (past the capacity counted, not written). Mirror of
// backend-cpu/src/kernels/seed_clusters.rs and shaders/wgsl/seed_clusters.wgsl; the
// list's order is the atomics'.

__kernel void seed_clusters(__global const SeedParams* p, __global const float4* caster_rects,
                            __global uint* list, volatile __global uint* list_length) {
    uint t = get_global_id(0);
    if (t >= p->window_w * p->window_h) return;
    uint cluster = seed_cluster(t, p->grid_w, p->first_x, p->first_y, p->window_w);
    bool overlaps = false;
    for (uint r = 0u; r < p->rect_count; r++)
        overlaps = overlaps || cluster_overlaps_rect(cluster, p->grid_w, caster_rects[r]);
    if (overlaps) {
        uint at = atomic_inc(&list_length[0]);
        if (at < p->capacity) list[at] = cluster;
    }
}
