// direct_light: radiance from the lights with shadow rays; mirror and glass pixels follow
// their specular ray tree. Mirror of backend-cpu/src/kernels/direct_light.rs.

// Reflected radiance of a Lambertian surface at `pos` (shading normal `n`, geometric
// normal `ng`, both on the viewer's side), lit by every light with shadow rays.
inline float3 shade_diffuse(SCENE_PARAMS, uint light_count, float3 pos, float3 n, float3 ng,
                            float3 albedo) {
    float3 e = (float3)(0.0f); // irradiance, W/m^2
    for (uint li = 0u; li < light_count; li++) {
        __global const GpuLight* light = &lights[li];
        float3 wi;
        float dist, scale;
        float3 lpos = load3g(light->position);
        if (light->kind == LIGHT_DIRECTIONAL) {
            wi = -load3g(light->direction);
            dist = INFINITY;
            scale = 1.0f;
        } else {
            float3 to = lpos - pos;
            float d2 = dot3(to, to);
            if (d2 <= 0.0f) continue;
            float d = sqrt(d2);
            wi = to / d;
            float falloff = light->kind == LIGHT_SPOT
                                ? spot_falloff(dot3(-wi, load3g(light->direction)),
                                               light->cos_inner, light->cos_outer)
                                : 1.0f;
            dist = d;
            scale = saturate_radiance(falloff / d2);
        }
        float cos_t = dot3(n, wi);
        if (cos_t <= 0.0f || scale <= 0.0f || dot3(ng, wi) <= 0.0f) continue;
        float3 origin = offset_ray_origin(pos, ng);
        float t_max = isfinite(dist) ? length3(origin - lpos) * (1.0f - 1e-5f) : INFINITY;
        if (occluded(nodes, node_count, vertices, triangles, origin, wi, t_max)) continue;
        e = saturate_radiance3(e + load3g(light->intensity) * (scale * cos_t));
    }
    return albedo / PI_F * e;
}

typedef struct {
    float3 origin;
    float3 dir;
    float3 weight;
    uint depth;
} ChainRay;

inline ChainRay chain_ray(float3 origin, float3 dir, float3 weight, uint depth) {
    ChainRay r;
    r.origin = origin;
    r.dir = dir;
    r.weight = weight;
    r.depth = depth;
    return r;
}

// Radiance along a camera ray that meets mirrors and glass: the ray tree is walked
// depth first with an explicit stack, in the CPU's order (last pushed, first popped).
inline float3 specular_chain(SCENE_PARAMS, __global const DirectParams* p, float3 origin,
                             float3 dir) {
    ChainRay stack[MAX_SPECULAR_DEPTH + 2];
    uint sp = 0u;
    float3 l = (float3)(0.0f);
    stack[sp++] = chain_ray(origin, dir, (float3)(1.0f), 0u);
    while (sp > 0u) {
        ChainRay r = stack[--sp];
        Hit hit;
        if (!closest_hit(nodes, node_count, vertices, triangles, r.origin, r.dir, INFINITY, &hit))
            continue;
        SurfacePoint s = hit_surface(vertices, triangles, &hit);
        __global const GpuMaterial* m = &materials[triangles[hit.triangle].material];
        bool entering = dot3(r.dir, s.geometric_normal) < 0.0f;
        float3 weight = r.weight;
        if (m->kind == MATERIAL_DIELECTRIC && !entering)
            weight *= beer_lambert(load3g(m->absorption), hit.t);
        float3 ng_view = entering ? s.geometric_normal : -s.geometric_normal;
        if (m->kind == MATERIAL_DIFFUSE) {
            float3 n = facing_normal(s.shading_normal, r.dir);
            l += weight * shade_diffuse(SCENE_ARGS, p->light_count, s.position, n, ng_view,
                                        load3g(m->color));
        } else if (r.depth >= p->max_specular_depth) {
        } else if (m->kind == MATERIAL_MIRROR) {
            float3 w = weight * load3g(m->color);
            if (max_element3(w) >= p->min_weight && sp < MAX_SPECULAR_DEPTH + 2) {
                float3 n = facing_normal(s.shading_normal, r.dir);
                stack[sp++] = chain_ray(offset_ray_origin(s.position, ng_view),
                                         reflect(r.dir, n), w, r.depth + 1u);
            }
        } else {
            float3 facing = facing_normal(s.shading_normal, r.dir);
            float eta = entering ? 1.0f / m->ior : m->ior;
            float f = fresnel_dielectric(-dot3(r.dir, facing), eta);
            if (max_element3(weight) * f >= p->min_weight && sp < MAX_SPECULAR_DEPTH + 2) {
                stack[sp++] = chain_ray(offset_ray_origin(s.position, ng_view),
                                         reflect(r.dir, facing), weight * f, r.depth + 1u);
            }
            float3 t;
            if (refract(r.dir, facing, eta, &t)) {
                if (max_element3(weight) * (1.0f - f) >= p->min_weight &&
                    sp < MAX_SPECULAR_DEPTH + 2) {
                    stack[sp++] = chain_ray(offset_ray_origin(s.position, -ng_view),
                                             normalize3(t), weight * (1.0f - f), r.depth + 1u);
                }
            }
        }
    }
    return l;
}

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
        l = specular_chain(SCENE_ARGS, p, load3g(p->camera.position),
                           camera_ray(&p->camera, i % w, i / w));
    }
    out[i] = (float4)(saturate_radiance3(l), 1.0f);
}
