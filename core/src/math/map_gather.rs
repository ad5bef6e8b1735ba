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

use glam::{Vec2, Vec3};

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

/// The atlas texel (row-major index in an atlas `atlas_width` texels wide) under `uv`
/// on tile `tile = [x, y, side, _]`: `corner + floor(uv * side)`, clamped to the tile
/// (`frame::caustic_atlas::uv_texel`).
#[inline]
pub fn atlas_texel_index(tile: [u32; 4], uv: Vec2, atlas_width: u32) -> u32 {
    let s = tile[2] as f32;
    let cx = ((uv.x * s).floor().max(0.0) as u32).min(tile[2] - 1);
    let cy = ((uv.y * s).floor().max(0.0) as u32).min(tile[2] - 1);
    (tile[1] + cy) * atlas_width + tile[0] + cx
}

/// A (lo, hi) fixed-point sum as f32: `f32(hi) * 2^32 + f32(lo)` (exact in the parts
/// where they fit 24 bits; two roundings otherwise), what every backend computes the
/// same way (WGSL has no 64-bit integers nor f64).
#[inline]
pub fn join_u64_f32(lo: u32, hi: u32) -> f32 {
    hi as f32 * 4294967296.0 + lo as f32
}

/// The window of width `n` (odd) around texel `(x, y)` clipped to tile `[x0, y0, side,
/// _]`: `(first column, last column, first row, last row)`, inclusive, atlas texels.
#[inline]
pub fn tile_window(tile: [u32; 4], x: u32, y: u32, n: u32) -> (u32, u32, u32, u32) {
    let h = n / 2;
    let (x0, y0, s) = (tile[0], tile[1], tile[2]);
    (
        x.saturating_sub(h).max(x0),
        (x + h).min(x0 + s - 1),
        y.saturating_sub(h).max(y0),
        (y + h).min(y0 + s - 1),
    )
}

/// One texel of the flux-keeping `n x n` gather in the form a kernel runs it (one thread
/// per destination texel `t = (x, y)` of tile `tile`): `sum_s Phi_s / c_s` over the
/// sources `s` of `t`'s window inside the tile, `c_s` the covered texels of `s`'s window
/// (a source whose window covers nothing keeps its flux), over `t`'s world area: the
/// irradiance (W/m^2 per channel) of [`gather_tile_flux`] at `t`, 0 where `t` is not
/// covered. `flux(i)` is texel `i`'s flux (W), `area(i)` its world area (0: uncovered).
pub fn gather_caustic_texel(
    tile: [u32; 4],
    x: u32,
    y: u32,
    n: u32,
    atlas_width: u32,
    flux: impl Fn(u32) -> Vec3,
    area: impl Fn(u32) -> f32,
) -> Vec3 {
    let t = y * atlas_width + x;
    let area_t = area(t);
    let (ax, bx, ay, by) = tile_window(tile, x, y, n);
    let mut sum = Vec3::ZERO;
    for qy in ay..=by {
        for qx in ax..=bx {
            let q = qy * atlas_width + qx;
            let f = flux(q);
            if f == Vec3::ZERO {
                continue;
            }
            let (cx0, cx1, cy0, cy1) = tile_window(tile, qx, qy, n);
            let mut c = 0u32;
            for sy in cy0..=cy1 {
                for sx in cx0..=cx1 {
                    c += (area(sy * atlas_width + sx) > 0.0) as u32;
                }
            }
            if c == 0 {
                if q == t {
                    sum += f;
                }
            } else if area_t > 0.0 {
                sum += f / c as f32;
            }
        }
    }
    if area_t > 0.0 {
        sum / area_t
    } else {
        Vec3::ZERO
    }
}

/// Widest footprint (texels a side) the lookup averages; wider footprints are averaged
/// over this many (a distant receiver then aliases, as a texture without mip levels).
pub const MAX_FOOTPRINT_TEXELS: f32 = 32.0;

/// Side (atlas texels) of a pixel's footprint on a receiver: the pixel's cone of angular
/// size `pixel_angle` (radians, `2 tan(fov_y / 2) / height`) at `distance` along the camera
/// path (scene units, summed over its segments: a ray cone unfolded through mirrors and
/// glass, their curvature ignored) covers `(pixel_angle distance)^2 / cos` of the surface
/// (`cos` between the arriving ray and the normal, floored at 1e-3), i.e. that area over
/// `texel_area` texels, as a square.
#[inline]
pub fn footprint_texels(pixel_angle: f32, distance: f32, cos: f32, texel_area: f32) -> f32 {
    let w = pixel_angle * distance;
    let area = w * w / cos.abs().max(1e-3);
    if texel_area > 0.0 {
        (area / texel_area).sqrt()
    } else {
        0.0
    }
}

/// The caustic map at `uv` on tile `tile` (atlas `atlas_width` texels wide), filtered over
/// a pixel's footprint of `footprint` texels a side ([`footprint_texels`]): where it is at
/// most 1 texel, bilinear over the four texels around `uv * side - 0.5` (clamped to the
/// tile), each weighted by its bilinear weight if covered (`area(i) > 0`) and renormalised
/// by the covered weights; where it is wider, the mean of the covered texels whose centres
/// lie in the square `[f - side / 2, f + side / 2)` (at most [`MAX_FOOTPRINT_TEXELS`] a
/// side) around `f = uv * side_of_tile - 0.5`, so that a
/// caustic sharper than a pixel is integrated over the pixel as a screen-space deposit
/// integrates it, not point-sampled. Texels outside the receiver's UV triangles hold no
/// irradiance and are left out of both. `map(i)` is texel `i`'s irradiance (W/m^2).
pub fn sample_caustic_map(
    tile: [u32; 4],
    uv: Vec2,
    footprint: f32,
    atlas_width: u32,
    map: impl Fn(u32) -> Vec3,
    area: impl Fn(u32) -> f32,
) -> Vec3 {
    let s = tile[2] as f32;
    let fx = (uv.x * s - 0.5).clamp(0.0, s - 1.0);
    let fy = (uv.y * s - 0.5).clamp(0.0, s - 1.0);
    if footprint > 1.0 {
        let h = 0.5 * footprint.min(MAX_FOOTPRINT_TEXELS);
        let x0 = (fx - h).ceil().max(0.0) as u32;
        let x1 = (((fx + h).ceil() - 1.0).min(s - 1.0)) as u32;
        let y0 = (fy - h).ceil().max(0.0) as u32;
        let y1 = (((fy + h).ceil() - 1.0).min(s - 1.0)) as u32;
        let mut sum = Vec3::ZERO;
        let mut n = 0u32;
        for y in y0..=y1 {
            for x in x0..=x1 {
                let i = (tile[1] + y) * atlas_width + tile[0] + x;
                if area(i) > 0.0 {
                    sum += map(i);
                    n += 1;
                }
            }
        }
        if n > 0 {
            return sum / n as f32;
        }
    }
    let (x0, y0) = (fx.floor(), fy.floor());
    let (wx, wy) = (fx - x0, fy - y0);
    let (ix0, iy0) = (x0 as u32, y0 as u32);
    let (ix1, iy1) = ((ix0 + 1).min(tile[2] - 1), (iy0 + 1).min(tile[2] - 1));
    let mut sum = Vec3::ZERO;
    let mut wsum = 0.0f32;
    for (ix, iy, w) in [
        (ix0, iy0, (1.0 - wx) * (1.0 - wy)),
        (ix1, iy0, wx * (1.0 - wy)),
        (ix0, iy1, (1.0 - wx) * wy),
        (ix1, iy1, wx * wy),
    ] {
        let i = (tile[1] + iy) * atlas_width + tile[0] + ix;
        if area(i) > 0.0 && w > 0.0 {
            sum += w * map(i);
            wsum += w;
        }
    }
    if wsum > 0.0 {
        sum / wsum
    } else {
        Vec3::ZERO
    }
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

    #[test]
    fn the_kernel_form_is_the_tile_gather_over_the_area() {
        // a 6x6 tile at (3, 2) of a 12-wide atlas, random coverage and areas
        let (w, tile) = (12u32, [3u32, 2, 6, 0]);
        let mut k = 0u32;
        let mut rnd = || {
            k += 1;
            random_f32(11, k, 0, 0)
        };
        let len = (w * 10) as usize;
        let area: Vec<f32> = (0..len)
            .map(|_| if rnd() > 0.25 { 0.5 + rnd() } else { 0.0 })
            .collect();
        let flux: Vec<Vec3> = (0..len).map(|_| Vec3::splat(rnd())).collect();
        let at = |x: u32, y: u32| ((tile[1] + y) * w + tile[0] + x) as usize;
        let tile_flux: Vec<Vec3> = (0..36).map(|i| flux[at(i % 6, i / 6)]).collect();
        let covered: Vec<bool> = (0..36).map(|i| area[at(i % 6, i / 6)] > 0.0).collect();
        let want = gather_tile_flux(&tile_flux, &covered, 6, 3);
        for i in 0..36u32 {
            let (x, y) = (tile[0] + i % 6, tile[1] + i / 6);
            let e =
                gather_caustic_texel(tile, x, y, 3, w, |q| flux[q as usize], |q| area[q as usize]);
            let a = area[at(i % 6, i / 6)];
            let f = if a > 0.0 {
                want[i as usize] / a
            } else {
                Vec3::ZERO
            };
            assert!(
                (e - f).length() <= 1e-5 * f.length().max(1.0),
                "texel {i}: {e} vs {f}"
            );
        }
    }

    #[test]
    fn the_lookup_is_exact_on_a_uniform_map_and_ignores_uncovered_texels() {
        let (w, tile) = (8u32, [2u32, 1, 4, 0]);
        let area: Vec<f32> = (0..64)
            .map(|i| if i % 8 == 5 { 0.0 } else { 1.0 })
            .collect();
        for (u, v) in [(0.0, 0.0), (0.3, 0.7), (0.8, 0.5), (0.5, 1.0)] {
            for fp in [0.0, 1.0, 2.5, 7.0, 100.0] {
                let e = sample_caustic_map(
                    tile,
                    Vec2::new(u, v),
                    fp,
                    w,
                    |_| Vec3::splat(2.0),
                    |i| area[i as usize],
                );
                assert_eq!(e, Vec3::splat(2.0), "uv ({u}, {v}), footprint {fp}");
            }
        }
        assert_eq!(atlas_texel_index(tile, Vec2::new(1.0, 0.0), w), 8 + 2 + 3);
    }

    #[test]
    fn a_wide_footprint_integrates_a_one_texel_caustic() {
        // all the flux in one texel of a 16x16 tile: a footprint of 4 texels averages it
        // over the 4x4 texels around uv, as a pixel of that size would see it
        let (w, tile) = (16u32, [0u32, 0, 16, 0]);
        let map = |i: u32| {
            if i == 8 * 16 + 8 {
                Vec3::splat(16.0)
            } else {
                Vec3::ZERO
            }
        };
        let uv = Vec2::new(8.5 / 16.0, 8.5 / 16.0);
        let point = sample_caustic_map(tile, uv, 1.0, w, map, |_| 1.0);
        let wide = sample_caustic_map(tile, uv, 4.0, w, map, |_| 1.0);
        assert_eq!(point, Vec3::splat(16.0));
        // texel centres in [6, 10): 4x4 texels
        assert_eq!(wide, Vec3::splat(1.0));
        assert!((footprint_texels(0.01, 2.0, 1.0, 1e-4) - 2.0).abs() < 1e-5);
    }
}
