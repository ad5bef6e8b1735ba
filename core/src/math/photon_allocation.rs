//! Photons allocated to lights by power (Smal 2019, section 24.2.1, PhotonGi): "a total
//! number of photons to emit from all light sources ... allocated to lights proportional
//! to each light's intensity. Hence, all photons initially carry roughly the same power."

/// Splits `total` photons over lights of emitted power `powers` (W, the luminance of each
/// light's flux; any common unit) in proportion to power, by largest remainder: light `i`
/// gets `floor(total p_i / P)` and the photons left go one each to the largest fractional
/// parts (ties to the lower index), so the counts add up to `total` exactly and no light
/// is more than one photon from its share. A light of power 0 (or a non-finite or negative
/// power, which the scene validation refuses earlier) gets none. Every light with power
/// gets at least one photon while `total` allows, taken from the largest allocations:
/// a light left without photons would be missing from the estimate, a bias, not noise.
pub fn allocate_photons(total: u64, powers: &[f64]) -> Vec<u64> {
    let p: Vec<f64> = powers
        .iter()
        .map(|&x| if x.is_finite() && x > 0.0 { x } else { 0.0 })
        .collect();
    let sum: f64 = p.iter().sum();
    let mut counts = vec![0u64; p.len()];
    if total == 0 || sum <= 0.0 {
        return counts;
    }
    let mut fractions: Vec<(f64, usize)> = Vec::with_capacity(p.len());
    let mut given = 0u64;
    for (i, &x) in p.iter().enumerate() {
        let share = total as f64 * (x / sum);
        let whole = share.floor().min(total as f64) as u64;
        counts[i] = whole;
        given += whole;
        fractions.push((share - whole as f64, i));
    }
    // the floors can overshoot `total` by rounding only in the last place: take back
    while given > total {
        let i = (0..counts.len())
            .max_by_key(|&i| counts[i])
            .expect("a light");
        counts[i] -= 1;
        given -= 1;
    }
    fractions.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
    for &(_, i) in fractions.iter().filter(|(_, i)| p[*i] > 0.0) {
        if given == total {
            break;
        }
        counts[i] += 1;
        given += 1;
    }
    // at least one photon for every light with power, while the budget allows
    let lit = p.iter().filter(|&&x| x > 0.0).count() as u64;
    if total >= lit {
        for i in 0..counts.len() {
            if p[i] > 0.0 && counts[i] == 0 {
                let donor = (0..counts.len())
                    .max_by_key(|&j| counts[j])
                    .expect("a light");
                counts[donor] -= 1;
                counts[i] = 1;
            }
        }
    }
    counts
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    #[test]
    fn shares_follow_power() {
        assert_eq!(allocate_photons(100, &[1.0, 3.0]), vec![25, 75]);
        assert_eq!(allocate_photons(10, &[1.0, 1.0, 1.0]), vec![4, 3, 3]);
        assert_eq!(allocate_photons(5, &[0.0, 2.0]), vec![0, 5]);
        assert_eq!(allocate_photons(0, &[1.0]), vec![0]);
        assert_eq!(allocate_photons(7, &[]), Vec::<u64>::new());
        assert_eq!(allocate_photons(7, &[0.0, f64::NAN, -1.0]), vec![0, 0, 0]);
        // a light of 1 W beside one of 1e9 W still gets a photon
        assert_eq!(allocate_photons(1000, &[1e9, 1.0]), vec![999, 1]);
    }

    proptest! {
        #[test]
        fn counts_add_up_and_stay_within_one_of_the_share(
            total in 0u64..5_000_000,
            powers in prop::collection::vec(0.0f64..1e6, 1..12),
        ) {
            let c = allocate_photons(total, &powers);
            let sum: f64 = powers.iter().sum();
            let lit = powers.iter().filter(|&&p| p > 0.0).count() as u64;
            if sum > 0.0 {
                prop_assert_eq!(c.iter().sum::<u64>(), total);
                for (k, &p) in c.iter().zip(&powers) {
                    let share = total as f64 * p / sum;
                    // within one of the share, or the one photon a dim light is given
                    // (taken from a light within `lit` of its share)
                    prop_assert!((*k as f64 - share).abs() <= 1.0 + lit as f64, "{} vs {}", k, share);
                    if p == 0.0 { prop_assert_eq!(*k, 0); }
                    if p > 0.0 && total >= lit { prop_assert!(*k >= 1); }
                }
            } else {
                prop_assert!(c.iter().all(|&k| k == 0));
            }
        }
    }
}
