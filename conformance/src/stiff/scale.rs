//! The scale group: the sphere scene scaled down and up, and offset far from the origin,
//! against the unscaled frame.

use super::runner::{outcome, run_checked};
use super::scenes::{settings, sphere_scene, transform_scene};
use super::{Outcome, GRID};
use crate::harness::measure::relative_l2;
use crate::harness::tolerance::{self, divergence_allowance};
use crate::harness::verdict::Verdict;
use crate::techniques::sspm;
use caustica_core::backend::Backend;
use glam::Vec3;

/// Renders the sphere scene and its transform on `b`, compares the caustics.
///
/// The transformed scene differs from the original by one rounding of every coordinate
/// (relative `2^-24` of the coordinate's magnitude): the same kind of perturbation as two
/// backends' different roundings, so a non-diverged photon lands on the same pixel and
/// [`sspm::compare_frames`]' image bound `sqrt(2 k / n) + 1e-4` applies (k the
/// divergence allowance of n deposited photons). `extra_rel` is the relative size of a
/// larger perturbation (an offset's coarser grid): [`tolerance::PATH_DIVERGENCE`]'s 1%
/// allowance is argued for perturbations of ~1e-6 (divergence well below 0.1%, 10x
/// margin), and the divergence bands grow linearly with the perturbation, so `k` grows by
/// `extra_rel / 1e-6` (capped at n).
///
/// With `instanced`, the scaled scene's ball is an instance (object space: the unscaled
/// ball at the origin; its transform carries the scale and the offset), so rays enter its
/// BLAS scaled by `1 / s`: the same single rounding per coordinate, in object space.
fn scale_case(
    b: &mut dyn Backend,
    s: f32,
    o: Vec3,
    extra_rel: f64,
    instanced: bool,
) -> Result<Outcome, String> {
    let base = sphere_scene();
    let scaled = if instanced {
        super::scenes::instanced_spheres(&base)
    } else {
        base.clone()
    };
    let scene = transform_scene(&scaled, s, o);
    let st = settings(GRID);
    let what = if instanced { "instance " } else { "" };
    let mut v = Verdict::new(format!("{what}scale {s:e} offset {o}"));
    let f = run_checked(b, &scene, &st, &mut v)?;
    let r = sspm::render_frame(b, &base, &st)?;
    let agree: Vec<bool> = f
        .gbuffer
        .iter()
        .zip(&r.gbuffer)
        .map(|(a, b)| a.material == b.material)
        .collect();
    let agreeing = agree.iter().filter(|x| **x).count() as f64 / agree.len() as f64;
    v.check(agreeing >= tolerance::GBUFFER_MATERIAL_AGREEMENT, || {
        format!("G-buffer materials agree on {agreeing:.4} of the pixels")
    });
    let n = r.stats.photons_deposited.max(f.stats.photons_deposited);
    let widen = (extra_rel / 1e-6).max(1.0);
    let k = ((divergence_allowance(n) as f64) * widen).min(n as f64);
    let bound = if n == 0 {
        0.0
    } else {
        (2.0 * k / n as f64).sqrt() + 1e-4
    };
    let mut key = String::new();
    for (name, x, y) in [
        ("raw", &r.raw, &f.raw),
        ("filtered", &r.filtered, &f.filtered),
    ] {
        let e = relative_l2(&x.pixels, &y.pixels, Some(&agree));
        let mse = caustica_core::frame::metrics::relative_mse(
            y,
            x,
            &caustica_core::frame::metrics::CausticMask::from_reference(x),
        );
        v.check(e <= bound, || {
            format!("{name} caustics: relative L2 {e:.3e} vs unscaled (allowed {bound:.3e})")
        });
        if key.is_empty() {
            key = format!("rel L2 {e:.2e} (<= {bound:.2e}), relMSE {mse:.1e}");
        }
    }
    v.check(r.stats.photons_stored > 0, || "nothing stored".into());
    // The filter keeps the focus at every scale: its radius is counted in photons and
    // pixels, never in scene units, so the focused caustic's peak survives the gather
    // (the density gather leaves pixels holding 9 k photons in their 3x3 window as they
    // are; 0.9 leaves room for the sparse pixels around the peak spreading into it or
    // not).
    let mask = caustica_core::frame::metrics::CausticMask::from_reference(&f.raw);
    let peak = caustica_core::frame::metrics::peak_ratio(&f.filtered, &f.raw, &mask);
    v.check(peak >= 0.9, || {
        format!("filtered peak {peak:.3} of the raw peak: the focus was blurred")
    });
    key.push_str(&format!(", filtered peak {peak:.3} of raw"));
    outcome(key, v)
}

pub(super) fn scale_small(b: &mut dyn Backend) -> Result<Outcome, String> {
    scale_case(b, 1e-4, Vec3::ZERO, 0.0, false)
}

pub(super) fn scale_large(b: &mut dyn Backend) -> Result<Outcome, String> {
    scale_case(b, 1e5, Vec3::ZERO, 0.0, false)
}

pub(super) fn instance_scale_small(b: &mut dyn Backend) -> Result<Outcome, String> {
    scale_case(b, 1e-4, Vec3::ZERO, 0.0, true)
}

pub(super) fn instance_scale_large(b: &mut dyn Backend) -> Result<Outcome, String> {
    scale_case(b, 1e5, Vec3::ZERO, 0.0, true)
}

pub(super) fn offset_far(b: &mut dyn Backend) -> Result<Outcome, String> {
    // At |p| ~ 1e6 the f32 grid is 2^-4 = 0.0625: positions are rounded by up to 0.0625,
    // relative 0.0625 / 4000 (the scene diagonal x 1e3) = 1.6e-5 of the scene. A unit-size
    // scene at 1e6 is not representable in f32 at all (its grid is 1/16 of the ball's
    // radius): world-space f32 needs features >> |p| 2^-23.
    let s = 1e3;
    let extra = 0.0625 / (4.0 * s as f64);
    scale_case(b, s, Vec3::splat(1e6), extra, false)
}
