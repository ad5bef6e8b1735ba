// needs: types vector fixed_point atlas photon_map_add atlas_deposit
// deposit_atlas (seed 001 section 3.2): each texture-space photon (uv, triangle) is added
// in fixed point to the atlas texel under its uv on its triangle's receiver tile. Mirror
// of backend-opencl/kernels/deposit_atlas.cl and backend-cpu/src/kernels/caustic_map.rs;
// the sums are bitwise the CPU's for the same photons.

@group(0) @binding(0) var<uniform> params: AtlasParams;
@group(0) @binding(1) var<storage, read> triangle_tiles: array<u32>;
@group(0) @binding(2) var<storage, read> tiles: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> photons: array<Photon>;
@group(0) @binding(4) var<storage, read> photon_count: array<u32>;
@group(0) @binding(5) var<storage, read_write> counters: array<atomic<u32>>;
@group(0) @binding(6) var<storage, read_write> triangle_reach: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read_write> photon_map0: array<atomic<u32>>;
@group(0) @binding(8) var<storage, read_write> photon_map1: array<atomic<u32>>;
@group(0) @binding(9) var<storage, read_write> photon_map2: array<atomic<u32>>;

var<workgroup> lc: array<atomic<u32>, COUNTER_WORDS>;

fn deposit_atlas(i: u32, li: u32) {
    counters_clear_local(li);
    let p = params;
    let photon_capacity = arrayLength(&photons);
    if (i < min(photon_count[0], photon_capacity)) {
        deposit_atlas_photon(photons[i], p.width, p.flux_quantum, p.hit_distance_quantum);
    }
    counters_flush_local(li);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    // No early return: every invocation reaches the barriers in deposit_atlas.
    deposit_atlas(i, li);
}
