// needs: layout prelude photon_map
// tile_hit_distance (Kim 2019, section 30.3.2): photon-weighted mean hit distance per
// tile_size^2 tile, 0 for empty tiles. Mirror of backend-opencl/kernels/
// tile_hit_distance.cl and backend-cpu/src/kernels/tile_hit_distance.rs. The u64 sums are (lo, hi)
// u32 pairs with carry (exact, as the OpenCL ulong sums); the mean is taken in f32 from
// the exact hi * 2^32 + lo split, as resolve_caustics.cl without fp64 (the CPU divides in
// f64: a few f32 roundings away).

@group(0) @binding(0) var<uniform> params: GatherParams;
@group(0) @binding(1) var<storage, read> photon_map0: array<u32>;
@group(0) @binding(2) var<storage, read> photon_map1: array<u32>;
@group(0) @binding(3) var<storage, read> photon_map2: array<u32>;
@group(0) @binding(4) var<storage, read_write> tiles: array<f32>;

// (lo, hi) u64 pair plus (lo, hi): the OpenCL `ulong +=` (wrapping, as ulong).
fn add_u64(a: vec2<u32>, lo: u32, hi: u32) -> vec2<u32> {
    let l = a.x + lo;
    let carry = select(0u, 1u, l < lo);
    return vec2<u32>(l, a.y + hi + carry);
}

// hi * 2^32 (exact when f32(hi) is) + lo, in f32 (resolve_caustics.wgsl's join_u64_wide).
fn join_u64_wide(lo: u32, hi: u32) -> f32 {
    return f32(hi) * 4294967296.0f + f32(lo);
}

fn tile_hit_distance(t: u32) {
    let p = params;
    let w = p.camera.width;
    let h = p.camera.height;
    let ts = p.tile_size;
    let tw = (w + ts - 1u) / ts;
    let th = (h + ts - 1u) / ts;
    if (t >= tw * th) {
        return;
    }
    let tx = t % tw;
    let ty = t / tw;
    var sum = vec2<u32>(0u, 0u);
    var n = vec2<u32>(0u, 0u);
    for (var y = ty * ts; y < min((ty + 1u) * ts, h); y++) {
        for (var x = tx * ts; x < min((tx + 1u) * ts, w); x++) {
            let m = y * w + x;
            sum = add_u64(sum, photon_map_word(m, 6u), photon_map_word(m, 7u));
            n = add_u64(n, photon_map_word(m, 8u), photon_map_word(m, 9u));
        }
    }
    if (n.x == 0u && n.y == 0u) {
        tiles[t] = 0.0;
        return;
    }
    tiles[t] = join_u64_wide(sum.x, sum.y) * p.hit_distance_quantum / join_u64_wide(n.x, n.y);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    tile_hit_distance(i);
}
