// bilateral_gather (Kim 2019, section 30.3.2): one direction of the separable edge-aware
// photon gather. Mirror of backend-cpu/src/kernels/bilateral_gather.rs.

// Gather radius in pixels at a receiver pixel.
inline float gather_radius_px(__global const GatherParams* p, const GBufferTexel* g,
                              float tile_hit_distance) {
    float d = tile_hit_distance > 0.0f ? tile_hit_distance : p->hit_distance_min;
    d = clampf(d, p->hit_distance_min, p->hit_distance_max);
    float world = p->roughness * d;
    __global const GpuCamera* c = &p->camera;
    float pixel = sqrt(pixel_footprint(g->depth, c->width, c->height, c->tan_half_fov_x,
                                       c->tan_half_fov_y));
    if (!(pixel > 0.0f)) return 0.0f;
    return fmin(world / pixel, (float)p->max_radius_px);
}

__kernel void bilateral_gather(__global const GatherParams* p,
                               GBUFFER_PARAMS(__global const),
                               __global const float* tiles, __global const float4* input,
                               __global float4* out) {
    int w = (int)p->camera.width, h = (int)p->camera.height, ts = (int)p->tile_size;
    int tw = (w + ts - 1) / ts;
    int i = (int)get_global_id(0);
    if (i >= w * h) return;
    int x = i % w, y = i / w;
    GBufferTexel gt = load_gbuffer(GBUFFER_ARGS, (uint)i);
    const GBufferTexel* g = &gt;
    if ((g->flags & GBUFFER_RECEIVER) == 0u) {
        out[i] = (float4)(0.0f, 0.0f, 0.0f, input[i].w);
        return;
    }
    float r = gather_radius_px(p, g, tiles[(y / ts) * tw + x / ts]);
    int radius = (int)ceil(r);
    float s = fmax(0.5f * r, 0.5f);
    float inv_2s2 = 1.0f / (2.0f * (s * s));
    float3 n = load3(g->normal);
    float3 sum = (float3)(0.0f);
    float wsum = 0.0f;
    for (int k = -radius; k <= radius; k++) {
        int qx = p->axis == 0u ? x + k : x;
        int qy = p->axis == 0u ? y : y + k;
        if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
        int q = qy * w + qx;
        GBufferTexel gqt = load_gbuffer(GBUFFER_ARGS, (uint)q);
        const GBufferTexel* gq = &gqt;
        if ((gq->flags & GBUFFER_RECEIVER) == 0u) continue;
        float ws = exp(-(float)(k * k) * inv_2s2);
        float wd = exp(-fabs(gq->depth - g->depth) / (p->sigma_depth * g->depth));
        float wn = p->normal_power > 0.0f ? pow(fmax(dot3(n, load3(gq->normal)), 0.0f), p->normal_power)
                                          : 1.0f;
        float wgt = ws * wd * wn;
        sum += wgt * input[q].xyz;
        wsum += wgt;
    }
    float3 o = wsum > 0.0f ? saturate_radiance3(sum / wsum) : (float3)(0.0f);
    out[i] = (float4)(o, input[i].w);
}
