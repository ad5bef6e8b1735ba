// photon_count_table: one direction of the blocked summed-area table of the photon
// counts clamped at 9 k (core/src/math/density_gather.rs). Mirror of
// backend-cpu/src/kernels/density_gather.rs and shaders/wgsl/photon_count_table.wgsl.
// Axis 0: a work-group per row and block; 1: a work-group per eight columns of a block, in
// place. Wrapping uint sums: exact, the same bits on every backend. Axis 1 also writes
// every pixel's edge texel (on the screen; the atlas's come with its layout).

// Threads of a work-group (the launch's 64); table_block is a power of two of at least
// 64. The column pass cuts a block's column into COLUMN_CHUNKS chunks; a work-group takes
// SCAN_COLUMNS neighbouring columns (core/src/math/density_gather.rs).
#define SCAN_THREADS 64u
#define COLUMN_CHUNKS 8u
#define SCAN_COLUMNS 8u

// Axis 0: work-group g takes row g / blocks, block g % blocks; its work-items read
// neighbouring pixels and a Hillis-Steele scan in local memory gives the prefix sums,
// chunk by chunk with the carry of the chunks before.
void photon_count_row_block(__global const GatherParams* p, PHOTON_MAP_PARAMS(__global const),
                            __global uint* table, __local uint* scratch, uint g, uint li) {
    uint w = p->camera.width, b = p->table_block;
    uint blocks = (w + b - 1u) / b;
    if (g >= p->camera.height * blocks) return;
    uint y = g / blocks, x0 = (g % blocks) * b;
    uint x_end = min(x0 + b, w);
    uint carry = 0u;
    for (uint c = x0; c < x_end; c += SCAN_THREADS) {
        uint x = c + li, i = y * w + x;
        uint v = 0u;
        if (x < x_end)
            v = clamped_photon_count(photon_map_word(PHOTON_MAP_ARGS, i, 8u),
                                     photon_map_word(PHOTON_MAP_ARGS, i, 9u), p->knn_photons);
        scratch[li] = v;
        barrier(CLK_LOCAL_MEM_FENCE);
        for (uint d = 1u; d < SCAN_THREADS; d <<= 1) {
            uint add = li >= d ? scratch[li - d] : 0u;
            barrier(CLK_LOCAL_MEM_FENCE);
            scratch[li] += add;
            barrier(CLK_LOCAL_MEM_FENCE);
        }
        if (x < x_end) table[i] = carry + scratch[li];
        carry += scratch[SCAN_THREADS - 1u];
        barrier(CLK_LOCAL_MEM_FENCE);
    }
}

// Axis 1: work-item t = g * 64 + li writes pixel t's edge texel; work-group g also scans
// SCAN_COLUMNS neighbouring columns of one block, each column in COLUMN_CHUNKS chunks: a
// chunk's sum, the chunks above it through local memory, then the chunk's prefix sums in
// place.
void photon_count_column_block(__global const GatherParams* p, __global uint* table,
                               GATHER_GBUFFER_PARAMS(__global const), __global float4* edge,
                               __local uint* scratch, uint g, uint li) {
    uint w = p->camera.width, h = p->camera.height, b = p->table_block;
    uint t = g * SCAN_THREADS + li;
    if (t < w * h && p->surface != GATHER_SURFACE_ATLAS)
        edge[t] = edge_texel(load_gather_texel(GATHER_GBUFFER_ARGS, t));
    uint groups_x = (w + SCAN_COLUMNS - 1u) / SCAN_COLUMNS;
    uint blocks = (h + b - 1u) / b;
    if (g >= groups_x * blocks) return;
    uint x = (g % groups_x) * SCAN_COLUMNS + li % SCAN_COLUMNS;
    uint chunk = li / SCAN_COLUMNS, rows = b / COLUMN_CHUNKS;
    uint y0 = (g / groups_x) * b + chunk * rows;
    uint y1 = min(y0 + rows, h);
    uint chunk_sum = 0u;
    if (x < w)
        for (uint y = y0; y < y1; y++) chunk_sum += table[y * w + x];
    scratch[li] = chunk_sum;
    barrier(CLK_LOCAL_MEM_FENCE);
    uint sum = 0u;
    for (uint k = 0u; k < chunk; k++) sum += scratch[k * SCAN_COLUMNS + li % SCAN_COLUMNS];
    if (x < w)
        for (uint y = y0; y < y1; y++) {
            sum += table[y * w + x];
            table[y * w + x] = sum;
        }
}

__kernel __attribute__((reqd_work_group_size(64, 1, 1))) void photon_count_table(
    __global const GatherParams* p, PHOTON_MAP_PARAMS(__global const), __global uint* table,
    GATHER_GBUFFER_PARAMS(__global const), __global float4* edge) {
    __local uint scratch[SCAN_THREADS];
    uint g = get_group_id(0), li = get_local_id(0);
    if (p->axis == 0u)
        photon_count_row_block(p, PHOTON_MAP_ARGS, table, scratch, g, li);
    else
        photon_count_column_block(p, table, GATHER_GBUFFER_ARGS, edge, scratch, g, li);
}
