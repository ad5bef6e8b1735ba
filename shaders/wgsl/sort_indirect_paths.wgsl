// needs: layout prelude
// sort_indirect_paths (PhotonGi's sorted_waves schedule): the order in which the next wave
// takes the queued paths, a counting sort of the keys the queuing wave wrote
// (trace_indirect with params.queue_keys: path_keys[slot] = (key, rank), buckets[key] its
// count), one phase a launch: PATH_SORT_SCAN (one workgroup) turns the counts in `buckets`
// into each bucket's first slot; PATH_SORT_SCATTER (a thread per path, the first
// min(path_counts[count_word], arrayLength(path_keys)) of the queue) writes path i's queue
// slot at order[buckets[key] + rank]. No atomics: the order is the ranks', which the
// queuing wave's atomics drew. Mirror of backend-opencl/kernels/sort_indirect_paths.cl and
// backend-cpu/src/kernels/sort_indirect_paths.rs (core::math::path_sort).
// Bindings: params, path_keys (read), path_counts (read), order (written by SCATTER),
// buckets (counts, then first slots: written by SCAN, read by SCATTER).

@group(0) @binding(0) var<uniform> params: PathSortParams;
@group(0) @binding(1) var<storage, read> path_keys: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> path_counts: array<u32>;
@group(0) @binding(3) var<storage, read_write> order: array<u32>;
@group(0) @binding(4) var<storage, read_write> buckets: array<atomic<u32>>;

// The workgroup's partial sums (SCAN).
var<workgroup> partial: array<u32, WORKGROUP_SIZE>;

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

// PATH_SORT_SCATTER: path `i`'s queue slot at its bucket's first slot plus its rank there.
fn path_sort_scatter(i: u32) {
    let p = params;
    let capacity = arrayLength(&path_keys);
    if (i >= min(path_counts[p.count_word], capacity)) {
        return;
    }
    let kr = path_keys[i];
    // a key a queuing wave did not write (a corrupt queue) is not placed
    if (kr.x >= PATH_SORT_BUCKETS) {
        return;
    }
    let s = atomicLoad(&buckets[kr.x]) + kr.y;
    if (s < capacity) {
        order[s] = i;
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    if (params.phase != PATH_SORT_SCAN) {
        path_sort_scatter((wg.y * nwg.x + wg.x) * 64u + li);
    }
    // the phase is the launch's: a workgroup-uniform exit before the scan's barriers
    if (params.phase != PATH_SORT_SCAN) {
        return;
    }
    path_sort_scan(li);
}
