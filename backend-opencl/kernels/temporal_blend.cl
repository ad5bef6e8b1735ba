// temporal_blend (Smal 2019, section 24.4.1, Eqs. 10-13): a pixel's estimate blended with
// its reprojected history (the contract in core/src/kernels/temporal_blend.rs). Mirror of
// backend-cpu/src/kernels/temporal_blend.rs.

// View depth of receiver (x, y), 0 off the image or where the pixel is no receiver.
inline float receiver_depth_at(GBUFFER_PARAMS(__global const), int x, int y, int w, int h) {
    if (x < 0 || y < 0 || x >= w || y >= h) return 0.0f;
    uint i = (uint)(y * w + x);
    if ((gbuffer3[i].w & GBUFFER_RECEIVER) == 0u) return 0.0f;
    return as_float(gbuffer0[i].w);
}

__kernel void temporal_blend(__global const TemporalParams* p, GBUFFER_PARAMS(__global const),
                             __global const float4* input, __global const float4* history,
                             __global const float4* history_edge, __global float4* out,
                             __global float4* next_history, __global float4* next_edge) {
    int w = (int)p->camera.width, h = (int)p->camera.height;
    uint j = get_global_id(0);
    if (j >= (uint)(w * h)) return;
    GBufferTexel g = load_gbuffer(GBUFFER_ARGS, j);
    float4 cur = input[j];
    if ((g.flags & GBUFFER_RECEIVER) == 0u) {
        out[j] = cur;
        next_history[j] = cur;
        next_edge[j] = (float4)(EDGE_TEXEL_NOT_RECEIVER, 0.0f, 0.0f, 0.0f);
        return;
    }
    int x = (int)j % w, y = (int)j / w;
    float alpha = 0.0f;
    float3 hist = (float3)(0.0f);
    float3 pos = load3(g.position), nrm = load3(g.normal);
    if (p->history_frames > 0u) {
        uint qx, qy;
        float zq;
        if (project_to_pixel(&p->previous, pos, &qx, &qy, &zq)) {
            uint q = qy * p->camera.width + qx;
            float4 e = history_edge[q];
            if (e.x > 0.0f) {
                float4 n = (float4)(receiver_depth_at(GBUFFER_ARGS, x - 1, y, w, h),
                                    receiver_depth_at(GBUFFER_ARGS, x + 1, y, w, h),
                                    receiver_depth_at(GBUFFER_ARGS, x, y - 1, w, h),
                                    receiver_depth_at(GBUFFER_ARGS, x, y + 1, w, h));
                float step = reprojection_depth_step(g.depth, n);
                float wz = depth_weight(zq, e.x, step, p->sigma_z, p->epsilon);
                float wn = normal_weight(nrm, e.yzw, p->sigma_n);
                alpha = temporal_alpha(wz, wn, p->alpha_max);
                hist = history[q].xyz;
            }
        }
    }
    float3 rgb = blend_with_history(cur.xyz, hist, alpha);
    float4 o = (float4)(rgb, cur.w);
    out[j] = o;
    next_history[j] = o;
    next_edge[j] = (float4)(g.depth, nrm);
}
