// direct_light: radiance from the lights with shadow rays; mirror and glass pixels follow
// their specular ray tree (common/specular_tree.cl). Mirror of
// backend-cpu/src/kernels/direct_light.rs.

__kernel void direct_light(SCENE_PARAMS, __global const DirectParams* p,
                           GBUFFER_PARAMS(__global const), __global float4* out) {
    uint i = get_global_id(0);
    uint w = p->camera.width;
    if (i >= w * p->camera.height) return;
    GBufferTexel gt = load_gbuffer(GBUFFER_ARGS, i);
    const GBufferTexel* g = &gt;
    if (g->depth <= 0.0f) {
        out[i] = (float4)(0.0f, 0.0f, 0.0f, 1.0f);
        return;
    }
    float3 l;
    if ((g->flags & GBUFFER_RECEIVER) != 0u) {
        float3 n = load3(g->normal);
        l = shade_diffuse(SCENE_ARGS, p->light_count, load3(g->position), n, n,
                          load3(g->albedo));
    } else {
        DiffuseEnd end = diffuse_end_direct(p->light_count);
        l = specular_tree(SCENE_ARGS, &end, p->max_specular_depth, p->min_weight,
                          p->fresnel_model,
                          load3g(p->camera.position), camera_ray(&p->camera, i % w, i / w));
    }
    out[i] = (float4)(saturate_radiance3(l), 1.0f);
}
