//! Sampling warps shared by every backend. All map the unit square [0,1)^2 to a domain
//! with constant Jacobian (equal-area), so that a stratified pw x ph grid of photons
//! carries equal flux per photon (Kim 2019 Eq. 1).

use glam::{Vec2, Vec3};

/// Side of the square tiles in which a light's photon grid is handed to threads (cells
/// per tile row and column).
pub const PHOTON_TILE: u32 = 8;

/// The row-major index `iy * grid_w + ix` of the `g`-th photon of a `grid_w` x `grid_h`
/// grid in tile order: bands [`PHOTON_TILE`] rows high, each band tile by tile from left
/// to right, each tile row by row (the last tile of a band and the last band may be
/// narrower). A bijection of `0 .. grid_w * grid_h` onto itself; a batch is a range of
/// `g` and thread `i` of it traces photon `tiled_photon_index(first + i, ..)`. A photon's
/// path depends on its index alone, so the order changes which thread traces it, never
/// what it does: a warp's 32 photons lie in an 8 x 4 block of the grid (rays through the
/// same nodes and triangles) where row order put them on one line of 32 cells.
/// Measured on the H200: `trace_photons` 3.71 -> 2.74 ms on `sphere`, 1.41 -> 1.17 ms on
/// `cornell` (OpenCL, 2048^2 photons).
#[inline]
pub fn tiled_photon_index(g: u32, grid_w: u32, grid_h: u32) -> u32 {
    tiled_index(g, grid_w, grid_h, PHOTON_TILE)
}

/// [`tiled_photon_index`] with tiles `tile` cells a side (at least 1): the row-major
/// index of the `g`-th cell of a `grid_w` x `grid_h` grid taken in bands `tile` rows
/// high, each band tile by tile, each tile row by row. A bijection of
/// `0 .. grid_w * grid_h` onto itself.
#[inline]
pub fn tiled_index(g: u32, grid_w: u32, grid_h: u32, tile: u32) -> u32 {
    if grid_w == 0 || grid_h == 0 || tile == 0 {
        return g;
    }
    // band_y * grid_w and tile_x * band_h are at most g; tile * band_h at most tile^2
    let band = g / grid_w / tile;
    let band_y = band * tile;
    let band_h = tile.min(grid_h - band_y);
    let r = g - band_y * grid_w;
    let tile_x = r / (tile * band_h) * tile;
    let tile_w = tile.min(grid_w - tile_x);
    let q = r - tile_x * band_h;
    (band_y + q / tile_w) * grid_w + tile_x + q % tile_w
}

/// Point in cell (`ix`, `iy`) of a `grid_w` x `grid_h` grid over [0,1)^2, jittered
/// inside the cell by `jitter` in [0,1)^2 (stratified sampling).
#[inline]
pub fn stratified_cell(ix: u32, iy: u32, grid_w: u32, grid_h: u32, jitter: Vec2) -> Vec2 {
    Vec2::new(
        (ix as f32 + jitter.x) / grid_w as f32,
        (iy as f32 + jitter.y) / grid_h as f32,
    )
}

/// Uniform direction on the unit sphere from `u` in [0,1)^2 (Archimedes' equal-area
/// cylinder map: `z = 1 - 2 u.x`, `phi = 2 pi u.y`). Solid angle per unit area: 4 pi.
#[inline]
pub fn uniform_sphere(u: Vec2) -> Vec3 {
    let z = 1.0 - 2.0 * u.x;
    let r = (1.0 - z * z).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u.y;
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

/// `1 - cos` of a cone's half-angle below which the cone is narrow: 2^-10 (half-angles
/// below about 2.56 degrees). A narrow cone is sampled and measured from `1 - cos_max`
/// computed without cancellation ([`cone_one_minus_cos`]) instead of from `cos_max`.
///
/// Why: `cos_max` is an f32 in [0.5, 1] (spacing 2^-24), so `1 - cos_max` carries an
/// absolute error up to about 2^-24 however it was computed, a relative error of
/// `2^-24 / (1 - cos_max)`: at the threshold 2^-14 (6e-5), below it growing as the cone
/// narrows (8% for a caster sphere seen at `r / d = 1e-3`, nothing left once `r / d` is
/// below 2^-12.5, where `cos_max` rounds to 1). Wider cones keep the `cos_max` forms and
/// their bits.
pub const NARROW_CONE: f32 = 1.0 / 1024.0;

/// `1 - cos(theta)` of a cone of half-angle `theta` whose squared sine is `sin2` (in
/// [0, 1]), without cancellation: `sin2 / (1 + sqrt(1 - sin2))`, within a few ulps.
/// (A sphere of radius `r` seen from `d` bounds a cone of `sin2 = (r / d)^2`.)
#[inline]
pub fn cone_one_minus_cos(sin2: f32) -> f32 {
    sin2 / (1.0 + (1.0 - sin2).max(0.0).sqrt())
}

/// `1 - cos(theta)` for a half-angle `theta` in radians, without cancellation:
/// `2 sin^2(theta / 2)`.
#[inline]
pub fn one_minus_cos_of_angle(theta: f32) -> f32 {
    let s = (0.5 * theta).sin();
    2.0 * s * s
}

/// Uniform direction in the cone of half-angle `acos(cos_max)` around +z, from `u` in
/// [0,1)^2: `cos = 1 - u.x (1 - cos_max)`. `one_minus_cos` is `1 - cos_max` computed
/// without cancellation (the cone's `TraceParams::axis.w`): a narrow cone
/// ([`NARROW_CONE`]) takes `t = u.x one_minus_cos`, `cos = 1 - t` and `sin = sqrt(t (2 -
/// t))` from it, so that its directions spread over the whole cone however narrow (from
/// `cos_max`, whose `1 - cos_max` has cancelled, they fell on a few rings, all on the
/// axis once `cos_max` rounds to 1); a wider cone keeps `sin = sqrt(1 - cos^2)`. Solid
/// angle of the cone: [`cone_solid_angle`].
#[inline]
pub fn uniform_cone(u: Vec2, cos_max: f32, one_minus_cos: f32) -> Vec3 {
    let (cos_t, sin_t) = if one_minus_cos < NARROW_CONE {
        let t = u.x * one_minus_cos;
        (1.0 - t, (t * (2.0 - t)).max(0.0).sqrt())
    } else {
        let cos_t = 1.0 - u.x * (1.0 - cos_max);
        (cos_t, (1.0 - cos_t * cos_t).max(0.0).sqrt())
    };
    let phi = std::f32::consts::TAU * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Unit direction through point `u` in [0,1)^2 of a perspective light view plane
/// (Vanderstichelen 2021, its ray formula corrected as `frame::emission::light_view_plane`
/// says):
/// `normalize(axis + ndc.x * right + ndc.y * up)` with `ndc = (2 u.x - 1, 1 - 2 u.y)` (row
/// 0 at the top); `right` and `up` are the plane's unit vectors scaled by the tangents of
/// the half fields of view (world space).
#[inline]
pub fn view_plane_direction(axis: Vec3, right: Vec3, up: Vec3, u: Vec2) -> Vec3 {
    let ndc = Vec2::new(2.0 * u.x - 1.0, 1.0 - 2.0 * u.y);
    (axis + ndc.x * right + ndc.y * up).normalize()
}

/// Solid angle of texel (`ix`, `iy`) of a `w x h` perspective view plane with half-extent
/// tangents `tan_x`, `tan_y`, over that of a texel at the plane's centre: `1 / q^(3/2)`
/// with `q = 1 + a^2 + b^2` at the texel's centre `(a, b)` in tangent units (the
/// integrand of `dx dy / (1 + x^2 + y^2)^(3/2)`, midpoint rule; error bound in
/// `frame::emission::light_view_plane`).
#[inline]
pub fn view_plane_texel_weight(ix: u32, iy: u32, w: u32, h: u32, tan_x: f32, tan_y: f32) -> f32 {
    let a = (2.0 * (ix as f32 + 0.5) / w as f32 - 1.0) * tan_x;
    let b = (1.0 - 2.0 * (iy as f32 + 0.5) / h as f32) * tan_y;
    let q = 1.0 + a * a + b * b;
    1.0 / (q * q.sqrt())
}

/// Solid angle (sr) of a cone with half-angle `acos(cos_max)`, `one_minus_cos` being
/// `1 - cos_max` computed without cancellation: `2 pi one_minus_cos` for a narrow cone
/// ([`NARROW_CONE`]), `2 pi (1 - cos_max)` otherwise (the directions [`uniform_cone`]
/// draws from the same two values cover exactly this cone).
#[inline]
pub fn cone_solid_angle(cos_max: f32, one_minus_cos: f32) -> f32 {
    if one_minus_cos < NARROW_CONE {
        std::f32::consts::TAU * one_minus_cos
    } else {
        std::f32::consts::TAU * (1.0 - cos_max)
    }
}

/// Right-handed orthonormal basis (t, b) completing unit vector `n` (Duff et al. 2017,
/// "Building an Orthonormal Basis, Revisited"): continuous except at n.z = -0 sign flip.
#[inline]
pub fn orthonormal_basis(n: Vec3) -> (Vec3, Vec3) {
    let sign = if n.z >= 0.0 { 1.0 } else { -1.0 };
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (
        Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x),
        Vec3::new(b, sign + n.y * n.y * a, -n.y),
    )
}

/// Maps a direction expressed in the frame (t, b, n) to world space.
#[inline]
pub fn to_world(local: Vec3, n: Vec3) -> Vec3 {
    let (t, b) = orthonormal_basis(n);
    t * local.x + b * local.y + n * local.z
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Tile order of any tile side is a bijection of the grid's indices.
    #[test]
    fn tiled_index_is_a_bijection_for_any_tile() {
        for tile in [1, 2, 3, 4, 8] {
            for (w, h) in [(1, 1), (5, 3), (4, 4), (9, 17), (16, 6)] {
                let mut seen: Vec<u32> = (0..w * h).map(|g| tiled_index(g, w, h, tile)).collect();
                seen.sort_unstable();
                assert_eq!(seen, (0..w * h).collect::<Vec<_>>(), "{w}x{h}, tile {tile}");
            }
        }
    }

    /// Tile order is a bijection of the grid's indices for any grid shape, including
    /// partial tiles and bands, and keeps each 64 consecutive photons of a full tile in
    /// one 8 x 8 block.
    #[test]
    fn tiled_photon_index_is_a_bijection_with_8x8_tiles() {
        for (w, h) in [
            (1, 1),
            (1, 9),
            (9, 1),
            (7, 5),
            (8, 8),
            (9, 17),
            (16, 24),
            (33, 15),
            (64, 64),
        ] {
            let n = w * h;
            let mut seen = vec![false; n as usize];
            for g in 0..n {
                let i = tiled_photon_index(g, w, h);
                assert!(i < n, "{w}x{h}: g {g} -> {i}");
                assert!(!seen[i as usize], "{w}x{h}: {i} twice");
                seen[i as usize] = true;
            }
        }
        let (w, h) = (2048, 2048);
        for t in [0u32, 1, 255, 256, 4095, 65535] {
            let cells: Vec<(u32, u32)> = (0..64)
                .map(|k| tiled_photon_index(t * 64 + k, w, h))
                .map(|i| (i % w, i / w))
                .collect();
            let (x0, y0) = cells[0];
            assert_eq!((x0 % 8, y0 % 8), (0, 0));
            for (k, &(x, y)) in cells.iter().enumerate() {
                assert_eq!((x - x0, y - y0), (k as u32 % 8, k as u32 / 8));
            }
        }
        // the last index of the largest grids stays in range (no overflow)
        let (w, h) = (u32::MAX / 3, 3);
        assert_eq!(tiled_photon_index(w * h - 1, w, h), w * h - 1);
    }

    #[test]
    fn basis_is_orthonormal() {
        for &n in &[
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::Z,
            Vec3::new(1.0, -2.0, 0.3).normalize(),
        ] {
            let (t, b) = orthonormal_basis(n);
            assert!(t.dot(b).abs() < 1e-6 && t.dot(n).abs() < 1e-6 && b.dot(n).abs() < 1e-6);
            assert!((t.length() - 1.0).abs() < 1e-6 && (b.length() - 1.0).abs() < 1e-6);
            assert!((t.cross(b) - n).length() < 1e-5);
        }
    }

    #[test]
    fn cone_covers_its_solid_angle() {
        let cos_max = 0.8f32;
        for i in 0..16 {
            for j in 0..16 {
                let d = uniform_cone(
                    stratified_cell(i, j, 16, 16, Vec2::splat(0.5)),
                    cos_max,
                    0.2,
                );
                assert!(d.z >= cos_max - 1e-6 && (d.length() - 1.0).abs() < 1e-5);
            }
        }
        assert!((cone_solid_angle(-1.0, 2.0) - 4.0 * std::f32::consts::PI).abs() < 1e-5);
    }

    /// `1 - cos` of half-angles from 1e-8 rad to 90 degrees, by squared sine and by angle,
    /// within 4 ulps of f64; the solid angle within 5; wide cones keep `2 pi (1 - cos_max)`
    /// bit for bit.
    #[test]
    fn narrow_cones_are_measured_without_cancellation() {
        let ulps = |got: f32, want: f64| {
            let ulp = 2f64.powi(want.abs().log2().floor() as i32 - 23);
            (got as f64 - want).abs() / ulp
        };
        let n = 2000;
        for k in 0..=n {
            // log-spaced half-angles, 1e-8 rad to pi / 2
            let theta = 1e-8f32 * (std::f32::consts::FRAC_PI_2 / 1e-8).powf(k as f32 / n as f32);
            let t64 = theta as f64;
            let want = 2.0 * (0.5 * t64).sin().powi(2);
            let by_angle = one_minus_cos_of_angle(theta);
            assert!(
                ulps(by_angle, want) <= 4.0,
                "{theta:e}: {by_angle:e} vs {want:e}"
            );
            let s2 = theta.sin() * theta.sin();
            let s2_64 = s2 as f64;
            let want2 = s2_64 / (1.0 + (1.0 - s2_64).sqrt());
            let by_sin = cone_one_minus_cos(s2);
            assert!(
                ulps(by_sin, want2) <= 4.0,
                "{theta:e}: {by_sin:e} vs {want2:e}"
            );
            let cos_max = theta.cos();
            let omega = cone_solid_angle(cos_max, by_angle);
            if by_angle < NARROW_CONE {
                let exact = std::f64::consts::TAU * want;
                assert!(
                    ulps(omega, exact) <= 5.0,
                    "{theta:e}: {omega:e} vs {exact:e}"
                );
            } else {
                let today = std::f32::consts::TAU * (1.0 - cos_max);
                assert_eq!(omega.to_bits(), today.to_bits());
            }
        }
        // what the narrow form avoids: at 1e-4 rad the cosine is 1 in f32
        assert_eq!(1.0 - 1e-4f32.cos(), 0.0);
        assert!(cone_solid_angle(1e-4f32.cos(), one_minus_cos_of_angle(1e-4)) > 0.0);
    }

    /// A narrow cone's directions lie inside it, spread over its whole angle (their
    /// largest angle from the axis within 1% of the half-angle), each of unit length; at
    /// the threshold both forms agree to the f32 rounding of the wide one.
    #[test]
    fn narrow_cone_directions_fill_the_cone() {
        for theta in [1e-7f32, 1e-5, 1e-3, 0.04] {
            let h = one_minus_cos_of_angle(theta);
            assert!(h < NARROW_CONE);
            let cos_max = theta.cos();
            let mut widest = 0.0f64;
            let mut rings = std::collections::BTreeSet::new();
            for i in 0..32 {
                for j in 0..32 {
                    let u = stratified_cell(i, j, 32, 32, Vec2::splat(0.5));
                    let d = uniform_cone(u, cos_max, h);
                    assert!((d.length() - 1.0).abs() < 2e-7, "{theta}: {d}");
                    let sin = (d.x as f64).hypot(d.y as f64);
                    assert!(
                        sin <= (theta as f64).sin() * (1.0 + 1e-6),
                        "{theta}: {sin:e}"
                    );
                    widest = widest.max(sin);
                    rings.insert(sin.to_bits());
                }
            }
            let want = (theta as f64).sin();
            assert!(
                widest > 0.99 * want,
                "{theta}: widest {widest:e} of {want:e}"
            );
            assert!(rings.len() >= 32, "{theta}: {} rings", rings.len());
        }
        // just above the threshold the wide form: its directions' sines are the exact
        // ones to its error
        let theta = 0.046f32;
        let h = one_minus_cos_of_angle(theta);
        assert!(h >= NARROW_CONE);
        for i in 0..16 {
            let u = Vec2::new((i as f32 + 0.5) / 16.0, 0.3);
            let wide = uniform_cone(u, theta.cos(), h);
            let t = u.x as f64 * h as f64;
            let exact_sin = (t * (2.0 - t)).sqrt();
            let sin_wide = (wide.x as f64).hypot(wide.y as f64);
            // sin^2 = 1 - cos^2 off by up to ~3 2^-24, so sin by that over 2 sin
            let bound = 2.0 * 2f64.powi(-24) / exact_sin + 1e-7;
            assert!(
                (sin_wide - exact_sin).abs() < bound,
                "{i}: {sin_wide} vs {exact_sin}"
            );
        }
    }
}
