//! Fixed-point photon accumulation. Flux is summed as integers in units of a
//! per-frame *flux quantum*, so sums are exact, order-independent and bitwise reproducible
//! on every backend and thread count. A photon contributes `round(flux / quantum)` per
//! channel: at most `u32::MAX` (larger is clamped and counted as saturation) and, when
//! positive flux rounds to zero, it is counted as underflow. Sums are 64-bit.

/// The brightest value of a frame is at least this many units (24 bits of precision: a
/// relative rounding error <= 2^-25), see [`power_of_two_quantum`].
pub const FLUX_QUANTA_PER_MAX_PHOTON: f32 = 16_777_216.0;

/// ... and fewer than this many (2^25); 2^39 such photons fit a 64-bit sum.
pub const MAX_PHOTON_QUANTA: f32 = 33_554_432.0;

/// The smallest quantum: the smallest normal f32, 2^-126. A subnormal quantum would be
/// flushed to zero by GPUs (and `2^k` for `k < -126` computed as `1 / 2^-k` is zero once
/// `2^-k` overflows), making every deposit saturate.
pub const MIN_FLUX_QUANTUM: f32 = f32::MIN_POSITIVE;

/// The smallest `max_value` whose quantum keeps `max_value / quantum` in `[2^24, 2^25)`:
/// 2^-102 (its quantum is [`MIN_FLUX_QUANTUM`]). `scene::limits::MIN_INTENSITY` keeps a
/// valid scene's brightest emitted photon above it.
pub const MIN_FULL_PRECISION_VALUE: f32 = MIN_FLUX_QUANTUM * FLUX_QUANTA_PER_MAX_PHOTON;

/// The quantum (a power of two) for values up to `max_value`: `max_value / quantum` lies
/// in `[2^24, 2^25)`. A power of two makes `value / quantum` exact on every device (an
/// approximate GPU division of a power of two still scales the exponent exactly), so all
/// backends round `value / quantum` to the same integer, and the sums match bitwise.
/// Non-positive or non-finite `max_value` gives 1.
///
/// The quantum is never below [`MIN_FLUX_QUANTUM`] (2^-126, normal): for `max_value`
/// below [`MIN_FULL_PRECISION_VALUE`] (2^-102) it is 2^-126 and `max_value` has fewer than
/// 2^24 units (fewer bits of precision); a value below 2^-127 rounds to no unit, which
/// [`quantize`] counts as underflow (the frame stats' `fixed_point_underflow`) where the
/// value itself is normal. Scene validation keeps every light's emitted photons above
/// that range (`scene::limits::MIN_INTENSITY`) unless its emission domain is tiny.
pub fn power_of_two_quantum(max_value: f32) -> f32 {
    if !(max_value > 0.0 && max_value.is_finite()) {
        return 1.0;
    }
    // floor(log2(max_value)) from the exponent bits (subnormals count as 2^-127)
    let e = ((max_value.to_bits() >> 23) & 0xff) as i32 - 127;
    if e - 24 < -126 {
        return MIN_FLUX_QUANTUM;
    }
    2f32.powi(e - 24)
}

/// Outcome of quantizing one value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quantized {
    /// `round(value / quantum)`, clamped to `u32::MAX`; 0 for negative or NaN values.
    pub units: u32,
    /// A positive value rounded to zero units.
    pub underflow: bool,
    /// The value was clamped to `u32::MAX` units.
    pub saturated: bool,
}

/// `round(value / quantum)` clamped to u32, with underflow / saturation flags.
/// NaN and negative values give 0 units (and count as underflow only if positive).
#[inline]
pub fn quantize(value: f32, quantum: f32) -> Quantized {
    let x = value / quantum;
    if !(x > 0.0) {
        return Quantized {
            units: 0,
            underflow: false,
            saturated: false,
        };
    }
    let r = (x + 0.5).floor();
    if r >= 4_294_967_295.0 {
        return Quantized {
            units: u32::MAX,
            underflow: false,
            saturated: true,
        };
    }
    let units = r as u32;
    Quantized {
        units,
        underflow: units == 0,
        saturated: false,
    }
}

/// Joins a (lo, hi) pair of u32 words into a u64.
#[inline]
pub fn join_u64(w: [u32; 2]) -> u64 {
    w[0] as u64 | ((w[1] as u64) << 32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn rounding_underflow_and_saturation() {
        assert_eq!(quantize(2.4, 1.0).units, 2);
        assert_eq!(quantize(2.5, 1.0).units, 3);
        assert!(quantize(0.4, 1.0).underflow);
        assert!(!quantize(0.0, 1.0).underflow);
        assert!(quantize(1e12, 1.0).saturated);
        assert_eq!(quantize(f32::NAN, 1.0).units, 0);
        assert_eq!(join_u64([1, 2]), (2u64 << 32) | 1);
    }

    #[test]
    fn power_of_two_quantum_keeps_25_bits() {
        for &m in &[1e-30f32, 3.7e-6, 1.0, 1.5, 2.0, 12345.6, 1e30] {
            let q = power_of_two_quantum(m);
            assert_eq!(q.to_bits() & 0x7f_ffff, 0, "{q} is a power of two");
            let units = m / q;
            assert!(
                (FLUX_QUANTA_PER_MAX_PHOTON..MAX_PHOTON_QUANTA).contains(&units),
                "{m}: {units}"
            );
        }
        assert_eq!(power_of_two_quantum(0.0), 1.0);
        assert_eq!(power_of_two_quantum(f32::NAN), 1.0);
    }

    /// Below 2^-102 the quantum stays 2^-126 (normal) instead of going subnormal or zero:
    /// the value keeps its units down to 2^-127, and a smaller one counts as underflow.
    #[test]
    fn power_of_two_quantum_is_never_subnormal() {
        assert_eq!(MIN_FULL_PRECISION_VALUE, 2f32.powi(-102));
        // the last value of full precision, and the first one below
        let q = power_of_two_quantum(MIN_FULL_PRECISION_VALUE);
        assert_eq!(q, MIN_FLUX_QUANTUM);
        assert_eq!(MIN_FULL_PRECISION_VALUE / q, FLUX_QUANTA_PER_MAX_PHOTON);
        let below = f32::from_bits(MIN_FULL_PRECISION_VALUE.to_bits() - 1);
        assert_eq!(power_of_two_quantum(below), MIN_FLUX_QUANTUM);
        for m in [1e-31f32, 1e-35, 1e-38, 1e-40, 1e-45, f32::MIN_POSITIVE] {
            let q = power_of_two_quantum(m);
            assert!(q.is_normal() && q == MIN_FLUX_QUANTUM, "{m:e}: {q:e}");
            // the brightest value keeps its units (no saturation) ...
            let r = quantize(m, q);
            assert!(
                !r.saturated && r.units as f32 <= FLUX_QUANTA_PER_MAX_PHOTON,
                "{m:e}"
            );
            // ... and below half the quantum it is counted as underflow, not dropped silently
            if m < 0.5 * MIN_FLUX_QUANTUM {
                assert!(r.underflow && r.units == 0, "{m:e}: {r:?}");
            } else {
                assert!(r.units >= 1, "{m:e}: {r:?}");
            }
        }
        // every exponent from the largest f32 down to the smallest subnormal
        let mut m = f32::MAX;
        while m > 0.0 {
            let q = power_of_two_quantum(m);
            assert!(
                q.is_normal() && q.to_bits() & 0x7f_ffff == 0,
                "{m:e}: {q:e}"
            );
            if m >= MIN_FULL_PRECISION_VALUE {
                assert!((FLUX_QUANTA_PER_MAX_PHOTON..MAX_PHOTON_QUANTA).contains(&(m / q)));
            }
            m *= 0.5;
        }
    }
}
