// dispatch_args: the launch shapes of kernels whose work count is on the device, one
// thread per row of `table` ([first, bound, per_item, word]). Mirror of
// backend-cpu/src/kernels/dispatch_args.rs (core::kernels::dispatch_record). OpenCL 1.2
// has no indirect launch: the records are still written (for the conformance check and
// for any later reader), and the kernels they size launch their bound here.

// core::kernels::dispatch_record, written to record `r` of `args`.
inline void dispatch_record(__global uint* args, uint r, uint count, uint first, uint bound,
                            uint per_item) {
    uint items = live_clusters(count, first, bound);
    // saturating, as core's
    uint threads = (per_item > 0u && items > 0xffffffffu / per_item) ? 0xffffffffu
                                                                     : items * per_item;
    uint groups = (threads + WORKGROUP_SIZE - 1u) / WORKGROUP_SIZE;
    uint gx = min(groups, DISPATCH_MAX_GROUPS_X);
    uint gy = gx > 0u ? (groups + gx - 1u) / gx : 1u;
    uint w = min(threads, DISPATCH_TRACE_WIDTH);
    uint h = w > 0u ? (threads + w - 1u) / w : 1u;
    __global uint* o = args + r * DISPATCH_RECORD_WORDS;
    o[DISPATCH_GROUPS_X] = gx;
    o[DISPATCH_GROUPS_Y] = gy;
    o[DISPATCH_GROUPS_Z] = 1u;
    o[DISPATCH_WIDTH] = w;
    o[DISPATCH_HEIGHT] = h;
    o[DISPATCH_DEPTH] = 1u;
    o[DISPATCH_THREADS] = threads;
    o[DISPATCH_ITEMS] = items;
}

__kernel void dispatch_args(uint rows, __global const uint4* table, uint count_words,
                            __global const uint* counts, __global uint* args) {
    uint r = get_global_id(0);
    if (r >= rows) return;
    uint4 row = table[r];
    dispatch_record(args, r, row.w < count_words ? counts[row.w] : 0u, row.x, row.y, row.z);
}
