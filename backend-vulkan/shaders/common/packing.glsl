// Mirror of core/src/packing.rs and backend-opencl/kernels/packing.cl: octahedral unit
// vectors in two snorm16.

float sign_not_zero(float v) { return v >= 0.0 ? 1.0 : -1.0; }

precise vec2 oct_encode(vec3 n) {
    float l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if (l1 <= 0.0 || !is_finite(l1)) return vec2(0.0, 0.0);
    vec2 p = vec2(n.x, n.y) / l1;
    if (n.z >= 0.0) return p;
    return vec2((1.0 - abs(p.y)) * sign_not_zero(p.x), (1.0 - abs(p.x)) * sign_not_zero(p.y));
}

precise vec3 oct_decode(vec2 e) {
    vec3 v = vec3(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    if (v.z < 0.0) {
        float x = (1.0 - abs(v.y)) * sign_not_zero(v.x);
        float y = (1.0 - abs(v.x)) * sign_not_zero(v.y);
        v.x = x;
        v.y = y;
    }
    return normalize_or(v, vec3(0.0, 0.0, 1.0));
}

// Rust's f32::round (and OpenCL's round): half away from zero. GLSL's round() may round
// halves either way and floor(x + 0.5) is wrong just below one half, so it is built from
// trunc: x - trunc(x) is exact (the fraction of an f32 is an f32; from 2^23 up every f32
// is an integer and the fraction is 0), and t +- 1 is exact below 2^24.
precise float round_half_away(float x) {
    float t = trunc(x);
    precise float fraction = x - t;
    if (abs(fraction) >= 0.5) return t + sign_not_zero(x);
    return t;
}

// `as i32 as u32`: the value is within +-32767, so the conversion is exact and the bit
// reinterpretation gives Rust's two's complement word.
uint snorm16(float x) {
    precise float scaled = clampf(x, -1.0, 1.0) * 32767.0;
    return uint(int(round_half_away(scaled))) & 0xFFFFu;
}

uint pack_unit_vector(vec3 n) {
    vec2 e = oct_encode(n);
    return snorm16(e.x) | (snorm16(e.y) << 16);
}

// `bits as u16 as i16`: arithmetic shifts of the int sign-extend each 16-bit half.
precise vec3 unpack_unit_vector(uint p) {
    float x = max(float(int(p << 16) >> 16) / 32767.0, -1.0);
    float y = max(float(int(p) >> 16) / 32767.0, -1.0);
    return oct_decode(vec2(x, y));
}
