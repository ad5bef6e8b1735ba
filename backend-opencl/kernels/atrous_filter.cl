// atrous_filter (Smal 2019, section 24.4.2, Eqs. 14-18): one edge-avoiding A-Trous
// iteration with variance clipping of its detail coefficient (the contract in
// core/src/kernels/atrous_filter.rs). Mirror of backend-cpu/src/kernels/atrous_filter.rs.

// Pixel i's edge texel: from the G-buffer on iteration 0 (which writes them all), from
// the edge texels on the later iterations (one 16-byte texel for three planes).
inline float4 atrous_edge(GATHER_GBUFFER_PARAMS(__global const), __global const float4* edge,
                          uint first, uint i) {
    return first != 0u ? edge_texel(load_gather_texel(GATHER_GBUFFER_ARGS, i)) : edge[i];
}

// View depth of receiver (x, y); 0 off the image or on a non-receiver.
inline float atrous_depth(GATHER_GBUFFER_PARAMS(__global const), __global const float4* edge,
                          uint first, int x, int y, int w, int h) {
    if (x < 0 || y < 0 || x >= w || y >= h) return 0.0f;
    float4 t = atrous_edge(GATHER_GBUFFER_ARGS, edge, first, (uint)(y * w + x));
    return edge_texel_is_receiver(t) ? t.x : 0.0f;
}

__kernel void atrous_filter(__global const AtrousParams* p, GATHER_GBUFFER_PARAMS(__global const),
                            __global const float4* input, __global float4* details,
                            __global float4* out, __global float4* edge) {
    int w = (int)p->camera.width, h = (int)p->camera.height;
    uint j = get_global_id(0);
    if (j >= (uint)(w * h)) return;
    uint first = p->iteration == 0u;
    float4 e = atrous_edge(GATHER_GBUFFER_ARGS, edge, first, j);
    if (first != 0u) edge[j] = e;
    float4 s_i = input[j];
    if (!edge_texel_is_receiver(e)) {
        out[j] = s_i;
        details[j] = (float4)(0.0f);
        return;
    }
    int x = (int)j % w, y = (int)j / w;
    float z = e.x;
    float3 n = e.yzw;
    float2 g = depth_gradient(
        z, (float4)(atrous_depth(GATHER_GBUFFER_ARGS, edge, first, x - 1, y, w, h),
                    atrous_depth(GATHER_GBUFFER_ARGS, edge, first, x + 1, y, w, h),
                    atrous_depth(GATHER_GBUFFER_ARGS, edge, first, x, y - 1, w, h),
                    atrous_depth(GATHER_GBUFFER_ARGS, edge, first, x, y + 1, w, h)));
    float sum_w = 0.0f;
    float3 sum = (float3)(0.0f), sum_sq = (float3)(0.0f);
    for (uint ky = 0u; ky < 5u; ky++) {
        for (uint kx = 0u; kx < 5u; kx++) {
            int dx = atrous_offset(kx, p->iteration), dy = atrous_offset(ky, p->iteration);
            int qx = x + dx, qy = y + dy;
            if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
            uint q = (uint)(qy * w + qx);
            float4 eq = atrous_edge(GATHER_GBUFFER_ARGS, edge, first, q);
            if (!edge_texel_is_receiver(eq)) continue;
            float step = g.x * (float)dx + g.y * (float)dy;
            float wgt = ATROUS_TAPS[kx] * ATROUS_TAPS[ky] *
                        depth_weight(z, eq.x, step, p->sigma_z, p->epsilon) *
                        normal_weight(n, eq.yzw, p->sigma_n);
            float3 v = input[q].xyz;
            sum_w += wgt;
            sum += wgt * v;
            sum_sq += wgt * v * v;
        }
    }
    float3 mean = sum / sum_w;
    float3 mean_sq = sum_sq / sum_w;
    float3 clipped = clipped_detail(s_i.xyz, mean, detail_bound(mean, mean_sq, p->clip_sigmas));
    float3 before = p->iteration > 0u ? details[j].xyz : (float3)(0.0f);
    float3 d = before + clipped;
    float3 o = p->last != 0u ? atrous_final(mean, d) : mean;
    details[j] = (float4)(d, 0.0f);
    out[j] = (float4)(o, s_i.w);
}
