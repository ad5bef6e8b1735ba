//! `bilateral_gather`, both directions, on the reference's raw caustics, G-buffer and tiles:
//! every pixel and channel within [`GATHER_REL`] relative, alpha (the mean hit distance,
//! passed through) bitwise equal. Pixels whose gather radius lies within `GATHER_REL` of an
//! integer are left out (there floating point decides the number of taps). Its check,
//! [`check_gather`], also holds `tile_hit_distance`'s comparison ([`compare_tiles`]) in the
//! same verdict; each of the two compares on the reference's inputs.

use super::tile_hit_distance::compare_tiles;
use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::tolerance::GATHER_REL;
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;
use caustica_core::device::layout::gbuffer_flags;

/// `tile_hit_distance` and both `bilateral_gather` directions on the reference's photon
/// map, raw caustics, G-buffer and tiles.
pub fn check_gather(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("tile_hit_distance + bilateral_gather");
    compare_tiles(fx, inputs, r, c, &mut v)?;
    let cam = &fx.camera;
    let ts = fx.settings.screen.tile_size;
    let tw = cam.width.div_ceil(ts);
    for axis in 0..2u32 {
        let params = fx.constants.gather_params(*cam, &fx.settings, axis);
        let a = fx.run_gather(r, axis, &inputs.gbuffer, &inputs.tiles, &inputs.raw)?;
        let b = fx.run_gather(c, axis, &inputs.gbuffer, &inputs.tiles, &inputs.raw)?;
        let (mut ambiguous, mut bad, mut worst, mut first_bad) = (0u64, 0u64, 0.0f32, None);
        for i in 0..a.len() {
            let (x, y) = (i as u32 % cam.width, i as u32 / cam.width);
            let g = &inputs.gbuffer[i];
            if g.flags & gbuffer_flags::RECEIVER != 0 {
                let tile = inputs.tiles[((y / ts) * tw + x / ts) as usize];
                let rad =
                    caustica_cpu::kernels::bilateral_gather::gather_radius_px(&params, g, tile);
                if rad < params.max_radius_px as f32
                    && (rad - rad.round()).abs() <= GATHER_REL * rad.max(1.0)
                {
                    ambiguous += 1;
                    continue;
                }
            }
            let mut e = 0.0f32;
            for ch in 0..3 {
                let scale = a[i][ch].abs().max(b[i][ch].abs());
                let d = (a[i][ch] - b[i][ch]).abs();
                let x = if d == 0.0 {
                    0.0
                } else {
                    d / (GATHER_REL * scale)
                };
                e = e.max(if x.is_nan() { f32::INFINITY } else { x });
            }
            // alpha (mean hit distance) passes through unchanged
            if a[i][3].to_bits() != b[i][3].to_bits() {
                e = f32::INFINITY;
            }
            worst = worst.max(e);
            if e > 1.0 {
                bad += 1;
                first_bad.get_or_insert(format!("({x},{y}): {:?} vs cpu {:?}", b[i], a[i]));
            }
        }
        v.check(bad == 0, || {
            format!(
                "bilateral_gather axis {axis} differs on {bad} pixels, first {}",
                first_bad.unwrap_or_default()
            )
        });
        v.note(format!(
            "axis {axis}: worst {worst:.3} of tolerance; {ambiguous} pixels with an integer radius skipped"
        ));
    }
    Ok(v)
}
