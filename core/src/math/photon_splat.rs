//! PhotonGi's splatting kernel (Smal 2019, section 24.3.1, Eqs. 2-9): each stored photon
//! spreads its power over a tri-axial ellipsoid around its hit point, and a surface point
//! inside the ellipsoid receives irradiance `E = Phi / a` (W/m^2), `a` the area of the
//! ellipse the ellipsoid cuts in the kernel plane.
//!
//! The kernel starts as a sphere and is scaled uniformly by `s_l s_d` (ray length, Eq. 2;
//! tile photon density, Eqs. 3-6), then shaped: along the photon's geometric normal `n` it
//! is compressed by `s_n`, along `u` (the arriving light direction projected onto the
//! kernel plane) stretched by `s_u = min(1 / cos, s_max)` (Eq. 7), and along `t = n x u`
//! left as is. The chapter's equations are partly illegible in its text; the forms here
//! follow its HLSL listings, which are intact (the derivation is in `docs/photon-gi.md`).
//!
//! Units: lengths in scene units (world and view space share them), areas in scene
//! units^2, power in W per channel.

use glam::Vec3;
use std::f32::consts::PI;

/// The chapter's kernel constants (its listing's names in brackets).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatConstants {
    /// Ray length at which the kernel stops growing (`MAX_RAY_LENGTH`, scene units; "can
    /// be derived from [the scene's] bounding box").
    pub max_ray_length: f32,
    /// Smallest ray-length scale (the listing's 0.1).
    pub min_length_scale: f32,
    /// Clamp of the density radius (`DYNAMIC_KERNEL_SCALE_MIN`, `_MAX`, scene units).
    pub density_radius_min: f32,
    /// See `density_radius_min`.
    pub density_radius_max: f32,
    /// Photons expected to contribute to each pixel (`n_tile`).
    pub photons_per_pixel: f32,
    /// Compression along the normal (`KernelCompress`, `s_n`).
    pub normal_compression: f32,
    /// Largest light-direction stretch (`MAX_SCALING_CONSTANT`, `s_max`).
    pub max_stretch: f32,
}

/// Eq. 2: the ray-length scale `s_l = clamp(l / l_max, min, 1)` (the listing clamps
/// below too, so that a photon arriving from a nearby surface keeps a kernel).
#[inline]
pub fn ray_length_scale(ray_length: f32, c: &SplatConstants) -> f32 {
    (ray_length / c.max_ray_length).clamp(c.min_length_scale, 1.0)
}

/// Eqs. 3-4: the view-space area of one screen tile at view depth `z_view`: `a_view =
/// z^2 c_tile`, `c_tile = (2 tan(fov_x / 2) t_x / r_x) (2 tan(fov_y / 2) t_y / r_y)` for
/// tiles of `t_x x t_y` pixels in an `r_x x r_y` image. This is the pixel footprint of
/// Kim 2019's Eq. 4 times the tile's pixels (`tan_half_fov_*` are the camera's).
#[inline]
pub fn tile_area_constant(
    tan_half_fov_x: f32,
    tan_half_fov_y: f32,
    tile_px: (u32, u32),
    image_px: (u32, u32),
) -> f32 {
    let wx = 2.0 * tan_half_fov_x * tile_px.0 as f32 / image_px.0 as f32;
    let wy = 2.0 * tan_half_fov_y * tile_px.1 as f32 / image_px.1 as f32;
    wx * wy
}

/// Eqs. 5-6: the density scale `s_d = clamp(sqrt(a_view / (pi n_p)), r_min, r_max)
/// n_tile`: the radius of a disc holding the tile's view-space area per photon (`n_p`
/// photons in the photon's screen tile at depth `z_view`), times the photons wanted per
/// pixel. A tile without a counted photon (cannot happen for the photon's own tile) gets
/// the largest radius.
#[inline]
pub fn density_scale(
    z_view: f32,
    tile_constant: f32,
    photons_in_tile: u32,
    c: &SplatConstants,
) -> f32 {
    let r = if photons_in_tile > 0 {
        (z_view * z_view * tile_constant / (PI * photons_in_tile as f32)).sqrt()
    } else {
        c.density_radius_max
    };
    r.clamp(c.density_radius_min, c.density_radius_max) * c.photons_per_pixel
}

/// The smallest uniform kernel scale at view depth `z_view`: `min_px` pixel footprints
/// (`2 z tan(fov_y / 2) / r_y` scene units each). Not in the chapter, whose rasterised
/// splats cover at least the pixels their triangles touch; a scattered kernel smaller
/// than a pixel reaches one pixel centre or none, unbiased but all noise.
#[inline]
pub fn min_splat_scale(z_view: f32, tan_half_fov_y: f32, height: u32, min_px: f32) -> f32 {
    min_px * (2.0 * z_view * tan_half_fov_y / height as f32)
}

/// Eq. 7: the stretch along `u`, `s_u = min(1 / cos(theta), s_max)`, `cos(theta)` between
/// the photon's normal and the direction towards the light it came from (saturated, as
/// the listing does).
#[inline]
pub fn light_stretch(normal: Vec3, to_light: Vec3, c: &SplatConstants) -> f32 {
    let cos = normal.dot(to_light).clamp(0.0, 1.0);
    if cos > 0.0 {
        (1.0 / cos).min(c.max_stretch)
    } else {
        c.max_stretch
    }
}

/// The kernel's frame and half-axes: `(n, u, t)` unit vectors (normal; the light direction
/// in the kernel plane; `n x u`) and their half-axis lengths `(s_n s, s_u s, s)` with the
/// uniform scale `s = s_l s_d` (Eq. 8's vertex transform scales the unit sphere by these).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SplatKernel {
    /// Unit normal `n` of the kernel plane (the photon's geometric normal).
    pub n: Vec3,
    /// Unit `u`: the direction to the light projected onto the kernel plane.
    pub u: Vec3,
    /// Unit `t = n x u`.
    pub t: Vec3,
    /// Half-axis lengths along `n`, `u`, `t` (scene units).
    pub axes: Vec3,
}

/// The kernel of a photon with geometric normal `normal`, arriving from `to_light` (unit,
/// pointing back along its path), with uniform scale `s = s_l s_d`. When the light
/// direction is along the normal, `u` is any unit vector of the plane (the stretch is 1).
pub fn splat_kernel(normal: Vec3, to_light: Vec3, s: f32, c: &SplatConstants) -> SplatKernel {
    let n = normal.normalize();
    let along = to_light - to_light.dot(n) * n;
    let u = if along.length_squared() > 1e-12 {
        along.normalize()
    } else {
        crate::math::sampling::orthonormal_basis(n).0
    };
    let t = n.cross(u);
    let su = light_stretch(n, to_light, c);
    SplatKernel {
        n,
        u,
        t,
        axes: Vec3::new(c.normal_compression * s, su * s, s),
    }
}

impl SplatKernel {
    /// Area of the ellipse the kernel cuts in its plane, `a = pi |u| |t|` (Eq. 9's `a`).
    pub fn ellipse_area(&self) -> f32 {
        PI * self.axes.y * self.axes.z
    }

    /// `v`'s coordinates in the kernel's frame: along `n`, `u` and `t`.
    #[inline]
    pub fn frame(&self, v: Vec3) -> Vec3 {
        Vec3::new(v.dot(self.n), v.dot(self.u), v.dot(self.t))
    }

    /// Whether point `p` lies inside the ellipsoid centred on `centre` (the photon's
    /// position); the chapter clips by depth against the compressed normal axis, which
    /// this test contains.
    pub fn contains(&self, centre: Vec3, p: Vec3) -> bool {
        let q = self.frame(p - centre) / self.axes;
        q.length_squared() <= 1.0
    }
}

/// Eq. 9: the irradiance a point inside the kernel receives from photon power `power`
/// (W per channel): `E = Phi / a`. Integrated over the ellipse this returns the photon's
/// power, so a splat neither adds nor loses energy on a flat receiver.
#[inline]
pub fn splat_irradiance(power: Vec3, kernel: &SplatKernel) -> Vec3 {
    let a = kernel.ellipse_area();
    if a > 0.0 {
        power / a
    } else {
        Vec3::ZERO
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn constants() -> SplatConstants {
        SplatConstants {
            max_ray_length: 10.0,
            min_length_scale: 0.1,
            density_radius_min: 0.01,
            density_radius_max: 1.0,
            photons_per_pixel: 1.0,
            normal_compression: 0.1,
            max_stretch: 4.0,
        }
    }

    #[test]
    fn scales_follow_the_chapter() {
        let c = constants();
        assert_eq!(ray_length_scale(5.0, &c), 0.5);
        assert_eq!(ray_length_scale(0.0, &c), 0.1);
        assert_eq!(ray_length_scale(50.0, &c), 1.0);
        // a 90-degree camera, 8x8 tiles of a 512x512 image: tile 1/32 of the view a side
        let k = tile_area_constant(1.0, 1.0, (8, 8), (512, 512));
        assert!((k - (2.0 / 64.0f32).powi(2)).abs() < 1e-9);
        // at depth 4 the tile is 0.125 units a side; 1 photon: r = sqrt(a / pi)
        let r = density_scale(4.0, k, 1, &c);
        assert!((r - (0.125f32 * 0.125 / PI).sqrt()).abs() < 1e-6);
        assert!(density_scale(4.0, k, 4, &c) < r);
        assert_eq!(density_scale(4.0, k, 1_000_000, &c), 0.01);
        let n = Vec3::Z;
        assert_eq!(light_stretch(n, Vec3::Z, &c), 1.0);
        assert!(
            (light_stretch(n, Vec3::new(1.0, 0.0, 1.0).normalize(), &c) - 2f32.sqrt()).abs() < 1e-6
        );
        assert_eq!(light_stretch(n, Vec3::X, &c), 4.0);
        assert_eq!(light_stretch(n, -Vec3::Z, &c), 4.0);
    }

    #[test]
    fn a_splat_on_a_plane_carries_the_photons_power() {
        // integrate E over the kernel plane by a fine grid: the total is the power
        let c = constants();
        let to_light = Vec3::new(0.6, 0.2, 0.5).normalize();
        let k = splat_kernel(Vec3::Z, to_light, 0.3, &c);
        let power = Vec3::new(2.0, 1.0, 0.5);
        let e = splat_irradiance(power, &k);
        let (n, half) = (800, 1.5f32);
        let cell = (2.0 * half / n as f32).powi(2);
        let mut sum = Vec3::ZERO;
        for iy in 0..n {
            for ix in 0..n {
                let p = Vec3::new(
                    -half + (ix as f32 + 0.5) * 2.0 * half / n as f32,
                    -half + (iy as f32 + 0.5) * 2.0 * half / n as f32,
                    0.0,
                );
                if k.contains(Vec3::ZERO, p) {
                    sum += e * cell;
                }
            }
        }
        assert!(
            (sum - power).abs().max_element() < 5e-3 * power.max_element(),
            "{sum}"
        );
        // the frame is orthonormal and u follows the light
        assert!(k.u.dot(k.n).abs() < 1e-6 && k.t.dot(k.u).abs() < 1e-6);
        assert!(k.u.dot(to_light) > 0.0);
    }
}
