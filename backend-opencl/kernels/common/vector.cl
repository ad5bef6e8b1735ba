// Vector helpers with glam's exact operation order (Vec3 is scalar in glam): products
// and sums are evaluated left to right, so results round as in the Rust reference.

inline float3 load3(const float* a) { return (float3)(a[0], a[1], a[2]); }
inline float3 load3g(__global const float* a) { return (float3)(a[0], a[1], a[2]); }
inline float3 load3c(__constant const float* a) { return (float3)(a[0], a[1], a[2]); }
inline void store3(float* a, float3 v) { a[0] = v.x; a[1] = v.y; a[2] = v.z; }
inline void store3g(__global float* a, float3 v) { a[0] = v.x; a[1] = v.y; a[2] = v.z; }

inline float dot3(float3 a, float3 b) { return a.x * b.x + a.y * b.y + a.z * b.z; }
inline float3 cross3(float3 a, float3 b) {
    return (float3)(a.y * b.z - b.y * a.z, a.z * b.x - b.z * a.x, a.x * b.y - b.x * a.y);
}
inline float length3(float3 a) { return sqrt(dot3(a, a)); }
inline float3 normalize3(float3 a) { return a * (1.0f / length3(a)); }
inline float3 normalize_or(float3 a, float3 fallback) {
    float rcp = 1.0f / length3(a);
    return (isfinite(rcp) && rcp > 0.0f) ? a * rcp : fallback;
}
// glam's max_element: `if a > b { a } else { b }`, y and z first.
inline float gt_max(float a, float b) { return a > b ? a : b; }
inline float max_element3(float3 a) { return gt_max(a.x, gt_max(a.y, a.z)); }
// core::geometry::normalize_scaled: normalised after division by the largest |component|,
// so that no squared length is subnormal (flushed to zero on some devices).
inline float3 normalize_scaled(float3 v, float3 fallback) {
    float scale = 1.0f / max_element3(fabs(v));
    if (!(isfinite(scale) && scale > 0.0f)) return fallback;
    return normalize_or(v * scale, fallback);
}
inline bool all_finite3(float3 a) { return isfinite(a.x) && isfinite(a.y) && isfinite(a.z); }
// Rust's f32::clamp for ordered bounds (NaN passes through, as in Rust).
inline float clampf(float x, float lo, float hi) { return x < lo ? lo : (x > hi ? hi : x); }
