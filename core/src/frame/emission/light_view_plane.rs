//! Light view planes (Vanderstichelen 2021, section 3.1): the virtual image plane in front of a light
//! from whose texels CausticMap and AdaptiveCaustics shoot one photon each.
//!
//! **The frame.** Vanderstichelen 2021 builds a pinhole camera at the light: `W` along the light's
//! direction scaled by a focal distance, `U = normalize(W x up) * ulen`,
//! `V = normalize(U x W) * vlen` with `ulen = f tan(fov / 2) aspect`, `vlen = f tan(fov /
//! 2)`. Its texel `(i, j)` of a `w x h` plane has `p = ((i, j) + 0.5) / (w, h)` and
//! `ndc = (2 p.x - 1, 1 - 2 p.y)` (so row 0 is the top), and its ray direction is printed
//! as `normalize(ndc.x * W + ndc.y * U + W)`. That line is garbled (the first term must
//! be the right vector and the second the up vector: with `W` twice the rays would not
//! span the plane); the pinhole ray through the texel is
//! `normalize(W + ndc.x * U + ndc.y * V)`. Here the focal distance is 1 and `U`, `V` are
//! unit vectors, so with `t = (tan_half_x, tan_half_y)` the ray is
//! `normalize(w + ndc.x t.x u + ndc.y t.y v)`: [`LightViewPlane::texel_direction`].
//!
//! **Aimed at the casters.** A point light outside the casters' bounding sphere gets one
//! square perspective plane whose field of view is the cone that bounds that sphere (the
//! caster cone of `emission`), a spot light the narrower of that cone and its own outer
//! cone; a light whose cone is wider than [`MAX_PLANE_HALF_ANGLE_DEG`] (the light among
//! the casters, or a spot wider than that) gets the six faces of a cube around it, six
//! 90-degree frusta that together see every direction. A directional light gets one
//! orthographic plane over the rectangle onto which the projection volume (or the
//! casters' box) projects along the light, starting up-light of the scene.
//!
//! **Physical flux per photon** (replacing the source's user "intensity rate"). A
//! perspective texel's photon carries the light's intensity `I` (W/sr per channel) times
//! the texel's solid angle, `Phi = I * Omega_texel`; spot lights multiply the falloff at
//! the photon's direction in the kernel. `Omega_texel` is the integral of
//! `dx dy / (1 + x^2 + y^2)^(3/2)` over the texel on the unit-distance plane, taken at the
//! texel's centre (midpoint rule: relative error about `(h^2 / 8)(1 + 2 r^2)` for a texel
//! of side `h` at radius `r` in tangent units, below 1e-5 for 256^2 texels over a 90-degree
//! plane; the tests check the sum against the exact solid angle of the plane,
//! `4 atan(t_x t_y / sqrt(1 + t_x^2 + t_y^2))`). An orthographic texel's photon carries
//! the irradiance `E` (W/m^2 per channel) times the texel's area. The caustic map is
//! therefore in physical units: summed over the plane, the photons carry exactly the flux
//! the light sends through it.

use crate::device::layout::{emission_kind, TraceParams};
use crate::frame::emission::{emission_domain, EmissionDomain, NoEmission, PointEmission};
use crate::math::geometry::Aabb;
use crate::math::sampling::{orthonormal_basis, view_plane_texel_weight, NARROW_CONE};
use crate::scene::Light;
use glam::Vec3;

/// Widest half-angle (degrees) one perspective plane covers; wider cones get six cube
/// faces. At 60 degrees a plane's corner texels see `(1 + 2 tan^2)^(3/2) = 15.6` times less
/// solid angle than its centre ones; wider planes would spend most texels on a thin rim.
pub const MAX_PLANE_HALF_ANGLE_DEG: f32 = 60.0;

/// How a light view plane maps texels to rays.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ViewPlaneProjection {
    /// A pinhole at the light (point and spot lights): rays from `origin` through the
    /// plane at distance 1 along `w`.
    Perspective,
    /// Parallel rays along `w` from the plane itself (directional lights).
    Orthographic,
}

/// One light view plane: a `resolution.0 x resolution.1` grid of texels, each the source
/// of one photon.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightViewPlane {
    /// Perspective or orthographic.
    pub projection: ViewPlaneProjection,
    /// Perspective: the pinhole (the light's position); orthographic: the plane's centre
    /// (world space, up-light of the scene).
    pub origin: Vec3,
    /// Unit forward vector: the plane's normal, towards the scene (world space).
    pub w: Vec3,
    /// Unit right vector: texel column `i` grows along it (world space).
    pub u: Vec3,
    /// Unit up vector: texel row `j` grows *against* it, as Vanderstichelen 2021's `ndc.y = 1 - 2 p.y`
    /// (world space; `u x v = w`).
    pub v: Vec3,
    /// Half-extent of the plane along `u` and `v`: tangents of the half field of view
    /// (perspective) or half the side in scene units (orthographic).
    pub half_extent: (f32, f32),
    /// Texels along `u` and `v`.
    pub resolution: (u32, u32),
    /// The light's intensity (W/sr per channel; perspective) or irradiance (W/m^2 per
    /// channel; orthographic).
    pub power: Vec3,
}

impl LightViewPlane {
    /// Vanderstichelen 2021's normalised device coordinates of texel `(i, j)`'s centre: `x = 2 p.x - 1`,
    /// `y = 1 - 2 p.y` with `p = ((i, j) + 0.5) / resolution`, each in (-1, 1).
    pub fn texel_ndc(&self, i: u32, j: u32) -> (f32, f32) {
        let px = (i as f32 + 0.5) / self.resolution.0 as f32;
        let py = (j as f32 + 0.5) / self.resolution.1 as f32;
        (2.0 * px - 1.0, 1.0 - 2.0 * py)
    }

    /// Texel `(i, j)`'s centre on the plane, in units of its half-extent's kind
    /// (tangents or scene units) along `u` and `v`.
    fn texel_plane_point(&self, i: u32, j: u32) -> (f32, f32) {
        let (x, y) = self.texel_ndc(i, j);
        (x * self.half_extent.0, y * self.half_extent.1)
    }

    /// Origin of texel `(i, j)`'s photon (world space): the pinhole, or the texel's centre
    /// on an orthographic plane.
    pub fn texel_origin(&self, i: u32, j: u32) -> Vec3 {
        match self.projection {
            ViewPlaneProjection::Perspective => self.origin,
            ViewPlaneProjection::Orthographic => {
                let (a, b) = self.texel_plane_point(i, j);
                self.origin + a * self.u + b * self.v
            }
        }
    }

    /// Unit direction of texel `(i, j)`'s photon (world space): `normalize(w + x u + y v)`
    /// through the texel's centre (Vanderstichelen 2021, section 3.1, corrected as the module doc says), or
    /// `w` on an orthographic plane.
    pub fn texel_direction(&self, i: u32, j: u32) -> Vec3 {
        match self.projection {
            ViewPlaneProjection::Perspective => {
                let (a, b) = self.texel_plane_point(i, j);
                (self.w + a * self.u + b * self.v).normalize()
            }
            ViewPlaneProjection::Orthographic => self.w,
        }
    }

    /// The measure one texel covers: solid angle (sr, midpoint rule, see the module doc)
    /// on a perspective plane, area (scene units^2) on an orthographic one.
    pub fn texel_measure(&self, i: u32, j: u32) -> f32 {
        let (w, h) = (self.resolution.0 as f32, self.resolution.1 as f32);
        let (dx, dy) = (2.0 * self.half_extent.0 / w, 2.0 * self.half_extent.1 / h);
        match self.projection {
            ViewPlaneProjection::Perspective => {
                dx * dy
                    * view_plane_texel_weight(
                        i,
                        j,
                        self.resolution.0,
                        self.resolution.1,
                        self.half_extent.0,
                        self.half_extent.1,
                    )
            }
            ViewPlaneProjection::Orthographic => dx * dy,
        }
    }

    /// Flux of texel `(i, j)`'s photon (W per channel, before a spot light's falloff):
    /// `I * Omega_texel` or `E * A_texel`.
    pub fn photon_flux(&self, i: u32, j: u32) -> Vec3 {
        self.power * self.texel_measure(i, j)
    }

    /// The measure of the whole plane, exactly: the solid angle of the rectangle
    /// `[-t_x, t_x] x [-t_y, t_y]` at distance 1, `4 atan(t_x t_y / sqrt(1 + t_x^2 +
    /// t_y^2))` (sr), or its area (scene units^2).
    pub fn plane_measure(&self) -> f64 {
        let (tx, ty) = (self.half_extent.0 as f64, self.half_extent.1 as f64);
        match self.projection {
            ViewPlaneProjection::Perspective => {
                4.0 * (tx * ty / (1.0 + tx * tx + ty * ty).sqrt()).atan()
            }
            ViewPlaneProjection::Orthographic => 4.0 * tx * ty,
        }
    }

    /// Texels on the plane.
    pub fn texels(&self) -> u64 {
        self.resolution.0 as u64 * self.resolution.1 as u64
    }

    /// Parameters of a `trace_photons` dispatch over texels `first .. first + count` of
    /// this plane in tile order ([`crate::math::sampling::tiled_photon_index`] gives each
    /// its row-major texel), one photon each, jittered inside its texel by the
    /// `seed`'s random numbers: a perspective plane as
    /// [`emission_kind::VIEW_PLANE`](crate::device::layout::emission_kind::VIEW_PLANE)
    /// (photon flux `I * Omega_texel`, the kernel weighting the centre texel's flux by
    /// `view_plane_texel_weight`), an orthographic one as a rectangle of parallel rays
    /// (photon flux `E * A_texel`).
    #[allow(clippy::too_many_arguments)]
    pub fn trace_params(
        &self,
        light: u32,
        (first, count): (u32, u32),
        seed: u32,
        max_bounces: u32,
        min_relative_power: f32,
        flux_quantum: f32,
    ) -> TraceParams {
        let (hx, hy) = self.half_extent;
        let (w, h) = self.resolution;
        let texel = (2.0 * hx / w as f32) * (2.0 * hy / h as f32);
        let (emission, origin, rect_u, rect_v) = match self.projection {
            ViewPlaneProjection::Perspective => (
                emission_kind::VIEW_PLANE,
                self.origin,
                (self.u * hx).extend(hx),
                (self.v * hy).extend(hy),
            ),
            ViewPlaneProjection::Orthographic => (
                emission_kind::RECTANGLE,
                // corner at ndc (-1, 1): row 0 at the top, as on the perspective plane
                self.origin - hx * self.u + hy * self.v,
                (2.0 * hx * self.u).extend(0.0),
                (-2.0 * hy * self.v).extend(0.0),
            ),
        };
        TraceParams {
            light,
            emission,
            grid_w: w,
            grid_h: h,
            first,
            count,
            seed,
            max_bounces,
            origin: origin.extend(1.0).to_array(),
            axis: self.w.extend(0.0).to_array(),
            rect_u: rect_u.to_array(),
            rect_v: rect_v.to_array(),
            photon_flux: (self.power * texel).extend(min_relative_power).to_array(),
            flux_quantum,
            split_budget: 1,
            fresnel_model: crate::math::optics::fresnel_model::EXACT,
            // no first-segment test until the technique adds its casters' balls
            // (`CasterSpheres::apply`)
            caster_sphere_count: 0,
            // a frame on its own: jitter from its seed (an accumulation sets its stratum)
            jitter_seed: seed,
            stratum: 0,
            // spectral, the default (a technique sets its `frame.dispersion`)
            dispersion_mode: crate::math::spectrum::dispersion_mode::SPECTRAL,
            _pad: 0,
            caster_spheres: [[0.0; 4]; crate::device::layout::MAX_CASTER_SPHERES],
        }
    }
}

/// Perspective plane from `position` along unit `axis` covering the cone of half-angle
/// `acos(cos_max)` (a square plane whose inscribed circle is the cone); `one_minus_cos`
/// is `1 - cos_max` computed without cancellation, from which a narrow cone
/// ([`NARROW_CONE`]) takes its tangent `sqrt(h (2 - h)) / (1 - h)`.
fn cone_plane(
    position: Vec3,
    axis: Vec3,
    (cos_max, one_minus_cos): (f32, f32),
    power: Vec3,
    res: u32,
) -> LightViewPlane {
    let (u, v) = orthonormal_basis(axis);
    let t = if one_minus_cos < NARROW_CONE {
        let h = one_minus_cos;
        (h * (2.0 - h)).sqrt() / (1.0 - h)
    } else {
        let c = cos_max.clamp(1e-6, 1.0);
        (1.0 - c * c).max(0.0).sqrt() / c
    };
    LightViewPlane {
        projection: ViewPlaneProjection::Perspective,
        origin: position,
        w: axis,
        u,
        v,
        half_extent: (t, t),
        resolution: (res, res),
        power,
    }
}

/// The six 90-degree faces of a cube around `position`, each `res x res` texels: together
/// they see every direction once (their solid angles sum to `4 pi`).
fn cube_planes(position: Vec3, power: Vec3, res: u32) -> Vec<LightViewPlane> {
    [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
    ]
    .into_iter()
    .map(|w| {
        let (u, v) = orthonormal_basis(w);
        LightViewPlane {
            projection: ViewPlaneProjection::Perspective,
            origin: position,
            w,
            u,
            v,
            half_extent: (1.0, 1.0),
            resolution: (res, res),
            power,
        }
    })
    .collect()
}

/// The light view planes of `light` aimed at the caustic casters' box `casters` in a scene
/// bounded by `scene`, with `resolution x resolution` texels each (a cube's six faces
/// share the budget: `resolution / sqrt(6)` texels a side, at least 1), or why the light
/// sends no photon towards a caster. `aim`: `CasterCone` fits the plane to the casters
/// (CausticMap's default), `Sphere` covers the light's whole cone (a spot's outer cone,
/// a point light's six cube faces: the dense baseline of Wyman 2009's comparison).
pub fn light_view_planes(
    light: &Light,
    casters: Aabb,
    scene: Aabb,
    resolution: u32,
    aim: PointEmission,
) -> Result<Vec<LightViewPlane>, NoEmission> {
    let domain = emission_domain(light, casters, scene, aim)?;
    Ok(planes_of_domain(&domain, light, resolution))
}

fn planes_of_domain(d: &EmissionDomain, light: &Light, res: u32) -> Vec<LightViewPlane> {
    let res = res.max(1);
    match light {
        Light::Directional { irradiance, .. } => {
            // the emission rectangle: corner `origin`, edges rect_u, rect_v, rays along axis
            // the emission rectangle: corner `origin`, edges `rect_u`, `rect_v` along the
            // basis (t, b) of the light's direction (t x b = the direction), rays along it
            let (u, v) = orthonormal_basis(d.axis);
            let (lu, lv) = (d.rect_u.dot(u), d.rect_v.dot(v));
            vec![LightViewPlane {
                projection: ViewPlaneProjection::Orthographic,
                origin: d.origin + 0.5 * d.rect_u + 0.5 * d.rect_v,
                w: d.axis,
                u,
                v,
                half_extent: (0.5 * lu, 0.5 * lv),
                resolution: (res, res),
                power: *irradiance,
            }]
        }
        Light::Point { intensity, .. } | Light::Spot { intensity, .. } => {
            let max_cos = MAX_PLANE_HALF_ANGLE_DEG.to_radians().cos();
            if d.cos_max >= max_cos {
                vec![cone_plane(
                    d.origin,
                    d.axis,
                    (d.cos_max, d.one_minus_cos),
                    *intensity,
                    res,
                )]
            } else {
                let face = ((res as f64 / 6f64.sqrt()).round() as u32).max(1);
                cube_planes(d.origin, *intensity, face)
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn aabb(min: Vec3, max: Vec3) -> Aabb {
        let mut b = Aabb::EMPTY;
        b.grow(min);
        b.grow(max);
        b
    }

    fn sum_measure(p: &LightViewPlane) -> f64 {
        let mut s = 0.0f64;
        for j in 0..p.resolution.1 {
            for i in 0..p.resolution.0 {
                s += p.texel_measure(i, j) as f64;
            }
        }
        s
    }

    #[test]
    fn texel_solid_angles_sum_to_the_plane_solid_angle() {
        // 60-degree half-angle, the widest single plane, at 256^2 texels
        let t = 60f32.to_radians().tan();
        let p = cone_plane(
            Vec3::ZERO,
            Vec3::Z,
            (60f32.to_radians().cos(), 0.5),
            Vec3::ONE,
            256,
        );
        assert!((p.half_extent.0 - t).abs() < 1e-5);
        let rel = (sum_measure(&p) / p.plane_measure() - 1.0).abs();
        // midpoint rule: (h^2 / 8)(1 + 2 r^2) with h = 2t / 256 at r <= sqrt(2) t: 3e-4 at
        // the corners, far less on average
        assert!(rel < 2e-5, "relative error {rel}");
    }

    /// A narrow cone's plane has the cone's tangent within a few ulps (from `1 - cos`;
    /// the cosine alone rounds to 1 at 1e-4 rad and gave a plane of no extent).
    #[test]
    fn a_narrow_cone_plane_has_the_cones_tangent() {
        for theta in [1e-7f32, 1e-4, 0.01, 0.04] {
            let h = crate::math::sampling::one_minus_cos_of_angle(theta);
            let p = cone_plane(Vec3::ZERO, Vec3::Z, (theta.cos(), h), Vec3::ONE, 8);
            let want = (theta as f64).tan();
            let rel = (p.half_extent.0 as f64 - want).abs() / want;
            assert!(rel < 1e-6, "{theta:e}: {} vs {want:e}", p.half_extent.0);
        }
    }

    #[test]
    fn a_cube_of_planes_sees_the_whole_sphere() {
        let planes = cube_planes(Vec3::new(1.0, 2.0, 3.0), Vec3::ONE, 64);
        let total: f64 = planes.iter().map(|p| p.plane_measure()).sum();
        assert!((total / (4.0 * std::f64::consts::PI) - 1.0).abs() < 1e-12);
        let summed: f64 = planes.iter().map(sum_measure).sum();
        assert!((summed / (4.0 * std::f64::consts::PI) - 1.0).abs() < 2e-4);
        for p in &planes {
            // right-handed, unit, and every direction points into its own face's frustum
            assert!((p.u.cross(p.v) - p.w).length() < 1e-6, "{p:?}");
            for (i, j) in [(0, 0), (63, 0), (0, 63), (63, 63), (31, 32)] {
                let d = p.texel_direction(i, j);
                assert!(d.dot(p.w) > 0.57, "{d} outside face {:?}", p.w);
            }
        }
    }

    #[test]
    fn rows_run_down_and_columns_right_as_in_001() {
        let c = 45f32.to_radians().cos();
        let p = cone_plane(Vec3::ZERO, Vec3::Z, (c, 1.0 - c), Vec3::ONE, 8);
        let top_left = p.texel_direction(0, 0);
        let bottom_right = p.texel_direction(7, 7);
        assert!(top_left.dot(p.u) < 0.0 && top_left.dot(p.v) > 0.0);
        assert!(bottom_right.dot(p.u) > 0.0 && bottom_right.dot(p.v) < 0.0);
    }

    #[test]
    fn a_point_light_plane_covers_the_caster_cone() {
        let light = Light::Point {
            position: Vec3::new(0.0, 5.0, 0.0),
            intensity: Vec3::splat(2.0),
        };
        let casters = aabb(Vec3::splat(-0.5), Vec3::splat(0.5));
        let scene = aabb(Vec3::splat(-3.0), Vec3::splat(6.0));
        let planes =
            light_view_planes(&light, casters, scene, 128, PointEmission::CasterCone).unwrap();
        assert_eq!(planes.len(), 1);
        let p = planes[0];
        // every corner of the casters' box projects inside the plane
        for c in casters.corners() {
            let d = (c - p.origin).normalize();
            let z = d.dot(p.w);
            assert!(z > 0.0);
            assert!((d.dot(p.u) / z).abs() <= p.half_extent.0 + 1e-6);
            assert!((d.dot(p.v) / z).abs() <= p.half_extent.1 + 1e-6);
        }
        // flux per photon = I * Omega_texel; all photons = I * Omega_plane
        let f: f64 = (0..128)
            .flat_map(|j| (0..128).map(move |i| (i, j)))
            .map(|(i, j)| p.photon_flux(i, j).x as f64)
            .sum();
        assert!((f / (2.0 * p.plane_measure()) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn a_light_among_the_casters_gets_six_faces() {
        let light = Light::Point {
            position: Vec3::ZERO,
            intensity: Vec3::ONE,
        };
        let casters = aabb(Vec3::splat(-1.0), Vec3::splat(1.0));
        let planes =
            light_view_planes(&light, casters, casters, 600, PointEmission::CasterCone).unwrap();
        assert_eq!(planes.len(), 6);
        // the budget is shared: 600 / sqrt(6) = 245 a side
        assert!(planes.iter().all(|p| p.resolution == (245, 245)));
    }

    #[test]
    fn a_directional_plane_carries_irradiance_times_area() {
        let light = Light::Directional {
            direction: Vec3::new(0.3, -1.0, 0.2),
            irradiance: Vec3::new(3.0, 2.0, 1.0),
            projection_volume: None,
        };
        let casters = aabb(Vec3::new(-1.0, 0.0, -1.0), Vec3::new(1.0, 1.0, 1.0));
        let scene = aabb(Vec3::new(-4.0, -1.0, -4.0), Vec3::new(4.0, 2.0, 4.0));
        let p =
            light_view_planes(&light, casters, scene, 64, PointEmission::CasterCone).unwrap()[0];
        assert_eq!(p.projection, ViewPlaneProjection::Orthographic);
        assert!((p.w - light_dir(&light)).length() < 1e-6);
        let total: f64 = (0..64)
            .flat_map(|j| (0..64).map(move |i| (i, j)))
            .map(|(i, j)| p.photon_flux(i, j).x as f64)
            .sum();
        assert!((total / (3.0 * p.plane_measure()) - 1.0).abs() < 1e-5);
        // every caster corner lies in the plane's prism
        for c in casters.corners() {
            let r = c - p.origin;
            assert!(r.dot(p.w) > 0.0, "plane is up-light");
            assert!(r.dot(p.u).abs() <= p.half_extent.0 * 1.0001);
            assert!(r.dot(p.v).abs() <= p.half_extent.1 * 1.0001);
        }
        // texel origins stay on the plane and run right / down
        let (a, b) = (p.texel_origin(0, 0), p.texel_origin(63, 63));
        assert!((a - p.origin).dot(p.w).abs() < 1e-4 && (b - p.origin).dot(p.w).abs() < 1e-4);
        assert!((b - a).dot(p.u) > 0.0 && (b - a).dot(p.v) < 0.0);
    }

    fn light_dir(l: &Light) -> Vec3 {
        match l {
            Light::Directional { direction, .. } => direction.normalize(),
            _ => unreachable!(),
        }
    }
}
