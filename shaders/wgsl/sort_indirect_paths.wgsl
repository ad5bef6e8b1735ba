// needs: layout prelude
// sort_indirect_paths (PhotonGi's sorted_waves schedule): the first
// min(path_counts[count_word], arrayLength(paths_in)) queued paths counted into the
// buckets of their key (PATH_SORT_HISTOGRAM, a thread per path), the counts turned into
// first slots (PATH_SORT_SCAN, one workgroup), each path moved to the next slot of its
// bucket (PATH_SORT_SCATTER). Mirror of backend-opencl/kernels/sort_indirect_paths.cl and
// backend-cpu/src/kernels/sort_indirect_paths.rs (core::math::path_sort).

@group(0) @binding(0) var<uniform> params: PathSortParams;
@group(0) @binding(1) var<storage, read> paths_in: array<IndirectPath>;
@group(0) @binding(2) var<storage, read> path_counts: array<u32>;
@group(0) @binding(3) var<storage, read_write> paths_out: array<IndirectPath>;
@group(0) @binding(4) var<storage, read_write> buckets: array<atomic<u32>>;

// The workgroup's partial sums (SCAN).
var<workgroup> partial: array<u32, WORKGROUP_SIZE>;

// core::math::path_sort::path_sort_key.
fn path_sort_key(origin: vec3<f32>, direction: vec3<f32>, origin_min: vec3<f32>,
                 origin_scale: vec3<f32>) -> u32 {
    let top = f32((1u << PATH_SORT_BITS) - 1u);
    let c = vec3<u32>(min(max((origin - origin_min) * origin_scale, vec3<f32>(0.0)),
                          vec3<f32>(top)));
    var morton = 0u;
    for (var b = 0u; b < PATH_SORT_BITS; b++) {
        morton |= ((c.x >> b) & 1u) << (3u * b) | ((c.y >> b) & 1u) << (3u * b + 1u) |
                  ((c.z >> b) & 1u) << (3u * b + 2u);
    }
    let octant = select(0u, 1u, direction.x < 0.0) | select(0u, 2u, direction.y < 0.0) |
                 select(0u, 4u, direction.z < 0.0);
    return octant << (3u * PATH_SORT_BITS) | morton;
}

fn key_of(i: u32) -> u32 {
    let q = paths_in[i];
    return path_sort_key(q.origin, q.direction, params.origin_min, params.origin_scale);
}

// PATH_SORT_SCAN (one workgroup): each thread sums its run of PATH_SORT_BUCKETS /
// WORKGROUP_SIZE counts; thread 0 scans the runs; each thread writes its run's first
// slots.
fn path_sort_scan(li: u32) {
    let per = u32(PATH_SORT_BUCKETS) / WORKGROUP_SIZE;
    var sum = 0u;
    for (var k = 0u; k < per; k++) {
        sum += atomicLoad(&buckets[li * per + k]);
    }
    partial[li] = sum;
    workgroupBarrier();
    if (li == 0u) {
        var run = 0u;
        for (var t = 0u; t < WORKGROUP_SIZE; t++) {
            let s = partial[t];
            partial[t] = run;
            run += s;
        }
    }
    workgroupBarrier();
    var first = partial[li];
    for (var k = 0u; k < per; k++) {
        let count = atomicLoad(&buckets[li * per + k]);
        atomicStore(&buckets[li * per + k], first);
        first += count;
    }
}

// PATH_SORT_HISTOGRAM and PATH_SORT_SCATTER: path `i`'s bucket count, or its slot.
fn path_sort_path(i: u32) {
    let p = params;
    if (i >= min(path_counts[p.count_word], arrayLength(&paths_in))) {
        return;
    }
    let k = key_of(i);
    if (p.phase == PATH_SORT_HISTOGRAM) {
        atomicAdd(&buckets[k], 1u);
    } else {
        let slot = atomicAdd(&buckets[k], 1u);
        if (slot < arrayLength(&paths_out)) {
            paths_out[slot] = paths_in[i];
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    if (params.phase != PATH_SORT_SCAN) {
        path_sort_path((wg.y * nwg.x + wg.x) * 64u + li);
    }
    // the phase is the launch's: a workgroup-uniform exit before the scan's barriers
    if (params.phase != PATH_SORT_SCAN) {
        return;
    }
    path_sort_scan(li);
}
