//! Every tolerance of the suite, each with its argument. The per-kernel checks
//! ([`crate::kernels`]) and the whole-frame comparison ([`crate::techniques`]) take their
//! bounds from here, so that all of them can be weighed against the same facts.
//!
//! # Floating-point facts the tolerances rest on
//!
//! - f32 unit roundoff is `2^-24 ~ 6e-8` ([`F32_ROUNDOFF`]): a correctly rounded operation
//!   errs by at most that relative amount. Rust on the CPU rounds `+ - * /` and `sqrt`
//!   correctly and never contracts `a * b + c` into an FMA unless asked.
//! - OpenCL C 1.2 single precision (spec. section 7.4) allows `x / y` and `1 / x` 2.5 ulp,
//!   `sqrt` 3 ulp, `exp` 3 ulp, `sin`/`cos` 4 ulp and `pow` 16 ulp; GPU compilers contract
//!   `a * b + c` into FMAs (1 rounding instead of 2) and may flush subnormals to zero.
//!   WGSL and Vulkan SPIR-V give similar or looser bounds.
//! - So an expression of ~10 operations agrees across backends to ~10-30 ulp ~ 1e-6
//!   relative, unless it cancels (a difference of nearly equal numbers, a dot product of
//!   nearly orthogonal vectors), where the *absolute* error stays ~ulp of the operands.
//! - A ray whose direction differs by ~1e-6 follows the same path unless it passes within
//!   ~1e-6 (relative) of a discrete decision: a triangle edge between faces with different
//!   normals, a silhouette, a Fresnel choice `xi < F`, the total-internal-reflection
//!   boundary, a pixel boundary, a depth-test threshold. Refraction through curved
//!   surfaces amplifies a direction error by ~`1 + L / R` per interaction, so a long
//!   chain widens these bands; still only a small fraction of photon paths diverge
//!   ([`PATH_DIVERGENCE`]), and each diverged path changes a count by at most one photon
//!   and a flux by at most one photon's flux.
//! - Integer sums (the fixed-point photon map and counters) are exact and
//!   order-independent on every backend: inputs that agree give bitwise-equal sums.
//!
//! A tolerance is never widened to make a backend pass: a failure is a bug in
//! the backend, in the CPU reference, or in an argument here, to be understood first.

use crate::strategies::MIN_CURVATURE_RADIUS;
use caustica_core::scene::Scene;
use caustica_core::Dispersion;

/// f32 unit roundoff, `2^-24`.
pub const F32_ROUNDOFF: f64 = 5.960_464_477_539_063e-8;

/// `primary_gbuffer`: fraction of pixels whose material id must agree (99.5%).
///
/// A pixel's material can differ only where its camera ray passes within a few ulps of a
/// silhouette or of a triangle edge: a ray through an edge shared by two faces hits one of
/// them (the triangle test is watertight on every backend, Woop, Benthin and Wald 2013, as
/// Vulkan's hardware test is), but which one is a tie that a rounding difference in the
/// ray may break either way, and the faces' materials may differ. The camera ray is a handful of operations ending in a
/// normalisation (3-ulp sqrt, 2.5-ulp divide): directions agree to ~5e-7 rad, which at
/// these resolutions (~0.01 rad per pixel) is ~5e-5 of a pixel. For cameras in general
/// position the expected number of affected pixels is far below one per image; 0.5% is
/// the margin for edges that line up with pixel centres by symmetry (a whole row or
/// diagonal of exact ties: see [`BUILTIN_SIZE`] for the one the built-ins have, which the
/// fixed inputs avoid).
///
/// [`BUILTIN_SIZE`]: super::cases::BUILTIN_SIZE
pub const GBUFFER_MATERIAL_AGREEMENT: f64 = 0.995;

/// `primary_gbuffer`: positions, view depth and view distance must agree within
/// `GBUFFER_POSITION_REL * (t / max(|cos|, GBUFFER_MIN_COS) + |p|)`, where `t` is the view
/// distance, `cos` the cosine between the camera ray and the surface normal, `|p|` the
/// largest coordinate.
///
/// Argument: a ~5e-7 rad direction difference moves the hit point along the surface by
/// `t * 5e-7 / |cos|`; the ray/triangle test (two cross products, three dots, a ~2.5-ulp
/// reciprocal: ~10 ulp ~ 6e-7 relative) adds `t * 6e-7 / |cos|` (its determinant scales
/// with `cos`); interpolating the position from barycentrics adds ~3 ulp of `|p|`. Sum:
/// `~1.1e-6 * t / |cos| + 2e-7 * |p|`; 1e-5 leaves a 9x margin. Rays more grazing than
/// `GBUFFER_MIN_COS` get no further slack and count among the outliers
/// ([`GBUFFER_GEOMETRY_AGREEMENT`]).
pub const GBUFFER_POSITION_REL: f32 = 1e-5;
/// See [`GBUFFER_POSITION_REL`].
pub const GBUFFER_MIN_COS: f32 = 1e-3;

/// `primary_gbuffer`: how fast the interpolated shading normal can turn per scene unit
/// along a surface (rad per unit). Flat faces: 0 (normals agree to normalisation rounding,
/// ~3e-7). Smooth tessellated spheres: `1 / R`, and the smallest radius generated or built
/// in is [`MIN_CURVATURE_RADIUS`] = 0.1 (the pool's waves curve with radius >= 0.3), so 10;
/// twice that for margin. Normals must agree within `1e-5 + NORMAL_GRADIENT * position
/// tolerance`.
pub const NORMAL_GRADIENT: f32 = 2.0 / MIN_CURVATURE_RADIUS;

/// `primary_gbuffer`: the same for texture coordinates (uv per scene unit). The worst case
/// is a UV sphere's polar triangles, where u spans `1 / segments` over a ring edge of length
/// `2 pi R sin(pi / rings) / segments`: gradient `1 / (2 pi R sin(pi / rings))`, at most
/// ~12 for the generated spheres (R >= 0.1, <= 24 rings) and ~10 for the built-ins; 50
/// leaves a 4x margin.
pub const UV_GRADIENT: f32 = 50.0;

/// `primary_gbuffer`: among pixels with equal material, the fraction whose geometry must
/// agree within the tolerances above (99.9%). The rest are rays within a few ulps of an
/// edge between faces with different normals (a box or prism edge: the position agrees but
/// the normal jumps) or more grazing than `GBUFFER_MIN_COS`; as for materials, the
/// expected count is far below one pixel per image.
pub const GBUFFER_GEOMETRY_AGREEMENT: f64 = 0.999;

/// Fraction of photon paths that may diverge between two correct backends (1%).
///
/// Emission directions come from `sin`/`cos` (4 ulp in OpenCL) and a normalisation, so
/// they agree to a few 1e-7. A path diverges only where a perturbation of that size, grown
/// by ~`1 + L / R` per curved interaction, crosses a discrete decision (module docs):
/// per decision the chance is the band width over the decision variable's range, ~1e-6
/// for the first interactions and at most ~1e-3 after a dozen amplifying ones (the bounce
/// limit is 12). Expected divergence is therefore well below 0.1% of the paths; 1% is a
/// 10x margin. Each diverged path moves one photon (count +-1, flux +- one photon's flux),
/// hence [`divergence_allowance`].
pub const PATH_DIVERGENCE: f64 = 0.01;

/// Photon count difference allowed among `n` photons: `ceil(PATH_DIVERGENCE * n) + 2` (the
/// `+ 2`: one diverged path in each direction must not fail a case with a handful of
/// photons).
pub fn divergence_allowance(n: u64) -> u64 {
    (PATH_DIVERGENCE * n as f64).ceil() as u64 + 2
}

/// `trace_photons`: a photon of one backend *matches* when the other stored a photon
/// within `PHOTON_POSITION_REL * scene diagonal` whose flux agrees within
/// [`photon_flux_match_rel`]. A non-diverged path's landing point
/// differs by its initial ~1e-6 relative error times the chaotic amplification, ~3 per
/// curved interaction (`1 + L / R` with `L ~ 2R` inside a ball): <= 3^4 = 81 for the <= 4
/// interactions of nearly every stored photon, i.e. < 1e-4 relative; 1e-3 is a 10x margin.
/// Longer chains that stray further are part of the [`PATH_DIVERGENCE`] allowance.
pub const PHOTON_POSITION_REL: f32 = 1e-3;

/// `trace_photons`: fraction of each backend's photons that must match one of the other's
/// (99%, from [`PATH_DIVERGENCE`]), plus 2 photons of slack.
pub const PHOTON_MATCH: f64 = 1.0 - PATH_DIVERGENCE;

/// Relative flux tolerance of a photon match: [`PHOTON_FLUX_REL`] plus Beer-Lambert over
/// a path inside a medium whose length differs by up to twice the position tolerance `tol`
/// (entry and exit points each within `tol`): `exp(2 sigma_max tol) - 1`, `sigma_max` the
/// largest absorption coefficient of the scene. Channel choice (dispersion), mirror
/// reflectances and the Fresnel branch are the same on a non-diverged path.
pub fn photon_flux_match_rel(scene: &Scene, tol: f32) -> f32 {
    let sigma_max = scene
        .materials
        .values()
        .map(|m| match m {
            caustica_core::scene::Material::Dielectric { absorption, .. } => {
                absorption.max_element()
            }
            _ => 0.0,
        })
        .fold(0.0f32, f32::max);
    PHOTON_FLUX_REL as f32 + (2.0 * sigma_max * tol).exp_m1()
}

/// Relative flux difference of a non-diverged photon: at most 12 interactions, each a
/// Beer-Lambert `exp` (3 ulp) and a couple of multiplies: ~60 ulp ~ 4e-6; 1e-5 is the
/// bound used for flux sums on top of the diverged photons' whole flux.
pub const PHOTON_FLUX_REL: f64 = 1e-5;

/// Difference of any channel of a spectral photon's flux between two correct backends,
/// relative to the photon's largest channel, from its colour (`math::spectrum::
/// wavelength_rgb`): (a) evaluating the weight: each lobe `w exp(-x)` of the fit errs by
/// `(3 + 2x)` ulp from `exp` (Vulkan's bound; OpenCL's is 3) plus ~4 ulp from its
/// arguments and products, the matrix rows and scale add a few more, and a channel near
/// the clip cancels: at most 62 ulp of the largest channel over 380-780 nm (at 712 nm,
/// where red and green are both small), 7.4e-6; (b) the wavelength itself: `0.38 + 0.4 u`
/// and `1000 l` may each round differently where a device fuses the multiply-add, <= 2
/// ulp of the wavelength in nm (9.3e-5 nm at 780 nm), times the weight's steepest
/// relative slope, 0.149 / nm: 2.8e-5. Together 3.5e-5; 4e-5 bounds it
/// (`spectral_flux_rel_bounds_the_weights_error` recomputes both from core's constants).
/// The multiply by the weight and everything after it are [`PHOTON_FLUX_REL`]'s.
pub const SPECTRAL_FLUX_REL: f64 = 4e-5;

/// The most a spectral photon's channel sum can exceed its emitted channel sum, as a
/// factor: `max over l of (sum over c of wavelength_rgb(l)_c) / 3` (2.44, blue near 450 nm;
/// 1 for three bands and without dispersion), over a 0.01 nm grid, times 1.001: between
/// grid points the weight moves by at most its steepest relative slope (0.149 / nm, see
/// [`SPECTRAL_FLUX_REL`]) times 0.005 nm, 7.5e-4. Energy is conserved per channel only in
/// expectation (`math::spectrum`), so a frame's stored channel sum is bounded by its
/// emitted one times this.
pub fn spectral_sum_gain() -> f64 {
    use caustica_core::math::spectrum::{wavelength_at, wavelength_rgb};
    let n = 40_000;
    let max = (0..=n)
        .map(|i| {
            let w = wavelength_rgb(wavelength_at(i as f32 / n as f32));
            (w.x + w.y + w.z) as f64 / 3.0
        })
        .fold(1.0f64, f64::max);
    max * 1.001
}

/// How close two photons' fluxes must be for a match: each channel within `rel` of the
/// larger of the two values plus `spectral` of the larger photon's largest channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FluxMatch {
    /// Relative to the channel ([`photon_flux_match_rel`]).
    pub rel: f32,
    /// Relative to the photon's largest channel ([`SPECTRAL_FLUX_REL`] where photons take
    /// a spectral colour, else 0).
    pub spectral: f32,
}

impl FluxMatch {
    /// The tolerance of `scene`'s photons under `dispersion` with position tolerance
    /// `tol` (scene units).
    pub fn of(scene: &Scene, dispersion: Dispersion, tol: f32) -> FluxMatch {
        let spectral = dispersion == Dispersion::Spectral
            && scene.materials.values().any(|m| m.is_dispersive());
        FluxMatch {
            rel: photon_flux_match_rel(scene, tol),
            spectral: if spectral {
                SPECTRAL_FLUX_REL as f32
            } else {
                0.0
            },
        }
    }

    /// True when fluxes `a` and `b` match.
    pub fn close(&self, a: [f32; 3], b: [f32; 3]) -> bool {
        let largest = a.iter().chain(&b).fold(0.0f32, |m, x| m.max(x.abs()));
        (0..3).all(|c| {
            (a[c] - b[c]).abs() <= self.rel * a[c].abs().max(b[c].abs()) + self.spectral * largest
        })
    }

    /// Bound of the difference of one channel's sum over non-diverged photons whose
    /// channel sums are at most `channel` and whose sums over all channels are at most
    /// `all` (every photon's largest channel is at most its channel sum).
    pub fn sum_bound(&self, channel: f64, all: f64) -> f64 {
        PHOTON_FLUX_REL * channel + self.spectral as f64 * all
    }
}

/// `deposit_screen` on the same photons and G-buffer: fraction of photon-map texels that
/// must be bitwise equal (99.9%). The sums are integers, so a texel differs only when a
/// photon's outcome differs: its projected pixel coordinate (two dots and a 2.5-ulp
/// division) within a few ulps of a pixel boundary, its view depth within a few ulps of
/// the depth-test threshold, or its direction within a few ulps of perpendicular to the
/// normal. Each band is ~1e-6 of its variable's range, so ~1e-5 of the photons at most;
/// each changes at most two texels.
pub const DEPOSIT_TEXEL_AGREEMENT: f64 = 0.999;

/// `deposit_screen`: photons whose outcome may differ, as a fraction of the photons (see
/// [`DEPOSIT_TEXEL_AGREEMENT`]: ~1e-5 expected, 1e-3 allowed), plus 2.
pub const DEPOSIT_PHOTON_CHANGES: f64 = 1e-3;

/// `resolve_caustics` on bitwise-equal texels: relative radiance tolerance
/// `RESOLVE_REL + RESOLVE_COS_REL / max(|cos|, MIN_COSINE)`. Radiance is
/// `units * quantum * albedo / (pi * area)` with `area` from the pixel footprint (~6
/// operations, one division) and the obliquity `|ray . f| / |ray . n|`: u64 -> float
/// conversion 0.5 ulp, ~10 roundings plus two 2.5-ulp divisions and the camera ray's
/// normalisation: ~20 ulp ~ 1.2e-6, hence 1e-5. The dot `ray . n` has an absolute error of
/// a few ulps (~2.4e-7), a relative one of `2.4e-7 / |cos|`: hence 1e-6 / |cos|.
pub const RESOLVE_REL: f32 = 1e-5;
/// See [`RESOLVE_REL`].
pub const RESOLVE_COS_REL: f32 = 1e-6;

/// `tile_hit_distance`: relative tolerance. Integer sums of the same photon map are exact;
/// the mean is two conversions, a multiply and a 2.5-ulp division: ~4 ulp; 1e-5 is ~40x.
pub const TILE_REL: f32 = 1e-5;

/// `bilateral_gather` on the same inputs: relative tolerance per pixel and channel.
///
/// The output is a normalised weighted mean `sum(w x) / sum(w)` of non-negative inputs with
/// weights `exp(.) * exp(.) * pow(.)` (3 + 3 + 16 ulp in OpenCL, plus the products: ~25 ulp
/// ~ 1.5e-6 each). For non-negative terms a relative weight error `e` changes the mean by at
/// most `2 e` relative, and summing <= 33 taps in another order by at most ~33 ulp ~ 2e-6:
/// ~5e-6 in all, so 1e-5. Pixels whose radius `r` lies within 1e-5 of an integer are left
/// out: there `ceil(r)`, the number of taps, is not determined by floating point, and the
/// extra tap's weight `exp(-2 ceil(r)^2 / r^2) ~ 0.13` is not small.
pub const GATHER_REL: f32 = 1e-5;

/// `gather_footprint` and `density_gather` on the same inputs: a pixel and channel agree
/// when `|a - b| <= DENSITY_GATHER_REL * (max(|a|, |b|) + S)`, where `S` is the sum of the
/// magnitudes the pixel gathers from (its taps' inputs, unweighted; for `gather_footprint`
/// its own flux), converted like the output.
///
/// - The radius `sqrt(k a / c)` is computed from the same integers on both sides (the
///   window search is integer arithmetic on the bitwise-equal table): two exact
///   conversions, a product, a 2.5-ulp division and a 3-ulp sqrt, ~7 ulp ~ 4e-7.
/// - A tap's weight is `footprint_weight * edge`: the pixel-integrated Epanechnikov factor
///   `(3/4) (G(u_b) - G(u_a))`, `G(u) = u - u^3/3`, `u = (d +- 1/2) / r` (two 2.5-ulp
///   divisions, cubes, a difference of values <= 2/3) errs by ~10 ulp of 1 *absolutely*:
///   the difference cancels near the support's edge, where its relative error is
///   unbounded but its value, and so its contribution, is ~0 (the kernel is continuous
///   there, so unlike the bilateral gather no tap count is ambiguous); the edge weight
///   errs by ~25 ulp (`exp` 3, `pow` 16, products) relatively. Weights lie in `[0, 1]`, so
///   each tap's weight errs by <= ~2e-6 absolutely, the sum by <= 2e-6 `S`.
/// - The normaliser is such a sum over `n <= 33` taps (the pixel itself among them). Each
///   weight's absolute error is a few ulp of the `G` values it subtracts (<= 2/3), ~2e-7,
///   and a source's weights add up to ~1 inside a receiver (less only where the image
///   border or an edge cuts the support, which also removes those taps): relative error
///   ~`n` 2e-7 <= ~7e-6, plus the summation order.
/// - The last pass converts flux to radiance like `resolve_caustics` ([`RESOLVE_REL`],
///   [`RESOLVE_COS_REL`] on top, added by the check).
///
/// ~6e-6 in all; 1e-5.
pub const DENSITY_GATHER_REL: f32 = 1e-5;

/// Subnormal flushing: a GPU may flush subnormal operands and results to zero (OpenCL
/// without `CL_FP_DENORM`, Vulkan and WGSL unless the shader asks to preserve them; the
/// NVIDIA drivers do). A sum of `terms` non-negative terms then loses every term below
/// `f32::MIN_POSITIVE` and at most one partial sum below it: at most `(terms + 1)
/// MIN_POSITIVE` absolutely, in the sum's own units (measured on the H200: `rooms`' dimmest
/// gathered pixels, 7.7e-42 on the CPU, came back 0 from wgpu and vulkan).
pub fn flushed_sum_allowance(terms: usize) -> f32 {
    (terms as f32 + 1.0) * f32::MIN_POSITIVE
}

/// `direct_light` on the same G-buffer: a pixel agrees when
/// `|a - b| <= DIRECT_REL * max(|a|, |b|) + DIRECT_FLOOR * (channel maximum)`.
///
/// Diffuse pixels: `albedo / pi * I * cos * falloff / d^2` with a sqrt, a divide and a dot:
/// ~10 ulp ~ 1e-6. The spot smoothstep divides by `cos_inner - cos_outer` (>= 0.005 for the
/// cones generated, half-angles 0.5 degrees apart at 40), amplifying the ~1e-7 cosine error
/// to <= 2e-5. Mirror and glass pixels follow a chain whose end point moves by ~1e-6 times
/// ~3 per curved interaction; the branches that carry weight are the first 2-3 (Fresnel
/// weights fall as `F^k`): <= 3e-5. Hence 1e-4. The floor covers values near zero whose
/// relative error is unbounded (the outer edge of a spot cone, where the smoothstep ~ 3t^2).
pub const DIRECT_REL: f32 = 1e-4;
/// See [`DIRECT_REL`].
pub const DIRECT_FLOOR: f32 = 1e-6;

/// `direct_light`: fraction of pixels that must agree (99%). The others are pixels whose
/// shadow ray or specular chain passes within a few (amplified) ulps of an occluder's
/// silhouette or a triangle edge, or crosses a total-internal-reflection or `min_weight`
/// decision, or sits on the hard edge of a spot whose inner and outer angles are equal;
/// silhouettes cover a few percent of the pixels and the flip band is ~1e-4 of a pixel
/// wide, so 1% is a wide margin.
pub const DIRECT_AGREEMENT: f64 = 0.99;

/// `|a - b| <= rel * max(|a|, |b|)`; false for NaN.
pub(crate) fn within_rel(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs())
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustica_core::math::spectrum::{
        CieLobe, CIE_X_LOBES, CIE_Y_LOBES, CIE_Z_LOBES, SPECTRAL_RGB_SCALE, XYZ_TO_LINEAR_SRGB,
    };

    /// Per function of the fit at `nm`: (value, error bound in ulp-weighted units: the sum
    /// over its lobes of `|w| exp(-x) (7 + 2x)`).
    fn lobes(nm: f64, lobes: &[CieLobe]) -> (f64, f64) {
        lobes.iter().fold((0.0, 0.0), |(v, e), l| {
            let mu = l.mean_nm as f64;
            let s = if nm < mu {
                l.inv_sigma_below
            } else {
                l.inv_sigma_above
            } as f64;
            let x = 0.5 * ((nm - mu) * s).powi(2);
            let g = (-x).exp();
            (
                v + l.weight as f64 * g,
                e + (l.weight as f64).abs() * g * (7.0 + 2.0 * x),
            )
        })
    }

    /// (weight per channel, error bound per channel in units of one ulp, 2^-23).
    fn weight(nm: f64) -> ([f64; 3], [f64; 3]) {
        let f = [
            lobes(nm, &CIE_X_LOBES),
            lobes(nm, &CIE_Y_LOBES),
            lobes(nm, &CIE_Z_LOBES),
        ];
        let w = std::array::from_fn(|c| {
            let m = XYZ_TO_LINEAR_SRGB[c];
            let v: f64 = (0..3).map(|j| m[j] as f64 * f[j].0).sum();
            v.max(0.0) * SPECTRAL_RGB_SCALE[c] as f64
        });
        let e = std::array::from_fn(|c| {
            let m = XYZ_TO_LINEAR_SRGB[c];
            let v: f64 = (0..3).map(|j| (m[j] as f64).abs() * f[j].1).sum();
            v * SPECTRAL_RGB_SCALE[c] as f64
        });
        (w, e)
    }

    #[test]
    fn spectral_flux_rel_bounds_the_weights_error() {
        let ulp = 2f64.powi(-23);
        let largest = |v: [f64; 3]| v.iter().fold(0.0f64, |m, x| m.max(*x));
        let (mut eval, mut slope) = (0.0f64, 0.0f64);
        for i in 0..=40_000 {
            let nm = 380.0 + 400.0 * i as f64 / 40_000.0;
            let (w, e) = weight(nm);
            if largest(w) == 0.0 {
                continue;
            }
            eval = eval.max(largest(e) / largest(w) * ulp);
            let h = 1e-3;
            let (a, b) = (weight(nm - h).0, weight(nm + h).0);
            let d = (0..3).map(|c| (b[c] - a[c]).abs()).fold(0.0, f64::max) / (2.0 * h);
            slope = slope.max(d / largest(w));
        }
        // two roundings of the wavelength in nm, at most 2 ulp of 780 nm
        let wavelength = slope * 2.0 * 780.0 * ulp;
        eprintln!("evaluation {eval:.2e}, wavelength rounding {wavelength:.2e}");
        assert!(
            eval + wavelength <= SPECTRAL_FLUX_REL,
            "{}",
            eval + wavelength
        );
        // and the constant is not loose by more than its rounding up
        assert!(eval + wavelength > 0.8 * SPECTRAL_FLUX_REL);
    }
}
