// The specular ray tree of a camera ray (backend-cpu direct_light::specular_tree), shared by
// direct_light and caustic_map_lookup: walked depth first with an explicit stack, in the
// CPU's order (last pushed, first popped): both Fresnel branches of a dielectric, mirrors
// scaled by their reflectance, Beer-Lambert inside dielectrics, branches below
// `min_weight` or past `max_depth` specular surfaces cut. At each diffuse surface it adds
// `weight *` the kernel's diffuse end (given the path's length over all its segments and
// the cosine between the arriving ray and the normal) (`DiffuseEnd`: the lights' shading for direct_light,
// the caustic map for caustic_map_lookup; OpenCL C has no function pointers).

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
                                ? light_spot_falloff(-wi, light)
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
    float dist; // distance travelled from the tree's origin to `origin`
} ChainRay;

inline ChainRay chain_ray(float3 origin, float3 dir, float3 weight, uint depth, float dist) {
    ChainRay r;
    r.origin = origin;
    r.dir = dir;
    r.weight = weight;
    r.depth = depth;
    r.dist = dist;
    return r;
}

// What a diffuse end of the tree adds: the lights' shading (`triangle_tiles` null) or the
// caustic map (map_gather.cl's sample_caustic_map).
typedef struct {
    uint light_count;
    __global const uint* triangle_tiles;
    __global const uint4* tiles;
    __global const uint2* texels;
    __global const float4* map;
    __global const uint* centroids;
    uint atlas_width;
    float pixel_angle;
    float3 right;
} DiffuseEnd;

inline DiffuseEnd diffuse_end_direct(uint light_count) {
    DiffuseEnd e;
    e.light_count = light_count;
    e.triangle_tiles = 0;
    e.tiles = 0;
    e.texels = 0;
    e.map = 0;
    e.centroids = 0;
    e.atlas_width = 0u;
    e.pixel_angle = 0.0f;
    e.right = (float3)(0.0f);
    return e;
}

inline float3 diffuse_end(SCENE_PARAMS, const DiffuseEnd* e, const Hit* hit,
                          const SurfacePoint* s, __global const GpuMaterial* m, float3 n,
                          float3 ng_view, float distance, float cos_in, float3 dir) {
    if (e->triangle_tiles == 0)
        return shade_diffuse(SCENE_ARGS, e->light_count, s->position, n, ng_view,
                             load3g(m->color));
    uint tile = e->triangle_tiles[hit->triangle];
    if (tile == NO_TILE) return (float3)(0.0f);
    uint4 t = e->tiles[tile];
    __global const GpuTriangle* tri = &triangles[hit->triangle];
    __global const GpuVertex* v0 = &vertices[tri->indices[0]];
    __global const GpuVertex* v1 = &vertices[tri->indices[1]];
    __global const GpuVertex* v2 = &vertices[tri->indices[2]];
    float2 extent = footprint_extent(dir, e->right, e->pixel_angle * distance,
                                     load3g(v0->position), load3g(v1->position),
                                     load3g(v2->position), (float2)(v0->u, v0->v),
                                     (float2)(v1->u, v1->v), (float2)(v2->u, v2->v), t.z);
    if (extent.x < 0.0f) {
        // no UV Jacobian: the isotropic footprint
        uint texel = atlas_texel_index(t, s->uv, e->atlas_width);
        extent = (float2)(0.5f * footprint_texels(e->pixel_angle, distance, cos_in,
                                                  atlas_area(e->texels, texel)));
    }
    float3 irradiance = sample_caustic_map(e->texels, e->map, e->centroids, t, s->uv, extent,
                                           e->atlas_width);
    return load3g(m->color) / PI_F * irradiance;
}

inline float3 specular_tree(SCENE_PARAMS, const DiffuseEnd* end, uint max_depth,
                            float min_weight, uint fresnel_model, float3 origin,
                            float3 dir) {
    ChainRay stack[MAX_SPECULAR_DEPTH + 2];
    uint sp = 0u;
    float3 l = (float3)(0.0f);
    stack[sp++] = chain_ray(origin, dir, (float3)(1.0f), 0u, 0.0f);
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
            l += weight * diffuse_end(SCENE_ARGS, end, &hit, &s, m, n, ng_view, r.dist + hit.t,
                                      -dot3(r.dir, n), r.dir);
        } else if (r.depth >= max_depth) {
        } else if (m->kind == MATERIAL_MIRROR) {
            float3 w = weight * load3g(m->color);
            if (max_element3(w) >= min_weight && sp < MAX_SPECULAR_DEPTH + 2) {
                float3 n = facing_normal(s.shading_normal, r.dir);
                stack[sp++] = chain_ray(offset_ray_origin(s.position, ng_view),
                                         reflect(r.dir, n), w, r.depth + 1u, r.dist + hit.t);
            }
        } else {
            float3 facing = facing_normal(s.shading_normal, r.dir);
            float eta = entering ? 1.0f / m->ior : m->ior;
            float f = fresnel_reflectance(-dot3(r.dir, facing), eta, fresnel_model);
            if (max_element3(weight) * f >= min_weight && sp < MAX_SPECULAR_DEPTH + 2) {
                stack[sp++] = chain_ray(offset_ray_origin(s.position, ng_view),
                                         reflect(r.dir, facing), weight * f, r.depth + 1u,
                                         r.dist + hit.t);
            }
            float3 t;
            if (refract(r.dir, facing, eta, &t)) {
                if (max_element3(weight) * (1.0f - f) >= min_weight &&
                    sp < MAX_SPECULAR_DEPTH + 2) {
                    stack[sp++] = chain_ray(offset_ray_origin(s.position, -ng_view),
                                             normalize3(t), weight * (1.0f - f), r.depth + 1u,
                                             r.dist + hit.t);
                }
            }
        }
    }
    return l;
}
