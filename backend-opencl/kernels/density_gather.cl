// density_gather: one direction of the scatter-normalised, density-adaptive caustic
// gather (core/src/math/density_gather.rs; the contract in core/src/kernels/
// density_gather.rs). Mirror of backend-cpu/src/kernels/density_gather.rs.

__kernel void density_gather(__global const GatherParams* p, GBUFFER_PARAMS(__global const),
                             __global const float4* edge, __global const float4* input,
                             __global float4* out, __global uint* source_index) {
    int w = (int)p->camera.width, h = (int)p->camera.height;
    int x, y;
    if (p->axis == 0u) {
        int i = (int)get_global_id(0);
        if (i >= w * h) return;
        x = i % w;
        y = i / w;
    } else if (!column_pass_pixel((uint)get_global_id(0), (uint)w, (uint)h, &x, &y)) {
        return;
    }
    int j = y * w + x;
    float4 ej = edge[j];
    if (!edge_texel_is_receiver(ej)) {
        out[j] = (float4)(0.0f);
        return;
    }
    float r = input[j].w;
    float3 sum = (float3)(0.0f);
    // the sources that can have weight here, in increasing offset (the taps left out
    // have no flux or no weight): the mask's set bits within the reach grid's bound
    int taps = pass_reach(source_index, w, h, x, y, p->axis, (int)p->max_radius_px);
    int along = p->axis == 0u ? x : y;
    int lo = max(along - taps, 0);
    int hi = min(along + taps, (p->axis == 0u ? w : h) - 1);
    for (int k = lo / 32; k <= hi / 32 && lo <= hi; k++) {
        uint bits = source_bits(source_index, w, h, p->axis, x, y, k, lo, hi);
        while (bits != 0u) {
            int d = k * 32 + lowest_bit(bits) - along;
            bits &= bits - 1u;
            int q = (p->axis == 0u ? y : y + d) * w + (p->axis == 0u ? x + d : x);
            // source q, destination j: a source without flux adds nothing; then the
            // source's radius at offset j - q (non-receivers hold no flux)
            float4 s = input[q];
            if (s.x == 0.0f && s.y == 0.0f && s.z == 0.0f) continue;
            float ws = footprint_weight(-d, s.w);
            if (ws == 0.0f) continue;
            float4 eq = edge[q];
            if (!edge_texel_is_receiver(eq)) continue;
            float wgt = ws * edge_weight_of(p, eq, ej);
            sum += wgt * s.xyz;
        }
    }
    // (flux and weights are >= 0: a sum without a positive channel is 0)
    if (!(sum.x > 0.0f || sum.y > 0.0f || sum.z > 0.0f)) {
        out[j] = (float4)(0.0f, 0.0f, 0.0f, p->axis == 0u ? r : 0.0f);
        return;
    }
    if (p->axis == 0u) {
        float4 o = (float4)(sum / gather_normaliser(p, edge, x, y, r, 1u), r);
        out[j] = o;
        // the column pass's sources
        put_source(source_index, w, h, 1u, x, y, o, (int)p->max_radius_px);
    } else if (p->surface == GATHER_SURFACE_ATLAS) {
        // irradiance E = Phi / A over the texel's world area (its edge texel's y)
        float3 e = saturate_radiance3(sum * saturate_radiance(1.0f / ej.y));
        out[j] = (float4)(e, r);
    } else {
        // Kim 2019, Eq. 5: L = (albedo / pi) Phi / A (the scale saturates first: no 0 / 0)
        GBufferTexel gt = load_gbuffer(GBUFFER_ARGS, (uint)j);
        __global const GpuCamera* cam = &p->camera;
        float3 ray = camera_ray(cam, (uint)x, (uint)y);
        float footprint = pixel_footprint(gt.depth, cam->width, cam->height,
                                          cam->tan_half_fov_x, cam->tan_half_fov_y);
        float area = pixel_surface_area(footprint, dot3(ray, load3g(cam->forward)),
                                        dot3(ray, load3(gt.normal)));
        float scale = saturate_radiance(1.0f / (PI_F * area));
        float3 l = saturate_radiance3(sum * scale) * load3(gt.albedo);
        // alpha: the radius where the filter gave light
        out[j] = (float4)(l, r);
    }
}
