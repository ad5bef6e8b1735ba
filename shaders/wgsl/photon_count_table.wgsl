// needs: types photon_map
// photon_count_table: one direction of the blocked summed-area table of the photon
// counts clamped at 9 k (core/src/math/density_gather.rs). Mirror of
// backend-opencl/kernels/photon_count_table.cl and backend-cpu/src/kernels/
// density_gather.rs. Axis 0: a thread per row and block; 1: a thread per column and
// block, in place, and every pixel's edge texel (on the screen; the atlas's come with its
// layout). Wrapping u32 sums: exact, the same bits on every backend.

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


fn photon_count_table(t: u32) {
    let p = params;
    let w = p.camera.width;
    let h = p.camera.height;
    let b = p.table_block;
    if (p.axis == 0u) {
        // a thread per row and block
        let blocks = (w + b - 1u) / b;
        if (t >= h * blocks) {
            return;
        }
        let y = t / blocks;
        let x0 = (t % blocks) * b;
        var sum = 0u;
        for (var x = x0; x < min(x0 + b, w); x++) {
            let i = y * w + x;
            sum += clamped_photon_count(photon_map_word(i, 8u), photon_map_word(i, 9u),
                                        p.knn_photons);
            table[i] = sum;
        }
    } else {
        // a thread per pixel writes its edge texel; the first w x blocks also scan, a
        // thread per column and block (neighbouring threads, neighbouring columns)
        // (the atlas's edge texels come with its layout)
        if (t < w * h && p.surface != GATHER_SURFACE_ATLAS) {
            edge[t] = edge_texel(load_gather_texel(t));
        }
        let blocks = (h + b - 1u) / b;
        if (t >= w * blocks) {
            return;
        }
        let x = t % w;
        let y0 = (t / w) * b;
        var sum = 0u;
        for (var y = y0; y < min(y0 + b, h); y++) {
            sum += table[y * w + x];
            table[y * w + x] = sum;
        }
    }
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    photon_count_table(i);
}
