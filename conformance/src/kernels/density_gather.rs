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

/// Compares `a` (reference) and `b` per pixel and channel: `|a - b| <= rel * (max(|a|,
/// |b|) + gathered) + absolute` with `(rel, gathered, absolute) = tol(i, ch)`; alpha must
/// be bitwise equal when `alpha_exact`, unless the pixel is dark (all channels 0) on one
/// side and its channels are within the bound on the other. A pass writes the dark pixel
/// (alpha 0) where its sum is exactly 0, and that test is not continuous: a GPU may flush
/// a subnormal sum to zero, and a weight at the very edge of a kernel's support (two
/// nearly equal antiderivatives subtracted) rounds to 0 on one backend and to one ulp on
/// another, as a fused multiply-add keeps a bit the separate product lost. The channels'
/// bound holds that difference either way. Records the failures in `v` under `what`.
pub(crate) fn compare(
    v: &mut Verdict,
    what: &str,
    cam: &GpuCamera,
    (a, b): (&[[f32; 4]], &[[f32; 4]]),
    tol: &dyn Fn(usize, usize) -> (f32, f32, f32),
    alpha_exact: bool,
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
        // a side whose sum was exactly zero wrote the dark pixel (alpha 0): allowed where
        // the other side's channels are within their bound (`e <= 1`)
        let dark = |p: &[f32; 4]| p[..3].iter().all(|c| *c == 0.0);
        let dark_on_one_side = (dark(&a[i]) || dark(&b[i])) && e <= 1.0;
        if alpha_exact && a[i][3].to_bits() != b[i][3].to_bits() && !dark_on_one_side {
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
        compare(
            &mut v,
            &format!("density_gather axis {axis}"),
            &cam,
            (&a, &b),
            &tol,
            true,
        );
    }
    Ok(v)
}
