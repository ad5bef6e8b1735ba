// rsm_importance (Smal 2019, section 24.2.1): level 0 writes a face's RSM texels and
// importance from the G-buffer its face camera rendered; level k > 0 the 2x2 sums of level
// k - 1 of faces 0 ..= p->face. Mirror of backend-cpu/src/kernels/rsm_importance.rs
// (rsm_texel, rsm_level) and shaders/wgsl/rsm_importance.wgsl.

__kernel void rsm_importance(__global const RsmParams* p, __global const GpuLight* lights,
                             GBUFFER_PARAMS(__global const), __global RsmTexel* texels,
                             __global float* pyramid) {
    uint i = get_global_id(0);
    if (p->level == 0u) {
        uint n = p->side * p->side;
        if (i >= n) return;
        RsmTexel t = {{0.0f, 0.0f, 0.0f}, 0u, {0.0f, 0.0f, 0.0f}, RSM_TEXEL_NONE};
        float importance = 0.0f;
        GBufferTexel g = load_gbuffer(GBUFFER_ARGS, i);
        if (g.material != NO_MATERIAL) {
            __global const GpuLight* light = &lights[p->light];
            uint x = i % p->side, y = i / p->side;
            float falloff = 1.0f;
            if (light->kind == LIGHT_SPOT) {
                float3 dir = camera_ray(&p->face_camera, x, y);
                falloff = light_spot_falloff(dir, light);
            }
            float3 arriving =
                light->kind == LIGHT_DIRECTIONAL
                    ? ortho_texel_flux(load3g(light->intensity), p->side,
                                       -p->face_camera.tan_half_fov_x)
                    : texel_arriving_flux(load3g(light->intensity), falloff, x, y, p->side,
                                          p->face_camera.tan_half_fov_x);
            float3 albedo = load3(g.albedo);
            float imp = luminance(arriving * albedo);
            if (imp > 0.0f && isfinite(imp)) {
                bool diffuse = (g.flags & GBUFFER_RECEIVER) != 0u;
                store3(t.position, load3(g.position));
                t.normal = pack_unit_vector(load3(g.normal));
                store3(t.flux, diffuse ? arriving * albedo : arriving);
                t.kind = diffuse ? RSM_TEXEL_DIFFUSE : RSM_TEXEL_SPECULAR;
                importance = pyramid_weight(p->sampling, imp);
            }
        }
        texels[p->face * n + i] = t;
        pyramid[p->face * pyramid_len(p->side) + i] = importance;
    } else {
        uint s = p->side >> p->level;
        if (i >= (p->face + 1u) * s * s) return;
        uint sb = 2u * s;
        uint face = i / (s * s), j = i % (s * s);
        uint base = face * pyramid_len(p->side);
        uint below = base + level_offset(p->side, p->level - 1u);
        uint x = 2u * (j % s), y = 2u * (j / s);
        // rsm::pyramid_sum: (a + c) + (b + d), columns first
        float a = pyramid[below + y * sb + x];
        float c = pyramid[below + (y + 1u) * sb + x];
        float b = pyramid[below + y * sb + x + 1u];
        float d = pyramid[below + (y + 1u) * sb + x + 1u];
        pyramid[base + level_offset(p->side, p->level) + j] = (a + c) + (b + d);
    }
}
