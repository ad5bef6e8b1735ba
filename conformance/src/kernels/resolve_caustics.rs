//! `resolve_caustics`, on texels whose photon-map sums two backends produced bitwise equal:
//! radiance within [`RESOLVE_REL`] + [`RESOLVE_COS_REL`] / cos. It runs with
//! `deposit_screen`, whose check ([`super::deposit_screen::check_deposit`]) calls [`compare_resolve`].

use crate::harness::measure::v3;
use crate::harness::tolerance::{RESOLVE_COS_REL, RESOLVE_REL};
use crate::harness::verdict::Verdict;
use caustica_core::device::layout::{
    camera_ray, gbuffer_flags, DepositTexel, GBufferTexel, GpuCamera,
};
use caustica_core::math::fixed_point::join_u64;
use caustica_core::math::footprint::MIN_COSINE;

/// Compares the raw caustics of two backends (`reference` and `candidate`: each one's photon
/// map and `resolve_caustics` output on the same `gbuffer` of camera `cam`) on the texels
/// whose photon-map sums are bitwise equal: a texel with no photon or no receiver must be
/// zero on both, any other within `RESOLVE_REL + RESOLVE_COS_REL / max(|cos|, MIN_COSINE)`
/// relative, `cos` between the camera ray and the normal. Records a failure in `v`; returns
/// the worst error as a fraction of its tolerance.
pub fn compare_resolve(
    cam: &GpuCamera,
    gbuffer: &[GBufferTexel],
    reference: (&[DepositTexel], &[[f32; 4]]),
    candidate: (&[DepositTexel], &[[f32; 4]]),
    v: &mut Verdict,
) -> f32 {
    let ((ma, ia), (mb, ib)) = (reference, candidate);
    let (mut checked, mut bad, mut worst, mut first_bad) = (0u64, 0u64, 0.0f32, None);
    for (i, g) in gbuffer.iter().enumerate() {
        if ma[i] != mb[i] {
            continue;
        }
        checked += 1;
        let (a, b) = (ia[i], ib[i]);
        let empty = join_u64(ma[i].photons) == 0 || g.flags & gbuffer_flags::RECEIVER == 0;
        let ok = if empty {
            a == [0.0; 4] && b == [0.0; 4]
        } else {
            let ray = camera_ray(cam, i as u32 % cam.width, i as u32 / cam.width);
            let cos = ray.dot(v3(g.normal)).abs().max(MIN_COSINE);
            let rel = RESOLVE_REL + RESOLVE_COS_REL / cos;
            let mut e = 0.0f32;
            for ch in 0..4 {
                let d = (a[ch] - b[ch]).abs();
                let x = if d == 0.0 {
                    0.0
                } else {
                    d / (rel * a[ch].abs().max(b[ch].abs()))
                };
                e = e.max(if x.is_nan() { f32::INFINITY } else { x });
            }
            worst = worst.max(e);
            e <= 1.0
        };
        if !ok {
            bad += 1;
            first_bad.get_or_insert(format!(
                "({}, {}): {b:?} vs cpu {a:?}",
                i as u32 % cam.width,
                i as u32 / cam.width
            ));
        }
    }
    v.check(bad == 0, || {
        format!(
            "resolve_caustics differs on {bad} of {checked} texels with equal sums, first {}",
            first_bad.unwrap_or_default()
        )
    });
    worst
}
