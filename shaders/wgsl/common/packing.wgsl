// Mirror of core/src/packing.rs and backend-opencl/kernels/packing.cl: octahedral unit
// vectors in two snorm16.

fn sign_not_zero(v: f32) -> f32 {
    return select(-1.0, 1.0, v >= 0.0);
}

fn oct_encode(n: vec3<f32>) -> vec2<f32> {
    let l1 = abs(n.x) + abs(n.y) + abs(n.z);
    if (l1 <= 0.0 || !is_finite_f32(l1)) {
        return vec2<f32>(0.0, 0.0);
    }
    let p = vec2<f32>(n.x, n.y) / l1;
    if (n.z >= 0.0) {
        return p;
    }
    return vec2<f32>((1.0 - abs(p.y)) * sign_not_zero(p.x), (1.0 - abs(p.x)) * sign_not_zero(p.y));
}

fn oct_decode(e: vec2<f32>) -> vec3<f32> {
    var v = vec3<f32>(e.x, e.y, 1.0 - abs(e.x) - abs(e.y));
    if (v.z < 0.0) {
        let x = (1.0 - abs(v.y)) * sign_not_zero(v.x);
        let y = (1.0 - abs(v.x)) * sign_not_zero(v.y);
        v.x = x;
        v.y = y;
    }
    return normalize_or(v, vec3<f32>(0.0, 0.0, 1.0));
}

// Rust's f32::round (and OpenCL's round): half away from zero. WGSL's round() rounds half
// to even, so it is built from trunc: x - trunc(x) is exact (the fraction of an f32 is an
// f32; from 2^23 up every f32 is an integer and the fraction is 0).
fn round_half_away(x: f32) -> f32 {
    let t = trunc(x);
    if (abs(x - t) >= 0.5) {
        return t + sign_not_zero(x);
    }
    return t;
}

// `as i32 as u32`: the value is within +-32767, so the conversion is exact and the bit
// reinterpretation gives Rust's two's complement word.
fn snorm16(x: f32) -> u32 {
    return bitcast<u32>(i32(round_half_away(clampf(x, -1.0, 1.0) * 32767.0))) & 0xFFFFu;
}

fn pack_unit_vector(n: vec3<f32>) -> u32 {
    let e = oct_encode(n);
    return snorm16(e.x) | (snorm16(e.y) << 16u);
}

// `bits as u16 as i16`: arithmetic shifts of the i32 sign-extend each 16-bit half.
fn unpack_unit_vector(p: u32) -> vec3<f32> {
    let x = max(f32(bitcast<i32>(p << 16u) >> 16u) / 32767.0, -1.0);
    let y = max(f32(bitcast<i32>(p) >> 16u) / 32767.0, -1.0);
    return oct_decode(vec2<f32>(x, y));
}
