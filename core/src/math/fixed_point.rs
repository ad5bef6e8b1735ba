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

/// The quantum (a power of two) for values up to `max_value`: `max_value / quantum` lies
/// in `[2^24, 2^25)`. A power of two makes `value / quantum` exact on every device (an
/// approximate GPU division of a power of two still scales the exponent exactly), so all
/// backends round `value / quantum` to the same integer, and the sums match bitwise.
/// Non-positive or non-finite `max_value` gives 1.
pub fn power_of_two_quantum(max_value: f32) -> f32 {
    if !(max_value > 0.0 && max_value.is_finite()) {
        return 1.0;
    }
    // floor(log2(max_value)) from the exponent bits (subnormals count as 2^-127)
    let e = ((max_value.to_bits() >> 23) & 0xff) as i32 - 127;
    2f32.powi((e - 24).max(-149))
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
}
