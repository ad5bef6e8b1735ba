// Mirror of core/src/geometry.rs and backend-opencl/kernels/geometry.cl: Moller-Trumbore,
// the scale-aware ray offset (Waechter and Binder) and surface interpolation. The ray
// tracing kernels let the hardware intersect triangles (trace.glsl); intersect_triangle
// is kept for side-by-side reading and for kernels that test one triangle.

struct TriangleHit { float t; float u; float v; };

bool intersect_triangle(vec3 origin, vec3 dir, vec3 v0, vec3 v1, vec3 v2, float t_min,
                        float t_max, out TriangleHit hit) {
    precise vec3 e1 = v1 - v0;
    precise vec3 e2 = v2 - v0;
    vec3 p = cross3(dir, e2);
    float det = dot3(e1, p);
    if (det == 0.0 || !is_finite(det)) return false;
    precise float inv_det = 1.0 / det;
    precise vec3 s = origin - v0;
    precise float u = dot3(s, p) * inv_det;
    if (!(u >= 0.0 && u <= 1.0)) return false;
    vec3 q = cross3(s, e1);
    precise float v = dot3(dir, q) * inv_det;
    precise float u_plus_v = u + v;
    if (v < 0.0 || u_plus_v > 1.0) return false;
    precise float t = dot3(e2, q) * inv_det;
    if (t > t_min && t < t_max) {
        hit.t = t;
        hit.u = u;
        hit.v = v;
        return true;
    }
    return false;
}

// Scale-aware offset: p + n * (2^-15 * largest |coordinate|), see core/src/geometry.rs.
const float OFFSET_REL = 1.0 / 32768.0;
const float OFFSET_MIN_SCALE = 7.888609e-31;

vec3 offset_ray_origin(vec3 p, vec3 n) {
    float m = max(max(abs(p.x), abs(p.y)), max(abs(p.z), OFFSET_MIN_SCALE));
    precise float d = m * OFFSET_REL;
    precise vec3 o = p + n * d;
    return o;
}

struct SurfacePoint {
    vec3 position;
    vec3 geometric_normal;
    vec3 shading_normal;
    vec2 uv;
};

// OpenCL takes the three vertices by pointer, GLSL by value.
SurfacePoint surface_point(GpuVertex a, GpuVertex b, GpuVertex c, float u, float v) {
    precise float w = 1.0 - u - v;
    vec3 pa = a.position, pb = b.position, pc = c.position;
    vec3 na = a.normal, nb = b.normal, nc = c.normal;
    precise vec3 edge_b = pb - pa, edge_c = pc - pa;
    vec3 ng = normalize_or(cross3(edge_b, edge_c), vec3(0.0, 1.0, 0.0));
    precise vec3 n_sum = na + nb + nc;
    if (dot3(ng, n_sum) < 0.0) ng = -ng;
    precise vec3 ns_interpolated = w * na + u * nb + v * nc;
    vec3 ns = normalize_or(ns_interpolated, ng);
    if (!all_finite3(ns)) ns = ng;
    SurfacePoint s;
    precise vec3 position = w * pa + u * pb + v * pc;
    precise vec2 uv = vec2(w * a.u + u * b.u + v * c.u, w * a.v + u * b.v + v * c.v);
    s.position = position;
    s.geometric_normal = ng;
    s.shading_normal = ns;
    s.uv = uv;
    return s;
}
