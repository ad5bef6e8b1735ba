// sort_indirect_paths (PhotonGi's sorted_waves schedule): the order in which the next wave
// takes the first min(path_counts[count_word], path_capacity) queued paths, from the
// (key, rank) that the queuing wave wrote beside each (trace_indirect's queue_keys) and
// the buckets' counts it left: the counts turned into first slots (PATH_SORT_SCAN, one
// workgroup), each path's queue slot written at its bucket's first slot plus its rank
// (PATH_SORT_SCATTER, a thread per path, no atomics). Mirror of
// backend-cpu/src/kernels/sort_indirect_paths.rs and shaders/wgsl/sort_indirect_paths.wgsl.

__kernel void sort_indirect_paths(__global const PathSortParams* p,
                                  __global const uint2* path_keys, uint path_capacity,
                                  __global const uint* path_counts, __global uint* order,
                                  __global uint* buckets) {
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
    uint2 kr = path_keys[i];
    // a key a queuing wave did not write (a corrupt queue) is not placed
    if (kr.x >= (uint)PATH_SORT_BUCKETS) return;
    uint slot = buckets[kr.x] + kr.y;
    if (slot < path_capacity) order[slot] = i;
}
