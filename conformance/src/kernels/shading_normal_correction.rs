//! `shading_normal_correction` on the reference's direction map, the last of PhotonGi's
//! kernels, and [`check_photon_gi`], which checks the five in one chain for every light
//! of the fixture's scene (point: six faces, spot: one or six, directional: one
//! orthographic face): faces of `RSM_SIDE^2` texels rendered on the reference (an
//! orthographic face also on the candidate, compared as `primary_gbuffer`'s check
//! compares the camera's), then
//!
//! 1. `rsm_importance` ([`super::rsm_importance`]), 2. `sample_rsm`
//!    ([`super::sample_rsm`]), 3. `trace_indirect` ([`super::trace_indirect`]) and 4.
//!    `splat_photons` ([`super::splat_photons`]), each on the reference's output of the
//!    one before, each module saying what it compares and why (the splat's counters on
//!    each backend by themselves, [`super::splat_photons::check_splat_counters`]);
//! 5. `shading_normal_correction` on the reference's splat direction sums
//!    (`compare_correction`): where Eq. 20 does not apply (no receiver, no splat, or a
//!    shading normal that does not depart from the geometric one) the input passes
//!    through bitwise; elsewhere the factor is within 16 ulp of the mean direction's
//!    cancellation.

use super::rsm_importance::*;
use super::sample_rsm::*;
use super::splat_photons::*;
use super::trace_indirect::*;
use crate::harness::fixture::{run_and_free, Fixture, ReferenceInputs};
use crate::harness::tolerance::DEPOSIT_TEXEL_AGREEMENT;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::{
    counter, gbuffer_flags, CorrectionParams, DepositTexel, GBufferTexel,
};
use caustica_core::kernels::ShadingNormalCorrection;
use caustica_core::math::fixed_point::join_u64;
use caustica_core::math::irradiance_filter::shading_normal_departs;
use caustica_core::math::packing::unpack_unit_vector;
use caustica_core::recording::Recording;
use caustica_core::techniques::photon_gi::rsm_faces;

/// Runs `shading_normal_correction` on `b` over the reference's G-buffer and direction
/// map, on a fixed input image.
pub(crate) fn run_correction(
    fx: &Fixture,
    b: &mut dyn Backend,
    gbuffer: &[GBufferTexel],
    directions: &[DepositTexel],
    input: &[[f32; 4]],
) -> Result<Vec<[f32; 4]>, String> {
    let mut rec = Recording::new();
    let g = rec.upload_gbuffer(gbuffer);
    let d = rec.upload_photon_map(directions);
    let i = rec.upload(input, "input");
    let out = rec.create(input.len() as u32, "corrected");
    rec.kernel(ShadingNormalCorrection {
        params: CorrectionParams {
            width: fx.camera.width,
            height: fx.camera.height,
            max_stretch: 4.0,
            epsilon: caustica_core::techniques::photon_gi::SHADING_EPSILON,
        },
        gbuffer: g,
        direction_map: d,
        input: i,
        out,
    });
    run_and_free(b, "shading_normal_correction", &rec, |b| read_buf(b, out))
}

/// Point 5 of the module doc: light `l`'s corrected images `ca` / `cb` (reference,
/// candidate) of `input` under direction sums `da` and G-buffer `gbuffer`; returns how
/// many pixels Eq. 20 changed.
pub(crate) fn compare_correction(
    v: &mut Verdict,
    l: u32,
    gbuffer: &[GBufferTexel],
    da: &[DepositTexel],
    input: &[[f32; 4]],
    (ca, cb): (&[[f32; 4]], &[[f32; 4]]),
) -> u64 {
    let mut corrected = 0u64;
    let mut correction_bad = Vec::new();
    for (k, ((x, y), t)) in ca.iter().zip(cb).zip(da).enumerate() {
        let w = join_u64(t.hit_distance) as f32;
        let v = glam::Vec3::from_array([0, 1, 2].map(|ch| 2.0 * join_u64(t.flux[ch]) as f32 - w));
        let g = &gbuffer[k];
        let ng = unpack_unit_vector(g.geometric_normal);
        // where Eq. 20 does not apply (no receiver, no splat, or a shading normal that
        // does not depart from the geometric one: exact decisions on the same
        // G-buffer) the input passes through bitwise
        let applies = g.flags & gbuffer_flags::RECEIVER != 0
            && w > 0.0
            && shading_normal_departs(glam::Vec3::from(g.normal), ng);
        if !applies {
            let ok = y.map(f32::to_bits) == input[k].map(f32::to_bits);
            if !ok && correction_bad.len() < 3 {
                correction_bad.push(format!("pixel {k}: {y:?}, input {:?} kept", input[k]));
            }
            continue;
        }
        let (f, den) = (
            x[0] / input[k][0],
            v.normalize_or_zero().dot(ng).max(0.0) + 1e-4,
        );
        corrected += (f != 1.0) as u64;
        // the mean direction 2 d - w carries ~4 ulp of w (cancellation: times w / |v|),
        // each dot product 3 ulp, the division 2.5 ulp: 16 ulp x w / |v| of the
        // factor's numerator and denominator, relative to the denominator
        let bound =
            16.0 * f32::EPSILON * (w / v.length().max(f32::MIN_POSITIVE)).max(1.0) * (1.0 + f)
                / den
                + 1e-6;
        let ok = (0..4).all(|ch| (x[ch] - y[ch]).abs() <= bound * x[ch].abs().max(input[k][ch]))
            && y.iter().all(|c| c.is_finite());
        if !ok && correction_bad.len() < 3 {
            correction_bad.push(format!("pixel {k}: {y:?} vs cpu {x:?} (bound {bound:.2e})"));
        }
    }
    v.check(correction_bad.is_empty(), || {
        format!(
            "light {l}: shading_normal_correction differs: {}",
            correction_bad.join("; ")
        )
    });
    corrected
}

/// PhotonGi's four kernels on the same inputs (see the module doc).
pub fn check_photon_gi(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("photon_gi kernels");
    let mut checked = 0;
    for (li, light) in fx.ds.lights.iter().enumerate() {
        checked += 1;
        let l = li as u32;
        let faces = rsm_faces(light, RSM_SIDE, &fx.ds.bounds);
        let nf = faces.len() as u32;
        let gbufs = face_gbuffers(fx, r, &faces)?;
        // 0. an orthographic face's G-buffer itself (the new primary-ray path; a
        // perspective face is the camera's path, which `primary_gbuffer`'s check covers
        // with generated cameras: cube faces inside an axis-aligned box aim texel rays at
        // shared edges, where hardware and software traversal legitimately part, 16 of
        // 1024 texels of a `cornell` face on lavapipe's Vulkan)
        if faces[0].tan_half_fov_x < 0.0 {
            let gc = face_gbuffers(fx, c, &faces)?;
            v.absorb(
                crate::kernels::primary_gbuffer::compare_gbuffers(
                    &fx.ds, &faces[0], &gbufs[0], &gc[0],
                )
                .0,
            );
        }
        // 1. rsm_importance
        let (ta, pa) = run_rsm(fx, r, l, &faces, &gbufs)?;
        let (tb, pb) = run_rsm(fx, c, l, &faces, &gbufs)?;
        compare_rsm(&mut v, l, light, (&ta, &pa), (&tb, &pb));
        // 2. sample_rsm
        let sa = run_sample(fx, r, l, faces[0], nf, &ta, &pa)?;
        let sb = run_sample(fx, c, l, faces[0], nf, &ta, &pa)?;
        compare_samples(&mut v, l, &sa, &sb);
        // 3. trace_indirect on the reference's photons
        let mean = sa
            .iter()
            .map(|p| p.flux.iter().cloned().fold(0.0f32, f32::max))
            .sum::<f32>()
            / SAMPLES as f32;
        let power_scale = mean.max(f32::MIN_POSITIVE);
        let quantum = power_scale / 1_048_576.0;
        let (pha, tia, ca) = run_trace(fx, r, &sa, &inputs.gbuffer, power_scale, quantum)?;
        let (phb, tib, cb) = run_trace(fx, c, &sa, &inputs.gbuffer, power_scale, quantum)?;
        compare_indirect(
            &mut v,
            fx,
            l,
            (&pha, &tia, &ca),
            (&phb, &tib, &cb),
            power_scale,
            quantum,
        );
        // 3'. the same paths in waves: on each backend exactly its single launch's
        // photons, so against the reference as the single launch
        let scales = (power_scale, quantum);
        let ((phwa, tiwa, cwa), _) =
            run_trace_waves(fx, r, &sa, &inputs.gbuffer, scales, WAVES, false)?;
        let ((phwb, tiwb, cwb), _) =
            run_trace_waves(fx, c, &sa, &inputs.gbuffer, scales, WAVES, false)?;
        // and sorted: each queue keyed by the wave that fills it and taken in its keys'
        // order, the same photons; the last keyed queue's keys and order by definition
        let sorted_r = run_trace_waves(fx, r, &sa, &inputs.gbuffer, scales, WAVES, true)?;
        let sorted_c = run_trace_waves(fx, c, &sa, &inputs.gbuffer, scales, WAVES, true)?;
        for (name, single, ((phs, tis, cs), queue)) in [
            ("reference, sorted", (&pha, &tia, &ca), &sorted_r),
            ("candidate, sorted", (&phb, &tib, &cb), &sorted_c),
        ] {
            compare_schedules(&mut v, name, l, (single.0, single.1, single.2), (phs, tis, cs));
            match queue {
                Some(q) => check_keyed_queue(&mut v, name, l, q),
                None => {
                    v.check(false, || format!("light {l}, {name}: no keyed queue"));
                }
            }
        }
        compare_schedules(
            &mut v,
            "reference",
            l,
            (&pha, &tia, &ca),
            (&phwa, &tiwa, &cwa),
        );
        compare_schedules(
            &mut v,
            "candidate",
            l,
            (&phb, &tib, &cb),
            (&phwb, &tiwb, &cwb),
        );
        compare_indirect(
            &mut v,
            fx,
            l,
            (&pha, &tia, &ca),
            (&phwb, &tiwb, &cwb),
            power_scale,
            quantum,
        );
        // 4. splat_photons on the reference's photons
        let sp = splat_params(fx, power_scale, quantum);
        let (ma, ka, da) = run_splat(fx, r, &inputs.gbuffer, &pha, &tia, sp)?;
        let (mb, kb, db) = run_splat(fx, c, &inputs.gbuffer, &pha, &tia, sp)?;
        let (same, flux_bad) = splat_agreement((&ma, &da), (&mb, &db));
        // every splatted pixel is one deposit: each backend's counter is its map's count
        for (who, m, k) in [("reference", &ma, &ka), ("candidate", &mb, &kb)] {
            let splats: u64 = m.iter().map(|t| join_u64(t.photons)).sum();
            v.check(k[counter::DEPOSITED] as u64 == splats, || {
                format!(
                    "light {l}: the {who}'s splat counted {} deposits for {splats} splats \
                     in its map",
                    k[counter::DEPOSITED]
                )
            });
        }
        // 4'. the splat's underflow, saturation and deposit counts, exactly, on each
        // backend
        for who in ["reference", "candidate"] {
            let b: &mut dyn Backend = if who == "reference" { &mut *r } else { &mut *c };
            let note = check_splat_counters(&mut v, fx, who, b, &inputs.gbuffer, &pha, &tia, sp)?;
            v.note(format!("light {l}: {note}"));
        }
        // 5. shading_normal_correction on the reference's direction map
        let input: Vec<[f32; 4]> = (0..ma.len())
            .map(|i| [1.0 + (i % 5) as f32, 1.0, 0.5, 0.25])
            .collect();
        let ca = run_correction(fx, r, &inputs.gbuffer, &da, &input)?;
        let cb = run_correction(fx, c, &inputs.gbuffer, &da, &input)?;
        let corrected = compare_correction(&mut v, l, &inputs.gbuffer, &da, &input, (&ca, &cb));
        let n = ma.len() as f64;
        v.check(same as f64 >= DEPOSIT_TEXEL_AGREEMENT * n, || {
            format!("light {l}: {same} of {n} texels hold the same splats")
        });
        v.check(flux_bad == 0, || {
            format!("light {l}: {flux_bad} texel channels differ in flux")
        });
        let splatted = ma.iter().filter(|t| join_u64(t.photons) > 0).count();
        v.note(format!(
            "light {l}: {nf} faces, {} / {} photons stored, {splatted} texels splatted, \
             {corrected} corrected by Eq. 20",
            pha.len(),
            phb.len()
        ));
    }
    v.check(checked > 0, || "the scene has no light".into());
    Ok(v)
}
