//! Hierarchical sample warping by an importance pyramid: the wavelet importance sampling of
//! Clarberg, Jarosz, Akenine-Möller and Jensen ("Wavelet Importance Sampling", SIGGRAPH
//! 2005), as Smal 2019, section 24.2.1 (PhotonGi) uses it to pick reflective-shadow-map
//! texels in proportion to the power their photons carry, without normalising the map.
//!
//! The pyramid holds the Haar *scaling* coefficients of the importance map: level 0 is the
//! map (padded with zeros to a power-of-two square), each coarser level the 2x2 sums of
//! the one below, the last a single total (the coefficients up to the Haar transform's
//! constant factors, which cancel in every ratio used here). A sample `u` in `[0, 1)^2`
//! descends from the total to a texel: at each node it is first warped horizontally by
//! the ratio of the left column's coefficient to the node's (Smal 2019, Figure 24-3 c-d), then
//! vertically within the chosen column (e-f), and rescaled to `[0, 1)^2` inside the chosen
//! quarter, so a low-discrepancy sequence stays well distributed over the texels and the
//! leftover `u` places the sample inside its texel.
//!
//! The probability of a texel is the product of the ratios taken on the way down, which
//! equals `weight / total` in exact arithmetic; [`WarpedSample::probability`] is that
//! product (the probability the warp actually realises, so that dividing by it is
//! unbiased whatever the rounding of the sums). Sums are f32, as the shader ports keep
//! them.

use glam::Vec2;

/// An importance map as a pyramid of 2x2 sums (see the module doc).
#[derive(Clone, Debug, PartialEq)]
pub struct ImportancePyramid {
    /// Side of level 0 (a power of two, at least the map's width and height).
    pub side: u32,
    /// Level `k` holds `(side >> k)^2` sums, row-major; the last level is the total.
    pub levels: Vec<Vec<f32>>,
}

/// A warped sample: its texel of the importance map, the probability of that texel, and
/// where inside the texel it lies.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct WarpedSample {
    /// Texel `(x, y)` of level 0 (inside the map's own width and height: padding has zero
    /// weight and is never chosen).
    pub texel: (u32, u32),
    /// Probability of choosing `texel` (discrete, over the texels; the density over the
    /// map's `[0, 1)^2` domain is this times the texel count of the padded square).
    pub probability: f32,
    /// The sample's position inside the texel, in `[0, 1)^2`.
    pub within: Vec2,
}

/// Why an importance map cannot be warped by.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ImportanceError {
    /// The weights do not fill the stated size.
    #[error("importance map of {width}x{height} texels needs {expected} weights, got {got}")]
    Size {
        /// Map width (texels).
        width: u32,
        /// Map height (texels).
        height: u32,
        /// `width * height`.
        expected: usize,
        /// Weights given.
        got: usize,
    },
    /// A weight is negative, NaN or infinite (an importance is a power, never below 0).
    #[error("importance weight {index} is {value}: weights must be finite and >= 0")]
    Weight {
        /// Row-major index of the weight.
        index: usize,
        /// Its value.
        value: f32,
    },
}

/// The largest f32 below 1: where a rescaled sample that rounded up to 1 is put back.
const ONE_MINUS_ULP: f32 = 1.0 - f32::EPSILON / 2.0;

/// One warp step: `u` in `[0, 1)` goes to the first part with probability `p` (in
/// `[0, 1]`), and is rescaled to `[0, 1)` inside the part it went to. Returns (first part,
/// rescaled `u`, the chosen part's probability).
#[inline]
pub fn warp_split(u: f32, p: f32) -> (bool, f32, f32) {
    if u < p {
        (true, (u / p).min(ONE_MINUS_ULP), p)
    } else {
        let q = 1.0 - p;
        (false, ((u - p) / q).clamp(0.0, ONE_MINUS_ULP), q)
    }
}

/// `part / whole`, 0 when the whole is 0 (a node without weight is never entered).
#[inline]
pub fn warp_ratio(part: f32, whole: f32) -> f32 {
    if whole > 0.0 {
        (part / whole).clamp(0.0, 1.0)
    } else {
        0.0
    }
}

impl ImportancePyramid {
    /// The pyramid of a `width x height` importance map (row-major `weights`, each finite
    /// and >= 0).
    pub fn new(weights: &[f32], width: u32, height: u32) -> Result<Self, ImportanceError> {
        let expected = width as usize * height as usize;
        if weights.len() != expected || expected == 0 {
            return Err(ImportanceError::Size {
                width,
                height,
                expected,
                got: weights.len(),
            });
        }
        if let Some((index, &value)) = weights
            .iter()
            .enumerate()
            .find(|(_, w)| !(w.is_finite() && **w >= 0.0))
        {
            return Err(ImportanceError::Weight { index, value });
        }
        let side = width.max(height).next_power_of_two();
        let mut base = vec![0.0f32; side as usize * side as usize];
        for y in 0..height as usize {
            let row = &weights[y * width as usize..(y + 1) * width as usize];
            base[y * side as usize..y * side as usize + width as usize].copy_from_slice(row);
        }
        let mut levels = vec![base];
        let mut s = side;
        while s > 1 {
            let below = levels.last().expect("level 0");
            let h = s / 2;
            let mut up = vec![0.0f32; h as usize * h as usize];
            for y in 0..h as usize {
                for x in 0..h as usize {
                    let at = |dx: usize, dy: usize| below[(2 * y + dy) * s as usize + 2 * x + dx];
                    // columns first, as the warp reads them
                    up[y * h as usize + x] = (at(0, 0) + at(0, 1)) + (at(1, 0) + at(1, 1));
                }
            }
            levels.push(up);
            s = h;
        }
        Ok(ImportancePyramid { side, levels })
    }

    /// The map's total weight.
    pub fn total(&self) -> f32 {
        self.levels.last().map_or(0.0, |l| l[0])
    }

    /// Warps `u` in `[0, 1)^2` to a texel chosen with probability proportional to its
    /// weight; `None` when the map has no weight.
    pub fn warp(&self, mut u: Vec2) -> Option<WarpedSample> {
        if !(self.total() > 0.0) {
            return None;
        }
        let (mut x, mut y) = (0u32, 0u32);
        let mut probability = 1.0f32;
        for k in (0..self.levels.len() - 1).rev() {
            let level = &self.levels[k];
            let s = (self.side >> k) as usize;
            let (cx, cy) = (2 * x as usize, 2 * y as usize);
            let a = level[cy * s + cx];
            let b = level[cy * s + cx + 1];
            let c = level[(cy + 1) * s + cx];
            let d = level[(cy + 1) * s + cx + 1];
            // horizontally by the left column's share, then vertically in that column
            let (left, ux, px) = warp_split(u.x, warp_ratio(a + c, (a + c) + (b + d)));
            let (top, bottom) = if left { (a, c) } else { (b, d) };
            let (upper, uy, py) = warp_split(u.y, warp_ratio(top, top + bottom));
            u = Vec2::new(ux, uy);
            probability *= px * py;
            x = 2 * x + (!left) as u32;
            y = 2 * y + (!upper) as u32;
        }
        Some(WarpedSample {
            texel: (x, y),
            probability,
            within: u,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The 2D Hammersley point `i` of `n` (a low-discrepancy set, as Smal 2019 warps).
    fn hammersley(i: u32, n: u32) -> Vec2 {
        Vec2::new(
            (i as f32 + 0.5) / n as f32,
            i.reverse_bits() as f32 / 4294967296.0,
        )
    }

    fn map(w: u32, h: u32) -> Vec<f32> {
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32, (i / w) as f32);
                // a smooth field with a bright spot and dark (zero) texels
                let v =
                    (1.0 + (0.7 * x).sin() * (0.4 * y).cos()) * if i % 7 == 3 { 0.0 } else { 1.0 };
                v + if (x, y) == (2.0, 1.0) { 40.0 } else { 0.0 }
            })
            .collect()
    }

    #[test]
    fn bad_maps_are_refused_by_name() {
        assert!(matches!(
            ImportancePyramid::new(&[1.0; 5], 2, 3),
            Err(ImportanceError::Size { .. })
        ));
        let e = ImportancePyramid::new(&[1.0, f32::NAN, 0.0, 1.0], 2, 2).unwrap_err();
        assert!(matches!(e, ImportanceError::Weight { index: 1, .. }), "{e}");
        assert!(ImportancePyramid::new(&[1.0, -1.0], 2, 1).is_err());
        let empty = ImportancePyramid::new(&[0.0; 4], 2, 2).unwrap();
        assert_eq!(empty.warp(Vec2::splat(0.5)), None);
    }

    #[test]
    fn probabilities_are_the_weights_share() {
        let (w, h) = (13, 6);
        let m = map(w, h);
        let p = ImportancePyramid::new(&m, w, h).unwrap();
        let total: f64 = m.iter().map(|&v| v as f64).sum();
        assert!((p.total() as f64 - total).abs() <= 1e-5 * total);
        for i in 0..4096 {
            let s = p.warp(hammersley(i, 4096)).unwrap();
            let (x, y) = s.texel;
            assert!(x < w && y < h, "padding chosen: {:?}", s.texel);
            let weight = m[(y * w + x) as usize];
            assert!(weight > 0.0, "a zero-weight texel was chosen");
            let exact = weight as f64 / total;
            assert!(
                (s.probability as f64 - exact).abs() <= 1e-5 * exact,
                "{:?}: {} vs {exact}",
                s.texel,
                s.probability
            );
            assert!((0.0..1.0).contains(&s.within.x) && (0.0..1.0).contains(&s.within.y));
        }
    }

    #[test]
    fn a_low_discrepancy_set_lands_in_proportion_to_the_weights() {
        let (w, h) = (16, 16);
        let m = map(w, h);
        let p = ImportancePyramid::new(&m, w, h).unwrap();
        let n = 1 << 16;
        let mut hits = vec![0u32; (w * h) as usize];
        for i in 0..n {
            let s = p.warp(hammersley(i, n)).unwrap();
            hits[(s.texel.1 * w + s.texel.0) as usize] += 1;
        }
        let total: f64 = m.iter().map(|&v| v as f64).sum();
        for (i, (&k, &v)) in hits.iter().zip(&m).enumerate() {
            let expected = n as f64 * v as f64 / total;
            // a warped low-discrepancy set: counts within a few of their expectation
            assert!(
                (k as f64 - expected).abs() <= 3.0 + 0.02 * expected,
                "texel {i}: {k} vs {expected}"
            );
        }
    }

    #[test]
    fn dividing_by_the_probability_is_unbiased() {
        // the estimator f(texel) / p(texel) of sum_t f(t), over one warped set, for an f
        // unlike the importance (a stand-in for the irradiance the first bounce carries)
        let (w, h) = (12, 9);
        let m = map(w, h);
        let f: Vec<f64> = (0..w * h)
            .map(|i| m[i as usize] as f64 * (1.0 + (i % 5) as f64))
            .collect();
        let exact: f64 = f.iter().sum();
        let p = ImportancePyramid::new(&m, w, h).unwrap();
        let n = 1 << 15;
        let est: f64 = (0..n)
            .map(|i| {
                let s = p.warp(hammersley(i, n)).unwrap();
                f[(s.texel.1 * w + s.texel.0) as usize] / s.probability as f64
            })
            .sum::<f64>()
            / n as f64;
        assert!((est - exact).abs() <= 2e-3 * exact, "{est} vs {exact}");
    }
}
