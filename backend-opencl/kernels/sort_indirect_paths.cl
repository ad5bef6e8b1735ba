// sort_indirect_paths (PhotonGi's sorted_waves schedule): the first
// min(path_counts[count_word], path_capacity) queued paths counted into the buckets of
// their key (PATH_SORT_HISTOGRAM, a thread per path), the counts turned into first slots
// (PATH_SORT_SCAN, one workgroup), each path moved to the next slot of its bucket
// (PATH_SORT_SCATTER). Mirror of backend-cpu/src/kernels/sort_indirect_paths.rs
// (core::math::path_sort) and shaders/wgsl/sort_indirect_paths.wgsl.

// core::math::path_sort::path_sort_key.
inline uint path_sort_key(float3 origin, float3 direction, float3 origin_min,
                          float3 origin_scale) {
    float top = (float)((1u << PATH_SORT_BITS) - 1u);
    float3 c = fmin(fmax((origin - origin_min) * origin_scale, (float3)(0.0f)), (float3)(top));
    uint x = (uint)c.x, y = (uint)c.y, z = (uint)c.z;
    uint morton = 0u;
    for (uint b = 0u; b < PATH_SORT_BITS; b++)
        morton |= ((x >> b) & 1u) << (3u * b) | ((y >> b) & 1u) << (3u * b + 1u) |
                  ((z >> b) & 1u) << (3u * b + 2u);
    uint octant = (direction.x < 0.0f ? 1u : 0u) | (direction.y < 0.0f ? 2u : 0u) |
                  (direction.z < 0.0f ? 4u : 0u);
    return octant << (3u * PATH_SORT_BITS) | morton;
}

__kernel void sort_indirect_paths(__global const PathSortParams* p,
                                  __global const IndirectPath* paths_in, uint path_capacity,
                                  __global const uint* path_counts,
                                  __global IndirectPath* paths_out,
                                  volatile __global uint* buckets) {
    __local uint partial[WORKGROUP_SIZE];
    if (p->phase == PATH_SORT_SCAN) {
        // each thread sums its run of PATH_SORT_BUCKETS / WORKGROUP_SIZE counts; thread 0
        // scans the runs; each thread writes its run's first slots
        uint li = get_local_id(0);
        uint per = (uint)PATH_SORT_BUCKETS / WORKGROUP_SIZE;
        uint sum = 0u;
        for (uint k = 0u; k < per; k++) sum += buckets[li * per + k];
        partial[li] = sum;
        barrier(CLK_LOCAL_MEM_FENCE);
        if (li == 0u) {
            uint run = 0u;
            for (uint t = 0u; t < WORKGROUP_SIZE; t++) {
                uint s = partial[t];
                partial[t] = run;
                run += s;
            }
        }
        barrier(CLK_LOCAL_MEM_FENCE);
        uint first = partial[li];
        for (uint k = 0u; k < per; k++) {
            uint count = buckets[li * per + k];
            buckets[li * per + k] = first;
            first += count;
        }
        return;
    }
    uint i = get_global_id(0);
    if (i >= min(path_counts[p->count_word], path_capacity)) return;
    IndirectPath q = paths_in[i];
    uint k = path_sort_key(load3(q.origin), load3(q.direction), load3g(p->origin_min),
                           load3g(p->origin_scale));
    if (p->phase == PATH_SORT_HISTOGRAM) {
        atomic_inc(&buckets[k]);
    } else {
        uint slot = atomic_inc(&buckets[k]);
        if (slot < path_capacity) paths_out[slot] = q;
    }
}
