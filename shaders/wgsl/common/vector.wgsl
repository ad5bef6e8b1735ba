// Vector helpers with glam's exact operation order (Vec3 is scalar in glam): products and
// sums are evaluated left to right, so results round as in the Rust reference. Mirror of
// backend-opencl/kernels/vector.cl (its load3/store3 helpers have no WGSL counterpart:
// the structs hold vec3<f32> fields).

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}

fn length3(a: vec3<f32>) -> f32 {
    return sqrt(dot3(a, a));
}

fn normalize3(a: vec3<f32>) -> vec3<f32> {
    return a * (1.0 / length3(a));
}

// WGSL has no isfinite/isnan (and may assume neither occurs), so they are bit tests.
fn is_finite_f32(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

fn is_nan_f32(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7fffffffu) > 0x7f800000u;
}

// C's copysign: the magnitude of `mag` with the sign bit of `sgn`.
fn copysign_f32(mag: f32, sgn: f32) -> f32 {
    return bitcast<f32>((bitcast<u32>(mag) & 0x7fffffffu) | (bitcast<u32>(sgn) & 0x80000000u));
}

fn normalize_or(a: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let rcp = 1.0 / length3(a);
    if (is_finite_f32(rcp) && rcp > 0.0) {
        return a * rcp;
    }
    return fallback;
}

// glam's max_element: `if a > b { a } else { b }`, y and z first.
fn gt_max(a: f32, b: f32) -> f32 {
    return select(b, a, a > b);
}

fn max_element3(a: vec3<f32>) -> f32 {
    return gt_max(a.x, gt_max(a.y, a.z));
}

// core::geometry::normalize_scaled: normalised after division by the largest |component|,
// so that no squared length is subnormal (NVIDIA's Vulkan flushes those to zero).
fn normalize_scaled(v: vec3<f32>, fallback: vec3<f32>) -> vec3<f32> {
    let scale = 1.0 / max_element3(abs(v));
    if (!(is_finite_f32(scale) && scale > 0.0)) {
        return fallback;
    }
    return normalize_or(v * scale, fallback);
}

fn all_finite3(a: vec3<f32>) -> bool {
    return is_finite_f32(a.x) && is_finite_f32(a.y) && is_finite_f32(a.z);
}

// Rust's f32::clamp for ordered bounds (NaN passes through, as in Rust); WGSL's clamp
// leaves NaN indeterminate.
fn clampf(x: f32, lo: f32, hi: f32) -> f32 {
    if (x < lo) {
        return lo;
    }
    if (x > hi) {
        return hi;
    }
    return x;
}
