//! The caustic map's N x N neighbour gather (Vanderstichelen 2021, section "3.1 Denoising", second
//! render pass), fixed so that it keeps the map's flux, within one atlas tile.
//!
//! **The source's normalisation.** Vanderstichelen 2021 sums the `N x N` texels around a texel
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
//! flux is kept exactly in real arithmetic, and where all windows are whole it is Vanderstichelen 2021's
//! average with the corrected `1 / N^2`. The gather never crosses a tile's border: a
//! tile is one receiver, and its neighbours in the atlas are other receivers.
//!
//! The map holds irradiance (W/m^2, `frame::receivers::atlas::layout`); the gather works on flux
//! (irradiance times the texel's world area) and converts back with the destination's
//! area.

use glam::{Vec2, Vec3};

/// Vanderstichelen 2021's default window: 3 x 3 on a 2048^2 map.
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

/// Vanderstichelen 2021's gather as printed: the window's sum over `N^2 + (N - 1) / 2` (kept to measure
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
/// (`frame::receivers::atlas::layout::uv_texel`).
#[inline]
pub fn atlas_texel_index(tile: [u32; 4], uv: Vec2, atlas_width: u32) -> u32 {
    let s = tile[2] as f32;
    let cx = ((uv.x * s).floor().max(0.0) as u32).min(tile[2] - 1);
    let cy = ((uv.y * s).floor().max(0.0) as u32).min(tile[2] - 1);
    (tile[1] + cy) * atlas_width + tile[0] + cx
}

/// Words per atlas texel of the centroid sums (`AtlasBuffers::centroids`): the sums of
/// the texel's photons' offsets inside it along x and along y, in 1/[`CENTROID_SUBTEXELS`]
/// of a texel ([`centroid_offset`]), and their count.
pub const CENTROID_WORDS: u32 = 3;

/// Steps a photon's offset inside its texel is quantised to, per axis.
pub const CENTROID_SUBTEXELS: u32 = 256;

/// Photons a texel's centroid sums hold at most: past it (2^24 photons in one texel,
/// where an offset sum could wrap its 32 bits) the lookup spreads the texel's flux
/// over its whole area again, and the deposit counts the crossing as saturated.
pub const CENTROID_MAX_PHOTONS: u32 = 1 << 24;

/// A photon's offset inside its atlas texel at `uv` on tile `tile`, per axis in
/// 1/[`CENTROID_SUBTEXELS`] of a texel (0..=255): `floor(uv side 256) - 256 texel`,
/// clamped, with the texel [`atlas_texel_index`]'s (clamped to the tile). Products by
/// powers of two and a floor only, so that every backend computes the same integers.
#[inline]
pub fn centroid_offset(tile: [u32; 4], uv: Vec2) -> [u32; 2] {
    let s = tile[2] as f32;
    let q = |u: f32| {
        let c = ((u * s).floor().max(0.0) as u32).min(tile[2] - 1);
        let steps = (u * s * CENTROID_SUBTEXELS as f32).floor().max(0.0) as u32;
        steps
            .saturating_sub(c * CENTROID_SUBTEXELS)
            .min(CENTROID_SUBTEXELS - 1)
    };
    [q(uv.x), q(uv.y)]
}

/// The mean position (texel-local, 0..1 per axis) of a texel's photons from its centroid
/// sums `(sum x, sum y, photons)`: `(sum + n / 2) / (256 n)`, each photon at the middle
/// of its step; the texel's middle (1/2, 1/2) without photons or past
/// [`CENTROID_MAX_PHOTONS`].
#[inline]
pub fn texel_centroid(sum_x: u32, sum_y: u32, n: u32) -> Vec2 {
    if n == 0 || n >= CENTROID_MAX_PHOTONS {
        return Vec2::splat(0.5);
    }
    let (nf, d) = (n as f32, (n * CENTROID_SUBTEXELS) as f32);
    Vec2::new((sum_x as f32 + 0.5 * nf) / d, (sum_y as f32 + 0.5 * nf) / d)
}

/// The share of a texel's flux inside `[lo, hi)` (texel-local coordinates along one
/// axis) when it lies uniformly on the widest interval around its photons' mean `c` that
/// the texel holds, `[c - a, c + a]` with `a = min(c, 1 - c)`: the whole texel for
/// `c = 1/2` (a texel read as uniform), the half next to a border for photons all on
/// that half. A focused caustic's edge (a fold, where a ball's marginal rays cross) runs
/// through texels whose flux lies on one side of it; read as uniform, such a texel hands
/// flux across the edge to the pixel beyond it wherever a pixel border cuts it.
#[inline]
pub fn centroid_share(c: f32, lo: f32, hi: f32) -> f32 {
    let a = c.min(1.0 - c).max(0.5 / CENTROID_SUBTEXELS as f32);
    ((hi.min(c + a) - lo.max(c - a)).max(0.0) / (2.0 * a)).min(1.0)
}

/// The word and the bit of scene triangle `t` in a triangle reach mask (one bit per
/// triangle, 32 to a `u32` word): the atlas deposit (`trace_photons`' `fused_deposit`) or-s the bit of every photon's triangle
/// into it.
#[inline]
pub fn triangle_reach_bit(t: u32) -> (u32, u32) {
    (t >> 5, 1u32 << (t & 31))
}

/// Words of a triangle reach mask over `triangles` scene triangles (at least one).
#[inline]
pub fn triangle_reach_words(triangles: u32) -> u32 {
    triangles.div_ceil(32).max(1)
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

/// Flag in a tile's fourth word (`[x, y, side, receiver | flag]`,
/// `device::layout::AtlasTileTexel`): every texel of the tile is covered (a UV triangle of
/// the receiver holds its centre, so its world area is > 0), as for receivers whose UVs
/// fill their square (the built-in quads and spheres). The gather then knows each
/// source's covered count from the window's size alone ([`window_coverage`]).
pub const TILE_FULLY_COVERED: u32 = 1 << 31;

/// The receiver object index of a tile's fourth word (without [`TILE_FULLY_COVERED`]).
pub fn tile_receiver(word: u32) -> u32 {
    word & !TILE_FULLY_COVERED
}

/// `c_s` of the gather: the covered texels of source `(qx, qy)`'s window of width `n`
/// inside `tile`. In a tile flagged [`TILE_FULLY_COVERED`] that is the clipped window's
/// size, which equals the count of texels with `area(i) > 0` over it; otherwise they are
/// counted. The kernels' `window_coverage` mirror it (the count a texel of the
/// `gather_caustic_map` kernel's hottest loop made 9 reads for: 0.26 against 0.15 ms for
/// the 2048^2 atlas of Vanderstichelen 2021's setting 0 on an H200).
pub fn window_coverage(
    tile: [u32; 4],
    qx: u32,
    qy: u32,
    n: u32,
    atlas_width: u32,
    area: impl Fn(u32) -> f32,
) -> u32 {
    let (cx0, cx1, cy0, cy1) = tile_window(tile, qx, qy, n);
    if tile[3] & TILE_FULLY_COVERED != 0 {
        return (cx1 - cx0 + 1) * (cy1 - cy0 + 1);
    }
    let mut c = 0u32;
    for sy in cy0..=cy1 {
        for sx in cx0..=cx1 {
            c += (area(sy * atlas_width + sx) > 0.0) as u32;
        }
    }
    c
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
    // an uncovered destination receives nothing (its sum would be dropped below)
    if !(area_t > 0.0) {
        return Vec3::ZERO;
    }
    let (ax, bx, ay, by) = tile_window(tile, x, y, n);
    let mut sum = Vec3::ZERO;
    for qy in ay..=by {
        for qx in ax..=bx {
            let q = qy * atlas_width + qx;
            let f = flux(q);
            if f == Vec3::ZERO {
                continue;
            }
            let c = window_coverage(tile, qx, qy, n, atlas_width, &area);
            if c == 0 {
                if q == t {
                    sum += f;
                }
            } else {
                sum += f / c as f32;
            }
        }
    }
    sum / area_t
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

/// Half-extents (texels, along the tile's x and y) of the axis-aligned rectangle that
/// bounds a pixel's footprint on a receiver's triangle: the pixel's cross-section, a
/// square of side `width` (scene units: the cone's width at the surface, `pixel_angle`
/// times the path's length) perpendicular to the arriving unit direction `dir`, with one
/// side along the camera's `right` made perpendicular to `dir`, projected along `dir` onto
/// the triangle's plane (world corners `p`; so a grazing view stretches it by
/// `1 / cos`, with `cos` floored at 1e-3), then mapped to the tile's texels by the
/// triangle's world-to-UV map (UV corners `t`, a tile of `side` texels; the map is affine
/// on a triangle, `uv - t0 = [t1 - t0, t2 - t0] G^-1 [e1, e2]^T (x - p0)`, `G` the Gram
/// matrix of the edges `e1 = p1 - p0`, `e2 = p2 - p0`). The rectangle is the bound of that
/// parallelogram, which it equals where the pixel's sides run along the tile's axes (a
/// receiver whose UVs follow the camera's right and up, as `sphere`'s plane seen from its
/// camera). Through mirrors and glass the square's orientation is the camera's, not the
/// path's (a ray cone unfolded along the path, as [`footprint_texels`]). `(-1, -1)` where
/// the triangle has no area or no UV area: the caller falls back to
/// [`footprint_texels`].
pub fn footprint_extent(
    dir: Vec3,
    right: Vec3,
    width: f32,
    p: [Vec3; 3],
    t: [Vec2; 3],
    side: u32,
) -> Vec2 {
    let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
    let (g11, g12, g22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
    let det = g11 * g22 - g12 * g12;
    let (d1, d2) = (t[1] - t[0], t[2] - t[0]);
    let n = e1.cross(e2);
    let n_len = n.length();
    if !(det > 0.0 && n_len > 0.0) || d1.perp_dot(d2) == 0.0 {
        return Vec2::splat(-1.0);
    }
    let n = n / n_len;
    // the cross-section's sides: `right` made perpendicular to `dir`, and dir x that
    // (a camera ray is never along `right`; a mirrored one may be: then world x, or y)
    let mut a = right - dir * right.dot(dir);
    if !(a.dot(a) > 1e-12) {
        a = Vec3::X - dir * dir.x;
        if !(a.dot(a) > 1e-12) {
            a = Vec3::Y - dir * dir.y;
        }
    }
    let a = a * (1.0 / a.dot(a).sqrt());
    let b = dir.cross(a);
    // along `dir` onto the plane: v - dir (n . v) / (n . dir)
    let c = dir.dot(n);
    let c = if c.abs() < 1e-3 {
        1e-3f32.copysign(c)
    } else {
        c
    };
    let onto = |v: Vec3| width * (v - dir * (n.dot(v) / c));
    let to_texels = |v: Vec3| {
        let (x1, x2) = (e1.dot(v), e2.dot(v));
        let alpha = (g22 * x1 - g12 * x2) / det;
        let beta = (g11 * x2 - g12 * x1) / det;
        (d1 * alpha + d2 * beta) * side as f32
    };
    let (ta, tb) = (to_texels(onto(a)), to_texels(onto(b)));
    0.5 * (ta.abs() + tb.abs())
}

/// One texel's share `[i, i + 1) ∩ [lo, hi)` of an interval (texels).
#[inline]
fn overlap(i: u32, lo: f32, hi: f32) -> f32 {
    ((i as f32 + 1.0).min(hi) - (i as f32).max(lo)).max(0.0)
}

/// The caustic map at `uv` on tile `tile` (atlas `atlas_width` texels wide), averaged over
/// a pixel's footprint, the axis-aligned rectangle of half-extents `extent` (texels,
/// [`footprint_extent`]) centred on `uv * side` (texel `i` spans `[i, i + 1)`): where it is
/// wider than a texel on either axis, the flux of the covered texels (`area(i) > 0`) it
/// overlaps over the overlapped area, each texel's irradiance weighted by the share of its
/// flux inside the rectangle, per axis [`centroid_share`] of its photons' mean
/// `centroid(i)` ([`texel_centroid`]; a centroid of (1/2, 1/2) gives the overlap's area:
/// the texel read as uniform), so that a caustic sharper than a pixel is integrated over
/// the pixel, as a screen-space deposit integrates it, not point-sampled, and the flux of
/// a texel that a focused caustic's edge crosses stays on its side of the edge
/// (half-extents clamped to `[1/2, MAX_FOOTPRINT_TEXELS / 2]`, the rectangle to the
/// tile); otherwise (both half-extents at most 1/2) bilinear over the four
/// texels around `uv * side - 0.5` (clamped to the tile), each weighted by its bilinear
/// weight if covered and renormalised by the covered weights. Texels outside the
/// receiver's UV triangles hold no irradiance and are left out of both. `map(i)` is texel
/// `i`'s irradiance (W/m^2).
pub fn sample_caustic_map(
    tile: [u32; 4],
    uv: Vec2,
    extent: Vec2,
    atlas_width: u32,
    map: impl Fn(u32) -> Vec3,
    area: impl Fn(u32) -> f32,
    centroid: impl Fn(u32) -> Vec2,
) -> Vec3 {
    let s = tile[2] as f32;
    if extent.x > 0.5 || extent.y > 0.5 {
        let hx = extent.x.clamp(0.5, 0.5 * MAX_FOOTPRINT_TEXELS);
        let hy = extent.y.clamp(0.5, 0.5 * MAX_FOOTPRINT_TEXELS);
        let (cx, cy) = ((uv.x * s).clamp(0.0, s), (uv.y * s).clamp(0.0, s));
        let (lx, hx) = ((cx - hx).max(0.0), (cx + hx).min(s));
        let (ly, hy) = ((cy - hy).max(0.0), (cy + hy).min(s));
        let (x0, x1) = (lx.floor() as u32, (hx.ceil() as u32).clamp(1, tile[2]) - 1);
        let (y0, y1) = (ly.floor() as u32, (hy.ceil() as u32).clamp(1, tile[2]) - 1);
        let mut sum = Vec3::ZERO;
        let mut wsum = 0.0f32;
        for y in y0..=y1 {
            let wy = overlap(y, ly, hy);
            for x in x0..=x1 {
                let i = (tile[1] + y) * atlas_width + tile[0] + x;
                let w = overlap(x, lx, hx) * wy;
                if area(i) > 0.0 && w > 0.0 {
                    let c = centroid(i);
                    let share = centroid_share(c.x, lx - x as f32, hx - x as f32)
                        * centroid_share(c.y, ly - y as f32, hy - y as f32);
                    sum += share * map(i);
                    wsum += w;
                }
            }
        }
        if wsum > 0.0 {
            return sum / wsum;
        }
    }
    let fx = (uv.x * s - 0.5).clamp(0.0, s - 1.0);
    let fy = (uv.y * s - 0.5).clamp(0.0, s - 1.0);
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
    fn a_fully_covered_tiles_flag_changes_no_bit_of_the_gather() {
        // a 7x7 tile at (2, 3) of a 13-wide atlas, every texel covered, sparse flux
        let (w, plain) = (13u32, [2u32, 3, 7, 5]);
        let flagged = [2u32, 3, 7, 5 | TILE_FULLY_COVERED];
        assert_eq!(tile_receiver(flagged[3]), 5);
        let mut k = 0u32;
        let mut rnd = || {
            k += 1;
            random_f32(13, k, 0, 0)
        };
        let len = (w * 12) as usize;
        let area: Vec<f32> = (0..len).map(|_| 0.25 + rnd()).collect();
        let flux: Vec<Vec3> = (0..len)
            .map(|_| {
                if rnd() < 0.4 {
                    Vec3::new(rnd(), rnd(), 0.0)
                } else {
                    Vec3::ZERO
                }
            })
            .collect();
        for n in [1, 3, 5, 9] {
            for i in 0..49u32 {
                let (x, y) = (plain[0] + i % 7, plain[1] + i / 7);
                assert_eq!(
                    window_coverage(flagged, x, y, n, w, |q| area[q as usize]),
                    window_coverage(plain, x, y, n, w, |q| area[q as usize]),
                    "n {n} texel {i}"
                );
                let g = |t| {
                    gather_caustic_texel(t, x, y, n, w, |q| flux[q as usize], |q| area[q as usize])
                };
                let (a, b) = (g(plain), g(flagged));
                assert_eq!(
                    a.to_array().map(f32::to_bits),
                    b.to_array().map(f32::to_bits),
                    "n {n} texel {i}"
                );
            }
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
                    Vec2::new(0.5 * fp, 0.25 * fp),
                    w,
                    |_| Vec3::splat(2.0),
                    |i| area[i as usize],
                    |_| Vec2::splat(0.5),
                );
                assert_eq!(e, Vec3::splat(2.0), "uv ({u}, {v}), footprint {fp}");
            }
        }
        assert_eq!(atlas_texel_index(tile, Vec2::new(1.0, 0.0), w), 8 + 2 + 3);
    }

    /// A texel read as uniform (no photons' centroid).
    const MID: fn(u32) -> Vec2 = |_| Vec2::splat(0.5);

    #[test]
    fn a_texels_centroid_keeps_its_flux_on_its_side_of_a_pixel_border() {
        // photons only on the left half of texel 8 of a 16-texel row: a footprint whose
        // border cuts the texel in the middle gets all of its flux on the left, none on
        // the right; the two footprints together keep the texel's flux
        let (w, tile) = (16u32, [0u32, 0, 16, 0]);
        let lit = 8 * 16 + 8;
        let map = |i: u32| Vec3::splat(if i == lit { 16.0 } else { 0.0 });
        let n = 1000u32;
        // offsets 0..=127 in steps: the left half, mean 63.5 / 256 + 1 / 512 = 0.25
        let left = texel_centroid(63 * n + n / 2, 128 * n - n / 2, n);
        assert!(
            (left.x - 0.25).abs() < 1e-3 && (left.y - 0.5).abs() < 1e-3,
            "{left}"
        );
        let centroid = |i: u32| if i == lit { left } else { Vec2::splat(0.5) };
        let at = |x: f32| {
            let uv = Vec2::new(x / 16.0, 8.5 / 16.0);
            sample_caustic_map(tile, uv, Vec2::splat(2.0), w, map, |_| 1.0, centroid).x
        };
        // footprints [4.5, 8.5) and [8.5, 12.5) in x, 16 texels each
        let (l, r) = (at(6.5), at(10.5));
        assert!((l - 1.0).abs() < 1e-6 && r.abs() < 1e-6, "{l} {r}");
        // read as uniform, half of it crosses
        let u = |x: f32| {
            let uv = Vec2::new(x / 16.0, 8.5 / 16.0);
            sample_caustic_map(tile, uv, Vec2::splat(2.0), w, map, |_| 1.0, MID).x
        };
        assert!((u(6.5) - 0.5).abs() < 1e-6 && (u(10.5) - 0.5).abs() < 1e-6);
    }

    #[test]
    fn centroid_shares_over_a_partition_add_up_to_one() {
        for k in 0..200u32 {
            let c = texel_centroid(k * 37 % 256, 0, 1).x;
            let cuts = [0.0, random_f32(3, k, 0, 0), random_f32(3, k, 1, 0), 1.0];
            let mut cuts = cuts;
            cuts.sort_by(f32::total_cmp);
            let total: f32 = cuts.windows(2).map(|p| centroid_share(c, p[0], p[1])).sum();
            assert!((total - 1.0).abs() < 1e-5, "c {c}: {total}");
            assert!(centroid_share(c, -1.0, 2.0) == 1.0);
        }
        // no photons, and past the most the sums hold: the texel's middle
        assert_eq!(texel_centroid(0, 0, 0), Vec2::splat(0.5));
        assert_eq!(texel_centroid(7, 7, CENTROID_MAX_PHOTONS), Vec2::splat(0.5));
        // offsets: the step inside the clamped texel
        let tile = [4u32, 0, 8, 0];
        assert_eq!(centroid_offset(tile, Vec2::new(0.0, 1.0)), [0, 255]);
        assert_eq!(
            centroid_offset(tile, Vec2::new(0.5 / 8.0, 3.25 / 8.0)),
            [128, 64]
        );
        assert_eq!(centroid_offset(tile, Vec2::new(-0.5, 2.0)), [0, 255]);
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
        let point = sample_caustic_map(tile, uv, Vec2::splat(0.5), w, map, |_| 1.0, MID);
        let wide = sample_caustic_map(tile, uv, Vec2::splat(2.0), w, map, |_| 1.0, MID);
        assert_eq!(point, Vec3::splat(16.0));
        // the rectangle [6.5, 10.5)^2: 16 texels of area, the lit one inside
        assert_eq!(wide, Vec3::splat(1.0));
        // the rectangle [8.5, 12.5) x [6.5, 10.5): the lit texel [8, 9) half inside
        let off = Vec2::new(10.5 / 16.0, 8.5 / 16.0);
        let half = sample_caustic_map(tile, off, Vec2::splat(2.0), w, map, |_| 1.0, MID);
        assert!((half.x - 0.5).abs() < 1e-6, "{half}");
        // a rectangle, 2 texels wide and 8 tall around the lit texel
        let tall = sample_caustic_map(tile, uv, Vec2::new(1.0, 4.0), w, map, |_| 1.0, MID);
        assert!((tall.x - 1.0).abs() < 1e-6, "{tall}");
        assert!((footprint_texels(0.01, 2.0, 1.0, 1e-4) - 2.0).abs() < 1e-5);
    }

    #[test]
    fn the_footprint_extent_follows_the_view_and_the_uvs() {
        // a unit square at z = 0 with uv = (x, y), on a 100-texel tile; a footprint of
        // width 0.1 covers 10 texels a side seen head-on
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let t = [Vec2::ZERO, Vec2::X, Vec2::Y];
        let close = |a: Vec2, b: Vec2| (a - b).abs().max_element() < 1e-3;
        let down = -Vec3::Z;
        let e = footprint_extent(down, Vec3::X, 0.1, p, t, 100);
        assert!(close(e, Vec2::new(5.0, 5.0)), "{e}");
        // 60 degrees from the normal in the y-z plane: stretched 1 / cos = 2 along y
        let (s, c) = (60f32.to_radians().sin(), 60f32.to_radians().cos());
        let e = footprint_extent(Vec3::new(0.0, s, -c), Vec3::X, 0.1, p, t, 100);
        assert!(close(e, Vec2::new(5.0, 10.0)), "{e}");
        // the camera rolled by 30 degrees: the rotated square's bound
        let r = Vec3::new(30f32.to_radians().cos(), 30f32.to_radians().sin(), 0.0);
        let e = footprint_extent(down, r, 0.1, p, t, 100);
        let h = 5.0 * (30f32.to_radians().cos() + 30f32.to_radians().sin());
        assert!(close(e, Vec2::splat(h)), "{e}");
        // UVs stretched 2x along u: twice the texels along x
        let e = footprint_extent(
            down,
            Vec3::X,
            0.1,
            p,
            [Vec2::ZERO, 2.0 * Vec2::X, Vec2::Y],
            100,
        );
        assert!(close(e, Vec2::new(10.0, 5.0)), "{e}");
        // no UV area: unknown
        let e = footprint_extent(down, Vec3::X, 0.1, p, [Vec2::ZERO; 3], 100);
        assert_eq!(e, Vec2::splat(-1.0));
    }
}
