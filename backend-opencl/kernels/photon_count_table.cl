// photon_count_table: one direction of the blocked summed-area table of the photon
// counts clamped at 9 k (core/src/math/density_gather.rs). Mirror of
// backend-cpu/src/kernels/photon_count_table.rs and shaders/wgsl/photon_count_table.wgsl.
// Axis 0: a work-group per row and block; 1: a work-group per eight columns of a block, in
// place. Wrapping uint sums: exact, the same bits on every backend. Axis 1 also writes
// every pixel's edge texel (on the screen; the atlas's come with its layout).

// SCAN_THREADS (layout.cl): the threads of a work-group (the launch's 64); table_block
// is a power of two of at least 64, so each work-item of a row block takes table_block /
// 64 pixels. The column pass cuts a block's column into COLUMN_CHUNKS chunks; a
// work-group takes SCAN_COLUMNS neighbouring columns (core/src/math/density_gather.rs).

// One Hillis-Steele step of the work-group's inclusive scan.
void scan_step(__local uint* scratch, uint li, uint d) {
    uint add = li >= d ? scratch[li - d] : 0u;
    barrier(CLK_LOCAL_MEM_FENCE);
    scratch[li] += add;
    barrier(CLK_LOCAL_MEM_FENCE);
}

// The clamped count of pixel i.
uint count_at(__global const GatherParams* p, PHOTON_MAP_PARAMS(__global const), uint i) {
    return clamped_photon_count(photon_map_word(PHOTON_MAP_ARGS, i, 8u),
                                photon_map_word(PHOTON_MAP_ARGS, i, 9u), p->knn_photons);
}

// Both axes in one body (the WGSL's structure: every barrier at the top level, reached by
// every work-item). Axis 0: work-group g takes row g / blocks, block g % blocks; work-item
// li sums its table_block / 64 neighbouring pixels, a work-group scan gives it the sum
// before them, and it writes their prefix sums. Axis 1: work-item t = g * 64 + li writes
// pixel t's edge texel; work-group g also scans SCAN_COLUMNS neighbouring columns of one
// block, each column in COLUMN_CHUNKS chunks: a chunk's sum, the chunks above it through
// local memory, then the chunk's prefix sums in place.
__kernel __attribute__((reqd_work_group_size(64, 1, 1))) void photon_count_table(
    __global const GatherParams* p, PHOTON_MAP_PARAMS(__global const), __global uint* table,
    GATHER_GBUFFER_PARAMS(__global const), __global float4* edge) {
    __local uint scratch[SCAN_THREADS];
    uint g = get_group_id(0), li = get_local_id(0);
    uint w = p->camera.width, h = p->camera.height, b = p->table_block;
    bool rows = p->axis == 0u;
    uint v = 0u;
    // axis 0
    uint row_blocks = max((w + b - 1u) / b, 1u);
    bool row_active = rows && g < h * row_blocks;
    uint y_row = g / row_blocks, m = b / SCAN_THREADS;
    uint xr = (g % row_blocks) * b + li * m;
    if (row_active)
        for (uint j = 0u; j < m && xr + j < w; j++)
            v += count_at(p, PHOTON_MAP_ARGS, y_row * w + xr + j);
    // axis 1
    uint t = g * SCAN_THREADS + li;
    if (!rows && t < w * h && p->surface != GATHER_SURFACE_ATLAS)
        edge[t] = edge_texel(load_gather_texel(GATHER_GBUFFER_ARGS, t));
    uint groups_x = (w + SCAN_COLUMNS - 1u) / SCAN_COLUMNS;
    uint col_blocks = (h + b - 1u) / b;
    uint x = (g % groups_x) * SCAN_COLUMNS + li % SCAN_COLUMNS;
    uint chunk = li / SCAN_COLUMNS, chunk_rows = b / COLUMN_CHUNKS;
    uint y0 = (g / groups_x) * b + chunk * chunk_rows;
    uint y1 = min(y0 + chunk_rows, h);
    bool col_active = !rows && g < groups_x * col_blocks && x < w;
    if (col_active)
        for (uint y = y0; y < y1; y++) v += table[y * w + x];
    scratch[li] = v;
    barrier(CLK_LOCAL_MEM_FENCE);
    uint col_sum = 0u;
    if (col_active)
        for (uint k = 0u; k < chunk; k++) col_sum += scratch[k * SCAN_COLUMNS + li % SCAN_COLUMNS];
    barrier(CLK_LOCAL_MEM_FENCE);
    scan_step(scratch, li, 1u);
    scan_step(scratch, li, 2u);
    scan_step(scratch, li, 4u);
    scan_step(scratch, li, 8u);
    scan_step(scratch, li, 16u);
    scan_step(scratch, li, 32u);
    if (row_active) {
        uint sum = scratch[li] - v;
        for (uint j = 0u; j < m && xr + j < w; j++) {
            sum += count_at(p, PHOTON_MAP_ARGS, y_row * w + xr + j);
            table[y_row * w + xr + j] = sum;
        }
    }
    if (col_active)
        for (uint y = y0; y < y1; y++) {
            col_sum += table[y * w + x];
            table[y * w + x] = col_sum;
        }
}
