//! `atrous_filter` on the same inputs: the reference's G-buffer and filtered caustics,
//! one inner iteration (taps 2 pixels apart, the detail sum started) and a last one (taps
//! 4 apart, reading a detail sum), on the same input buffers.
//!
//! Tolerances. Each tap's weight is one `exp` and one `pow` (a few ulp on the GPUs, up to
//! 16 for OpenCL's `pow`, WGSL's through `exp2(log2)`); the 25 weighted sums run in the
//! same order everywhere, so an output differs by the weights' relative error, ~1e-5, of
//! the largest value in the kernel: [`ATROUS_REL`] of the image's largest value, on every
//! pixel. The clip bound is a square root of a difference of such sums, and where that
//! difference cancels the bound may differ more: the detail sum gets the same allowance
//! scaled by its own largest value.

use crate::harness::fixture::{run_and_free, Fixture, ReferenceInputs};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::AtrousParams;
use caustica_core::kernels::AtrousFilter;
use caustica_core::math::irradiance_filter::FilterConstants;
use caustica_core::recording::Recording;

/// Relative tolerance (of the image's largest value) of an A-Trous output (see the module
/// doc): 100x the weights' ~1e-5.
pub const ATROUS_REL: f32 = 1e-3;

/// (output, detail sum) of one iteration.
type Iteration = (Vec<[f32; 4]>, Vec<[f32; 4]>);

fn run(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    b: &mut dyn Backend,
    (iteration, last): (u32, bool),
    details: &[[f32; 4]],
) -> Result<Iteration, String> {
    let c = FilterConstants::default();
    let n = inputs.filtered.len() as u32;
    let mut rec = Recording::new();
    let gbuffer = rec.upload_gbuffer(&inputs.gbuffer);
    let input = rec.upload(&inputs.filtered, "input");
    let det = rec.upload(details, "details");
    let out = rec.create(n, "out");
    rec.kernel(AtrousFilter {
        params: AtrousParams {
            camera: fx.camera,
            iteration,
            last: last as u32,
            sigma_z: c.sigma_z,
            sigma_n: c.sigma_n,
            epsilon: c.epsilon,
            clip_sigmas: 1.0,
            _pad: [0; 2],
        },
        gbuffer,
        input,
        details: det,
        out,
    });
    run_and_free(b, "atrous_filter", &rec, |b| {
        Ok((read_buf(b, out)?, read_buf(b, det)?))
    })
}

/// `atrous_filter` on the same inputs (see the module doc).
pub fn check_atrous_filter(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("atrous_filter");
    let n = inputs.filtered.len();
    let peak = |img: &[[f32; 4]]| {
        img.iter()
            .flat_map(|p| p[..3].iter())
            .fold(0.0f32, |m, x| m.max(x.abs()))
    };
    let zero = vec![[0.0f32; 4]; n];
    let first = run(fx, inputs, r, (1, false), &zero)?;
    for (what, step, details) in [
        ("inner iteration", (1u32, false), zero.clone()),
        ("last iteration", (2u32, true), first.1.clone()),
    ] {
        let a = run(fx, inputs, r, step, &details)?;
        let b = run(fx, inputs, c, step, &details)?;
        for (part, x, y) in [("output", &a.0, &b.0), ("detail sum", &a.1, &b.1)] {
            let tol = ATROUS_REL * peak(x).max(peak(&inputs.filtered));
            let differ = x
                .iter()
                .zip(y)
                .filter(|(p, q)| (0..4).any(|ch| (p[ch] - q[ch]).abs() > tol))
                .count();
            v.check(differ == 0, || {
                format!("{what}: {differ} of {n} pixels' {part} differ beyond {tol:e}")
            });
        }
    }
    Ok(v)
}
