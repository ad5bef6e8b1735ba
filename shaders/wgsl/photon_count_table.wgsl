// needs: layout prelude photon_map gather_texel
// photon_count_table: one direction of the blocked summed-area table of the photon
// counts clamped at 9 k (core/src/math/density_gather.rs). Mirror of
// backend-opencl/kernels/photon_count_table.cl and backend-cpu/src/kernels/
// density_gather.rs. Axis 0: a workgroup per row and block; 1: a workgroup per eight
// columns of a block, in place, and every pixel's edge texel (on the screen; the atlas's
// come with its layout). Wrapping u32 sums: exact, the same bits on every backend.

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> photon_map0: array<u32>;
@group(0) @binding(2) var<storage, read> photon_map1: array<u32>;
@group(0) @binding(3) var<storage, read> photon_map2: array<u32>;
@group(0) @binding(4) var<storage, read_write> table: array<u32>;
@group(0) @binding(5) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(6) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(7) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(8) var<storage, read_write> edge: array<vec4<f32>>;

// Per-pixel photon count as the summed-area table holds it: min(count, 9 k).
fn clamped_photon_count(lo: u32, hi: u32, k: u32) -> u32 {
    let clamp = COUNT_CLAMP_PER_K * k;
    return select(min(lo, clamp), clamp, hi != 0u);
}

// SCAN_THREADS: the threads of a workgroup (the launch's DEFAULT_WORKGROUP_SIZE);
// table_block is a power of two of at least 64, so each thread of a row block takes
// table_block / 64 pixels. The column pass splits a block's column into COLUMN_CHUNKS
// chunks of table_block / COLUMN_CHUNKS rows; a workgroup takes SCAN_COLUMNS =
// SCAN_THREADS / COLUMN_CHUNKS neighbouring columns.

var<workgroup> scan_scratch: array<u32, 64>;

// One Hillis-Steele step of the workgroup's inclusive scan (barriers at its top level).
fn scan_step(li: u32, d: u32) {
    var add = 0u;
    if (li >= d) {
        add = scan_scratch[li - d];
    }
    workgroupBarrier();
    scan_scratch[li] += add;
    workgroupBarrier();
}

// The clamped count of pixel (x, y).
fn count_at(x: u32, y: u32) -> u32 {
    let i = y * params.camera.width + x;
    return clamped_photon_count(photon_map_word(i, 8u), photon_map_word(i, 9u),
                                params.knn_photons);
}

// Both axes in one body, so that every barrier sits at its top level and every
// invocation reaches it (no early return). Axis 0: workgroup g takes row g / blocks,
// block g % blocks; thread li sums its table_block / 64 neighbouring pixels, a workgroup
// scan gives each thread the sum before its pixels, and it writes their prefix sums.
// Axis 1: thread t = g * 64 + li writes pixel t's edge texel; workgroup g also scans
// SCAN_COLUMNS neighbouring columns of one block, each column in COLUMN_CHUNKS chunks:
// a chunk's sum, the chunks above it through workgroup memory, then the chunk's prefix
// sums in place. Wrapping u32 sums in another order than the CPU's loop: exact, the
// same bits.
fn photon_count_table(g: u32, li: u32) {
    let p = params;
    let w = p.camera.width;
    let h = p.camera.height;
    let b = p.table_block;
    let rows = p.axis == 0u;
    var v = 0u;
    // axis 0
    let row_blocks = (w + b - 1u) / b;
    let row_active = rows && g < h * row_blocks;
    let y_row = g / max(row_blocks, 1u);
    let m = b / SCAN_THREADS;
    let xr = (g % max(row_blocks, 1u)) * b + li * m;
    if (row_active) {
        for (var j = 0u; j < m && xr + j < w; j++) {
            v += count_at(xr + j, y_row);
        }
    }
    // axis 1
    let t = g * SCAN_THREADS + li;
    if (!rows && t < w * h && p.surface != GATHER_SURFACE_ATLAS) {
        edge[t] = edge_texel(load_gather_texel(t));
    }
    let groups_x = (w + SCAN_COLUMNS - 1u) / SCAN_COLUMNS;
    let col_blocks = (h + b - 1u) / b;
    let x = (g % groups_x) * SCAN_COLUMNS + li % SCAN_COLUMNS;
    let chunk = li / SCAN_COLUMNS;
    let chunk_rows = b / COLUMN_CHUNKS;
    let y0 = (g / groups_x) * b + chunk * chunk_rows;
    let y1 = min(y0 + chunk_rows, h);
    let col_active = !rows && g < groups_x * col_blocks && x < w;
    if (col_active) {
        for (var y = y0; y < y1; y++) {
            v += table[y * w + x];
        }
    }
    scan_scratch[li] = v;
    workgroupBarrier();
    var col_sum = 0u;
    if (col_active) {
        for (var k = 0u; k < chunk; k++) {
            col_sum += scan_scratch[k * SCAN_COLUMNS + li % SCAN_COLUMNS];
        }
    }
    workgroupBarrier();
    scan_step(li, 1u);
    scan_step(li, 2u);
    scan_step(li, 4u);
    scan_step(li, 8u);
    scan_step(li, 16u);
    scan_step(li, 32u);
    if (row_active) {
        var sum = scan_scratch[li] - v;
        for (var j = 0u; j < m && xr + j < w; j++) {
            sum += count_at(xr + j, y_row);
            table[y_row * w + xr + j] = sum;
        }
    }
    if (col_active) {
        for (var y = y0; y < y1; y++) {
            col_sum += table[y * w + x];
            table[y * w + x] = col_sum;
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    photon_count_table(wg.y * nwg.x + wg.x, li);
}
