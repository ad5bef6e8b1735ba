//! Counter-based random numbers: every random number is a pure function of
//! (frame seed, photon index, bounce, dimension), so all backends draw the same numbers
//! and a result does not depend on thread count or scheduling.

/// PCG-style 32-bit integer hash (one LCG step followed by the PCG RXS-M-XS output
/// permutation).
#[inline]
pub fn pcg_hash(input: u32) -> u32 {
    let state = input.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((state >> ((state >> 28) + 4)) ^ state).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The random 32-bit word for (seed, index, bounce, dimension): hashes chained so that
/// every argument changes every bit.
#[inline]
pub fn random_u32(seed: u32, index: u32, bounce: u32, dimension: u32) -> u32 {
    let h = pcg_hash(seed ^ pcg_hash(index));
    let h = pcg_hash(h ^ bounce.wrapping_mul(0x9E37_79B9));
    pcg_hash(h ^ dimension.wrapping_mul(0x85EB_CA6B))
}

/// Uniform float in [0, 1) from the top 24 bits: `(x >> 8) * 2^-24` (exact in f32).
#[inline]
pub fn u32_to_unit_f32(x: u32) -> f32 {
    (x >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Uniform float in [0, 1) for (seed, index, bounce, dimension).
#[inline]
pub fn random_f32(seed: u32, index: u32, bounce: u32, dimension: u32) -> f32 {
    u32_to_unit_f32(random_u32(seed, index, bounce, dimension))
}

/// Steps of the R2 sequence (Roberts' generalised golden ratio: `1/phi2`, `1/phi2^2`,
/// `phi2` the plastic number) in 0.32 fixed point: point `k` is `k * step mod 1` in each
/// dimension, low-discrepancy for every prefix.
pub const R2_STEP: [u32; 2] = [3_242_174_889, 2_447_445_413];

/// Dimension `dim` (0: x, 1: y) of the jitter of photon `index` in its grid cell for
/// stratum `k` ([`crate::device::layout::TraceParams::stratum`]): the cell's random
/// rotation (`jitter_seed`) plus the `k`-th R2 point, mod 1, added in 0.32 fixed point (so
/// every port gets the same bits). Stratum 0 is the plain `random_f32(jitter_seed, index,
/// 0, dim)`; strata 0 .. N of one cell spread over it as a stratified sample does.
#[inline]
pub fn stratum_jitter(jitter_seed: u32, index: u32, dim: u32, k: u32) -> f32 {
    let r = random_u32(jitter_seed, index, 0, dim);
    u32_to_unit_f32(r.wrapping_add(k.wrapping_mul(R2_STEP[dim as usize & 1])))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn strata_spread_over_a_cell() {
        for index in [0u32, 7, 1 << 20] {
            // stratum 0 is the plain jitter
            assert_eq!(stratum_jitter(9, index, 0, 0), random_f32(9, index, 0, 0));
            // 64 strata over a 4 x 4 split of the cell: 4 each, give or take 2 (64
            // independent points would leave some sub-cell with 0 or 9 often)
            let mut n = [0u32; 16];
            for k in 0..64 {
                let (x, y) = (
                    stratum_jitter(9, index, 0, k),
                    stratum_jitter(9, index, 1, k),
                );
                n[(y * 4.0) as usize * 4 + (x * 4.0) as usize] += 1;
            }
            assert!(n.iter().all(|&c| (2..=6).contains(&c)), "{index}: {n:?}");
        }
    }

    #[test]
    fn unit_range_and_mean() {
        let mut sum = 0.0f64;
        let n = 100_000;
        for i in 0..n {
            let x = random_f32(7, i, 0, 0);
            assert!((0.0..1.0).contains(&x));
            sum += x as f64;
        }
        let mean = sum / n as f64;
        // std of the mean of U(0,1) is 0.289/sqrt(n) = 9e-4; 5 sigma.
        assert!((mean - 0.5).abs() < 4.6e-3, "mean {mean}");
        assert_eq!(u32_to_unit_f32(u32::MAX), 16_777_215.0 / 16_777_216.0);
    }

    #[test]
    fn dimensions_are_decorrelated() {
        // Correlation of successive dimensions over many indices is near zero.
        let n = 50_000;
        let (mut sx, mut sy, mut sxy) = (0.0f64, 0.0f64, 0.0f64);
        for i in 0..n {
            let x = random_f32(1, i, 2, 0) as f64 - 0.5;
            let y = random_f32(1, i, 2, 1) as f64 - 0.5;
            sx += x;
            sy += y;
            sxy += x * y;
        }
        let cov = sxy / n as f64 - (sx / n as f64) * (sy / n as f64);
        // var(U) = 1/12; correlation std ~ 1/sqrt(n) = 4.5e-3; 5 sigma on cov*12.
        assert!((cov * 12.0).abs() < 0.023, "correlation {}", cov * 12.0);
    }
}
