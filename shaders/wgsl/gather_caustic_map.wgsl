// needs: layout prelude vector atlas photon_map map_gather
// gather_caustic_map (Vanderstichelen 2021, section 3.1, "Denoising"): per atlas texel, the
// flux-keeping N x N gather inside its tile, as irradiance. Mirror of
// backend-opencl/kernels/gather_caustic_map.cl and backend-cpu/src/kernels/gather_caustic_map.rs.

@group(0) @binding(0) var<uniform> params: AtlasParams;
@group(0) @binding(1) var<storage, read> texels: array<vec2<u32>>;
@group(0) @binding(2) var<storage, read> tiles: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> photon_map0: array<u32>;
@group(0) @binding(4) var<storage, read> photon_map1: array<u32>;
@group(0) @binding(5) var<storage, read> photon_map2: array<u32>;
@group(0) @binding(6) var<storage, read_write> out: array<vec4<f32>>;

fn atlas_area(i: u32) -> f32 {
    return bitcast<f32>(texels[i].x);
}

fn atlas_flux(i: u32) -> vec3<f32> {
    let q = params.flux_quantum;
    return vec3<f32>(join_u64_f32(photon_map_word(i, 0u), photon_map_word(i, 1u)) * q,
                     join_u64_f32(photon_map_word(i, 2u), photon_map_word(i, 3u)) * q,
                     join_u64_f32(photon_map_word(i, 4u), photon_map_word(i, 5u)) * q);
}

fn gather_caustic_map(t: u32) {
    let p = params;
    if (t >= p.width * p.height) {
        return;
    }
    let tile = texels[t].y;
    if (tile == NO_TILE || tile >= arrayLength(&tiles)) {
        out[t] = vec4<f32>(0.0, 0.0, 0.0, 1.0);
        return;
    }
    let e = gather_caustic_texel(tiles[tile], t % p.width, t / p.width, p.gather_width, p.width);
    out[t] = vec4<f32>(e, 1.0);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    gather_caustic_map(i);
}
