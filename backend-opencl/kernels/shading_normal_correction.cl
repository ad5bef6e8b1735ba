// shading_normal_correction (Smal 2019, section 24.4.3, Eq. 20): per receiver pixel with
// splats, the filtered indirect radiance times min(max(0, w_i . n_s) / (w_i . n_g + eps),
// s_max), w_i the splats' power-weighted mean light direction. Mirror of
// backend-cpu/src/kernels/shading_normal_correction.rs (shading_normal_correction).

__kernel void shading_normal_correction(__global const CorrectionParams* p,
                                        GBUFFER_PARAMS(__global const),
                                        __global const uint* direction_map0,
                                        __global const uint* direction_map1,
                                        __global const uint* direction_map2,
                                        __global const float4* input, __global float4* out) {
    uint i = get_global_id(0);
    if (i >= p->width * p->height) return;
    float4 v = input[i];
    GBufferTexel g = load_gbuffer(GBUFFER_ARGS, i);
    uint t[10];
    for (uint k = 0u; k < 10u; k++)
        t[k] = photon_map_word(direction_map0, direction_map1, direction_map2, i, k);
    float w = join_u64_f32(t[6], t[7]);
    float3 n_g = unpack_unit_vector(g.geometric_normal);
    if ((g.flags & GBUFFER_RECEIVER) == 0u || !(w > 0.0f) ||
        !shading_normal_departs(load3(g.normal), n_g)) {
        out[i] = v;
        return;
    }
    float3 sums = (float3)(join_u64_f32(t[0], t[1]), join_u64_f32(t[2], t[3]),
                           join_u64_f32(t[4], t[5]));
    float3 w_i = mean_light_direction(sums, w);
    if (w_i.x == 0.0f && w_i.y == 0.0f && w_i.z == 0.0f) {
        out[i] = v;
        return;
    }
    float f = shading_normal_factor(w_i, load3(g.normal), n_g, p->max_stretch, p->epsilon);
    out[i] = (float4)(v.x * f, v.y * f, v.z * f, v.w);
}
