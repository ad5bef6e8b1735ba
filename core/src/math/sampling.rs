//! Sampling warps shared by every backend. All map the unit square [0,1)^2 to a domain
//! with constant Jacobian (equal-area), so that a stratified pw x ph grid of photons
//! carries equal flux per photon (seed 000 Eq. 1).

use glam::{Vec2, Vec3};

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

/// Uniform direction in the cone of half-angle `acos(cos_max)` around +z, from `u` in
/// [0,1)^2: `cos = 1 - u.x (1 - cos_max)`. Solid angle of the cone: `2 pi (1 - cos_max)`.
#[inline]
pub fn uniform_cone(u: Vec2, cos_max: f32) -> Vec3 {
    let cos_t = 1.0 - u.x * (1.0 - cos_max);
    let sin_t = (1.0 - cos_t * cos_t).max(0.0).sqrt();
    let phi = std::f32::consts::TAU * u.y;
    Vec3::new(sin_t * phi.cos(), sin_t * phi.sin(), cos_t)
}

/// Unit direction through point `u` in [0,1)^2 of a perspective light view plane (seed
/// 001 section 3.1, its garbled ray formula corrected as `frame::light_view_plane` says):
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
/// `frame::light_view_plane`).
#[inline]
pub fn view_plane_texel_weight(ix: u32, iy: u32, w: u32, h: u32, tan_x: f32, tan_y: f32) -> f32 {
    let a = (2.0 * (ix as f32 + 0.5) / w as f32 - 1.0) * tan_x;
    let b = (1.0 - 2.0 * (iy as f32 + 0.5) / h as f32) * tan_y;
    let q = 1.0 + a * a + b * b;
    1.0 / (q * q.sqrt())
}

/// Solid angle (sr) of a cone with half-angle `acos(cos_max)`.
#[inline]
pub fn cone_solid_angle(cos_max: f32) -> f32 {
    std::f32::consts::TAU * (1.0 - cos_max)
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
                let d = uniform_cone(stratified_cell(i, j, 16, 16, Vec2::splat(0.5)), cos_max);
                assert!(d.z >= cos_max - 1e-6 && (d.length() - 1.0).abs() < 1e-5);
            }
        }
        assert!((cone_solid_angle(-1.0) - 4.0 * std::f32::consts::PI).abs() < 1e-5);
    }
}
