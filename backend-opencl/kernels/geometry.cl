// Mirror of core/src/geometry.rs: Moller-Trumbore, the scale-aware ray offset
// (Waechter and Binder) and surface interpolation.

typedef struct { float t; float u; float v; } TriangleHit;

inline bool intersect_triangle(float3 origin, float3 dir, float3 v0, float3 v1, float3 v2,
                               float t_min, float t_max, TriangleHit* hit) {
    float3 e1 = v1 - v0;
    float3 e2 = v2 - v0;
    float3 p = cross3(dir, e2);
    float det = dot3(e1, p);
    if (det == 0.0f || !isfinite(det)) return false;
    float inv_det = 1.0f / det;
    float3 s = origin - v0;
    float u = dot3(s, p) * inv_det;
    if (!(u >= 0.0f && u <= 1.0f)) return false;
    float3 q = cross3(s, e1);
    float v = dot3(dir, q) * inv_det;
    if (v < 0.0f || u + v > 1.0f) return false;
    float t = dot3(e2, q) * inv_det;
    if (t > t_min && t < t_max) {
        hit->t = t;
        hit->u = u;
        hit->v = v;
        return true;
    }
    return false;
}

// Scale-aware offset: p + n * (2^-15 * largest |coordinate|), see core/src/geometry.rs.
#define OFFSET_REL (1.0f / 32768.0f)
#define OFFSET_MIN_SCALE 7.888609e-31f

inline float3 offset_ray_origin(float3 p, float3 n) {
    float m = fmax(fmax(fabs(p.x), fabs(p.y)), fmax(fabs(p.z), OFFSET_MIN_SCALE));
    float d = m * OFFSET_REL;
    return p + n * d;
}

typedef struct {
    float3 position;
    float3 geometric_normal;
    float3 shading_normal;
    float2 uv;
} SurfacePoint;

inline SurfacePoint surface_point(__global const GpuVertex* a, __global const GpuVertex* b,
                                  __global const GpuVertex* c, float u, float v) {
    float w = 1.0f - u - v;
    float3 pa = load3g(a->position), pb = load3g(b->position), pc = load3g(c->position);
    float3 na = load3g(a->normal), nb = load3g(b->normal), nc = load3g(c->normal);
    float3 ng = normalize_or(cross3(pb - pa, pc - pa), (float3)(0.0f, 1.0f, 0.0f));
    float3 n_sum = na + nb + nc;
    if (dot3(ng, n_sum) < 0.0f) ng = -ng;
    float3 ns = normalize_or(w * na + u * nb + v * nc, ng);
    if (!all_finite3(ns)) ns = ng;
    SurfacePoint s;
    s.position = w * pa + u * pb + v * pc;
    s.geometric_normal = ng;
    s.shading_normal = ns;
    s.uv = (float2)(w * a->u + u * b->u + v * c->u, w * a->v + u * b->v + v * c->v);
    return s;
}
