// needs: layout prelude vector sampling photon_clusters
// seed_clusters (AdaptiveCaustics' bounds seed): one thread per cluster of a window of
// one level's grid; a cluster whose footprint overlaps a caster's rectangle is appended
// to the level's list (past the capacity counted, not written). Mirror of
// backend-opencl/kernels/seed_clusters.cl and backend-cpu/src/kernels/seed_clusters.rs;
// the list's order is the atomics'.

@group(0) @binding(0) var<uniform> params: SeedParams;
@group(0) @binding(1) var<storage, read> caster_rects: array<vec4<f32>>;
@group(0) @binding(2) var<storage, read_write> list: array<u32>;
@group(0) @binding(3) var<storage, read_write> list_length: array<atomic<u32>>;

// core::math::photon_clusters::seed_cluster: thread t's cluster, the window in SEED_TILE
// tile order.
fn seed_cluster(t: u32, grid_w: u32, first_x: u32, first_y: u32, window_w: u32,
                window_h: u32) -> u32 {
    let i = tiled_index(t, window_w, window_h, SEED_TILE);
    return (first_y + i / window_w) * (grid_w / 2u) + first_x + i % window_w;
}

fn seed_clusters(t: u32) {
    let p = params;
    if (t >= p.window_w * p.window_h) {
        return;
    }
    let cluster = seed_cluster(t, p.grid_w, p.first_x, p.first_y, p.window_w, p.window_h);
    var overlaps = false;
    for (var r = 0u; r < p.rect_count; r++) {
        overlaps = overlaps || cluster_overlaps_rect(cluster, p.grid_w, caster_rects[r]);
    }
    if (overlaps) {
        let at = atomicAdd(&list_length[0], 1u);
        if (at < p.capacity) {
            list[at] = cluster;
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    seed_clusters((wg.y * nwg.x + wg.x) * 64u + li);
}
