// Mirror of core/src/packing.rs: octahedral unit vectors in two snorm16.

inline float sign_not_zero(float v) { return v >= 0.0f ? 1.0f : -1.0f; }

inline float2 oct_encode(float3 n) {
    float l1 = fabs(n.x) + fabs(n.y) + fabs(n.z);
    if (l1 <= 0.0f || !isfinite(l1)) return (float2)(0.0f, 0.0f);
    float2 p = (float2)(n.x, n.y) / l1;
    if (n.z >= 0.0f) return p;
    return (float2)((1.0f - fabs(p.y)) * sign_not_zero(p.x), (1.0f - fabs(p.x)) * sign_not_zero(p.y));
}

inline float3 oct_decode(float2 e) {
    float3 v = (float3)(e.x, e.y, 1.0f - fabs(e.x) - fabs(e.y));
    if (v.z < 0.0f) {
        float x = (1.0f - fabs(v.y)) * sign_not_zero(v.x);
        float y = (1.0f - fabs(v.x)) * sign_not_zero(v.y);
        v.x = x;
        v.y = y;
    }
    return normalize_or(v, (float3)(0.0f, 0.0f, 1.0f));
}

// Rust's f32::round: half away from zero.
inline float round_half_away(float x) { return round(x); }

inline uint snorm16(float x) {
    return ((uint)(int)round_half_away(clampf(x, -1.0f, 1.0f) * 32767.0f)) & 0xFFFFu;
}

inline uint pack_unit_vector(float3 n) {
    float2 e = oct_encode(n);
    return snorm16(e.x) | (snorm16(e.y) << 16);
}

inline float3 unpack_unit_vector(uint p) {
    float x = fmax((float)(short)(p & 0xFFFFu) / 32767.0f, -1.0f);
    float y = fmax((float)(short)(p >> 16) / 32767.0f, -1.0f);
    return oct_decode((float2)(x, y));
}
