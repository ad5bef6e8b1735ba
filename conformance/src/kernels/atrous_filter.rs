//! `atrous_filter` on the same inputs: the reference's G-buffer and filtered caustics,
//! the first iteration (from the G-buffer; its edge texels, the G-buffer's bits, bitwise),
//! one inner iteration (taps 2 pixels apart, the detail sum started) and a last one (taps
//! 4 apart, reading a detail sum), these two on the reference's edge texels.
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
use caustica_core::device::layout::{gbuffer_flags, AtrousParams};
use caustica_core::math::density_gather::edge_texel;
use caustica_core::kernels::AtrousFilter;
use caustica_core::math::irradiance_filter::FilterConstants;
use caustica_core::recording::Recording;

/// Relative tolerance (of the image's largest value) of an A-Trous output (see the module
/// doc): 100x the weights' ~1e-5.
pub const ATROUS_REL: f32 = 1e-3;

/// (output, detail sum, edge texels) of one iteration.
type Iteration = (Vec<[f32; 4]>, Vec<[f32; 4]>, Vec<[f32; 4]>);

fn run(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    b: &mut dyn Backend,
    (iteration, last): (u32, bool),
    details: &[[f32; 4]],
    edges: &[[f32; 4]],
) -> Result<Iteration, String> {
    let c = FilterConstants::default();
    let n = inputs.filtered.len() as u32;
    let mut rec = Recording::new();
    let gbuffer = rec.upload_gbuffer(&inputs.gbuffer);
    let input = rec.upload(&inputs.filtered, "input");
    let det = rec.upload(details, "details");
    let out = rec.create(n, "out");
    let edge = rec.upload(edges, "edge texels");
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
        edge,
    });
    run_and_free(b, "atrous_filter", &rec, |b| {
        Ok((read_buf(b, out)?, read_buf(b, det)?, read_buf(b, edge)?))
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
    // the edge texels iteration 0 must write: the G-buffer's bits
    let edges: Vec<[f32; 4]> = inputs
        .gbuffer
        .iter()
        .map(|g| edge_texel(g.flags & gbuffer_flags::RECEIVER != 0, g.depth, g.normal))
        .collect();
    // (a stale mark where iteration 0 must write, so that a texel it skips shows)
    let stale = vec![[f32::NAN; 4]; n];
    for who in ["reference", "candidate"] {
        let b: &mut dyn Backend = if who == "reference" { &mut *r } else { &mut *c };
        let written = run(fx, inputs, b, (0, false), &zero, &stale)?.2;
        let wrong = written
            .iter()
            .zip(&edges)
            .filter(|(x, y)| x.map(f32::to_bits) != y.map(f32::to_bits))
            .count();
        v.check(wrong == 0, || {
            format!("first iteration: {wrong} of {n} edge texels on the {who} are not the G-buffer's bits")
        });
    }
    let first = run(fx, inputs, r, (1, false), &zero, &edges)?;
    for (what, step, details, edge_in) in [
        ("first iteration", (0u32, false), zero.clone(), &stale),
        ("inner iteration", (1u32, false), zero.clone(), &edges),
        ("last iteration", (2u32, true), first.1.clone(), &edges),
    ] {
        let a = run(fx, inputs, r, step, &details, edge_in)?;
        let b = run(fx, inputs, c, step, &details, edge_in)?;
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
