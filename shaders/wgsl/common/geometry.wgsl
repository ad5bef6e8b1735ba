// Mirror of core/src/geometry.rs and backend-opencl/kernels/geometry.cl: the watertight
// ray-triangle test, the scale-aware ray origin offset and surface interpolation.

struct TriangleHit {
    t: f32,
    u: f32,
    v: f32,
}

// Per-ray part of the watertight test (mirror of core::geometry::WatertightRay): the
// permutation (kx, ky, kz) and the shear (sx, sy, sz); valid = false for a zero direction.
struct WatertightRay {
    origin: vec3<f32>,
    kx: i32,
    ky: i32,
    kz: i32,
    sx: f32,
    sy: f32,
    sz: f32,
    valid: bool,
}

fn watertight_ray(origin: vec3<f32>, dir: vec3<f32>) -> WatertightRay {
    let ad = abs(dir);
    var kz = 2;
    if (ad.x >= ad.y && ad.x >= ad.z) {
        kz = 0;
    } else if (ad.y >= ad.z) {
        kz = 1;
    }
    var kx = (kz + 1) % 3;
    var ky = (kx + 1) % 3;
    let dz = dir[kz];
    if (dz < 0.0) {
        let k = kx;
        kx = ky;
        ky = k;
    }
    return WatertightRay(origin, kx, ky, kz, dir[kx] / dz, dir[ky] / dz, 1.0 / dz, dz != 0.0);
}

// Woop's edge function q.x p.y - q.y p.x with the endpoints in a canonical order, negated
// back (core::geometry::edge_function): the two triangles of a shared edge compute exactly
// opposite values even where the driver contracts the products into an FMA (WGSL cannot
// forbid it; NVIDIA's driver does it).
fn edge_function(p: vec2<f32>, q: vec2<f32>) -> f32 {
    let swap = !(p.x < q.x || (p.x == q.x && p.y < q.y));
    let lo = select(p, q, swap);
    let hi = select(q, p, swap);
    let e = hi.x * lo.y - hi.y * lo.x;
    return select(e, 0.0 - e, swap);
}

// Watertight ray-triangle test (Woop, Benthin and Wald 2013), two-sided; mirror of
// core::geometry::WatertightRay::intersect, operation by operation.
fn intersect_watertight(r: ptr<function, WatertightRay>, v0: vec3<f32>, v1: vec3<f32>,
                        v2: vec3<f32>, t_min: f32, t_max: f32,
                        hit: ptr<function, TriangleHit>) -> bool {
    if (!(*r).valid) {
        return false;
    }
    let kx = (*r).kx;
    let ky = (*r).ky;
    let kz = (*r).kz;
    let sx = (*r).sx;
    let sy = (*r).sy;
    let sz = (*r).sz;
    let a = v0 - (*r).origin;
    let b = v1 - (*r).origin;
    let c = v2 - (*r).origin;
    let ax = a[kx] - sx * a[kz];
    let ay = a[ky] - sy * a[kz];
    let bx = b[kx] - sx * b[kz];
    let by = b[ky] - sy * b[kz];
    let cx = c[kx] - sx * c[kz];
    let cy = c[ky] - sy * c[kz];
    let u = edge_function(vec2<f32>(bx, by), vec2<f32>(cx, cy));
    let v = edge_function(vec2<f32>(cx, cy), vec2<f32>(ax, ay));
    let w = edge_function(vec2<f32>(ax, ay), vec2<f32>(bx, by));
    if ((u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0)) {
        return false;
    }
    let det = u + v + w;
    if (det == 0.0 || !is_finite_f32(det)) {
        return false;
    }
    let az = sz * a[kz];
    let bz = sz * b[kz];
    let cz = sz * c[kz];
    let inv_det = 1.0 / det;
    let t = (u * az + v * bz + w * cz) * inv_det;
    if (t > t_min && t < t_max) {
        (*hit).t = t;
        (*hit).u = v * inv_det;
        (*hit).v = w * inv_det;
        return true;
    }
    return false;
}

// One triangle, one ray (core::geometry::intersect_triangle).
fn intersect_triangle(origin: vec3<f32>, dir: vec3<f32>, v0: vec3<f32>, v1: vec3<f32>,
                      v2: vec3<f32>, t_min: f32, t_max: f32,
                      hit: ptr<function, TriangleHit>) -> bool {
    var r = watertight_ray(origin, dir);
    return intersect_watertight(&r, v0, v1, v2, t_min, t_max, hit);
}

// Scale-aware offset: p + n * (OFFSET_REL = 2^-15 * largest |coordinate|), see
// core/src/geometry.rs.

// core::math::geometry::ray_meets_sphere: whether the ray origin + t dir (t >= 0) may meet
// the ball (centre xyz, radius w); false only outside the test's rounding slack.
fn ray_meets_sphere(origin: vec3<f32>, dir: vec3<f32>, sphere: vec4<f32>) -> bool {
    let oc = sphere.xyz - origin;
    let tca = max(dot3(oc, dir), 0.0);
    let oc2 = dot3(oc, oc);
    let r = sphere.w;
    return !(oc2 - tca * tca > r * r + SPHERE_TEST_SLACK * oc2);
}

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
    var ng = normalize_scaled(cross3(pb - pa, pc - pa), vec3<f32>(0.0, 1.0, 0.0));
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
