// Mirror of core/src/geometry.rs: the watertight ray-triangle test, the scale-aware ray
// origin offset and surface interpolation.

typedef struct { float t; float u; float v; } TriangleHit;

// Component k (0, 1, 2) of v: OpenCL C cannot index a vector at run time.
inline float component3(float3 v, int k) { return k == 0 ? v.x : (k == 1 ? v.y : v.z); }

// Per-ray part of the watertight test (mirror of core::geometry::WatertightRay): the
// permutation (kx, ky, kz) and the shear (sx, sy, sz); valid = false for a zero direction.
typedef struct {
    float3 origin;
    int kx, ky, kz;
    float sx, sy, sz;
    bool valid;
} WatertightRay;

inline WatertightRay watertight_ray(float3 origin, float3 dir) {
    WatertightRay r;
    float3 ad = fabs(dir);
    r.kz = (ad.x >= ad.y && ad.x >= ad.z) ? 0 : (ad.y >= ad.z ? 1 : 2);
    r.kx = (r.kz + 1) % 3;
    r.ky = (r.kx + 1) % 3;
    float dz = component3(dir, r.kz);
    if (dz < 0.0f) {
        int k = r.kx;
        r.kx = r.ky;
        r.ky = k;
    }
    r.origin = origin;
    r.valid = dz != 0.0f;
    r.sx = component3(dir, r.kx) / dz;
    r.sy = component3(dir, r.ky) / dz;
    r.sz = 1.0f / dz;
    return r;
}

// Woop's edge function q.x p.y - q.y p.x with the endpoints in a canonical order, negated
// back (core::geometry::edge_function; with FP_CONTRACT off the plain expression rounds
// the same).
inline float edge_function(float2 p, float2 q) {
    bool swap = !(p.x < q.x || (p.x == q.x && p.y < q.y));
    float2 lo = swap ? q : p;
    float2 hi = swap ? p : q;
    float e = hi.x * lo.y - hi.y * lo.x;
    return swap ? 0.0f - e : e;
}

// Watertight ray-triangle test (Woop, Benthin and Wald 2013), two-sided; mirror of
// core::geometry::WatertightRay::intersect, operation by operation (FP_CONTRACT is off).
inline bool intersect_watertight(const WatertightRay* r, float3 v0, float3 v1, float3 v2,
                                 float t_min, float t_max, TriangleHit* hit) {
    if (!r->valid) return false;
    float3 a = v0 - r->origin;
    float3 b = v1 - r->origin;
    float3 c = v2 - r->origin;
    float ax = component3(a, r->kx) - r->sx * component3(a, r->kz);
    float ay = component3(a, r->ky) - r->sy * component3(a, r->kz);
    float bx = component3(b, r->kx) - r->sx * component3(b, r->kz);
    float by = component3(b, r->ky) - r->sy * component3(b, r->kz);
    float cx = component3(c, r->kx) - r->sx * component3(c, r->kz);
    float cy = component3(c, r->ky) - r->sy * component3(c, r->kz);
    float u = edge_function((float2)(bx, by), (float2)(cx, cy));
    float v = edge_function((float2)(cx, cy), (float2)(ax, ay));
    float w = edge_function((float2)(ax, ay), (float2)(bx, by));
    if ((u < 0.0f || v < 0.0f || w < 0.0f) && (u > 0.0f || v > 0.0f || w > 0.0f)) return false;
    float det = u + v + w;
    if (det == 0.0f || !isfinite(det)) return false;
    float az = r->sz * component3(a, r->kz);
    float bz = r->sz * component3(b, r->kz);
    float cz = r->sz * component3(c, r->kz);
    float inv_det = 1.0f / det;
    float t = (u * az + v * bz + w * cz) * inv_det;
    if (t > t_min && t < t_max) {
        hit->t = t;
        hit->u = v * inv_det;
        hit->v = w * inv_det;
        return true;
    }
    return false;
}

// One triangle, one ray (core::geometry::intersect_triangle).
inline bool intersect_triangle(float3 origin, float3 dir, float3 v0, float3 v1, float3 v2,
                               float t_min, float t_max, TriangleHit* hit) {
    WatertightRay r = watertight_ray(origin, dir);
    return intersect_watertight(&r, v0, v1, v2, t_min, t_max, hit);
}

// Scale-aware offset: p + n * (2^-15 * largest |coordinate|), see core/src/geometry.rs.

// core::math::geometry::ray_meets_sphere: whether the ray origin + t dir (t >= 0) may meet
// the ball (centre xyz, radius w); false only outside the test's rounding slack.
inline bool ray_meets_sphere(float3 origin, float3 dir, __global const float* sphere) {
    float3 oc = (float3)(sphere[0], sphere[1], sphere[2]) - origin;
    float tca = fmax(dot3(oc, dir), 0.0f);
    float oc2 = dot3(oc, oc);
    float r = sphere[3];
    return !(oc2 - tca * tca > r * r + SPHERE_TEST_SLACK * oc2);
}

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
    float3 ng = normalize_scaled(cross3(pb - pa, pc - pa), (float3)(0.0f, 1.0f, 0.0f));
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
