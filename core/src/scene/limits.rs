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
    use crate::scene::Wave;
    use glam::{Vec2, Vec3};

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
