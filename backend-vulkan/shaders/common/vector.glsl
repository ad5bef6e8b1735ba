// Vector helpers with glam's exact operation order (Vec3 is scalar in glam): products
// and sums are evaluated left to right, so results round as in the Rust reference.
// Mirror of backend-opencl/kernels/vector.cl (its load3/store3 helpers have no GLSL
// counterpart: the structs hold vec3 fields). `precise` returns: see prelude.glsl.

precise float dot3(vec3 a, vec3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
precise vec3 cross3(vec3 a, vec3 b) {
    return vec3(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}
precise float length3(vec3 a) { return sqrt(dot3(a, a)); }
precise vec3 normalize3(vec3 a) { return a * (1.0 / length3(a)); }

// OpenCL's isfinite / isnan as bit tests: Vulkan lets a driver assume that floats are
// never NaN or infinite unless the entry point declares SignedZeroInfNanPreserve, which
// would fold isnan / isinf away (the WGSL port does the same).
bool is_finite(float x) { return (floatBitsToUint(x) & 0x7f800000u) != 0x7f800000u; }
bool is_nan(float x) { return (floatBitsToUint(x) & 0x7fffffffu) > 0x7f800000u; }

precise vec3 normalize_or(vec3 a, vec3 fallback) {
    float rcp = 1.0 / length3(a);
    return (is_finite(rcp) && rcp > 0.0) ? a * rcp : fallback;
}
// glam's max_element: `if a > b { a } else { b }`, y and z first.
float gt_max(float a, float b) { return a > b ? a : b; }
float max_element3(vec3 a) { return gt_max(a.x, gt_max(a.y, a.z)); }
// core::geometry::normalize_scaled: normalised after division by the largest |component|,
// so that no squared length is subnormal (NVIDIA's Vulkan flushes those to zero).
vec3 normalize_scaled(vec3 v, vec3 fallback) {
    precise float scale = 1.0 / max_element3(abs(v));
    if (!(is_finite(scale) && scale > 0.0)) return fallback;
    precise vec3 scaled = v * scale;
    return normalize_or(scaled, fallback);
}
bool all_finite3(vec3 a) { return is_finite(a.x) && is_finite(a.y) && is_finite(a.z); }
// Rust's f32::clamp for ordered bounds (NaN passes through, as in Rust).
float clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }
