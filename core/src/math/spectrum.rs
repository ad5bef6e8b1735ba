//! Spectral dispersion: the wavelength a photon takes at its first dispersive surface, and
//! what that wavelength's power is in linear sRGB. Shader ports mirror these functions by
//! name (`spectral_sample`, `wavelength_at`, `cie_lobe`, `cie_xyz`, `xyz_to_linear_srgb`,
//! `wavelength_rgb`, `disperse`, `split_lane`).
//!
//! **Units.** Wavelengths are in micrometres everywhere in caustica (as Cauchy's `B` in
//! um^2, [`crate::math::optics::cauchy_ior`]); the colour-matching fit is written in
//! nanometres as published, and [`cie_xyz`] converts on entry.
//!
//! **Sampling.** A photon through dispersive glass carries one wavelength, drawn once at
//! its first dispersive surface and kept for the rest of its path (every later dielectric
//! refracts it with that wavelength's index). The wavelength of photon `index` of a light
//! whose seed is `seed` is point `index` of the golden-ratio (Weyl, "R1") sequence,
//! rotated by a hash of the seed ([`spectral_sample`]): consecutive photon indices lie
//! 0.618 of the range apart, and any `N` consecutive indices cover the range with the
//! lowest discrepancy an additive sequence has, so neighbouring photons of the emission
//! grid spread over the spectrum, and the rotation makes every photon's wavelength
//! uniform over [`SPECTRUM_MIN_UM`, `SPECTRUM_MAX_UM`] (unbiased across frames). The
//! arithmetic is 32-bit integer, so every backend draws the same bits.
//!
//! **Why not hero wavelengths.** Hero-wavelength sampling (Wilkie 2014) traces one path
//! for a hero wavelength and `C - 1` wavelengths rotated from it, and combines them by
//! spectral MIS; it pays where the path's geometry is shared by all of them. A caustic
//! photon path that is refracted by dispersive glass is not shared: the refracted
//! direction depends on the wavelength and the interface is a delta distribution, so the
//! secondary wavelengths' path densities are zero after the first refraction and only the
//! hero wavelength carries power from there on: the path collapses to one wavelength, as
//! a stratified single-wavelength photon does, at the cost of evaluating `C` spectra.
//! The only paths that keep their geometry are those that merely *reflect* off dispersive
//! glass (a few percent of its power, Fresnel at normal incidence); there hero's extra
//! wavelengths would lower colour noise, but a stratified sequence over the photon grid
//! does that across neighbouring photons for every path.
//!
//! **Colour.** A wavelength's power becomes XYZ through the CIE 1931 2-degree
//! colour-matching functions, in Wyman 2013's multi-lobe piecewise-Gaussian fit
//! ([`cie_xyz`]; its largest error against the CIE's 5 nm table over 380-780 nm is 0.014
//! in x-bar, 0.0073 in y-bar and 0.022 in z-bar, about 1.3%, 0.7% and 1.2% of their
//! peaks, tested below), then linear sRGB through IEC 61966-2-1's matrix
//! ([`xyz_to_linear_srgb`]). Spectral colours lie outside the sRGB gamut, so some
//! channels come out negative: photon power cannot be negative, so each channel is
//! clipped at 0, then scaled by [`SPECTRAL_RGB_SCALE`] so that its mean over the range is
//! exactly 1 ([`wavelength_rgb`]). A flat spectrum therefore integrates back to white
//! (1, 1, 1), and a photon of RGB flux `F` that takes wavelength `l` carries
//! `F * wavelength_rgb(l)`: the expected flux of every channel is `F`'s, as without
//! dispersion (the white balance is the equal-energy illuminant's, a per-channel scale).
//! The conversion is applied once, where the wavelength is drawn: nothing later depends on
//! a channel other than by per-channel products (mirror reflectance, Beer-Lambert), which
//! commute with it, so the photon's RGB flux is its deposit.
//!
//! **Three bands.** [`dispersion_mode::THREE_BANDS`] keeps Vanderstichelen 2021's
//! three-way split for comparison: the photon keeps one colour channel (chosen uniformly,
//! power x3) and refracts with that channel's wavelength
//! ([`CHANNEL_WAVELENGTH_UM`](crate::math::optics::CHANNEL_WAVELENGTH_UM)).

use crate::math::optics::CHANNEL_WAVELENGTH_UM;
use crate::math::rng::{pcg_hash, u32_to_unit_f32};
use glam::Vec3;

/// Shortest wavelength photons are given (micrometres): 380 nm, the CIE tables' start.
pub const SPECTRUM_MIN_UM: f32 = 0.38;
/// Width of the sampled range (micrometres): 400 nm, so the longest wavelength is
/// [`SPECTRUM_MAX_UM`]. Kept as its own constant so that no port subtracts two constants
/// (GLSL compilers fold such expressions in double precision).
pub const SPECTRUM_WIDTH_UM: f32 = 0.4;
/// Longest wavelength photons are given (micrometres): 780 nm.
pub const SPECTRUM_MAX_UM: f32 = 0.78;

/// Step of the wavelength sequence in 0.32 fixed point: `round(2^32 / phi)`, the golden
/// ratio's fractional part (the R1 sequence).
pub const WAVELENGTH_STEP: u32 = 0x9E37_79B9;

/// The f32 nearest 1/3: the stratum width of [`split_lane`]'s three wavelengths, and
/// their flux share.
pub const ONE_THIRD: f32 = 1.0 / 3.0;

/// Values of the kernels' `dispersion_mode` parameter (`frame.dispersion`): how a photon
/// takes a colour at its first dispersive surface.
pub mod dispersion_mode {
    /// One wavelength over the visible range per photon ([`super::disperse`]).
    pub const SPECTRAL: u32 = 0;
    /// Vanderstichelen 2021's three-way split: one colour channel per photon.
    pub const THREE_BANDS: u32 = 1;
}

/// One lobe of Wyman 2013's piecewise Gaussian: `weight * exp(-t^2 / 2)` with
/// `t = (lambda - mean_nm) * inv_sigma`, `inv_sigma` = `inv_sigma_below` below the mean
/// and `inv_sigma_above` from it on (1/nm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CieLobe {
    /// Height of the lobe (the function's units: dimensionless tristimulus per unit power).
    pub weight: f32,
    /// Centre (nanometres).
    pub mean_nm: f32,
    /// Reciprocal width below the centre (1/nm).
    pub inv_sigma_below: f32,
    /// Reciprocal width from the centre on (1/nm).
    pub inv_sigma_above: f32,
}

const fn lobe(weight: f32, mean_nm: f32, inv_sigma_below: f32, inv_sigma_above: f32) -> CieLobe {
    CieLobe {
        weight,
        mean_nm,
        inv_sigma_below,
        inv_sigma_above,
    }
}

/// x-bar's three lobes (Wyman 2013, the multi-lobe fit of the CIE 1931 functions; the
/// coefficients of its listing, in its order).
pub const CIE_X_LOBES: [CieLobe; 3] = [
    lobe(0.362, 442.0, 0.0624, 0.0374),
    lobe(1.056, 599.8, 0.0264, 0.0323),
    lobe(-0.065, 501.1, 0.0490, 0.0382),
];
/// y-bar's two lobes (Wyman 2013, as [`CIE_X_LOBES`]).
pub const CIE_Y_LOBES: [CieLobe; 2] = [
    lobe(0.821, 568.8, 0.0213, 0.0247),
    lobe(0.286, 530.9, 0.0613, 0.0322),
];
/// z-bar's two lobes (Wyman 2013, as [`CIE_X_LOBES`]).
pub const CIE_Z_LOBES: [CieLobe; 2] = [
    lobe(1.217, 437.0, 0.0845, 0.0278),
    lobe(0.681, 459.0, 0.0385, 0.0725),
];

/// CIE XYZ to linear sRGB (IEC 61966-2-1:1999, the encoding's matrix; D65 white, rows
/// R, G, B).
pub const XYZ_TO_LINEAR_SRGB: [[f32; 3]; 3] = [
    [3.2406, -1.5372, -0.4986],
    [-0.9689, 1.8758, 0.0415],
    [0.0557, -0.2040, 1.0570],
];

/// Per-channel scale of the clipped linear sRGB of a wavelength: the reciprocal of the
/// channel's mean over [`SPECTRUM_MIN_UM`, `SPECTRUM_MAX_UM`] of
/// `max(xyz_to_linear_srgb(cie_xyz(l)), 0)`, so that [`wavelength_rgb`] averages to
/// exactly 1 per channel (integrated in f64 by the midpoint rule over 400 000 intervals;
/// the test `flat_spectrum_integrates_to_white` recomputes it).
pub const SPECTRAL_RGB_SCALE: [f32; 3] = [2.2722244, 3.4646618, 3.660385];

/// An upper bound of every channel of [`wavelength_rgb`] (its largest is 6.95, blue at
/// 450 nm; tested): how much brighter than its emitted flux a channel of a spectral photon
/// can get, which the fixed-point quanta allow for.
pub const MAX_CHANNEL_WEIGHT: f32 = 7.0;

/// The sequence value in [0, 1) of photon `index` for seed `seed`: point `index` of the
/// R1 sequence, rotated by `pcg_hash(seed)`, in 0.32 fixed point
/// (`index * WAVELENGTH_STEP + pcg_hash(seed) mod 2^32`), to float as every random number
/// ([`u32_to_unit_f32`]).
#[inline]
pub fn spectral_sample(seed: u32, index: u32) -> f32 {
    u32_to_unit_f32(
        index
            .wrapping_mul(WAVELENGTH_STEP)
            .wrapping_add(pcg_hash(seed)),
    )
}

/// The wavelength (micrometres) at fraction `u` in [0, 1] of the sampled range:
/// `SPECTRUM_MIN_UM + u * SPECTRUM_WIDTH_UM`.
#[inline]
pub fn wavelength_at(u: f32) -> f32 {
    SPECTRUM_MIN_UM + u * SPECTRUM_WIDTH_UM
}

/// One lobe of the fit at `nm` nanometres (Wyman 2013, the piecewise Gaussian
/// `g(lambda; mu, sigma_1, sigma_2)`).
#[inline]
pub fn cie_lobe(nm: f32, l: &CieLobe) -> f32 {
    let inv_sigma = if nm < l.mean_nm {
        l.inv_sigma_below
    } else {
        l.inv_sigma_above
    };
    let t = (nm - l.mean_nm) * inv_sigma;
    l.weight * (-0.5 * t * t).exp()
}

/// The CIE 1931 2-degree colour-matching functions (x-bar, y-bar, z-bar) at
/// `wavelength_um` micrometres, in Wyman 2013's multi-lobe fit (see the module doc for
/// its error). Lobes are summed in their listed order.
#[inline]
pub fn cie_xyz(wavelength_um: f32) -> Vec3 {
    let nm = wavelength_um * 1000.0;
    let x = cie_lobe(nm, &CIE_X_LOBES[0])
        + cie_lobe(nm, &CIE_X_LOBES[1])
        + cie_lobe(nm, &CIE_X_LOBES[2]);
    let y = cie_lobe(nm, &CIE_Y_LOBES[0]) + cie_lobe(nm, &CIE_Y_LOBES[1]);
    let z = cie_lobe(nm, &CIE_Z_LOBES[0]) + cie_lobe(nm, &CIE_Z_LOBES[1]);
    Vec3::new(x, y, z)
}

/// CIE XYZ to linear sRGB ([`XYZ_TO_LINEAR_SRGB`]), each row summed left to right.
#[inline]
pub fn xyz_to_linear_srgb(xyz: Vec3) -> Vec3 {
    let m = &XYZ_TO_LINEAR_SRGB;
    Vec3::new(
        m[0][0] * xyz.x + m[0][1] * xyz.y + m[0][2] * xyz.z,
        m[1][0] * xyz.x + m[1][1] * xyz.y + m[1][2] * xyz.z,
        m[2][0] * xyz.x + m[2][1] * xyz.y + m[2][2] * xyz.z,
    )
}

/// The linear sRGB weight of light of wavelength `wavelength_um` (micrometres): its
/// colour-matched sRGB clipped at 0 and scaled per channel by [`SPECTRAL_RGB_SCALE`], so
/// that its mean over the sampled range is (1, 1, 1). Non-negative and finite for every
/// finite wavelength (zero far outside the range).
#[inline]
pub fn wavelength_rgb(wavelength_um: f32) -> Vec3 {
    let rgb = xyz_to_linear_srgb(cie_xyz(wavelength_um)).max(Vec3::ZERO);
    rgb * Vec3::from(SPECTRAL_RGB_SCALE)
}

/// A photon's wavelength (micrometres) and flux after its first dispersive surface, from
/// its flux `flux` there, under `mode` (one of [`dispersion_mode`]; any other value means
/// spectral): [`dispersion_mode::SPECTRAL`] gives photon `index` of seed `seed` the
/// wavelength `wavelength_at(spectral_sample(seed, index))` and the flux
/// `flux * wavelength_rgb(wavelength)`; [`dispersion_mode::THREE_BANDS`] keeps channel
/// `c = min(floor(3 xi), 2)` only, x3 (`xi` uniform in [0, 1)), with that channel's
/// wavelength. Either way the expected flux of each channel is `flux`'s.
#[inline]
pub fn disperse(flux: Vec3, mode: u32, seed: u32, index: u32, xi: f32) -> (f32, Vec3) {
    if mode == dispersion_mode::THREE_BANDS {
        let c = ((xi * 3.0) as usize).min(2);
        let mut one = [0.0; 3];
        one[c] = flux[c] * 3.0;
        return (CHANNEL_WAVELENGTH_UM[c], Vec3::from(one));
    }
    let wavelength = wavelength_at(spectral_sample(seed, index));
    (wavelength, flux * wavelength_rgb(wavelength))
}

/// Lane `lane` (0, 1 or 2) of the deterministic split at a photon's first dispersive
/// surface (the trace variant's `fresnel_split`): its wavelength (micrometres) and flux.
/// [`dispersion_mode::SPECTRAL`]: the three lanes stratify the range in thirds, lane `k`
/// at `wavelength_at((k + spectral_sample(seed, index)) / 3)` with a third of
/// `flux * wavelength_rgb(wavelength)`; [`dispersion_mode::THREE_BANDS`]: lane `c` keeps
/// channel `c` of `flux` with its wavelength (Vanderstichelen 2021). The lanes' expected
/// fluxes add up to `flux` per channel.
#[inline]
pub fn split_lane(flux: Vec3, mode: u32, seed: u32, index: u32, lane: u32) -> (f32, Vec3) {
    let c = (lane as usize).min(2);
    if mode == dispersion_mode::THREE_BANDS {
        let mut one = [0.0; 3];
        one[c] = flux[c];
        return (CHANNEL_WAVELENGTH_UM[c], Vec3::from(one));
    }
    let wavelength = wavelength_at((c as f32 + spectral_sample(seed, index)) * ONE_THIRD);
    (wavelength, flux * wavelength_rgb(wavelength) * ONE_THIRD)
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    /// The CIE 1931 2-degree standard observer at 5 nm, 380 to 780 nm (CIE 15:2004's
    /// table): nm, x-bar, y-bar, z-bar.
    const CIE_1931_5NM: [[f64; 4]; 81] = [
        [380.0, 0.001368, 0.000039, 0.006450],
        [385.0, 0.002236, 0.000064, 0.010550],
        [390.0, 0.004243, 0.000120, 0.020050],
        [395.0, 0.007650, 0.000217, 0.036210],
        [400.0, 0.014310, 0.000396, 0.067850],
        [405.0, 0.023190, 0.000640, 0.110200],
        [410.0, 0.043510, 0.001210, 0.207400],
        [415.0, 0.077630, 0.002180, 0.371300],
        [420.0, 0.134380, 0.004000, 0.645600],
        [425.0, 0.214770, 0.007300, 1.039050],
        [430.0, 0.283900, 0.011600, 1.385600],
        [435.0, 0.328500, 0.016840, 1.622960],
        [440.0, 0.348280, 0.023000, 1.747060],
        [445.0, 0.348060, 0.029800, 1.782600],
        [450.0, 0.336200, 0.038000, 1.772110],
        [455.0, 0.318700, 0.048000, 1.744100],
        [460.0, 0.290800, 0.060000, 1.669200],
        [465.0, 0.251100, 0.073900, 1.528100],
        [470.0, 0.195360, 0.090980, 1.287640],
        [475.0, 0.142100, 0.112600, 1.041900],
        [480.0, 0.095640, 0.139020, 0.812950],
        [485.0, 0.058950, 0.169300, 0.616200],
        [490.0, 0.032010, 0.208020, 0.465180],
        [495.0, 0.014700, 0.258600, 0.353300],
        [500.0, 0.004900, 0.323000, 0.272000],
        [505.0, 0.002400, 0.407300, 0.212300],
        [510.0, 0.009300, 0.503000, 0.158200],
        [515.0, 0.029100, 0.608200, 0.111700],
        [520.0, 0.063270, 0.710000, 0.078250],
        [525.0, 0.109600, 0.793200, 0.057250],
        [530.0, 0.165500, 0.862000, 0.042160],
        [535.0, 0.225750, 0.914850, 0.029840],
        [540.0, 0.290400, 0.954000, 0.020300],
        [545.0, 0.359700, 0.980300, 0.013400],
        [550.0, 0.433450, 0.994950, 0.008750],
        [555.0, 0.512050, 1.000000, 0.005750],
        [560.0, 0.594500, 0.995000, 0.003900],
        [565.0, 0.678400, 0.978600, 0.002750],
        [570.0, 0.762100, 0.952000, 0.002100],
        [575.0, 0.842500, 0.915400, 0.001800],
        [580.0, 0.916300, 0.870000, 0.001650],
        [585.0, 0.978600, 0.816300, 0.001400],
        [590.0, 1.026300, 0.757000, 0.001100],
        [595.0, 1.056700, 0.694900, 0.001000],
        [600.0, 1.062200, 0.631000, 0.000800],
        [605.0, 1.045600, 0.566800, 0.000600],
        [610.0, 1.002600, 0.503000, 0.000340],
        [615.0, 0.938400, 0.441200, 0.000240],
        [620.0, 0.854450, 0.381000, 0.000190],
        [625.0, 0.751400, 0.321000, 0.000100],
        [630.0, 0.642400, 0.265000, 0.000050],
        [635.0, 0.541900, 0.217000, 0.000030],
        [640.0, 0.447900, 0.175000, 0.000020],
        [645.0, 0.360800, 0.138200, 0.000010],
        [650.0, 0.283500, 0.107000, 0.000000],
        [655.0, 0.218700, 0.081600, 0.000000],
        [660.0, 0.164900, 0.061000, 0.000000],
        [665.0, 0.121200, 0.044580, 0.000000],
        [670.0, 0.087400, 0.032000, 0.000000],
        [675.0, 0.063600, 0.023200, 0.000000],
        [680.0, 0.046770, 0.017000, 0.000000],
        [685.0, 0.032900, 0.011920, 0.000000],
        [690.0, 0.022700, 0.008210, 0.000000],
        [695.0, 0.015840, 0.005723, 0.000000],
        [700.0, 0.011359, 0.004102, 0.000000],
        [705.0, 0.008111, 0.002929, 0.000000],
        [710.0, 0.005790, 0.002091, 0.000000],
        [715.0, 0.004109, 0.001484, 0.000000],
        [720.0, 0.002899, 0.001047, 0.000000],
        [725.0, 0.002049, 0.000740, 0.000000],
        [730.0, 0.001440, 0.000520, 0.000000],
        [735.0, 0.001000, 0.000361, 0.000000],
        [740.0, 0.000690, 0.000249, 0.000000],
        [745.0, 0.000476, 0.000172, 0.000000],
        [750.0, 0.000332, 0.000120, 0.000000],
        [755.0, 0.000235, 0.000085, 0.000000],
        [760.0, 0.000166, 0.000060, 0.000000],
        [765.0, 0.000117, 0.000042, 0.000000],
        [770.0, 0.000083, 0.000030, 0.000000],
        [775.0, 0.000059, 0.000021, 0.000000],
        [780.0, 0.000042, 0.000015, 0.000000],
    ];

    /// [`cie_xyz`] in f64 from the same (f32) coefficients.
    fn cie_xyz_f64(nm: f64) -> [f64; 3] {
        let sum = |lobes: &[CieLobe]| -> f64 {
            lobes
                .iter()
                .map(|l| {
                    let mu = l.mean_nm as f64;
                    let s = if nm < mu {
                        l.inv_sigma_below
                    } else {
                        l.inv_sigma_above
                    } as f64;
                    let t = (nm - mu) * s;
                    l.weight as f64 * (-0.5 * t * t).exp()
                })
                .sum()
        };
        [sum(&CIE_X_LOBES), sum(&CIE_Y_LOBES), sum(&CIE_Z_LOBES)]
    }

    /// Clipped linear sRGB of `nm` in f64, before the scale.
    fn clipped_rgb_f64(nm: f64) -> [f64; 3] {
        let c = cie_xyz_f64(nm);
        std::array::from_fn(|i| {
            let m = XYZ_TO_LINEAR_SRGB[i];
            (m[0] as f64 * c[0] + m[1] as f64 * c[1] + m[2] as f64 * c[2]).max(0.0)
        })
    }

    #[test]
    fn fit_error_against_the_cie_table() {
        // The bounds the module doc states: largest absolute error per function over the
        // 81 tabulated wavelengths (the fit itself evaluated in f32).
        let mut worst = [0.0f64; 3];
        for row in CIE_1931_5NM {
            let f = cie_xyz(row[0] as f32 / 1000.0);
            for k in 0..3 {
                worst[k] = worst[k].max((f[k] as f64 - row[k + 1]).abs());
            }
        }
        eprintln!("largest error: {worst:?}");
        assert!(worst[0] < 0.014, "x-bar {}", worst[0]);
        assert!(worst[1] < 0.0074, "y-bar {}", worst[1]);
        assert!(worst[2] < 0.0222, "z-bar {}", worst[2]);
    }

    #[test]
    fn flat_spectrum_integrates_to_white() {
        // 1. The scale constants are the reciprocal means of the clipped channels
        //    (midpoint rule in f64, 400 000 intervals of 1 pm: the integrand is piecewise
        //    smooth with a few kinks, so the rule errs by ~h^2 f'' ~ 1e-12 relative), to the
        //    f32 rounding of the constants (6e-8 relative) and beyond.
        let n = 400_000;
        let h = 400.0 / n as f64;
        let mut sum = [0.0f64; 3];
        for i in 0..n {
            let c = clipped_rgb_f64(380.0 + (i as f64 + 0.5) * h);
            for k in 0..3 {
                sum[k] += c[k];
            }
        }
        for k in 0..3 {
            let scale = n as f64 / sum[k];
            let rel = (scale / SPECTRAL_RGB_SCALE[k] as f64 - 1.0).abs();
            assert!(
                rel < 1e-7,
                "channel {k}: scale {scale} vs {}",
                SPECTRAL_RGB_SCALE[k]
            );
        }
        // 2. The f32 function's mean over a fine grid is white: each evaluation errs by a
        //    few ulp of the sum of its terms' magnitudes (exp 1-3 ulp, ~6 products and sums)
        //    which is at most ~2x the channel's value where it matters, so ~1e-6 relative;
        //    the scale constants add 6e-8. 1e-5 bounds it.
        let n = 100_000;
        let mut mean = [0.0f64; 3];
        for i in 0..n {
            let u = (i as f64 + 0.5) / n as f64;
            let w = wavelength_rgb((0.38 + 0.4 * u) as f32);
            for k in 0..3 {
                mean[k] += w[k] as f64 / n as f64;
            }
        }
        for (k, m) in mean.iter().enumerate() {
            assert!((m - 1.0).abs() < 1e-5, "channel {k}: mean {m}");
        }
    }

    #[test]
    fn sequence_stratifies_and_weights_average_to_one() {
        // Koksma-Hlawka in one dimension: |mean_N w - integral w| <= V(w) D*_N, with V the
        // total variation of w over the range and D*_N the star discrepancy of the N
        // sequence values, both computed here.
        let variation = {
            let mut v = [0.0f64; 3];
            let mut prev = wavelength_rgb(SPECTRUM_MIN_UM);
            for i in 1..=40_000 {
                let w = wavelength_rgb(wavelength_at(i as f32 / 40_000.0));
                for k in 0..3 {
                    v[k] += (w[k] - prev[k]).abs() as f64;
                }
                prev = w;
            }
            v
        };
        for seed in [0u32, 1, 0xdead_beef] {
            for n in [64u32, 1000, 1 << 16] {
                let mut u: Vec<f64> = (0..n).map(|i| spectral_sample(seed, i) as f64).collect();
                u.sort_by(f64::total_cmp);
                let d = u
                    .iter()
                    .enumerate()
                    .map(|(i, &x)| ((i as f64 + 1.0) / n as f64 - x).max(x - i as f64 / n as f64))
                    .fold(0.0, f64::max);
                // the golden-ratio sequence: D*_N well under (1 + ln N) / N
                assert!(
                    d <= (1.0 + (n as f64).ln()) / n as f64,
                    "seed {seed}, N {n}: D* {d}"
                );
                let mut mean = [0.0f64; 3];
                for i in 0..n {
                    let w = wavelength_rgb(wavelength_at(spectral_sample(seed, i)));
                    for k in 0..3 {
                        mean[k] += w[k] as f64 / n as f64;
                    }
                }
                for k in 0..3 {
                    // + 1e-5: the f32 weights' own error (flat_spectrum_integrates_to_white)
                    let bound = variation[k] * d + 1e-5;
                    assert!(
                        (mean[k] - 1.0).abs() <= bound,
                        "seed {seed}, N {n}, channel {k}: mean {} (bound {bound})",
                        mean[k]
                    );
                }
            }
        }
    }

    #[test]
    fn neighbouring_photons_spread_over_the_spectrum() {
        for seed in [3u32, 77] {
            for i in 0..1000u32 {
                let (a, b) = (spectral_sample(seed, i), spectral_sample(seed, i + 1));
                // consecutive points lie 0.618 or 0.382 apart (mod 1), up to 2^-24 rounding
                let d = (b - a).rem_euclid(1.0);
                assert!(
                    (d - 0.618_034).abs() < 1e-6 || (d - 0.381_966).abs() < 1e-6,
                    "{d}"
                );
            }
        }
    }

    #[test]
    fn weights_stay_under_their_bound() {
        let mut worst = 0.0f32;
        for i in 0..=400_000 {
            worst = worst.max(wavelength_rgb(wavelength_at(i as f32 / 400_000.0)).max_element());
        }
        assert!(worst > 6.9 && worst < MAX_CHANNEL_WEIGHT, "{worst}");
    }

    #[test]
    fn ends_of_the_range() {
        assert_eq!(wavelength_at(0.0), SPECTRUM_MIN_UM);
        assert_eq!(wavelength_at(1.0), SPECTRUM_MAX_UM);
        let largest = wavelength_at(u32_to_unit_f32(u32::MAX));
        // the top of the sequence rounds to the end of the range itself (a closed range)
        assert!(largest <= SPECTRUM_MAX_UM && largest > 0.7799);
        for wl in [SPECTRUM_MIN_UM, SPECTRUM_MAX_UM] {
            let w = wavelength_rgb(wl);
            assert!(w.is_finite() && w.min_element() >= 0.0, "{wl}: {w}");
            // the ends of the visible range carry little of any channel
            assert!(w.max_element() < 0.03, "{wl}: {w}");
        }
        // the split's lanes cover the three thirds
        let (a, _) = split_lane(Vec3::ONE, dispersion_mode::SPECTRAL, 5, 9, 0);
        let (c, _) = split_lane(Vec3::ONE, dispersion_mode::SPECTRAL, 5, 9, 2);
        assert!(a < 0.38 + 0.4 / 3.0 + 1e-6 && c >= 0.38 + 0.8 / 3.0 - 1e-6);
    }

    #[test]
    fn three_bands_keep_the_split_of_the_publication() {
        let f = Vec3::new(1.0, 2.0, 4.0);
        for (xi, c) in [(0.0f32, 0usize), (0.4, 1), (0.9, 2), (0.999_999_94, 2)] {
            let (wl, g) = disperse(f, dispersion_mode::THREE_BANDS, 1, 2, xi);
            assert_eq!(wl, CHANNEL_WAVELENGTH_UM[c]);
            let mut want = [0.0; 3];
            want[c] = f[c] * 3.0;
            assert_eq!(g, Vec3::from(want));
            let (wl, g) = split_lane(f, dispersion_mode::THREE_BANDS, 1, 2, c as u32);
            assert_eq!(wl, CHANNEL_WAVELENGTH_UM[c]);
            want[c] = f[c];
            assert_eq!(g, Vec3::from(want));
        }
    }

    proptest! {
        #[test]
        fn weights_are_finite_and_non_negative(wl in prop_oneof![
            Just(SPECTRUM_MIN_UM), Just(SPECTRUM_MAX_UM), 0.38f32..=0.78, 0.0f32..100.0,
            -100.0f32..0.0,
        ]) {
            let w = wavelength_rgb(wl);
            prop_assert!(w.is_finite() && w.min_element() >= 0.0, "{} -> {}", wl, w);
            let x = cie_xyz(wl);
            prop_assert!(x.is_finite());
        }

        #[test]
        fn dispersed_flux_is_finite_and_non_negative(
            flux in (0.0f32..1e30, 0.0f32..1e30, 0.0f32..1e30),
            mode in 0u32..3, seed: u32, index: u32, xi in 0.0f32..1.0, lane in 0u32..3,
        ) {
            let f = Vec3::new(flux.0, flux.1, flux.2);
            let (wl, g) = disperse(f, mode, seed, index, xi);
            prop_assert!((SPECTRUM_MIN_UM..=SPECTRUM_MAX_UM).contains(&wl));
            prop_assert!(g.is_finite() && g.min_element() >= 0.0, "{}", g);
            let (wl, g) = split_lane(f, mode, seed, index, lane);
            prop_assert!((SPECTRUM_MIN_UM..=SPECTRUM_MAX_UM).contains(&wl));
            prop_assert!(g.is_finite() && g.min_element() >= 0.0, "{}", g);
        }
    }
}
