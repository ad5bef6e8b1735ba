//! Edge-aware filtering of screen-space irradiance (Smal 2019, section 24.4, PhotonGi; meant
//! to be shared with the caustic techniques): the edge-stopping weights (Eqs. 10-11), the
//! temporal exponential moving average (Eqs. 12-13), the A-Trous wavelet iterations with
//! variance clipping of their detail coefficients (Eqs. 14-18) and the shading-normal
//! correction (Eq. 20). Screen space; irradiance in W/m^2 per channel.

use glam::Vec3;

/// The chapter's filter constants.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilterConstants {
    /// Depth weight's `sigma_z` (Eq. 10; "sigma_z = 1 was found to work well").
    pub sigma_z: f32,
    /// Normal weight's exponent `sigma_n` (Eq. 11; 32).
    pub sigma_n: f32,
    /// Largest temporal weight of the history (Eq. 13's 0.95).
    pub alpha_max: f32,
    /// Guard of Eq. 10's denominator against a zero depth gradient, relative to the depth
    /// (so the weight does not depend on the scene's scale).
    pub epsilon: f32,
}

impl Default for FilterConstants {
    fn default() -> Self {
        FilterConstants {
            sigma_z: 1.0,
            sigma_n: 32.0,
            alpha_max: 0.95,
            epsilon: 1e-3,
        }
    }
}

/// Eq. 10: `w_z(P, Q) = exp(-|z(P) - z(Q)| / (sigma_z |grad z(P) . (P - Q)| + eps z(P)))`,
/// with `depth_step` = `grad z(P) . (P - Q)`, the depth change the plane through `P`
/// predicts over the pixel offset to `Q` (view depth, scene units; the guard `eps` is
/// relative to the depth).
#[inline]
pub fn depth_weight(z_p: f32, z_q: f32, depth_step: f32, c: &FilterConstants) -> f32 {
    (-(z_p - z_q).abs() / (c.sigma_z * depth_step.abs() + c.epsilon * z_p.abs())).exp()
}

/// The depth step Eq. 10 tolerates for a nearest-pixel reprojection: half the largest
/// view-depth difference between the pixel (depth `z`) and its four neighbours
/// (`neighbours`, depth <= 0 for a neighbour that is no receiver or off the image, which
/// is skipped): the reprojected point lies within half a pixel of the history pixel's
/// centre.
#[inline]
pub fn reprojection_depth_step(z: f32, neighbours: [f32; 4]) -> f32 {
    let mut step = 0.0f32;
    for n in neighbours {
        if n > 0.0 {
            step = step.max((n - z).abs());
        }
    }
    0.5 * step
}

/// The view-depth gradient at a pixel of depth `z` (per pixel, x then y) from its
/// neighbours' depths `[left, right, up, down]` (<= 0: no receiver there, skipped): central
/// differences, one-sided where one neighbour is missing, 0 where both are.
#[inline]
pub fn depth_gradient(z: f32, n: [f32; 4]) -> (f32, f32) {
    let axis = |lo: f32, hi: f32| {
        if lo > 0.0 && hi > 0.0 {
            0.5 * (hi - lo)
        } else if hi > 0.0 {
            hi - z
        } else if lo > 0.0 {
            z - lo
        } else {
            0.0
        }
    };
    (axis(n[0], n[1]), axis(n[2], n[3]))
}

/// Eq. 11: `w_n(P, Q) = max(0, n(P) . n(Q))^sigma_n` (unit normals).
#[inline]
pub fn normal_weight(n_p: Vec3, n_q: Vec3, c: &FilterConstants) -> f32 {
    n_p.dot(n_q).max(0.0).powf(c.sigma_n)
}

/// Eq. 13: the history's weight `alpha = 0.95 w_z(P, Q) w_n(P, Q)` for the current pixel
/// `P` and its reprojection `Q` into the previous frame (0 on a camera cut or where the
/// reprojection leaves the image: the caller passes weights of 0).
#[inline]
pub fn temporal_alpha(w_z: f32, w_n: f32, c: &FilterConstants) -> f32 {
    (c.alpha_max * w_z * w_n).clamp(0.0, c.alpha_max)
}

/// Eq. 12: the exponential moving average `(1 - alpha) E + alpha E_history`.
#[inline]
pub fn blend_with_history(current: Vec3, history: Vec3, alpha: f32) -> Vec3 {
    current * (1.0 - alpha) + history * alpha
}

/// Eq. 14's 1D kernel `h` of one 5x5 A-Trous iteration (`h(Q)` is the product of the two
/// axes' taps), as the chapter gives it; the iteration normalises by `sum h w`, so its
/// scale cancels.
pub const ATROUS_TAPS: [f32; 5] = [1.0 / 8.0, 1.0 / 4.0, 1.0 / 2.0, 1.0 / 4.0, 1.0 / 8.0];

/// Pixel offset of tap `k` (0..5) in A-Trous iteration `i`: `(k - 2) 2^i` (the taps spread
/// by doubling, the samples between them skipped; Smal 2019, Figure 24-5).
#[inline]
pub fn atrous_offset(k: u32, iteration: u32) -> i32 {
    (k as i32 - 2) << iteration
}

/// Eq. 18's bound on iteration `i`'s detail coefficients: `gamma` standard deviations of
/// the irradiance within the spatial kernel (`mean`, `mean_sq`: the kernel's weighted
/// mean and mean of squares per channel), the variance clipping of Salvi [12].
#[inline]
pub fn detail_bound(mean: Vec3, mean_sq: Vec3, gamma: f32) -> Vec3 {
    (mean_sq - mean * mean).max(Vec3::ZERO).powf(0.5) * gamma
}

/// Eq. 18 at the last iteration: `E_final = s_n - sum_i clamp(d_i, -b_i, b_i)`, floored at
/// 0 (an irradiance or radiance is never negative; the clipped sum can overshoot where a
/// lone bright pixel meets a dark neighbourhood).
#[inline]
pub fn atrous_final(s_n: Vec3, clipped_details: Vec3) -> Vec3 {
    (s_n - clipped_details).max(Vec3::ZERO)
}

/// Eqs. 16-18: the detail coefficient `d_i = s_{i+1} - s_i` of one iteration, clipped to
/// `[-b_i, b_i]`. Summed over the iterations and subtracted from the last scaling
/// coefficient `s_n` it gives `E_final = s_n - sum_i clamp(d_i, -b_i, b_i)`: without
/// clipping that is `s_0` again (Eq. 17), with it the filter keeps what the variance says
/// is signal.
#[inline]
pub fn clipped_detail(s_i: Vec3, s_next: Vec3, bound: Vec3) -> Vec3 {
    (s_next - s_i).clamp(-bound, bound)
}

/// Eq. 20's factor on `E_final f_BRDF`: the filtered mean light direction `w_i` (unit)
/// against the shading normal instead of the geometric one,
/// `min(max(0, w_i . n_s) / (w_i . n_g + eps), s_max)`.
#[inline]
pub fn shading_normal_factor(w_i: Vec3, n_s: Vec3, n_g: Vec3, s_max: f32, eps: f32) -> f32 {
    let num = w_i.dot(n_s).max(0.0);
    let den = w_i.dot(n_g).max(0.0) + eps;
    (num / den).min(s_max)
}

/// What a splat contribution of flux `flux` (W per channel, `E x` the pixel's area)
/// arriving from unit light direction `to_light` adds to the direction map: its
/// luminance `w` as the weight (the map's hit distance) and `w (to_light + 1) / 2` per
/// axis (the map's flux channels; non-negative, so the unsigned fixed-point sums hold
/// them). Eq. 20's `w_i` is the power-weighted mean of the splats' directions.
#[inline]
pub fn light_direction_deposit(flux: Vec3, to_light: Vec3) -> (Vec3, f32) {
    let w = crate::math::rsm::luminance(flux);
    ((to_light + Vec3::ONE) * (0.5 * w), w)
}

/// Least per-axis difference between a pixel's shading normal and its (decoded) geometric
/// normal for which Eq. 20 is applied: 1e-3, ten times the snorm16 octahedral code's
/// error (~1e-4), so a flat surface (shading = geometric normal) is never corrected. Below
/// it the factor departs from 1 by less than ~1e-3 (the light's tangent times it).
pub const SHADING_DEPARTURE: f32 = 1e-3;

/// Whether Eq. 20 applies at a pixel: its shading normal `n_s` departs from its geometric
/// normal `n_g` by more than [`SHADING_DEPARTURE`] on some axis (exact operations, so every
/// backend decides alike on the same G-buffer). `splat_photons` deposits light directions
/// only there, `shading_normal_correction` corrects only there.
#[inline]
pub fn shading_normal_departs(n_s: Vec3, n_g: Vec3) -> bool {
    (n_s - n_g).abs().max_element() > SHADING_DEPARTURE
}

/// The unit mean light direction from a pixel's direction sums: `d` holds the summed
/// `w (d + 1) / 2` per axis and `w` the summed weights (any common unit); the result is
/// `normalize(2 d - w)`, zero where the weights cancel or are zero.
#[inline]
pub fn mean_light_direction(d: Vec3, w: f32) -> Vec3 {
    (2.0 * d - Vec3::splat(w)).normalize_or_zero()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_direction_sums_give_back_the_mean_direction() {
        // two splats of weights 1 and 3 from directions a and b: the mean is along a + 3b
        let (a, b) = (Vec3::new(0.6, 0.8, 0.0), Vec3::Z);
        let (da, wa) = light_direction_deposit(Vec3::ONE, a);
        let (db, wb) = light_direction_deposit(Vec3::splat(3.0), b);
        let m = mean_light_direction(da + db, wa + wb);
        assert!((m - (a + 3.0 * b).normalize()).abs().max_element() < 1e-6);
        assert_eq!(mean_light_direction(Vec3::ZERO, 0.0), Vec3::ZERO);
        // Eq. 20 on a flat receiver (n_s = n_g) is 1 up to eps; a shading normal tilted by
        // 30 degrees from light along n_g gives cos 30
        let n = Vec3::Y;
        assert!((shading_normal_factor(n, n, n, 10.0, 1e-4) - 1.0).abs() < 2e-4);
        let tilted = Vec3::new(0.5, 0.75f32.sqrt(), 0.0);
        let f = shading_normal_factor(n, tilted, n, 10.0, 1e-4);
        assert!((f - 0.75f32.sqrt() / (1.0 + 1e-4)).abs() < 1e-6);
        // grazing light on the geometric normal: clamped at s_max
        let grazing = Vec3::new(1.0, 1e-6, 0.0).normalize();
        assert_eq!(shading_normal_factor(grazing, tilted, n, 4.0, 1e-4), 4.0);
    }

    #[test]
    fn weights_stop_at_edges() {
        let c = FilterConstants::default();
        assert_eq!(depth_weight(2.0, 2.0, 0.0, &c), 1.0);
        // on a slanted plane the predicted change costs e^-1 at sigma_z = 1
        assert!((depth_weight(2.0, 2.5, 0.5, &c) - (-0.5f32 / 0.502).exp()).abs() < 1e-6);
        assert!(depth_weight(2.0, 3.0, 0.0, &c) < 1e-30);
        assert_eq!(normal_weight(Vec3::Z, Vec3::Z, &c), 1.0);
        assert_eq!(normal_weight(Vec3::Z, -Vec3::Z, &c), 0.0);
        assert!(normal_weight(Vec3::Z, Vec3::new(0.0, 0.2, 1.0).normalize(), &c) < 0.6);
        assert_eq!(temporal_alpha(1.0, 1.0, &c), 0.95);
        assert_eq!(temporal_alpha(0.0, 1.0, &c), 0.0);
        let e = blend_with_history(Vec3::ONE, Vec3::ZERO, 0.95);
        assert!((e - Vec3::splat(0.05)).abs().max_element() < 1e-7);
    }

    #[test]
    fn unclipped_details_give_back_the_input() {
        // Eq. 17: s_n - sum d_i = s_0 when nothing is clipped
        let s = [
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(1.5, 1.0, 2.0),
            Vec3::new(1.2, 1.1, 2.5),
        ];
        let big = Vec3::splat(1e9);
        let d: Vec3 = (0..2).map(|i| clipped_detail(s[i], s[i + 1], big)).sum();
        assert!((s[2] - d - s[0]).abs().max_element() < 1e-6);
        // a zero bound keeps the smooth s_n
        let d0: Vec3 = (0..2)
            .map(|i| clipped_detail(s[i], s[i + 1], Vec3::ZERO))
            .sum();
        assert_eq!(s[2] - d0, s[2]);
        assert_eq!(
            detail_bound(Vec3::splat(2.0), Vec3::splat(5.0), 2.0),
            Vec3::splat(2.0)
        );
        assert_eq!(atrous_offset(0, 2), -8);
        assert_eq!(atrous_offset(4, 0), 2);
    }

    #[test]
    fn the_shading_normal_replaces_the_cosine() {
        let w = Vec3::new(0.0, 0.6, 0.8);
        assert!((shading_normal_factor(w, Vec3::Z, Vec3::Z, 4.0, 0.0) - 1.0).abs() < 1e-6);
        let ns = Vec3::new(0.0, 0.6, 0.8);
        assert!((shading_normal_factor(w, ns, Vec3::Z, 4.0, 0.0) - 1.25).abs() < 1e-6);
        assert_eq!(shading_normal_factor(w, -Vec3::Z, Vec3::Z, 4.0, 0.0), 0.0);
        assert_eq!(
            shading_normal_factor(Vec3::Y, Vec3::Y, Vec3::Z, 4.0, 1e-4),
            4.0
        );
    }
}
