// needs: layout prelude vector packing gbuffer atlas irradiance_filter
// shading_normal_correction (Smal 2019, section 24.4.3, Eq. 20): per receiver pixel with
// splats, the filtered indirect radiance times min(max(0, w_i . n_s) / (w_i . n_g + eps),
// s_max), w_i the splats' power-weighted mean light direction. Mirror of
// backend-cpu/src/kernels/shading_normal_correction.rs (shading_normal_correction) and
// backend-opencl/kernels/shading_normal_correction.cl.

@group(0) @binding(0) var<uniform> params: CorrectionParams;
@group(0) @binding(1) var<storage, read> gbuffer0: array<vec4<u32>>;
@group(0) @binding(2) var<storage, read> gbuffer1: array<vec4<u32>>;
@group(0) @binding(3) var<storage, read> gbuffer2: array<vec4<u32>>;
@group(0) @binding(4) var<storage, read> gbuffer3: array<vec4<u32>>;
@group(0) @binding(5) var<storage, read> direction_map0: array<u32>;
@group(0) @binding(6) var<storage, read> direction_map1: array<u32>;
@group(0) @binding(7) var<storage, read> direction_map2: array<u32>;
@group(0) @binding(8) var<storage, read> input: array<vec4<f32>>;
@group(0) @binding(9) var<storage, read_write> out: array<vec4<f32>>;

// photon_map_word on the direction map.
fn direction_map_word(pixel: u32, word: u32) -> u32 {
    let at = deposit_word(pixel, word);
    if (at.x == 0u) {
        return direction_map0[at.y];
    }
    if (at.x == 1u) {
        return direction_map1[at.y];
    }
    return direction_map2[at.y];
}

fn shading_normal_correction(i: u32) {
    let p = params;
    if (i >= p.width * p.height) {
        return;
    }
    let v = input[i];
    let g = load_gbuffer(i);
    let w = join_u64_f32(direction_map_word(i, DEPOSIT_HIT_DISTANCE),
                         direction_map_word(i, DEPOSIT_HIT_DISTANCE + 1u));
    let n_g = unpack_unit_vector(g.geometric_normal);
    if ((g.flags & GBUFFER_RECEIVER) == 0u || !(w > 0.0f) ||
        !shading_normal_departs(g.normal, n_g)) {
        out[i] = v;
        return;
    }
    var sums: vec3<f32>;
    for (var ch = 0u; ch < 3u; ch++) {
        sums[ch] = join_u64_f32(direction_map_word(i, DEPOSIT_FLUX + 2u * ch),
                                direction_map_word(i, DEPOSIT_FLUX + 2u * ch + 1u));
    }
    let w_i = mean_light_direction(sums, w);
    if (all(w_i == vec3<f32>(0.0f))) {
        out[i] = v;
        return;
    }
    let f = shading_normal_factor(w_i, g.normal, n_g, p.max_stretch, p.epsilon);
    out[i] = vec4<f32>(v.xyz * f, v.w);
}

@compute @workgroup_size(64)
fn main(@builtin(workgroup_id) wg: vec3<u32>, @builtin(num_workgroups) nwg: vec3<u32>,
        @builtin(local_invocation_index) li: u32) {
    let i = (wg.y * nwg.x + wg.x) * 64u + li;
    shading_normal_correction(i);
}
