// density_gather: one direction of the scatter-normalised, density-adaptive caustic
// gather (core/src/math/density_gather.rs; the contract in core/src/kernels/
// density_gather.rs). Mirror of backend-cpu/src/kernels/density_gather.rs.

__kernel void density_gather(__global const GatherParams* p, GBUFFER_PARAMS(__global const),
                             __global const float* radius, __global const float4* input,
                             __global float4* out) {
    int w = (int)p->camera.width, h = (int)p->camera.height;
    int j = (int)get_global_id(0);
    if (j >= w * h) return;
    GatherTexel gj = load_gather_texel(GATHER_GBUFFER_ARGS, (uint)j);
    if (gj.receiver == 0u) {
        out[j] = (float4)(0.0f);
        return;
    }
    int x = j % w, y = j / w;
    int reach = (int)p->max_radius_px;
    float3 sum = (float3)(0.0f);
    for (int d = -reach; d <= reach; d++) {
        int qx = p->axis == 0u ? x + d : x;
        int qy = p->axis == 0u ? y : y + d;
        if (qx < 0 || qy < 0 || qx >= w || qy >= h) continue;
        int q = qy * w + qx;
        // source q, destination j: the source's radius, offset j - q (non-receivers have
        // radius 0 and weigh 0 but at d = 0, where j is a receiver)
        float ws = footprint_weight(-d, radius[q]);
        if (ws == 0.0f) continue;
        GatherTexel gq = load_gather_texel(GATHER_GBUFFER_ARGS, (uint)q);
        if (gq.receiver == 0u) continue;
        float4 s = input[q];
        float wgt = ws *
                    edge_weight(gq.depth, gq.normal, gj.depth, gj.normal, p->sigma_depth,
                                p->normal_power);
        sum += wgt * s.xyz;
    }
    float r = radius[j];
    if (p->axis == 0u) {
        out[j] = (float4)(sum / gather_normaliser(p, GATHER_GBUFFER_ARGS, x, y, r, 1u), r);
    } else {
        // 000 Eq. 5: L = (albedo / pi) Phi / A (the scale saturates first: no 0 / 0)
        GBufferTexel gt = load_gbuffer(GBUFFER_ARGS, (uint)j);
        __global const GpuCamera* cam = &p->camera;
        float3 ray = camera_ray(cam, (uint)x, (uint)y);
        float footprint = pixel_footprint(gt.depth, cam->width, cam->height,
                                          cam->tan_half_fov_x, cam->tan_half_fov_y);
        float area = pixel_surface_area(footprint, dot3(ray, load3g(cam->forward)),
                                        dot3(ray, load3(gt.normal)));
        float scale = saturate_radiance(1.0f / (PI_F * area));
        float3 l = saturate_radiance3(sum * scale) * load3(gt.albedo);
        // alpha: the radius where the filter gave light, 0 elsewhere
        bool lit = sum.x > 0.0f || sum.y > 0.0f || sum.z > 0.0f;
        out[j] = (float4)(l, lit ? r : 0.0f);
    }
}
