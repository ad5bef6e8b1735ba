//! PhotonGi's reflective shadow maps (Smal 2019, section 24.2.1): per light a set of faces
//! (square pinhole views from the light, rendered by the ray-traced G-buffer kernel),
//! each texel the first surface the light meets through it and the flux that leaves it;
//! an importance pyramid per face ([`crate::math::wavelet_warp`]'s 2x2 sums, stored flat);
//! and the warp of a low-discrepancy set through it to photons whose flux carries the
//! sampling probability.
//!
//! Parameterisation (Smal 2019 leaves it open; stated here): a point light gets six
//! 90-degree faces (a cube around it), a spot light one face whose half field of view is
//! its outer cone angle when that is below 60 degrees, else the cube's faces; a
//! directional light one orthographic face over the scene's bounding sphere
//! (`GpuCamera::orthographic`). A texel's flux: `I x falloff x dw`, `dw` the texel's solid
//! angle (`view_plane_texel_weight` times the centre texel's `(2 tan_x / side) (2 tan_y /
//! side)`), or for the orthographic face `E x` the texel's area ([`ortho_texel_flux`]), W
//! per channel.
//!
//! Flat pyramid layout of one face of side `R` (a power of two): level `k` holds
//! `(R >> k)^2` sums, row-major, starting at [`level_offset`]`(R, k)`; a face takes
//! [`pyramid_len`]`(R)` floats and face `f` starts at `f * pyramid_len(R)`.
//!
//! Units: world space, scene units; flux in W per channel.

use glam::{Vec2, Vec3};

/// What an RSM texel saw ([`RsmTexel::kind`](crate::device::layout::RsmTexel)).
pub mod rsm_texel_kind {
    /// Nothing (the light's ray escaped), or no flux reached it.
    pub const NONE: u32 = 0;
    /// A diffuse surface: the photon bounces diffusely from it.
    pub const DIFFUSE: u32 = 1;
    /// A mirror or dielectric: the photon is traced from the light through it.
    pub const SPECULAR: u32 = 2;
}

/// How `sample_rsm` chooses texels (`RsmParams::sampling`).
pub mod rsm_sampling {
    /// By importance, `luminance(flux x albedo)` (Smal 2019, section 24.2.1): the default.
    pub const IMPORTANCE: u32 = 0;
    /// Every texel that leaves flux equally likely: the estimate the importance warp must
    /// agree with in the mean (`photon_gi_frames.rs`' unbiasedness test), at a higher
    /// variance.
    pub const UNIFORM: u32 = 1;
}

/// A level-0 texel's entry in the importance pyramid: its importance `imp` (> 0, finite:
/// the texel leaves flux) under [`rsm_sampling::IMPORTANCE`], 1 under
/// [`rsm_sampling::UNIFORM`].
#[inline]
pub fn pyramid_weight(sampling: u32, imp: f32) -> f32 {
    if sampling == rsm_sampling::UNIFORM {
        1.0
    } else {
        imp
    }
}

/// Rec. 709 luminance of a linear colour (the importance of a texel is the luminance of
/// its leaving flux, Smal 2019, section 24.2.1).
#[inline]
pub fn luminance(c: Vec3) -> f32 {
    0.2126 * c.x + 0.7152 * c.y + 0.0722 * c.z
}

/// Levels of the pyramid of a face of side `side` (a power of two): `log2(side) + 1`.
#[inline]
pub fn level_count(side: u32) -> u32 {
    side.max(1).trailing_zeros() + 1
}

/// Offset of level `level` in a face's flat pyramid: `sum (side >> j)^2` over `j < level`.
#[inline]
pub fn level_offset(side: u32, level: u32) -> u32 {
    let mut off = 0;
    for j in 0..level {
        let s = side >> j;
        off += s * s;
    }
    off
}

/// Floats of one face's flat pyramid.
#[inline]
pub fn pyramid_len(side: u32) -> u32 {
    level_offset(side, level_count(side))
}

/// One level-`k` sum from level `k - 1` of the same face: `(a + c) + (b + d)` of the 2x2
/// block under texel `(x, y)` (columns first, as [`crate::math::wavelet_warp`] sums and
/// warps). `below(x, y)` reads level `k - 1`.
#[inline]
pub fn pyramid_sum(below: impl Fn(u32, u32) -> f32, x: u32, y: u32) -> f32 {
    let (cx, cy) = (2 * x, 2 * y);
    (below(cx, cy) + below(cx, cy + 1)) + (below(cx + 1, cy) + below(cx + 1, cy + 1))
}

/// The flux arriving through texel `(ix, iy)` of a face (W per channel): `intensity x
/// falloff x` the texel's solid angle (see the module doc).
#[inline]
pub fn texel_arriving_flux(
    intensity: Vec3,
    falloff: f32,
    ix: u32,
    iy: u32,
    side: u32,
    tan_half_fov: f32,
) -> Vec3 {
    let centre = (2.0 * tan_half_fov / side as f32) * (2.0 * tan_half_fov / side as f32);
    let w = crate::math::sampling::view_plane_texel_weight(
        ix,
        iy,
        side,
        side,
        tan_half_fov,
        tan_half_fov,
    );
    intensity * (falloff * (centre * w))
}

/// The flux arriving through a texel of a directional light's orthographic face (W per
/// channel): irradiance (W/m^2, on a plane facing the light) times the texel's area,
/// `(2 half / side)^2` for a face `2 half` scene units wide.
#[inline]
pub fn ortho_texel_flux(irradiance: Vec3, side: u32, half: f32) -> Vec3 {
    let edge = 2.0 * half / side as f32;
    irradiance * (edge * edge)
}

/// Origin of a photon on its way from a directional light to world point `p`: `p`
/// projected onto the orthographic face's plane (the plane through `plane_point`
/// orthogonal to the unit `forward`).
#[inline]
pub fn ortho_origin(p: Vec3, plane_point: Vec3, forward: Vec3) -> Vec3 {
    p - forward * (p - plane_point).dot(forward)
}

/// Radical inverse of `i` in base 2 (van der Corput), in `[0, 1)`.
#[inline]
pub fn radical_inverse2(i: u32) -> f32 {
    (i.reverse_bits() >> 8) as f32 * (1.0 / 16_777_216.0)
}

/// Point `i` of the `n`-point Hammersley set rotated by `shift` (Cranley-Patterson, one
/// rotation per light and frame so that frames differ and averages converge), in
/// `[0, 1)^2`.
#[inline]
pub fn hammersley(i: u32, n: u32, shift: Vec2) -> Vec2 {
    let u = Vec2::new((i as f32 + 0.5) / n.max(1) as f32, radical_inverse2(i)) + shift;
    Vec2::new(wrap_unit(u.x), wrap_unit(u.y))
}

/// The Hammersley sample that thread `t` of a launch over `n` samples traces (and so
/// the RSM photon it reads): a bijection of `0 .. n` onto itself that puts a warp's 32
/// samples in one small box of `[0, 1)^2` instead of a column across it. Point `i` is
/// `(i / n, radical_inverse2(i))`: neighbouring `i` share `u.x` but scatter over `u.y`,
/// whose top bits are `i`'s reversed low bits. Over the largest power of two `2^m <= n`
/// the order moves `t`'s low `m - k` bits to the top (`k = (m - 5) / 2`), so that a run
/// of `2^(m - k)` threads shares `i`'s low `k` bits (one `2^-k` stripe of `u.y`) and
/// steps through neighbouring high bits (`u.x` within `32 * 2^k / n` for a warp): the box
/// of 32 points' share of the square. Threads past `2^m` (and launches under 64) keep
/// their own index. A path depends on its sample index alone, so the order changes which
/// thread traces a sample, never what it does. Measured on the H200: `trace_indirect`
/// 8.92 -> 8.56 ms at Smal 2019's high setting, 1.66 -> 1.56 at its low (OpenCL).
#[inline]
pub fn coherent_sample_order(t: u32, n: u32) -> u32 {
    if n < 64 {
        return t;
    }
    let m = 31 - n.leading_zeros();
    if t >= 1 << m {
        return t;
    }
    let k = (m - 5) / 2;
    let hi = m - k;
    ((t & ((1 << hi) - 1)) << k) | (t >> hi)
}

/// Photons a launch of `trace_indirect` from the RSM photons traces: those of its chunk
/// `chunk_first .. chunk_first + chunk_size` below `count` (the light's photons); thread
/// `t` traces photon `chunk_first + coherent_sample_order(t, chunk_photons(..))`.
#[inline]
pub fn chunk_photons(count: u32, chunk_first: u32, chunk_size: u32) -> u32 {
    count.saturating_sub(chunk_first).min(chunk_size)
}

/// `x` (in `[0, 2)`) wrapped into `[0, 1)`.
#[inline]
fn wrap_unit(x: f32) -> f32 {
    let y = if x >= 1.0 { x - 1.0 } else { x };
    y.min(ONE_MINUS_ULP)
}

const ONE_MINUS_ULP: f32 = 1.0 - f32::EPSILON / 2.0;

/// A sample warped to a texel of one of a light's faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RsmChoice {
    /// Face (0-based among the light's faces).
    pub face: u32,
    /// Texel `(x, y)` of the face.
    pub texel: (u32, u32),
    /// Probability of this face and texel among all of the light's texels.
    pub probability: f32,
    /// The leftover sample inside the texel, in `[0, 1)^2` (it picks the bounce
    /// direction).
    pub within: Vec2,
}

/// Warps `u` to a face and texel of a light with `faces` faces of side `side`:
/// `read(face, index)` reads the face's flat pyramid. The face is chosen by `u.x` in
/// proportion to the faces' totals (each split `total_f / sum of the totals from f on`,
/// sums taken from the last face back), then the texel inside it by the pyramid
/// (`wavelet_warp`'s steps: horizontally by the left column's share, then vertically).
/// The probability is the product of the ratios taken (the one realised, so dividing by
/// it is unbiased whatever the rounding). `None` when no face has weight.
pub fn warp_rsm(
    read: impl Fn(u32, u32) -> f32,
    faces: u32,
    side: u32,
    mut u: Vec2,
) -> Option<RsmChoice> {
    use crate::math::wavelet_warp::{warp_ratio, warp_split};
    let top = level_offset(side, level_count(side) - 1);
    // from the last face back: rest_f = total_f + rest_(f+1)
    let mut rests = [0.0f32; 7];
    for f in (0..faces.min(6)).rev() {
        rests[f as usize] = read(f, top) + rests[f as usize + 1];
    }
    if !(rests[0] > 0.0) {
        return None;
    }
    let mut probability = 1.0f32;
    let mut face = faces.min(6) - 1;
    for f in 0..faces.min(6) - 1 {
        let (first, ux, pf) = warp_split(u.x, warp_ratio(read(f, top), rests[f as usize]));
        u.x = ux;
        probability *= pf;
        if first {
            face = f;
            break;
        }
    }
    let (mut x, mut y) = (0u32, 0u32);
    for k in (0..level_count(side) - 1).rev() {
        let s = side >> k;
        let base = level_offset(side, k);
        let at = |dx: u32, dy: u32| read(face, base + (2 * y + dy) * s + 2 * x + dx);
        let (a, b, c, d) = (at(0, 0), at(1, 0), at(0, 1), at(1, 1));
        let (left, ux, px) = warp_split(u.x, warp_ratio(a + c, (a + c) + (b + d)));
        let (top_row, bottom) = if left { (a, c) } else { (b, d) };
        let (upper, uy, py) = warp_split(u.y, warp_ratio(top_row, top_row + bottom));
        u = Vec2::new(ux, uy);
        probability *= px * py;
        x = 2 * x + (!left) as u32;
        y = 2 * y + (!upper) as u32;
    }
    (probability > 0.0).then_some(RsmChoice {
        face,
        texel: (x, y),
        probability,
        within: u,
    })
}

/// Cosine-weighted direction about unit `n` from `u` in `[0, 1)^2` (Malley: a uniform
/// disc point lifted to the hemisphere); pdf `cos / pi`.
#[inline]
pub fn cosine_hemisphere(u: Vec2, n: Vec3) -> Vec3 {
    let r = u.x.sqrt();
    let phi = std::f32::consts::TAU * u.y;
    let z = (1.0 - u.x).max(0.0).sqrt();
    crate::math::sampling::to_world(Vec3::new(r * phi.cos(), r * phi.sin(), z), n)
}

/// Jensen's Russian roulette at a diffuse bounce (Jensen 2001, as Smal 2019, section 24.2.2):
/// the path survives with probability `q = max(flux x albedo) / max(flux)` (clamped to
/// `[0, 1]`) and carries `flux x albedo / q`, which keeps its expectation. `xi` uniform in
/// `[0, 1)`. `None`: absorbed.
#[inline]
pub fn russian_roulette(flux: Vec3, albedo: Vec3, xi: f32) -> Option<Vec3> {
    let reflected = flux * albedo;
    let m = flux.max_element();
    if !(m > 0.0) {
        return None;
    }
    let q = (reflected.max_element() / m).clamp(0.0, 1.0);
    if xi < q {
        Some(reflected / q)
    } else {
        None
    }
}

#[cfg(test)]
mod tests {
    #[test]
    fn coherent_sample_order_is_a_bijection_that_keeps_a_warp_together() {
        for n in [1u32, 63, 64, 65, 100, 1000, 1024, 4097, 1 << 16, 1_000_003] {
            let mut seen = vec![false; n as usize];
            for t in 0..n {
                let i = coherent_sample_order(t, n);
                assert!(i < n && !seen[i as usize], "n {n}: t {t} -> {i}");
                seen[i as usize] = true;
            }
        }
        // a warp of the 2^20-sample order: one 2^-7 stripe of u.y, 32 neighbouring u.x steps
        let n = 1u32 << 20;
        let pts: Vec<Vec2> = (0..32)
            .map(|t| hammersley(coherent_sample_order(t, n), n, Vec2::ZERO))
            .collect();
        let (lo, hi) = pts
            .iter()
            .fold((Vec2::ONE, Vec2::ZERO), |(a, b), p| (a.min(*p), b.max(*p)));
        assert!(hi.y - lo.y < 1.0 / 128.0, "{lo} {hi}");
        assert!(hi.x - lo.x < 32.0 * 128.0 / n as f32, "{lo} {hi}");
    }

    use super::*;
    use crate::math::wavelet_warp::ImportancePyramid;

    fn flat_pyramid(weights: &[f32], side: u32) -> Vec<f32> {
        let p = ImportancePyramid::new(weights, side, side).unwrap();
        p.levels.concat()
    }

    #[test]
    fn the_flat_layout_holds_every_level() {
        assert_eq!(pyramid_len(1), 1);
        assert_eq!(pyramid_len(4), 16 + 4 + 1);
        assert_eq!(level_offset(8, 2), 64 + 16);
        assert_eq!(level_count(256), 9);
    }

    /// One face warps exactly as `wavelet_warp` does, probabilities included.
    #[test]
    fn one_face_warps_as_the_pyramid() {
        let side = 8;
        let w: Vec<f32> = (0..64).map(|i| ((i * 37) % 11) as f32).collect();
        let p = ImportancePyramid::new(&w, side, side).unwrap();
        let flat = flat_pyramid(&w, side);
        for i in 0..64 {
            let u = hammersley(i, 64, Vec2::new(0.3, 0.7));
            let a = p.warp(u).unwrap();
            let b = warp_rsm(|_, k| flat[k as usize], 1, side, u).unwrap();
            assert_eq!(
                (a.texel, a.probability, a.within),
                (b.texel, b.probability, b.within)
            );
        }
    }

    /// Over several faces, each texel's probability is its weight over the total, and
    /// dividing by it is unbiased (sum over a Hammersley set of weight / probability).
    #[test]
    fn faces_are_chosen_in_proportion_to_their_weight() {
        let side = 4;
        let faces: Vec<Vec<f32>> = (0..3)
            .map(|f| {
                (0..16)
                    .map(|i| ((i * (f + 3)) % 5) as f32 * (f + 1) as f32)
                    .collect()
            })
            .collect();
        let total: f32 = faces.iter().flatten().sum();
        let flats: Vec<Vec<f32>> = faces.iter().map(|w| flat_pyramid(w, side)).collect();
        let n = 4096;
        let mut est = 0.0f64;
        for i in 0..n {
            let u = hammersley(i, n, Vec2::new(0.11, 0.57));
            let c = warp_rsm(|f, k| flats[f as usize][k as usize], 3, side, u).unwrap();
            let w = faces[c.face as usize][(c.texel.1 * side + c.texel.0) as usize];
            assert!(w > 0.0, "a texel without weight was chosen");
            assert!((c.probability / (w / total) - 1.0).abs() < 1e-5);
            est += (w / c.probability) as f64;
        }
        assert!((est / n as f64 / total as f64 - 1.0).abs() < 1e-5);
    }

    #[test]
    fn roulette_keeps_the_expected_flux() {
        let flux = Vec3::new(2.0, 1.0, 0.5);
        let albedo = Vec3::new(0.5, 0.8, 0.2);
        let n = 10_000;
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            if let Some(f) = russian_roulette(flux, albedo, (i as f32 + 0.5) / n as f32) {
                sum += f;
            }
        }
        let mean = sum / n as f32;
        assert!((mean - flux * albedo).abs().max_element() < 1e-3, "{mean}");
        // an albedo-1 wall never ends a path by roulette
        assert_eq!(russian_roulette(flux, Vec3::ONE, 0.999_999), Some(flux));
    }

    #[test]
    fn cosine_directions_stay_in_the_hemisphere() {
        let n = Vec3::new(0.3, -0.4, 0.866).normalize();
        for i in 0..256 {
            let d = cosine_hemisphere(hammersley(i, 256, Vec2::ZERO), n);
            assert!((d.length() - 1.0).abs() < 1e-5 && d.dot(n) >= 0.0);
        }
    }
}
