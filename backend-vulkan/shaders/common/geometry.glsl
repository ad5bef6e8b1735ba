// Mirror of core/src/geometry.rs and backend-opencl/kernels/geometry.cl: the watertight
// ray-triangle test, the scale-aware ray origin offset and surface interpolation. The ray
// tracing kernels let the hardware intersect triangles (trace.glsl); intersect_triangle
// is kept for side-by-side reading and for kernels that test one triangle.

struct TriangleHit { float t; float u; float v; };

// Woop's edge function q.x p.y - q.y p.x with the endpoints in a canonical order, negated
// back (core::geometry::edge_function; with `precise` the plain expression rounds the
// same).
float edge_function(vec2 p, vec2 q) {
    bool swap = !(p.x < q.x || (p.x == q.x && p.y < q.y));
    vec2 lo = swap ? q : p;
    vec2 hi = swap ? p : q;
    precise float e = hi.x * lo.y - hi.y * lo.x;
    precise float neg = 0.0 - e;
    return swap ? neg : e;
}

// Watertight ray-triangle test (Woop, Benthin and Wald 2013), two-sided; mirror of
// core::geometry::intersect_triangle (the hardware's own triangle test is watertight too).
bool intersect_triangle(vec3 origin, vec3 dir, vec3 v0, vec3 v1, vec3 v2, float t_min,
                        float t_max, out TriangleHit hit) {
    vec3 ad = abs(dir);
    int kz = (ad.x >= ad.y && ad.x >= ad.z) ? 0 : (ad.y >= ad.z ? 1 : 2);
    int kx = (kz + 1) % 3;
    int ky = (kx + 1) % 3;
    float dz = dir[kz];
    if (dz < 0.0) {
        int k = kx;
        kx = ky;
        ky = k;
    }
    if (!(dz != 0.0)) return false;
    precise float sx = dir[kx] / dz;
    precise float sy = dir[ky] / dz;
    precise float sz = 1.0 / dz;
    precise vec3 a = v0 - origin;
    precise vec3 b = v1 - origin;
    precise vec3 c = v2 - origin;
    precise float ax = a[kx] - sx * a[kz];
    precise float ay = a[ky] - sy * a[kz];
    precise float bx = b[kx] - sx * b[kz];
    precise float by = b[ky] - sy * b[kz];
    precise float cx = c[kx] - sx * c[kz];
    precise float cy = c[ky] - sy * c[kz];
    precise float u = edge_function(vec2(bx, by), vec2(cx, cy));
    precise float v = edge_function(vec2(cx, cy), vec2(ax, ay));
    precise float w = edge_function(vec2(ax, ay), vec2(bx, by));
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) return false;
    precise float det = u + v + w;
    if (det == 0.0 || !is_finite(det)) return false;
    precise float az = sz * a[kz];
    precise float bz = sz * b[kz];
    precise float cz = sz * c[kz];
    precise float inv_det = 1.0 / det;
    precise float t = (u * az + v * bz + w * cz) * inv_det;
    if (t > t_min && t < t_max) {
        hit.t = t;
        hit.u = v * inv_det;
        hit.v = w * inv_det;
        return true;
    }
    return false;
}

// Scale-aware offset: p + n * (2^-15 * largest |coordinate|), see core/src/geometry.rs.

// core::math::geometry::ray_meets_sphere: whether the ray origin + t dir (t >= 0) may meet
// the ball (centre xyz, radius w); false only outside the test's rounding slack.
bool ray_meets_sphere(vec3 origin, vec3 dir, vec4 sphere) {
    precise vec3 oc = sphere.xyz - origin;
    precise float tca = max(dot3(oc, dir), 0.0);
    precise float oc2 = dot3(oc, oc);
    precise float r2 = sphere.w * sphere.w;
    precise float d2 = oc2 - tca * tca;
    precise float bound = r2 + SPHERE_TEST_SLACK * oc2;
    return !(d2 > bound);
}

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
    vec3 ng = normalize_scaled(cross3(edge_b, edge_c), vec3(0.0, 1.0, 0.0));
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
