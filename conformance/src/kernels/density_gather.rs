//! The density gather's three kernels on the reference's inputs, in one verdict
//! ([`check_density_gather`], here with the last of them):
//! `photon_count_table` ([`super::photon_count_table`]: the summed-area table, integer
//! sums, and the edge texels, copies: bitwise equal), `gather_footprint`
//! ([`super::gather_footprint`]: radius and normalised flux) and both `density_gather`
//! passes, each within [`DENSITY_GATHER_REL`] of the magnitudes it gathers (the argument
//! is there), the radius it passes through bitwise equal.

use super::gather_footprint::check_footprint;
use super::photon_count_table::check_count_table;
use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::tolerance::{
    flushed_sum_allowance, DENSITY_GATHER_REL, RESOLVE_COS_REL, RESOLVE_REL,
};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;
use caustica_core::device::layout::{gbuffer_pixel_area, GpuCamera};
use caustica_core::math::density_gather::footprint_weight;
use caustica_core::math::footprint::MIN_COSINE;
use glam::Vec3;

/// How [`compare`] judges alpha.
pub(crate) enum Alpha<'a> {
    /// Not compared.
    Free,
    /// Bitwise equal.
    Exact,
    /// Bitwise equal, but where one side wrote the dark pixel `[0, 0, 0, +0]` and the
    /// other a pixel whose channels are within their bound and whose alpha is `lit(i)`
    /// bitwise (the radius a lit pixel passes through). A pass writes the dark pixel where
    /// its sum is exactly 0, and that test is not continuous: a GPU may flush a subnormal
    /// sum to zero, and a weight at the very edge of a kernel's support, where
    /// [`footprint_weight`] subtracts two antiderivatives within a few ulps of each other
    /// (`G(u) = u - u^3 / 3` near `u = 1`, both about 2/3), is 0 on one backend and a few
    /// ulps of 2/3 (about 1e-7) on another, whose division, sum order or contraction
    /// rounds differently. Such a weight's share lies far below `DENSITY_GATHER_REL` of
    /// what the pixel gathers, which the channels' bound checks.
    ExactOrDark(&'a dyn Fn(usize) -> f32),
}

/// Compares `a` (reference) and `b` per pixel and channel: `|a - b| <= rel * (max(|a|,
/// |b|) + gathered) + absolute` with `(rel, gathered, absolute) = tol(i, ch)`, and alpha as
/// `alpha` says. Records the failures in `v` under `what`.
pub(crate) fn compare(
    v: &mut Verdict,
    what: &str,
    cam: &GpuCamera,
    (a, b): (&[[f32; 4]], &[[f32; 4]]),
    tol: &dyn Fn(usize, usize) -> (f32, f32, f32),
    alpha: Alpha,
) {
    let (mut bad, mut worst, mut first_bad) = (0u64, 0.0f32, None);
    for i in 0..a.len() {
        let mut e = 0.0f32;
        for ch in 0..3 {
            let d = (a[i][ch] - b[i][ch]).abs();
            let (rel, gathered, absolute) = tol(i, ch);
            let bound = rel * (a[i][ch].abs().max(b[i][ch].abs()) + gathered) + absolute;
            let x = if d == 0.0 { 0.0 } else { d / bound };
            e = e.max(if x.is_nan() { f32::INFINITY } else { x });
        }
        let same_alpha = a[i][3].to_bits() == b[i][3].to_bits();
        let alpha_ok = match &alpha {
            Alpha::Free => true,
            Alpha::Exact => same_alpha,
            Alpha::ExactOrDark(lit) => {
                let dark = |p: &[f32; 4]| p.iter().all(|c| c.to_bits() == 0);
                let lit_as = |p: &[f32; 4]| p[3].to_bits() == lit(i).to_bits();
                same_alpha
                    || (e <= 1.0
                        && ((dark(&a[i]) && lit_as(&b[i])) || (dark(&b[i]) && lit_as(&a[i]))))
            }
        };
        if !alpha_ok {
            e = f32::INFINITY;
        }
        worst = worst.max(e);
        if e > 1.0 {
            bad += 1;
            first_bad.get_or_insert(format!(
                "({}, {}): {:?} vs cpu {:?}",
                i as u32 % cam.width,
                i as u32 / cam.width,
                b[i],
                a[i]
            ));
        }
    }
    v.check(bad == 0, || {
        format!(
            "{what} differs on {bad} pixels, first {}",
            first_bad.unwrap_or_default()
        )
    });
    v.note(format!("{what}: worst {worst:.3} of tolerance"));
}

/// Sum over the taps of pixel `i`'s pass along `axis` (reach `max_radius_px`) of the
/// input's channel `ch` magnitude.
pub(crate) fn tap_sum(
    cam: &GpuCamera,
    reach: i32,
    axis: u32,
    input: &[[f32; 4]],
    i: usize,
    ch: usize,
) -> f32 {
    let (w, h) = (cam.width as i32, cam.height as i32);
    let (x, y) = (i as i32 % w, i as i32 / w);
    let mut s = 0.0f32;
    for d in -reach..=reach {
        let (qx, qy) = if axis == 0 { (x + d, y) } else { (x, y + d) };
        if qx >= 0 && qy >= 0 && qx < w && qy < h {
            s += input[(qy * w + qx) as usize][ch].abs();
        }
    }
    s
}

/// What subnormal flushing may take from pixel `i` of a `density_gather` pass (in flux,
/// before the conversion to the output): the pass sums `2 reach + 1` taps
/// ([`flushed_sum_allowance`]) and the row pass divides the sum by its normaliser, which
/// holds the pixel's own weight `footprint_weight(0, r_i)`.
pub(crate) fn flush_allowance(reach: i32, axis: u32, input: &[[f32; 4]], i: usize) -> f32 {
    let own = if axis == 0 {
        footprint_weight(0, input[i][3]).max(f32::EPSILON)
    } else {
        1.0
    };
    flushed_sum_allowance(2 * reach as usize + 1) / own
}

/// `photon_count_table`, `gather_footprint` and both `density_gather` passes on the
/// reference's photon map, G-buffer, table and intermediate images.
pub fn check_density_gather(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("photon_count_table + gather_footprint + density_gather");
    let cam = fx.camera;
    let reach = fx.settings.screen.max_radius_px as i32;

    check_count_table(&mut v, fx, inputs, r, c)?;

    check_footprint(&mut v, fx, inputs, r, c)?;

    for axis in 0..2u32 {
        let input = if axis == 0 {
            &inputs.footprints
        } else {
            &inputs.density_rows
        };
        let (g, e) = (&inputs.gbuffer, &inputs.edge);
        let (a, grid_a) = fx.run_density_gather(r, axis, g, e, input)?;
        let (b, grid_b) = fx.run_density_gather(c, axis, g, e, input)?;
        // the row pass adds its own output's grid for the column pass; the column pass
        // writes none
        for (who, out, grid) in [("reference", &a, &grid_a), ("candidate", &b, &grid_b)] {
            let mut want = fx.source_index_of(fx.empty_source_index(), axis, input);
            if axis == 0 {
                want = fx.source_index_of(want, 1, out);
            }
            v.check(*grid == want, || {
                format!("density_gather axis {axis}'s source index on the {who} is wrong")
            });
        }
        // flux -> output units: 1 for the row pass, albedo / (pi A) for the column pass
        let to_output = |i: usize, ch: usize| -> f32 {
            if axis == 0 {
                return 1.0;
            }
            let g = &inputs.gbuffer[i];
            let area = gbuffer_pixel_area(&cam, i as u32, g);
            g.albedo[ch] / (std::f32::consts::PI * area)
        };
        let rel = |i: usize| -> f32 {
            if axis == 0 {
                return DENSITY_GATHER_REL;
            }
            let g = &inputs.gbuffer[i];
            let ray = caustica_core::device::layout::camera_ray(
                &cam,
                i as u32 % cam.width,
                i as u32 / cam.width,
            );
            let cos = ray.dot(Vec3::from(g.normal)).abs().max(MIN_COSINE);
            DENSITY_GATHER_REL + RESOLVE_REL + RESOLVE_COS_REL / cos
        };
        let tol = |i: usize, ch: usize| {
            (
                rel(i),
                tap_sum(&cam, reach, axis, input, i, ch) * to_output(i, ch),
                flush_allowance(reach, axis, input, i) * to_output(i, ch),
            )
        };
        // the radius a lit pixel of the column pass passes through
        let lit_radius = |i: usize| input[i][3];
        compare(
            &mut v,
            &format!("density_gather axis {axis}"),
            &cam,
            (&a, &b),
            &tol,
            if axis == 0 {
                Alpha::Exact
            } else {
                Alpha::ExactOrDark(&lit_radius)
            },
        );
    }
    Ok(v)
}
