//! `temporal_blend` on the same inputs: the reference's G-buffer and filtered caustics, a
//! history image and the reference's own edge texels as the history's, seen from a
//! previous camera moved a little (so that the reprojection lands between pixels, leaves
//! the image at one side and meets depth and normal changes).
//!
//! Tolerances. The blend is `(1 - alpha) E + alpha H`, `alpha` from one `exp` and one
//! `pow` (GPU accuracy: a few ulp for `exp`, up to 16 for OpenCL's `pow`, WGSL's through
//! `exp2(log2)`), so `alpha` agrees within ~1e-5 relative and the output within
//! [`BLEND_REL`] of the larger of `E` and `H`. The reprojection's pixel comes from
//! `project_to_pixel` (two dots and a division, as `deposit_screen`'s), so a point within
//! a few ulps of a pixel edge may take the neighbour's history: at most
//! [`DEPOSIT_PHOTON_CHANGES`] of the pixels (plus 2) may differ beyond the tolerance. The
//! next frame's edge texels are copies of the G-buffer: bitwise.

use crate::harness::fixture::{run_and_free, Fixture, ReferenceInputs};
use crate::harness::tolerance::DEPOSIT_PHOTON_CHANGES;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::{GpuCamera, TemporalParams};
use caustica_core::kernels::TemporalBlend;
use caustica_core::math::irradiance_filter::FilterConstants;
use caustica_core::math::rng::pcg_hash;
use caustica_core::recording::Recording;

/// Relative tolerance of a blended channel (see the module doc): 100x the ~1e-5 of
/// `alpha`'s transcendental functions.
pub const BLEND_REL: f32 = 1e-3;

fn moved(c: GpuCamera) -> GpuCamera {
    let right = glam::Vec3::from(c.right);
    let forward = glam::Vec3::from(c.forward);
    GpuCamera {
        position: (glam::Vec3::from(c.position) + 0.03 * right + 0.01 * forward).to_array(),
        ..c
    }
}

/// (out, next_history, next_edge) of one blend on `b`.
type Blend = (Vec<[f32; 4]>, Vec<[f32; 4]>, Vec<[f32; 4]>);

fn run(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    b: &mut dyn Backend,
    history: &[[f32; 4]],
    history_edge: &[[f32; 4]],
) -> Result<Blend, String> {
    let c = FilterConstants::default();
    let n = inputs.filtered.len() as u32;
    let mut rec = Recording::new();
    let gbuffer = rec.upload_gbuffer(&inputs.gbuffer);
    let input = rec.upload(&inputs.filtered, "input");
    let hist = rec.upload(history, "history");
    let hedge = rec.upload(history_edge, "history edge");
    let out = rec.create(n, "out");
    let next_history = rec.create(n, "next history");
    let next_edge = rec.create(n, "next edge");
    rec.kernel(TemporalBlend {
        params: TemporalParams {
            camera: fx.camera,
            previous: moved(fx.camera),
            alpha_max: c.alpha_max,
            sigma_z: c.sigma_z,
            sigma_n: c.sigma_n,
            epsilon: c.epsilon,
            history_frames: 3,
            _pad: [0; 3],
        },
        gbuffer,
        input,
        history: hist,
        history_edge: hedge,
        out,
        next_history,
        next_edge,
    });
    run_and_free(b, "temporal_blend", &rec, |b| {
        Ok((
            read_buf(b, out)?,
            read_buf(b, next_history)?,
            read_buf(b, next_edge)?,
        ))
    })
}

/// `temporal_blend` on the same inputs (see the module doc).
pub fn check_temporal_blend(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("temporal_blend");
    let n = inputs.filtered.len();
    // a history unlike the input (so the blend shows), and the G-buffer's edge texels as
    // the history's (depth -1 where no receiver)
    let history: Vec<[f32; 4]> = (0..n as u32)
        .map(|i| {
            let h =
                |k: u32| (pcg_hash(i.wrapping_mul(4).wrapping_add(k)) >> 8) as f32 / 16_777_216.0;
            [h(0), h(1), h(2), 1.0]
        })
        .collect();
    let edge: Vec<[f32; 4]> = inputs
        .gbuffer
        .iter()
        .map(|g| {
            if g.flags & caustica_core::device::layout::gbuffer_flags::RECEIVER != 0 {
                [g.depth, g.normal[0], g.normal[1], g.normal[2]]
            } else {
                [-1.0, 0.0, 0.0, 0.0]
            }
        })
        .collect();
    let a = run(fx, inputs, r, &history, &edge)?;
    let b = run(fx, inputs, c, &history, &edge)?;
    let mut differ = 0u64;
    let mut blended = 0u64;
    for (i, (x, y)) in a.0.iter().zip(&b.0).enumerate() {
        let scale = inputs.filtered[i][..3]
            .iter()
            .chain(&history[i][..3])
            .fold(0.0f32, |m, v| m.max(v.abs()));
        let close = (0..4).all(|ch| (x[ch] - y[ch]).abs() <= BLEND_REL * scale);
        differ += (!close) as u64;
        blended += (*x != inputs.filtered[i]) as u64;
    }
    let allow = (DEPOSIT_PHOTON_CHANGES * n as f64).ceil() as u64 + 2;
    v.check(differ <= allow, || {
        format!("{differ} of {n} blended pixels differ beyond {BLEND_REL} (allowance {allow})")
    });
    v.check(a.0 == a.1, || "cpu: out and next_history differ".into());
    v.check(b.0 == b.1, || {
        "candidate: out and next_history differ".into()
    });
    let bits = |e: &[[f32; 4]]| e.iter().flatten().map(|x| x.to_bits()).collect::<Vec<_>>();
    v.check(bits(&a.2) == bits(&b.2), || {
        "next edge texels differ".into()
    });
    v.note(format!(
        "{blended} of {n} pixels blended with history, {differ} differ"
    ));
    Ok(v)
}
