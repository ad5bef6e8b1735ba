// needs: layout prelude photon_clusters
// dispatch_args: the launch shapes of kernels whose work count is on the device, one
// thread per row of `table` ([first, bound, per_item, word]). Mirror of
// backend-opencl/kernels/dispatch_args.cl and backend-cpu/src/kernels/dispatch_args.rs
// (core::kernels::dispatch_record). The row count (the OpenCL `rows` argument) is the
// table's length, bounded by the records `args` holds: a binding is at least 64 bytes
// (four rows, two records), so a short table's padding rows must not write past them.

@group(0) @binding(0) var<storage, read> table: array<vec4<u32>>;
@group(0) @binding(1) var<storage, read> counts: array<u32>;
@group(0) @binding(2) var<storage, read_write> args: array<u32>;

// core::kernels::dispatch_record, written to record `r` of `args`.
fn dispatch_record(r: u32, count: u32, first: u32, bound: u32, per_item: u32) {
    let items = live_clusters(count, first, bound);
    // saturating, as core's
    let threads = select(items * per_item, 0xffffffffu,
                         per_item > 0u && items > 0xffffffffu / per_item);
    let groups = (threads + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    let gx = min(groups, DISPATCH_MAX_GROUPS_X);
    var gy = 1u;
    if (gx > 0u) {
        gy = (groups + gx - 1u) / gx;
    }
    let w = min(threads, DISPATCH_TRACE_WIDTH);
    var h = 1u;
    if (w > 0u) {
        h = (threads + w - 1u) / w;
    }
    let o = r * DISPATCH_RECORD_WORDS;
    args[o + DISPATCH_GROUPS_X] = gx;
    args[o + DISPATCH_GROUPS_Y] = gy;
    args[o + DISPATCH_GROUPS_Z] = 1u;
    args[o + DISPATCH_WIDTH] = w;
    args[o + DISPATCH_HEIGHT] = h;
    args[o + DISPATCH_DEPTH] = 1u;
    args[o + DISPATCH_THREADS] = threads;
    args[o + DISPATCH_ITEMS] = items;
}

fn dispatch_args(r: u32) {
    if (r >= arrayLength(&table) || r >= arrayLength(&args) / DISPATCH_RECORD_WORDS) {
        return;
    }
    let row = table[r];
    var count = 0u;
    if (row.w < arrayLength(&counts)) {
        count = counts[row.w];
    }
    dispatch_record(r, count, row.x, row.y, row.z);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    dispatch_args((wg.y * nwg.x + wg.x) * 64u + li);
}
