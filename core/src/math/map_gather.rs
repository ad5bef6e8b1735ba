//! The caustic map's N x N neighbour gather (seed 001 section "3.1 Denoising", second
//! render pass), fixed so that it keeps the map's flux, within one atlas tile.
//!
//! **The source's normalisation.** 001 sums the `N x N` texels around a texel
//! (`gatherLength = (N - 1) / 2` on each side) and divides by
//! `gatherSqDistance * gatherSqDistance + gatherLength`, i.e. `N^2 + (N - 1) / 2`: 10 for
//! the default `N = 3`, where the window holds 9 texels. A uniform map comes out at 9/10
//! of itself: the gather loses 10% of the caustic's flux (`h / (N^2 + h)` with
//! `h = (N - 1) / 2` in general: 7.4% at N = 5). The average it means is `sum / N^2`.
//!
//! **Keeping flux.** Even `sum / N^2` keeps flux only where every texel of every window is
//! a texel of the receiver: at a tile's border or next to texels no triangle covers, a
//! gather-normalised average loses (or, after a renormalisation by the texels present,
//! gains) flux. So the gather here is normalised per *source* (as Sspm's density gather,
//! `math::density_gather`): texel `s` of the tile spreads its flux `Phi_s` equally over
//! the `c_s` covered texels of its window inside the tile, and destination `t` receives
//! `sum_s Phi_s / c_s` over the sources whose windows hold it. Every source's flux lands
//! somewhere (a source whose window holds no covered texel keeps its flux), so the tile's
//! flux is kept exactly in real arithmetic, and where all windows are whole it is 001's
//! average with the corrected `1 / N^2`. The gather never crosses a tile's border: a
//! tile is one receiver, and its neighbours in the atlas are other receivers.
//!
//! The map holds irradiance (W/m^2, `frame::caustic_atlas`); the gather works on flux
//! (irradiance times the texel's world area) and converts back with the destination's
//! area.

use glam::Vec3;

/// 001's default window: 3 x 3 on a 2048^2 map.
pub const DEFAULT_GATHER_WIDTH: u32 = 3;

/// Covered texels of the window of width `n` around `(x, y)` inside a `side x side` tile
/// (row-major `covered`).
pub fn covered_in_window(covered: &[bool], side: u32, x: u32, y: u32, n: u32) -> u32 {
    let h = (n / 2) as i64;
    let (x, y, s) = (x as i64, y as i64, side as i64);
    let mut c = 0;
    for qy in (y - h).max(0)..=(y + h).min(s - 1) {
        for qx in (x - h).max(0)..=(x + h).min(s - 1) {
            c += covered[(qy * s + qx) as usize] as u32;
        }
    }
    c
}

/// The flux-keeping `n x n` gather of one `side x side` tile (`n` odd): per texel, the
/// flux it receives from the sources whose windows hold it (see the module doc). `flux`
/// and the result are W per channel per texel, row-major.
pub fn gather_tile_flux(flux: &[Vec3], covered: &[bool], side: u32, n: u32) -> Vec<Vec3> {
    let h = (n / 2) as i64;
    let s = side as i64;
    let mut out = vec![Vec3::ZERO; flux.len()];
    // gather form, as a kernel runs it: destination t sums its window's sources
    for ty in 0..s {
        for tx in 0..s {
            let t = (ty * s + tx) as usize;
            let mut sum = Vec3::ZERO;
            for qy in (ty - h).max(0)..=(ty + h).min(s - 1) {
                for qx in (tx - h).max(0)..=(tx + h).min(s - 1) {
                    let q = (qy * s + qx) as usize;
                    if flux[q] == Vec3::ZERO {
                        continue;
                    }
                    let c = covered_in_window(covered, side, qx as u32, qy as u32, n);
                    if c == 0 {
                        // a source with no covered texel around it keeps its flux
                        if q == t {
                            sum += flux[q];
                        }
                    } else if covered[t] {
                        sum += flux[q] / c as f32;
                    }
                }
            }
            out[t] = sum;
        }
    }
    out
}

/// 001's gather as printed: the window's sum over `N^2 + (N - 1) / 2` (kept to measure
/// what the fix changes).
pub fn source_gather_texel(map: &[Vec3], side: u32, x: u32, y: u32, n: u32) -> Vec3 {
    let h = (n / 2) as i64;
    let s = side as i64;
    let mut sum = Vec3::ZERO;
    for qy in (y as i64 - h).max(0)..=(y as i64 + h).min(s - 1) {
        for qx in (x as i64 - h).max(0)..=(x as i64 + h).min(s - 1) {
            sum += map[(qy * s + qx) as usize];
        }
    }
    sum / ((n * n) as f32 + h as f32)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::rng::random_f32;

    fn total(v: &[Vec3]) -> f64 {
        v.iter().map(|f| f.x as f64).sum()
    }

    #[test]
    fn the_sources_normalisation_loses_a_tenth_at_n_3() {
        let map = vec![Vec3::ONE; 64];
        let g = source_gather_texel(&map, 8, 4, 4, 3);
        assert!((g.x - 0.9).abs() < 1e-6);
    }

    #[test]
    fn interior_texels_get_the_plain_average() {
        let side = 9;
        let flux: Vec<Vec3> = (0..81).map(|i| Vec3::splat((i % 7) as f32 + 1.0)).collect();
        let covered = vec![true; 81];
        let g = gather_tile_flux(&flux, &covered, side, 3);
        // texel (4, 4): every window around its neighbours is whole
        let mut avg = Vec3::ZERO;
        for y in 3..=5 {
            for x in 3..=5 {
                avg += flux[y * 9 + x];
            }
        }
        assert!((g[4 * 9 + 4] - avg / 9.0).length() < 1e-5);
    }

    #[test]
    fn the_gather_keeps_the_tiles_flux_at_borders_and_holes() {
        let mut k = 0u32;
        let mut rnd = || {
            k += 1;
            random_f32(7, k, 0, 0)
        };
        for (side, n) in [(1, 3), (5, 3), (16, 3), (16, 5), (33, 7)] {
            let len = (side * side) as usize;
            let covered: Vec<bool> = (0..len).map(|_| rnd() > 0.2).collect();
            // flux where photons landed: mostly covered texels, a few uncovered (edge
            // texels a photon's UV fell into)
            let flux: Vec<Vec3> = (0..len)
                .map(|i| {
                    if covered[i] || rnd() < 0.3 {
                        Vec3::splat(rnd() * 3.0)
                    } else {
                        Vec3::ZERO
                    }
                })
                .collect();
            let g = gather_tile_flux(&flux, &covered, side, n);
            let (a, b) = (total(&flux), total(&g));
            // f32 sums of ~len terms: relative error ~ len * 2^-24
            assert!(((b - a) / a).abs() < 1e-5, "{side} {n}: {a} -> {b}");
            // nothing lands on uncovered texels but what stayed there
            for i in 0..len {
                if !covered[i] {
                    assert!(g[i] == Vec3::ZERO || g[i] == flux[i], "texel {i}");
                }
            }
        }
    }
}
