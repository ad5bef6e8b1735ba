// Mirror of core/src/geometry.rs and backend-opencl/kernels/geometry.cl: Moller-Trumbore,
// the scale-aware ray offset (Waechter and Binder) and surface interpolation.

struct TriangleHit {
    t: f32,
    u: f32,
    v: f32,
}

fn intersect_triangle(origin: vec3<f32>, dir: vec3<f32>, v0: vec3<f32>, v1: vec3<f32>,
                      v2: vec3<f32>, t_min: f32, t_max: f32,
                      hit: ptr<function, TriangleHit>) -> bool {
    let e1 = v1 - v0;
    let e2 = v2 - v0;
    let p = cross3(dir, e2);
    let det = dot3(e1, p);
    if (det == 0.0 || !is_finite_f32(det)) {
        return false;
    }
    let inv_det = 1.0 / det;
    let s = origin - v0;
    let u = dot3(s, p) * inv_det;
    if (!(u >= 0.0 && u <= 1.0)) {
        return false;
    }
    let q = cross3(s, e1);
    let v = dot3(dir, q) * inv_det;
    if (v < 0.0 || u + v > 1.0) {
        return false;
    }
    let t = dot3(e2, q) * inv_det;
    if (t > t_min && t < t_max) {
        (*hit).t = t;
        (*hit).u = u;
        (*hit).v = v;
        return true;
    }
    return false;
}

// Scale-aware offset: p + n * (2^-15 * largest |coordinate|), see core/src/geometry.rs.
const OFFSET_REL: f32 = 1.0f / 32768.0f;
const OFFSET_MIN_SCALE: f32 = 7.888609e-31f;

fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    let m = max(max(abs(p.x), abs(p.y)), max(abs(p.z), OFFSET_MIN_SCALE));
    let d = m * OFFSET_REL;
    return p + n * d;
}

struct SurfacePoint {
    position: vec3<f32>,
    geometric_normal: vec3<f32>,
    shading_normal: vec3<f32>,
    uv: vec2<f32>,
}

// The OpenCL version takes pointers into the global vertex array; WGSL functions cannot
// take storage pointers, so the three vertices come by value.
fn surface_point(a: GpuVertex, b: GpuVertex, c: GpuVertex, u: f32, v: f32) -> SurfacePoint {
    let w = 1.0 - u - v;
    let pa = a.position;
    let pb = b.position;
    let pc = c.position;
    let na = a.normal;
    let nb = b.normal;
    let nc = c.normal;
    var ng = normalize_or(cross3(pb - pa, pc - pa), vec3<f32>(0.0, 1.0, 0.0));
    let n_sum = na + nb + nc;
    if (dot3(ng, n_sum) < 0.0) {
        ng = -ng;
    }
    var ns = normalize_or(w * na + u * nb + v * nc, ng);
    if (!all_finite3(ns)) {
        ns = ng;
    }
    var s: SurfacePoint;
    s.position = w * pa + u * pb + v * pc;
    s.geometric_normal = ng;
    s.shading_normal = ns;
    s.uv = vec2<f32>(w * a.u + u * b.u + v * c.u, w * a.v + u * b.v + v * c.v);
    return s;
}
