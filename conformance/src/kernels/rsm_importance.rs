//! `rsm_importance` (level 0 and every pyramid level) on the reference's face
//! G-buffers: texel kinds and positions are copies (bitwise), normals are packed
//! (within a snorm16 quantum: the octahedral map divides); the flux is
//! `I x falloff x dw` (a square root and two divisions, 2.5 ulp each on GPUs, and ~10
//! roundings: < 20 ulp ~ 1.2e-6), the level-0 importance its luminance, and a pyramid
//! sum adds at most `4^k` such terms in a fixed order with one rounding per level
//! (`k <= 5` here): all within [`RSM_REL`] = 1e-5 relative.
//!
//! One link of PhotonGi's chain, [`super::shading_normal_correction::check_photon_gi`].

use super::sample_rsm::*;
use crate::harness::fixture::{run_and_free, Fixture};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, read_gbuffer, Backend};
use caustica_core::device::layout::{GBufferTexel, GpuCamera, GpuLight, RsmParams, RsmTexel};
use caustica_core::kernels::{PrimaryGbuffer, RsmImportance};
use caustica_core::math::rsm::{level_count, pyramid_len};
use caustica_core::recording::Recording;

/// Texels per side of the checked RSM faces.
pub const RSM_SIDE: u32 = 32;
/// Relative tolerance of RSM fluxes, importances, pyramid sums and sampled fluxes (module
/// doc, point 1 and 2).
pub const RSM_REL: f32 = 1e-5;

pub(crate) fn rsm_params(
    light: u32,
    face: u32,
    cam: GpuCamera,
    level: u32,
    faces: u32,
    seed: u32,
) -> RsmParams {
    RsmParams {
        face_camera: cam,
        light,
        face,
        side: RSM_SIDE,
        level,
        face_count: faces,
        first_sample: 0,
        sample_count: SAMPLES,
        seed,
        ..Default::default()
    }
}

pub(crate) fn face_gbuffers(
    fx: &Fixture,
    r: &mut dyn Backend,
    faces: &[GpuCamera],
) -> Result<Vec<Vec<GBufferTexel>>, String> {
    faces
        .iter()
        .map(|cam| {
            let mut rec = Recording::new();
            let g = rec.create_gbuffer(RSM_SIDE * RSM_SIDE);
            rec.kernel(PrimaryGbuffer {
                scene: fx.args,
                camera: *cam,
                gbuffer: g,
            });
            run_and_free(r, "primary_gbuffer (RSM face)", &rec, |b| {
                read_gbuffer(b, &g)
            })
        })
        .collect()
}

pub(crate) fn run_rsm(
    fx: &Fixture,
    b: &mut dyn Backend,
    light: u32,
    faces: &[GpuCamera],
    gbufs: &[Vec<GBufferTexel>],
) -> Result<(Vec<RsmTexel>, Vec<f32>), String> {
    let n = faces.len() as u32;
    let mut rec = Recording::new();
    let texels = rec.create(n * RSM_SIDE * RSM_SIDE, "RSM texels");
    let pyramid = rec.create(n * pyramid_len(RSM_SIDE), "RSM pyramid");
    for (f, (cam, g)) in faces.iter().zip(gbufs).enumerate() {
        let gbuffer = rec.upload_gbuffer(g);
        rec.kernel(RsmImportance {
            params: rsm_params(light, f as u32, *cam, 0, n, 0),
            lights: fx.args.lights,
            gbuffer,
            texels,
            pyramid,
        });
    }
    let g1 = rec.upload_gbuffer(&gbufs[0][..1]);
    for level in 1..level_count(RSM_SIDE) {
        rec.kernel(RsmImportance {
            params: rsm_params(light, n - 1, faces[0], level, n, 0),
            lights: fx.args.lights,
            gbuffer: g1,
            texels,
            pyramid,
        });
    }
    run_and_free(b, "rsm_importance", &rec, |b| {
        Ok((read_buf(b, texels)?, read_buf(b, pyramid)?))
    })
}

/// Point 1 of the module doc: light `l`'s RSM texels `a` / `b` and pyramids (reference,
/// candidate).
pub(crate) fn compare_rsm(
    v: &mut Verdict,
    l: u32,
    light: &GpuLight,
    (ta, pa): (&[RsmTexel], &[f32]),
    (tb, pb): (&[RsmTexel], &[f32]),
) {
    // a spot's smoothstep falloff has an absolute error of a few ulps of 1: near the
    // outer cone the flux is tiny and its relative error large, so fluxes agree within
    // RSM_REL of the larger or of the face's largest texel flux (sums likewise)
    let peak = ta.iter().flat_map(|t| t.flux).fold(0.0f32, f32::max);
    // Inside a spot's transition the falloff is smoothstep(t), t = (cos - cos_outer) /
    // (cos_inner - cos_outer): the cosine, a dot product of two normalised vectors, may
    // differ by ~4 ulp of 1 (2^-22) where a GPU fuses its products (seen on the H200: a
    // spot whose transition spans a few degrees, flux 3.4e-5 relative apart), which
    // t divides by the transition's width and smoothstep's slope (<= 1.5) carries into
    // the falloff: an absolute error up to 1.5 * 2^-22 / width of the unit falloff,
    // i.e. of the flux at falloff 1 (at most the face's peak for a face in the cone;
    // 1e-6 rounds 3.6e-7 up for the peak not being at falloff 1).
    let spot = if light.kind == caustica_core::device::layout::light_kind::SPOT {
        peak * 1e-6 / (light.cos_inner - light.cos_outer).max(f32::MIN_POSITIVE)
    } else {
        0.0
    };
    let floor = (peak * RSM_REL).max(spot);
    let close = |a: f32, b: f32| rel_close(a, b, RSM_REL) || (a - b).abs() <= floor;
    let differs = |a: &RsmTexel, b: &RsmTexel| {
        a.kind != b.kind
            || a.position.map(f32::to_bits) != b.position.map(f32::to_bits)
            // packing divides by the normal's L1 norm: GPUs' approximate
            // division may move it by one snorm16 quantum (~3e-5 rad)
            || !within_one_quantum(a.normal, b.normal)
            || !(0..3).all(|k| close(a.flux[k], b.flux[k]))
    };
    let texel_bad = ta.iter().zip(tb).filter(|(a, b)| differs(a, b)).count();
    v.check(texel_bad == 0, || {
        // the first one, field by field (what a GPU-only failure needs to be read)
        let first = ta
            .iter()
            .zip(tb)
            .enumerate()
            .find(|(_, (a, b))| differs(a, b))
            .map(|(i, (a, b))| {
                format!(
                    "; first at texel {i}: kind {} vs {}, position {:?} vs {:?}, normal \
                     {:#010x} vs {:#010x}, flux {:?} vs {:?}",
                    a.kind, b.kind, a.position, b.position, a.normal, b.normal, a.flux, b.flux
                )
            })
            .unwrap_or_default();
        format!("light {l}: {texel_bad} RSM texels differ{first}")
    });
    let pyr_bad = pa
        .iter()
        .zip(pb)
        // a sum holds at most RSM_SIDE^2 texels, each within `floor`
        .filter(|(a, b)| {
            !rel_close(**a, **b, RSM_REL)
                && (**a - **b).abs() > floor * (RSM_SIDE * RSM_SIDE) as f32
        })
        .count();
    v.check(pyr_bad == 0, || {
        format!("light {l}: {pyr_bad} pyramid sums differ beyond {RSM_REL}")
    });
}

/// Two packed unit vectors whose snorm16 components differ by at most one.
pub(crate) fn within_one_quantum(a: u32, b: u32) -> bool {
    let d = |s: u32| ((a >> s) as u16 as i16 as i32 - (b >> s) as u16 as i16 as i32).abs();
    d(0) <= 1 && d(16) <= 1
}

pub(crate) fn rel_close(a: f32, b: f32, rel: f32) -> bool {
    (a - b).abs() <= rel * a.abs().max(b.abs()) || a == b
}
