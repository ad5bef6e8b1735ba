//! Packing functions for compact GPU records: octahedral unit vectors in two snorm16,
//! shared-exponent RGB (rgb9e5) and half floats. Shader ports mirror these by name.

use glam::{Vec2, Vec3};

fn sign_not_zero(v: f32) -> f32 {
    if v >= 0.0 {
        1.0
    } else {
        -1.0
    }
}

/// Octahedral map of a unit vector to [-1,1]^2.
#[inline]
pub fn oct_encode(n: Vec3) -> Vec2 {
    let l1 = n.x.abs() + n.y.abs() + n.z.abs();
    if l1 <= 0.0 || !l1.is_finite() {
        return Vec2::new(0.0, 0.0);
    }
    let p = Vec2::new(n.x, n.y) / l1;
    if n.z >= 0.0 {
        p
    } else {
        Vec2::new(
            (1.0 - p.y.abs()) * sign_not_zero(p.x),
            (1.0 - p.x.abs()) * sign_not_zero(p.y),
        )
    }
}

/// Inverse of [`oct_encode`]; returns a unit vector.
#[inline]
pub fn oct_decode(e: Vec2) -> Vec3 {
    let mut v = Vec3::new(e.x, e.y, 1.0 - e.x.abs() - e.y.abs());
    if v.z < 0.0 {
        let x = (1.0 - v.y.abs()) * sign_not_zero(v.x);
        let y = (1.0 - v.x.abs()) * sign_not_zero(v.y);
        v.x = x;
        v.y = y;
    }
    v.normalize_or(Vec3::Z)
}

/// Unit vector packed as two snorm16 (x in the low half, y in the high half).
#[inline]
pub fn pack_unit_vector(n: Vec3) -> u32 {
    let e = oct_encode(n);
    let q = |x: f32| ((x.clamp(-1.0, 1.0) * 32767.0).round() as i32 as u32) & 0xFFFF;
    q(e.x) | (q(e.y) << 16)
}

/// Inverse of [`pack_unit_vector`].
#[inline]
pub fn unpack_unit_vector(p: u32) -> Vec3 {
    let s = |bits: u32| ((bits as u16 as i16) as f32 / 32767.0).max(-1.0);
    oct_decode(Vec2::new(s(p & 0xFFFF), s(p >> 16)))
}

/// RGB packed as rgb9e5 (9-bit mantissas, shared 5-bit exponent, bias 15), the layout of
/// `VK_FORMAT_E5B9G9R9_UFLOAT_PACK32`. Negative and NaN inputs become 0; values beyond
/// the largest representable (65408) saturate, values below `2^-24` round to 0 or the
/// smallest step. Exact arithmetic only (the exponent from the float's bits, scaling by
/// powers of two, rounding half up by `floor(x + 0.5)` of an exact value), so the shader
/// ports give the same bits.
pub fn pack_rgb9e5(rgb: Vec3) -> u32 {
    const MAX: f32 = 65408.0; // (2^9 - 1) / 2^9 * 2^16
    let c = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, MAX) };
    let (r, g, b) = (c(rgb.x), c(rgb.y), c(rgb.z));
    let max_c = r.max(g).max(b);
    if max_c == 0.0 {
        return 0;
    }
    // floor(log2(max_c)) from the biased exponent (subnormals count as 2^-127: they
    // round to 0 below anyway), at least -16
    let e = ((max_c.to_bits() >> 23) & 0xFF) as i32 - 127;
    let mut exp_shared = e.max(-16) + 1 + 15;
    let mut scale = pow2(9 + 15 - exp_shared);
    if (max_c * scale + 0.5).floor() as u32 == 512 {
        exp_shared += 1;
        scale *= 0.5;
    }
    let q = |x: f32| ((x * scale + 0.5).floor() as u32).min(511);
    q(r) | (q(g) << 9) | (q(b) << 18) | ((exp_shared as u32) << 27)
}

/// `2^k` for `k` in `-126..=127`, from its bits (exact).
#[inline]
pub fn pow2(k: i32) -> f32 {
    f32::from_bits(((k + 127) as u32) << 23)
}

/// Inverse of [`pack_rgb9e5`].
pub fn unpack_rgb9e5(p: u32) -> Vec3 {
    let scale = pow2((p >> 27) as i32 - 15 - 9);
    Vec3::new(
        (p & 511) as f32 * scale,
        ((p >> 9) & 511) as f32 * scale,
        ((p >> 18) & 511) as f32 * scale,
    )
}

/// Two floats as IEEE half floats (x low, y high).
pub fn pack_half2(v: Vec2) -> u32 {
    half::f16::from_f32(v.x).to_bits() as u32 | ((half::f16::from_f32(v.y).to_bits() as u32) << 16)
}

/// Inverse of [`pack_half2`].
pub fn unpack_half2(p: u32) -> Vec2 {
    Vec2::new(
        half::f16::from_bits(p as u16).to_f32(),
        half::f16::from_bits((p >> 16) as u16).to_f32(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        #[test]
        fn unit_vector_roundtrip(x in -1.0f32..1.0, y in -1.0f32..1.0, z in -1.0f32..1.0) {
            let n = Vec3::new(x, y, z);
            prop_assume!(n.length() > 1e-3);
            let n = n.normalize();
            let back = unpack_unit_vector(pack_unit_vector(n));
            // snorm16 step 2/65534 in octahedral space; the octahedral map stretches by at
            // most ~2x, so angular error < 1e-4.
            prop_assert!((back - n).length() < 1e-4, "{n} -> {back}");
        }

        #[test]
        fn rgb9e5_roundtrip(r in 0.0f32..1000.0, g in 0.0f32..1000.0, b in 0.0f32..1000.0) {
            let v = Vec3::new(r, g, b);
            let back = unpack_rgb9e5(pack_rgb9e5(v));
            // 9-bit mantissa relative to the largest channel: error <= max/2^9.
            let tol = v.max_element() / 512.0 + 1e-30;
            prop_assert!((back - v).abs().max_element() <= tol, "{v} -> {back}");
        }
    }

    #[test]
    fn half_roundtrip() {
        let v = Vec2::new(1.5, -0.25);
        assert_eq!(unpack_half2(pack_half2(v)), v);
    }
}
