// The specular ray tree of a camera ray (backend-cpu direct_light::specular_tree), shared
// by direct_light and caustic_map_lookup. The including stage defines
// `vec3 diffuse_end(Hit hit, SurfacePoint s, GpuMaterial m, vec3 n, vec3 ng_view,
// float distance, float cos_in, vec3 dir)` first (distance: the path's length over all its
// segments; cos_in: between the arriving ray and n; dir: the arriving ray's direction):
// what a diffuse end adds, times the branch's weight (the lights' shading, or the caustic
// map).

struct ChainRay {
    vec3 origin;
    vec3 dir;
    vec3 weight;
    uint depth;
    float dist; // distance travelled from the tree's origin to `origin`
};

// OpenCL's chain_ray(origin, dir, weight, depth) is the struct constructor ChainRay(...)
// here. (A helper function would do, but glslang's `precise` propagation runs out of
// memory on a precise value that flows through a user function's struct result in this
// loop; the constructor is not a function call.)

// Radiance along a camera ray that meets mirrors and glass: the ray tree is walked
// depth first with an explicit stack, in the CPU's order (last pushed, first popped).
precise vec3 specular_tree(uint max_depth, float min_weight, uint fresnel_model, vec3 origin,
                           vec3 dir) {
    ChainRay stack[MAX_SPECULAR_DEPTH + 2u];
    uint sp = 0u;
    vec3 l = vec3(0.0);
    stack[sp++] = ChainRay(origin, dir, vec3(1.0), 0u, 0.0);
    while (sp > 0u) {
        ChainRay r = stack[--sp];
        Hit hit;
        if (!closest_hit(r.origin, r.dir, NO_T_MAX, hit)) continue;
        SurfacePoint s = hit_surface(hit);
        GpuMaterial m = materials[triangles[hit.triangle].material];
        bool entering = dot3(r.dir, s.geometric_normal) < 0.0;
        precise vec3 weight = r.weight;
        if (m.kind == MATERIAL_DIELECTRIC && !entering)
            weight *= beer_lambert(m.absorption.xyz, hit.t);
        vec3 ng_view = entering ? s.geometric_normal : -s.geometric_normal;
        if (m.kind == MATERIAL_DIFFUSE) {
            vec3 n = facing_normal(s.shading_normal, r.dir);
            precise float dist_in = r.dist + hit.t;
            l += weight * diffuse_end(hit, s, m, n, ng_view, dist_in, -dot3(r.dir, n), r.dir);
        } else if (r.depth >= max_depth) {
        } else if (m.kind == MATERIAL_MIRROR) {
            precise vec3 w = weight * m.color.xyz;
            if (max_element3(w) >= min_weight && sp < MAX_SPECULAR_DEPTH + 2u) {
                vec3 n = facing_normal(s.shading_normal, r.dir);
                stack[sp++] = ChainRay(offset_ray_origin(s.position, ng_view),
                                       reflect3(r.dir, n), w, r.depth + 1u, r.dist + hit.t);
            }
        } else {
            vec3 facing = facing_normal(s.shading_normal, r.dir);
            precise float eta = entering ? 1.0 / m.ior : m.ior;
            float f = fresnel_reflectance(-dot3(r.dir, facing), eta, fresnel_model);
            precise float reflected = max_element3(weight) * f;
            if (reflected >= min_weight && sp < MAX_SPECULAR_DEPTH + 2u) {
                precise vec3 w = weight * f;
                stack[sp++] = ChainRay(offset_ray_origin(s.position, ng_view),
                                       reflect3(r.dir, facing), w, r.depth + 1u,
                                       r.dist + hit.t);
            }
            vec3 t;
            if (refract3(r.dir, facing, eta, t)) {
                precise float transmitted = max_element3(weight) * (1.0 - f);
                if (transmitted >= min_weight && sp < MAX_SPECULAR_DEPTH + 2u) {
                    precise vec3 w = weight * (1.0 - f);
                    stack[sp++] = ChainRay(offset_ray_origin(s.position, -ng_view),
                                           normalize3(t), w, r.depth + 1u, r.dist + hit.t);
                }
            }
        }
    }
    return l;
}

