// The specular ray tree of a camera ray (core's backend-cpu direct_light::specular_tree):
// walked depth first with an explicit stack, in the CPU's order (last pushed, first
// popped): both Fresnel branches of a dielectric, mirrors scaled by their reflectance,
// Beer-Lambert inside dielectrics, branches below `min_weight` or past `max_depth`
// specular surfaces cut. At each diffuse surface it adds `weight * diffuse_end(hit, s, m,
// n, ng_view, distance, cos, dir)` (distance: the path's length over all its segments; cos:
// between the arriving ray and n; dir: the arriving ray's unit direction), a function the kernel module defines (direct_light: the lights' shading;
// caustic_map_lookup: the caustic map).

struct ChainRay {
    origin: vec3<f32>,
    dir: vec3<f32>,
    weight: vec3<f32>,
    depth: u32,
    // distance travelled from the tree's origin to `origin`
    dist: f32,
}

fn chain_ray(origin: vec3<f32>, dir: vec3<f32>, weight: vec3<f32>, depth: u32,
             dist: f32) -> ChainRay {
    return ChainRay(origin, dir, weight, depth, dist);
}

const SPECULAR_STACK_SIZE: u32 = MAX_SPECULAR_DEPTH + 2u;

fn specular_tree(max_depth: u32, min_weight: f32, fresnel_model: u32, origin: vec3<f32>,
                 dir: vec3<f32>) -> vec3<f32> {
    var stack: array<ChainRay, SPECULAR_STACK_SIZE>;
    var sp = 0u;
    var l = vec3<f32>(0.0);
    stack[sp] = chain_ray(origin, dir, vec3<f32>(1.0), 0u, 0.0);
    sp += 1u;
    while (sp > 0u) {
        sp -= 1u;
        let r = stack[sp];
        var hit: Hit;
        if (!closest_hit(r.origin, r.dir, NO_T_MAX, &hit)) {
            continue;
        }
        let s = hit_surface(hit);
        let m = materials[triangles[hit.triangle].material];
        let entering = dot3(r.dir, s.geometric_normal) < 0.0;
        var weight = r.weight;
        if (m.kind == MATERIAL_DIELECTRIC && !entering) {
            weight *= beer_lambert(m.absorption.xyz, hit.t);
        }
        let ng_view = select(-s.geometric_normal, s.geometric_normal, entering);
        if (m.kind == MATERIAL_DIFFUSE) {
            let n = facing_normal(s.shading_normal, r.dir);
            l += weight * diffuse_end(hit, s, m, n, ng_view, r.dist + hit.t, -dot3(r.dir, n),
                                      r.dir);
        } else if (r.depth >= max_depth) {
        } else if (m.kind == MATERIAL_MIRROR) {
            let w = weight * m.color.xyz;
            if (max_element3(w) >= min_weight && sp < SPECULAR_STACK_SIZE) {
                let n = facing_normal(s.shading_normal, r.dir);
                stack[sp] = chain_ray(offset_ray_origin(s.position, ng_view), reflect(r.dir, n),
                                      w, r.depth + 1u, r.dist + hit.t);
                sp += 1u;
            }
        } else {
            let facing = facing_normal(s.shading_normal, r.dir);
            let eta = select(m.ior, 1.0 / m.ior, entering);
            let f = fresnel_reflectance(-dot3(r.dir, facing), eta, fresnel_model);
            if (max_element3(weight) * f >= min_weight && sp < SPECULAR_STACK_SIZE) {
                stack[sp] = chain_ray(offset_ray_origin(s.position, ng_view),
                                      reflect(r.dir, facing), weight * f, r.depth + 1u,
                                      r.dist + hit.t);
                sp += 1u;
            }
            var t: vec3<f32>;
            if (refract(r.dir, facing, eta, &t)) {
                if (max_element3(weight) * (1.0 - f) >= min_weight &&
                    sp < SPECULAR_STACK_SIZE) {
                    stack[sp] = chain_ray(offset_ray_origin(s.position, -ng_view),
                                          normalize3(t), weight * (1.0 - f), r.depth + 1u,
                                          r.dist + hit.t);
                    sp += 1u;
                }
            }
        }
    }
    return l;
}
