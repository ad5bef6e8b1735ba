//! The numeric bounds of a scene, derived from f32 so that tessellation, the BVH build,
//! emission and deposit stay finite, and the budgets that keep a scene's memory and time
//! bounded. [`super::Scene::validate`] enforces them with a message that names the field
//! and the bound; the scene format's docs (`docs/scene-format.md`) list them.
//!
//! The derivations (f32: largest finite 2^128 (1 - 2^-24), smallest normal 2^-126, 24-bit
//! significand, so one ulp of `x` is at most `|x| 2^-23`):
//!
//! - **Coordinates** `|x| <= 2^40` (about 1.1e12 scene units). Differences of two points
//!   are then below `2^41 sqrt(3) < 2^42`, and the largest products the pipeline forms
//!   (the triangle test's and the BVH's cross and triple products, the squared distances
//!   of the light falloff) have at most three such factors: `2^126 < 2^128`, finite.
//! - **Lengths** (radius, side, thickness, height, size, wavelength) in `[2^-40, 2^41]`:
//!   the upper bound keeps the tessellated vertices inside the coordinate bound's
//!   products; the lower bound keeps a cube of a length normal (`2^-120 > 2^-126`), so
//!   areas and the triangle test's determinants do not flush to zero.
//! - **Resolution at the position**: a shape's extent must be at least `2^-16` of the
//!   largest coordinate of its centre. One ulp there is `<= |c| 2^-23`, so the extent
//!   spans at least 128 ulps and its vertices (at most 4096 around a circle: spacing
//!   `2 pi r / 4096 > 2^-9.4 r`) stay distinct at the default tessellation; finer
//!   tessellations that still collapse lose their zero-area triangles (dropped and
//!   counted by the device scene's build).
//! - **Intensity** `<= 2^60` W/sr and **irradiance** `<= 2^60` W per unit^2 per channel:
//!   a point light's flux `4 pi I < 2^64` is finite, but a directional light's `E A` over a
//!   projection area up to `2^84` unit^2 is not, so the flux of each light is checked
//!   again once its emission domain is known (at most [`MAX_LIGHT_FLUX`]).
//! - **Intensity** and **irradiance** `>= 2^-60` in the brightest channel unless zero (a
//!   light that is off): the fixed-point flux quantum stays a normal f32, see
//!   [`MIN_INTENSITY`].
//! - **Lights** at most [`MAX_LIGHTS`]: each light costs a photon pass and a shadow ray
//!   per pixel, so time is linear in lights; 64 bounds a frame at 64 passes.
//!
//! Radiance that still overflows (a light touching a surface: `I / d^2` with `d -> 0`)
//! is saturated at `f32::MAX` by the kernels that write images (`saturate_radiance`), so
//! no output texel is ever Inf or NaN.

use super::{Shape, TriangleMesh};

/// Largest absolute value of any coordinate (world space, scene units): 2^40.
pub const MAX_COORDINATE: f32 = 1_099_511_627_776.0;
/// Smallest length (scene units): 2^-40.
pub const MIN_LENGTH: f32 = 9.094_947e-13;
/// Largest length (scene units): 2^41.
pub const MAX_LENGTH: f32 = 2_199_023_255_552.0;
/// A shape's extent must be at least this fraction of its centre's largest coordinate
/// (2^-16: at least 128 f32 ulps at that position).
pub const MIN_EXTENT_PER_POSITION: f32 = 1.0 / 65_536.0;
/// Largest light intensity (W/sr per channel) or irradiance (W per unit^2 per channel):
/// 2^60, about 1.15e18.
pub const MAX_INTENSITY: f32 = 1_152_921_504_606_846_976.0;
/// Smallest non-zero light intensity (W/sr) or irradiance (W per unit^2), in a light's
/// brightest channel: 2^-60, about 8.67e-19 (a light of zero power is valid: it is
/// skipped, "light has zero power"). The derivation, from f32 (smallest normal 2^-126):
///
/// - A frame sums photon flux in fixed point, in units of a power-of-two quantum
///   `2^(e - 24)` where `2^e <= F < 2^(e + 1)` and `F` is the frame's brightest emitted
///   photon flux (`math::fixed_point::power_of_two_quantum`). The quantum is a normal
///   f32 (GPUs flush subnormals to zero: a zero quantum saturates every deposit) iff
///   `e - 24 >= -126`, i.e. `F >= 2^-102`
///   (`math::fixed_point::MIN_FULL_PRECISION_VALUE`).
/// - A photon's emitted flux is the light's power over its photon count: `I Omega / N`
///   for a point or spot light (`Omega` the solid angle of its emission cone, `4 pi` for
///   the whole sphere), `E A / N` for a directional light (`A` its emission rectangle's
///   area), with `N = photons_w x photons_h < 2^32` (`FrameSettings::validate`).
///   A dispersive surface's gain (>= 1) only raises `F`.
/// - At `I = 2^-60` over the whole sphere: `F > 2^-60 * 2^3.65 * 2^-32 = 2^-88.35`, so
///   `e >= -89` and the quantum is at least 2^-113, thirteen octaves above the smallest
///   normal. Generally `F >= 2^-102` holds for every light at or above the bound whose
///   domain is at least `2^-10` (sr, or unit^2 for a rectangle): a cone of half-angle
///   above about 1 degree (a caster sphere seen from more than 57 radii away gives a
///   smaller one). Only a brighter-than-the-bound intensity keeps a narrower domain's
///   quantum normal; below `2^-102` the quantum is clamped to 2^-126 (never subnormal) and
///   its photons count as `fixed_point_underflow`.
/// - Absorption, Fresnel weights and roulette shrink a photon's flux after emission; the
///   quantum, set by the emitted flux, does not see them. With the quantum at least
///   2^-113, a photon rounds to at least one unit only while its flux is at least half the
///   quantum (>= 2^-114, normal), so every photon that is stored is a normal f32 and every
///   smaller one is counted as underflow (a GPU may flush one below 2^-126 to zero
///   instead: it would have rounded to no unit either way).
/// - A reader that divides the quantum by the `k` frames or passes of an accumulation
///   keeps it normal for `k` up to 2^13 at the bound over the whole sphere (2^85 for a
///   1 W/sr light at 1024^2 photons).
pub const MIN_INTENSITY: f32 = 1.0 / MAX_INTENSITY;
/// Smallest index of refraction (2^-20): `eta = n1 / n2` and `eta^2` stay finite.
pub const MIN_IOR: f32 = 1.0 / 1_048_576.0;
/// Largest index of refraction (2^20).
pub const MAX_IOR: f32 = 1_048_576.0;
/// Largest flux one light may emit into its emission domain (W per channel): 2^100. A
/// frame sums at most [`MAX_LIGHTS`] (2^6) of them, far from f32's 2^128.
pub const MAX_LIGHT_FLUX: f32 = 1.267_650_6e30;
/// Most lights in one scene.
pub const MAX_LIGHTS: usize = 64;
/// Largest scene file read (bytes): 256 MiB. A larger file (or `/dev/zero`) is refused
/// after reading this much, not after filling memory.
pub const MAX_SCENE_FILE_BYTES: u64 = 256 << 20;
/// Most triangles (with equal bounding boxes) that may coincide: the BVH build (PLOC over
/// Morton codes) degrades quadratically on primitives whose boxes are identical
/// (measured: 10^4 coincident triangles take 3.7 s, 10^5 overflow its stack).
pub const MAX_COINCIDENT_TRIANGLES: u32 = 64;
/// Default budget of triangles per scene (2^24 = 16.8 M). The build needs about 200 bytes
/// per triangle on the host (vertices, triangles, the BVH builder's arrays), so the
/// default fits in about 3.4 GB; a setting (`max_triangles`) changes it.
pub const DEFAULT_MAX_TRIANGLES: u64 = 1 << 24;

/// Exact vertex and triangle counts [`super::shapes::tessellate`] produces for `shape`,
/// computed without tessellating (so the triangle budget is checked before allocating).
pub fn tessellated_size(shape: &Shape) -> (u64, u64) {
    match shape {
        Shape::Mesh {
            positions, indices, ..
        } => (positions.len() as u64, indices.len() as u64),
        Shape::ObjFile { .. } => (0, 0),
        Shape::Sphere { segments, .. } => {
            let s = (*segments).max(3) as u64;
            let rings = (s / 2).max(2);
            // every ring has 2 s triangles but the two polar rings, which have s
            ((rings + 1) * (s + 1), s * (2 * rings - 2))
        }
        Shape::Quad { .. } => (4, 2),
        Shape::Cuboid { .. } => (24, 12),
        Shape::Ring { segments, .. } => {
            let s = (*segments).max(3) as u64;
            (16 * s, 8 * s)
        }
        Shape::Prism { .. } => (18, 8),
        Shape::HeightField { resolution, .. } => {
            let r = (*resolution).max(1) as u64;
            ((r + 1) * (r + 1), 2 * r * r)
        }
    }
}

/// True when the triangle's area is zero or not finite in f32 (`e1 x e2 = 0`: its
/// vertices coincide or are collinear at f32 resolution).
pub fn is_degenerate(m: &TriangleMesh, t: [u32; 3]) -> bool {
    let p = |i: u32| m.positions[i as usize];
    // the cross product itself, not its square: edges up to 2^42 give components below
    // 2^85, finite, while their squares would overflow
    let n = (p(t[1]) - p(t[0])).cross(p(t[2]) - p(t[0]));
    !(n.is_finite() && n != glam::Vec3::ZERO)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::shapes::tessellate;
    use crate::scene::{Light, Wave};
    use glam::{Vec2, Vec3};

    fn with_light(light: Light) -> crate::scene::Scene {
        let mut s = crate::scene::builtin::builtin("sphere").expect("built-in scene");
        s.lights = vec![light];
        s
    }

    fn point(intensity: Vec3) -> Light {
        Light::Point {
            position: Vec3::new(0.0, 3.0, 0.0),
            intensity,
        }
    }

    fn spot(intensity: Vec3) -> Light {
        Light::Spot {
            position: Vec3::new(0.0, 3.0, 0.0),
            direction: -Vec3::Y,
            intensity,
            inner_angle_deg: 10.0,
            outer_angle_deg: 20.0,
        }
    }

    fn directional(irradiance: Vec3) -> Light {
        Light::Directional {
            direction: -Vec3::Y,
            irradiance,
            projection_volume: None,
        }
    }

    #[test]
    fn min_intensity_is_2_pow_minus_60() {
        assert_eq!(MIN_INTENSITY, 2f32.powi(-60));
        assert!(MIN_INTENSITY.is_normal());
    }

    /// A light's power below the bound (brightest channel positive) is refused by name;
    /// the bound itself, zero (a light that is off) and a dim channel next to a bright one
    /// are accepted.
    #[test]
    fn light_power_below_the_bound_is_refused_by_name() {
        let below = f32::from_bits(MIN_INTENSITY.to_bits() - 1);
        type MakeLight = fn(Vec3) -> Light;
        let lights: [(MakeLight, &str); 3] = [
            (point, "lights[0].intensity"),
            (spot, "lights[0].intensity"),
            (directional, "lights[0].irradiance"),
        ];
        for (make, path) in lights {
            for v in [
                Vec3::splat(below),
                Vec3::splat(1e-30),
                Vec3::new(0.0, f32::from_bits(1), 0.0),
                Vec3::new(0.0, 0.0, 0.5 * MIN_INTENSITY),
            ] {
                let problems = with_light(make(v)).validate().expect_err("refused");
                assert_eq!(problems.len(), 1, "{v}: {problems:?}");
                assert_eq!(problems[0].path, path);
                assert!(
                    problems[0].reason.contains("below the bound")
                        && problems[0].reason.contains(&format!("{MIN_INTENSITY:e}")),
                    "{}",
                    problems[0].reason
                );
            }
            for v in [
                Vec3::splat(MIN_INTENSITY),
                Vec3::new(MIN_INTENSITY, 0.0, 0.0),
                Vec3::ZERO,
                Vec3::new(1.0, 1e-30, 0.0),
                Vec3::splat(MAX_INTENSITY),
            ] {
                with_light(make(v))
                    .validate()
                    .unwrap_or_else(|p| panic!("{path} = {v}: {p:?}"));
            }
        }
    }

    #[test]
    fn tessellated_size_is_what_tessellate_makes() {
        let shapes = [
            Shape::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
                segments: 3,
            },
            Shape::Sphere {
                center: Vec3::ZERO,
                radius: 1.0,
                segments: 97,
            },
            Shape::Quad {
                center: Vec3::ZERO,
                u: Vec3::X,
                v: Vec3::Z,
            },
            Shape::Cuboid {
                min: Vec3::ZERO,
                max: Vec3::ONE,
            },
            Shape::Ring {
                center: Vec3::ZERO,
                radius: 1.0,
                thickness: 0.1,
                height: 0.2,
                segments: 5,
            },
            Shape::Prism {
                center: Vec3::ZERO,
                side: 1.0,
                length: 2.0,
            },
            Shape::HeightField {
                center: Vec3::ZERO,
                size: Vec2::ONE,
                resolution: 7,
                waves: vec![Wave {
                    amplitude: 0.1,
                    wavelength: 0.5,
                    direction: Vec2::X,
                    phase: 0.0,
                }],
            },
        ];
        for s in &shapes {
            let m = tessellate(s);
            assert_eq!(
                tessellated_size(s),
                (m.positions.len() as u64, m.indices.len() as u64),
                "{s:?}"
            );
            // procedural shapes at sane sizes have no degenerate triangle
            assert!(!m.indices.iter().any(|t| is_degenerate(&m, *t)), "{s:?}");
        }
    }
}
