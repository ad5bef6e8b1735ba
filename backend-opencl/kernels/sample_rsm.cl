// sample_rsm (Smal 2019, section 24.2.1, Figure 24-3): sample i of the light's rotated
// Hammersley set warped through its faces' importance pyramids (rsm::warp_rsm) to an RSM
// texel, and the photon leaving it. Mirror of backend-cpu/src/kernels/sample_rsm.rs
// (rsm_photon) and shaders/wgsl/sample_rsm.wgsl.

// rsm::warp_rsm over faces p->face .. + face_count.
inline bool warp_rsm(__global const RsmParams* p, __global const float* pyramid, float2 u,
                     uint* face_out, uint2* texel, float* probability, float2* within) {
    uint plen = pyramid_len(p->side);
    uint levels = level_count(p->side);
    uint top = level_offset(p->side, levels - 1u);
    uint faces = min(p->face_count, 6u);
    float rests[7];
    rests[faces] = 0.0f;
    for (int f = (int)faces - 1; f >= 0; f--)
        rests[f] = pyramid[(p->face + (uint)f) * plen + top] + rests[f + 1];
    if (!(rests[0] > 0.0f)) return false;
    float prob = 1.0f;
    uint face = faces - 1u;
    for (uint f = 0u; f + 1u < faces; f++) {
        float3 w = warp_split(u.x, warp_ratio(pyramid[(p->face + f) * plen + top], rests[f]));
        u.x = w.y;
        prob *= w.z;
        if (w.x > 0.5f) {
            face = f;
            break;
        }
    }
    uint base = (p->face + face) * plen;
    uint x = 0u, y = 0u;
    for (int k = (int)levels - 2; k >= 0; k--) {
        uint s = p->side >> (uint)k;
        uint off = base + level_offset(p->side, (uint)k);
        float a = pyramid[off + (2u * y) * s + 2u * x];
        float b = pyramid[off + (2u * y) * s + 2u * x + 1u];
        float c = pyramid[off + (2u * y + 1u) * s + 2u * x];
        float d = pyramid[off + (2u * y + 1u) * s + 2u * x + 1u];
        float3 h = warp_split(u.x, warp_ratio(a + c, (a + c) + (b + d)));
        bool left = h.x > 0.5f;
        float top_row = left ? a : b, bottom = left ? c : d;
        float3 v = warp_split(u.y, warp_ratio(top_row, top_row + bottom));
        u = (float2)(h.y, v.y);
        prob *= h.z * v.z;
        x = 2u * x + (left ? 0u : 1u);
        y = 2u * y + (v.x > 0.5f ? 0u : 1u);
    }
    *face_out = face;
    *texel = (uint2)(x, y);
    *probability = prob;
    *within = u;
    return prob > 0.0f;
}

__kernel void sample_rsm(__global const RsmParams* p, __global const GpuLight* lights,
                         __global const RsmTexel* texels, __global const float* pyramid,
                         __global RsmPhoton* photons) {
    uint i = get_global_id(0);
    if (i >= p->sample_count) return;
    float2 shift = (float2)(random_f32(p->seed, p->light, 0u, 0u),
                            random_f32(p->seed, p->light, 0u, 1u));
    float2 u = hammersley(i, p->sample_count, shift);
    RsmPhoton out = {{0.0f, 0.0f, 0.0f}, 0u, {0.0f, 0.0f, 0.0f}, 0u};
    uint face;
    uint2 texel;
    float probability;
    float2 within;
    if (warp_rsm(p, pyramid, u, &face, &texel, &probability, &within)) {
        RsmTexel t = texels[(p->face + face) * p->side * p->side + texel.y * p->side + texel.x];
        float scale = 1.0f / (probability * (float)p->sample_count);
        float3 flux = load3(t.flux) * scale;
        if (t.kind == RSM_TEXEL_DIFFUSE) {
            float3 n = unpack_unit_vector(t.normal);
            store3(out.origin, offset_ray_origin(load3(t.position), n));
            out.direction = pack_unit_vector(cosine_hemisphere(within, n));
            store3(out.flux, flux);
            out.bounces = 1u;
        } else if (t.kind == RSM_TEXEL_SPECULAR) {
            __global const GpuLight* light = &lights[p->light];
            float3 origin = light->kind == LIGHT_DIRECTIONAL
                                ? ortho_origin(load3(t.position), load3g(p->face_camera.position),
                                               load3g(p->face_camera.forward))
                                : load3g(light->position);
            store3(out.origin, origin);
            out.direction = pack_unit_vector(normalize3(load3(t.position) - origin));
            store3(out.flux, flux);
        }
    }
    photons[p->first_sample + i] = out;
}
