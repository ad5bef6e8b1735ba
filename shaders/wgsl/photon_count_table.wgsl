// needs: types photon_map
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

const COUNT_CLAMP_PER_K: u32 = 9u;

// Per-pixel photon count as the summed-area table holds it: min(count, 9 k).
fn clamped_photon_count(lo: u32, hi: u32, k: u32) -> u32 {
    let clamp = COUNT_CLAMP_PER_K * k;
    return select(min(lo, clamp), clamp, hi != 0u);
}

// What the gather needs of a G-buffer texel (planes 0, 1 and 3 only).
struct GatherTexel {
    receiver: u32,
    depth: f32,
    normal: vec3<f32>,
}

fn load_gather_texel(i: u32) -> GatherTexel {
    var t: GatherTexel;
    t.receiver = gbuffer3[i].w & GBUFFER_RECEIVER;
    t.depth = bitcast<f32>(gbuffer0[i].w);
    t.normal = bitcast<vec3<f32>>(gbuffer1[i].xyz);
    return t;
}

// Depth of a non-receiver's edge texel (receivers' view depths are positive).
const EDGE_TEXEL_NOT_RECEIVER: f32 = -1.0;

// A pixel's edge texel: (view depth, normal) of a receiver, the G-buffer's bits; depth
// EDGE_TEXEL_NOT_RECEIVER elsewhere.
fn edge_texel(t: GatherTexel) -> vec4<f32> {
    if (t.receiver != 0u) {
        return vec4<f32>(t.depth, t.normal);
    }
    return vec4<f32>(EDGE_TEXEL_NOT_RECEIVER, 0.0, 0.0, 0.0);
}


// Threads of a workgroup (the launch's DEFAULT_WORKGROUP_SIZE); table_block is a power
// of two of at least 64, so a block's row is a whole number of workgroup-wide chunks.
const SCAN_THREADS: u32 = 64u;
// The column pass splits a block's column into COLUMN_CHUNKS chunks of table_block /
// COLUMN_CHUNKS rows; a workgroup takes SCAN_THREADS / COLUMN_CHUNKS neighbouring columns.
const COLUMN_CHUNKS: u32 = 8u;
const SCAN_COLUMNS: u32 = 8u;

var<workgroup> scan_scratch: array<u32, 64>;

// Axis 0: workgroup g takes row g / blocks, block g % blocks; its threads read
// neighbouring pixels (coalesced) and a Hillis-Steele scan in workgroup memory gives the
// prefix sums, chunk by chunk with the carry of the chunks before. The same wrapping u32
// sums as a sequential loop, in another order: exact, the same bits.
fn photon_count_row_block(g: u32, li: u32) {
    let p = params;
    let w = p.camera.width;
    let b = p.table_block;
    let blocks = (w + b - 1u) / b;
    if (g >= p.camera.height * blocks) {
        return;
    }
    let y = g / blocks;
    let x0 = (g % blocks) * b;
    let x_end = min(x0 + b, w);
    var carry = 0u;
    for (var c = x0; c < x_end; c += SCAN_THREADS) {
        let x = c + li;
        let i = y * w + x;
        var v = 0u;
        if (x < x_end) {
            v = clamped_photon_count(photon_map_word(i, 8u), photon_map_word(i, 9u),
                                     p.knn_photons);
        }
        scan_scratch[li] = v;
        workgroupBarrier();
        for (var d = 1u; d < SCAN_THREADS; d = d << 1u) {
            var add = 0u;
            if (li >= d) {
                add = scan_scratch[li - d];
            }
            workgroupBarrier();
            scan_scratch[li] += add;
            workgroupBarrier();
        }
        if (x < x_end) {
            table[i] = carry + scan_scratch[li];
        }
        carry += scan_scratch[SCAN_THREADS - 1u];
        workgroupBarrier();
    }
}

// Axis 1: thread t (= g * 64 + li) writes pixel t's edge texel; workgroup g also scans
// SCAN_COLUMNS neighbouring columns of one block (g % column groups, g / column groups),
// each column in COLUMN_CHUNKS chunks: a chunk's sum, the chunks above it through
// workgroup memory, then the chunk's prefix sums in place. Exact wrapping u32 sums.
fn photon_count_column_block(g: u32, li: u32) {
    let p = params;
    let w = p.camera.width;
    let h = p.camera.height;
    let b = p.table_block;
    let t = g * SCAN_THREADS + li;
    if (t < w * h && p.surface != GATHER_SURFACE_ATLAS) {
        edge[t] = edge_texel(load_gather_texel(t));
    }
    let groups_x = (w + SCAN_COLUMNS - 1u) / SCAN_COLUMNS;
    let blocks = (h + b - 1u) / b;
    if (g >= groups_x * blocks) {
        return;
    }
    let x = (g % groups_x) * SCAN_COLUMNS + li % SCAN_COLUMNS;
    let chunk = li / SCAN_COLUMNS;
    let rows = b / COLUMN_CHUNKS;
    let y0 = (g / groups_x) * b + chunk * rows;
    let y1 = min(y0 + rows, h);
    var chunk_sum = 0u;
    if (x < w) {
        for (var y = y0; y < y1; y++) {
            chunk_sum += table[y * w + x];
        }
    }
    scan_scratch[li] = chunk_sum;
    workgroupBarrier();
    var sum = 0u;
    for (var k = 0u; k < chunk; k++) {
        sum += scan_scratch[k * SCAN_COLUMNS + li % SCAN_COLUMNS];
    }
    if (x < w) {
        for (var y = y0; y < y1; y++) {
            sum += table[y * w + x];
            table[y * w + x] = sum;
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let g = wg.y * nwg.x + wg.x;
    if (params.axis == 0u) {
        photon_count_row_block(g, li);
    } else {
        photon_count_column_block(g, li);
    }
}
