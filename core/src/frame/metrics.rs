//! Error metrics against a reference image: all over the pixels that receive
//! caustics, the mask taken from the reference. Images are linear radiance
//! (W/(sr m^2) per channel); sums are f64.
//!
//! - relative MSE: `sum_mask sum_rgb (x - r)^2 / sum_mask sum_rgb r^2` (dimensionless;
//!   0 is perfect, 1 is as wrong as a black image);
//! - RMSE: `sqrt(mean_mask mean_rgb (x - r)^2)` in radiance units;
//! - peak ratio: `max_mask lum(x) / max_mask lum(r)` (a focused caustic kept: 1);
//! - bias and variance over repeated seeds: relative bias
//!   `sum_mask sum_rgb (mean_k x_k - r) / sum_mask sum_rgb r` and relative variance
//!   `sum_mask sum_rgb var_k(x_k) / sum_mask sum_rgb r^2` (sample variance, K - 1);
//! - FLIP (Andersson et al. 2020, LDR-FLIP through the maintained `nv-flip` crate, behind
//!   core's `flip` feature): both
//!   images tone-mapped with [`crate::frame::image::tone_map`] at the exposure that maps the
//!   reference's 99th-percentile masked luminance to 1, FLIP's mean over the mask.

#[cfg(feature = "flip")]
use crate::frame::image::tone_map;
use crate::frame::image::{luminance, Image};
use serde::Serialize;

/// Pixels that receive caustics: reference luminance above `MASK_FRACTION` of its
/// maximum, which keeps out the odd far-away photon of a converged deposit.
pub const MASK_FRACTION: f32 = 1e-4;

/// The caustic mask of a reference.
#[derive(Clone, Debug, PartialEq)]
pub struct CausticMask {
    /// Per pixel (row-major): whether it belongs to the mask.
    pub inside: Vec<bool>,
    /// Number of pixels in the mask.
    pub count: usize,
}

impl CausticMask {
    /// The pixels whose reference luminance exceeds [`MASK_FRACTION`] of its maximum.
    pub fn from_reference(r: &Image) -> CausticMask {
        let lum: Vec<f32> = r
            .pixels
            .iter()
            .map(|p| luminance([p[0], p[1], p[2]]))
            .collect();
        let max = lum.iter().copied().fold(0.0f32, f32::max);
        let inside: Vec<bool> = lum
            .iter()
            .map(|&l| max > 0.0 && l > MASK_FRACTION * max)
            .collect();
        let count = inside.iter().filter(|&&b| b).count();
        CausticMask { inside, count }
    }

    fn pixels<'a>(&'a self, img: &'a Image) -> impl Iterator<Item = &'a [f32; 4]> + 'a {
        img.pixels
            .iter()
            .zip(&self.inside)
            .filter(|(_, &m)| m)
            .map(|(p, _)| p)
    }
}

/// Error of one image against a reference.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct ErrorStats {
    /// Relative MSE over the mask (dimensionless; 0 perfect, 1 as wrong as a black image).
    pub relative_mse: f64,
    /// W/(sr m^2).
    pub rmse: f64,
    /// Mean LDR-FLIP over the mask (0 identical, 1 maximally different); `None` when the
    /// mask is empty.
    pub flip: Option<f64>,
    /// Pixels in the caustic mask.
    pub mask_pixels: usize,
}

/// Both images of one size, each holding its `width * height` pixels.
fn same_size(x: &Image, r: &Image) -> bool {
    let whole = |i: &Image| i.pixels.len() as u64 == i.width as u64 * i.height as u64;
    x.width == r.width && x.height == r.height && whole(x) && whole(r)
}

/// Relative MSE over the mask (0 with an empty or black mask).
pub fn relative_mse(x: &Image, r: &Image, mask: &CausticMask) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (p, q) in mask.pixels(x).zip(mask.pixels(r)) {
        for c in 0..3 {
            num += (p[c] as f64 - q[c] as f64).powi(2);
            den += (q[c] as f64).powi(2);
        }
    }
    if den > 0.0 {
        num / den
    } else {
        0.0
    }
}

/// RMSE over the mask (radiance units).
pub fn rmse(x: &Image, r: &Image, mask: &CausticMask) -> f64 {
    let mut sum = 0.0f64;
    for (p, q) in mask.pixels(x).zip(mask.pixels(r)) {
        for c in 0..3 {
            sum += (p[c] as f64 - q[c] as f64).powi(2);
        }
    }
    if mask.count == 0 {
        0.0
    } else {
        (sum / (3 * mask.count) as f64).sqrt()
    }
}

/// Peak ratio: the largest luminance of `x` over the mask divided by the reference's
/// largest luminance (1 is a peak kept exactly; a filter that blurs a focused caustic
/// gives < 1). 0 when the reference is black.
pub fn peak_ratio(x: &Image, r: &Image, mask: &CausticMask) -> f64 {
    let peak = |img: &Image| {
        mask.pixels(img)
            .map(|p| luminance([p[0], p[1], p[2]]) as f64)
            .fold(0.0f64, f64::max)
    };
    let pr = peak(r);
    if pr > 0.0 {
        peak(x) / pr
    } else {
        0.0
    }
}

/// Relative bias and variance of repeated renders (different seeds) against a reference.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct BiasVariance {
    /// `sum (mean_k x_k - r) / sum r` over the mask and rgb (dimensionless, signed).
    pub relative_bias: f64,
    /// `sum var_k(x_k) / sum r^2` over the mask and rgb (sample variance, dimensionless).
    pub relative_variance: f64,
    /// Number of renders `K`.
    pub samples: usize,
}

/// Relative bias and variance of `samples` (renders with different seeds) against
/// reference `r` over `mask` (0 for both when the mask's reference is black).
pub fn bias_variance(samples: &[Image], r: &Image, mask: &CausticMask) -> BiasVariance {
    let k = samples.len();
    let (mut bias, mut var, mut sum_r, mut sum_r2) = (0.0f64, 0.0f64, 0.0f64, 0.0f64);
    for (i, q) in r.pixels.iter().enumerate() {
        if !mask.inside[i] {
            continue;
        }
        for (c, &rc) in q[..3].iter().enumerate() {
            let rc = rc as f64;
            let vals = samples.iter().map(|s| s.pixels[i][c] as f64);
            let mean = vals.clone().sum::<f64>() / k.max(1) as f64;
            bias += mean - rc;
            if k > 1 {
                var += vals.map(|v| (v - mean).powi(2)).sum::<f64>() / (k - 1) as f64;
            }
            sum_r += rc;
            sum_r2 += rc * rc;
        }
    }
    BiasVariance {
        relative_bias: if sum_r > 0.0 { bias / sum_r } else { 0.0 },
        relative_variance: if sum_r2 > 0.0 { var / sum_r2 } else { 0.0 },
        samples: k,
    }
}

/// The exposure at which the reference's 99th-percentile masked luminance maps to 1.
pub fn flip_exposure(r: &Image, mask: &CausticMask) -> f32 {
    let mut lum: Vec<f32> = mask
        .pixels(r)
        .map(|p| luminance([p[0], p[1], p[2]]))
        .collect();
    if lum.is_empty() {
        return 1.0;
    }
    lum.sort_by(f32::total_cmp);
    let p99 = lum[(lum.len() - 1) * 99 / 100];
    if p99 > 0.0 && p99.is_finite() {
        1.0 / p99
    } else {
        1.0
    }
}

#[cfg(feature = "flip")]
fn ldr(img: &Image, exposure: f32) -> Vec<u8> {
    img.pixels
        .iter()
        .flat_map(|p| {
            [
                tone_map(p[0], exposure),
                tone_map(p[1], exposure),
                tone_map(p[2], exposure),
            ]
        })
        .collect()
}

/// Mean LDR-FLIP over the mask; `None` without the `flip` feature (nv-flip's C++).
#[cfg(not(feature = "flip"))]
pub fn flip(_x: &Image, _r: &Image, _mask: &CausticMask) -> Option<f64> {
    None
}

/// Mean LDR-FLIP over the mask.
#[cfg(feature = "flip")]
pub fn flip(x: &Image, r: &Image, mask: &CausticMask) -> Option<f64> {
    if mask.count == 0 || !same_size(x, r) {
        return None;
    }
    let e = flip_exposure(r, mask);
    let (w, h) = (x.width, x.height);
    let test = nv_flip::FlipImageRgb8::with_data(w, h, &ldr(x, e));
    let reference = nv_flip::FlipImageRgb8::with_data(w, h, &ldr(r, e));
    let map = nv_flip::flip(reference, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let values = map.to_vec();
    let sum: f64 = values
        .iter()
        .zip(&mask.inside)
        .filter(|(_, &m)| m)
        .map(|(v, _)| *v as f64)
        .sum();
    Some(sum / mask.count as f64)
}

/// Every metric of `x` against reference `r` (images of the same size).
pub fn compare(x: &Image, r: &Image) -> ErrorStats {
    if !same_size(x, r) {
        return ErrorStats::default();
    }
    let mask = CausticMask::from_reference(r);
    ErrorStats {
        relative_mse: relative_mse(x, r, &mask),
        rmse: rmse(x, r, &mask),
        flip: flip(x, r, &mask),
        mask_pixels: mask.count,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(v: &[f32]) -> Image {
        Image::new(
            v.len() as u32,
            1,
            v.iter().map(|&x| [x, x, x, 1.0]).collect(),
        )
    }

    #[test]
    fn identical_images_have_zero_error_and_black_has_relative_mse_one() {
        let r = img(&[0.0, 1.0, 2.0, 4.0]);
        let e = compare(&r, &r);
        assert_eq!(e.relative_mse, 0.0);
        assert_eq!(e.rmse, 0.0);
        assert_eq!(e.mask_pixels, 3);
        assert!(e.flip.is_none_or(|f| f < 1e-6));
        assert_eq!(e.flip.is_some(), cfg!(feature = "flip"));
        let black = img(&[0.0; 4]);
        assert!((relative_mse(&black, &r, &CausticMask::from_reference(&r)) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bias_and_variance_of_known_samples() {
        let r = img(&[1.0, 1.0]);
        let mask = CausticMask::from_reference(&r);
        // samples 0.9 and 1.3 per pixel: mean 1.1 (bias +10%), variance 0.08
        let bv = bias_variance(&[img(&[0.9, 0.9]), img(&[1.3, 1.3])], &r, &mask);
        assert!((bv.relative_bias - 0.1).abs() < 1e-6, "{bv:?}");
        assert!((bv.relative_variance - 0.08).abs() < 1e-6, "{bv:?}");
    }
}
