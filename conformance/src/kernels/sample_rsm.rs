//! `sample_rsm` on the reference's texels and pyramid: the warp takes a texel by
//! comparing the sample with ratios of sums (one 2.5-ulp division each), so a sample
//! within a few ulps of a split point may take the neighbouring texel: at most
//! [`DEPOSIT_PHOTON_CHANGES`] of the samples (~1e-6 expected per split, ~20 splits)
//! may differ; the others have bitwise origins and bounce counts, flux within
//! [`RSM_REL`] (the probability is a product of ~20 ratios: ~50 ulp) and directions
//! within [`DIRECTION_TOL`] (`sin`, `cos`, `sqrt` of the cosine warp, then 16-bit
//! octahedral packing: one quantum is ~5e-5 rad).
//!
//! One link of PhotonGi's chain, [`super::shading_normal_correction::check_photon_gi`].

use super::rsm_importance::*;
use crate::harness::fixture::{run_and_free, Fixture};
use crate::harness::tolerance::DEPOSIT_PHOTON_CHANGES;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::{GpuCamera, RsmPhoton, RsmTexel};
use caustica_core::kernels::SampleRsm;
use caustica_core::math::packing::unpack_unit_vector;
use caustica_core::recording::Recording;

/// Samples per light.
pub const SAMPLES: u32 = 4096;
/// Angle (rad) within which sampled directions must agree (module doc, point 2).
pub const DIRECTION_TOL: f32 = 1e-3;

pub(crate) fn run_sample(
    fx: &Fixture,
    b: &mut dyn Backend,
    light: u32,
    face0: GpuCamera,
    faces: u32,
    texels: &[RsmTexel],
    pyramid: &[f32],
) -> Result<Vec<RsmPhoton>, String> {
    let mut rec = Recording::new();
    let t = rec.upload(texels, "RSM texels");
    let p = rec.upload(pyramid, "RSM pyramid");
    let photons = rec.create(SAMPLES, "RSM photons");
    rec.kernel(SampleRsm {
        params: rsm_params(light, 0, face0, 0, faces, 0x5eed ^ light),
        lights: fx.args.lights,
        texels: t,
        pyramid: p,
        photons,
        dispatch: None,
    });
    run_and_free(b, "sample_rsm", &rec, |b| read_buf(b, photons))
}

/// Point 2 of the module doc: light `l`'s samples `sa` / `sb` (reference, candidate).
pub(crate) fn compare_samples(v: &mut Verdict, l: u32, sa: &[RsmPhoton], sb: &[RsmPhoton]) {
    let mut other_texel = 0u64;
    let mut bad = 0u64;
    for (a, b) in sa.iter().zip(sb) {
        // the same texel gives origins a few ulps apart (the normal's unpacking and the
        // offset divide and normalise); another texel is a texel's width away
        let (oa, ob) = (glam::Vec3::from(a.origin), glam::Vec3::from(b.origin));
        if (oa - ob).length() > 1e-5 * (oa.abs().max_element() + 1.0) || a.bounces != b.bounces {
            other_texel += 1;
            continue;
        }
        let angle = unpack_unit_vector(a.direction)
            .dot(unpack_unit_vector(b.direction))
            .clamp(-1.0, 1.0)
            .acos();
        let flux_ok = (0..3).all(|k| rel_close(a.flux[k], b.flux[k], RSM_REL));
        let angle_ok = angle <= DIRECTION_TOL; // false for NaN
        bad += (!flux_ok || !angle_ok) as u64;
    }
    let allow = (DEPOSIT_PHOTON_CHANGES * SAMPLES as f64).ceil() as u64 + 2;
    v.check(other_texel <= allow, || {
        format!(
            "light {l}: {other_texel} of {SAMPLES} samples took another texel (allowance {allow})"
        )
    });
    v.check(bad == 0, || {
        format!("light {l}: {bad} samples differ in flux or direction")
    });
}
