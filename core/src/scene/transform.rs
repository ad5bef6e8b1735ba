//! An object's placement in the world: translation, rotation and scale (glTF's TRS order,
//! `world_from_object = T * R * S`). An object with a transform is an *instance*: its
//! shape is in object space, it gets its own bottom-level BVH, and the update API moves it
//! every frame without rebuilding that BVH; an object without one is part of the
//! scene's static level, in world space.

use glam::{Affine3A, Mat3A, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// Translation, rotation and scale of an instance (object space to world space).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Transform {
    /// Where the object's origin lands (world space, scene units; default 0).
    #[serde(default)]
    pub translation: Vec3,
    /// Unit quaternion `[x, y, z, w]` (default identity; normalised on use, its length
    /// must be within 1e-3 of 1).
    #[serde(default = "identity_rotation")]
    pub rotation: Quat,
    /// Scale along the object's axes (default 1; each component finite and of magnitude
    /// in [2^-20, 2^20]; negative mirrors the object, which flips its triangles' winding and
    /// so the side its normals face is taken from the transformed normals, not the winding).
    #[serde(default = "unit_scale")]
    pub scale: Vec3,
}

fn identity_rotation() -> Quat {
    Quat::IDENTITY
}

fn unit_scale() -> Vec3 {
    Vec3::ONE
}

/// Smallest and largest magnitude of a scale component (2^-20 and 2^20): the world
/// positions of an instance keep at least 3 significant decimal digits of its object-space
/// coordinates at either end.
pub const SCALE_RANGE: (f32, f32) = (1.0 / 1_048_576.0, 1_048_576.0);

impl Default for Transform {
    fn default() -> Self {
        Transform::IDENTITY
    }
}

impl Transform {
    /// No movement.
    pub const IDENTITY: Transform = Transform {
        translation: Vec3::ZERO,
        rotation: Quat::IDENTITY,
        scale: Vec3::ONE,
    };

    /// A translation only.
    pub fn from_translation(t: Vec3) -> Transform {
        Transform {
            translation: t,
            ..Transform::IDENTITY
        }
    }

    /// A point of object space in world space.
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.world_from_object().transform_point3(p)
    }

    /// `T * R * S`: object space to world space.
    pub fn world_from_object(&self) -> Affine3A {
        Affine3A::from_scale_rotation_translation(
            self.scale,
            self.rotation.normalize(),
            self.translation,
        )
    }

    /// The inverse, world space to object space: `S^-1 * R^-1 * T^-1`, composed from the
    /// parts (not a general matrix inverse), so it is as exact as the parts.
    pub fn object_from_world(&self) -> Affine3A {
        let inv_r = self.rotation.normalize().conjugate();
        let inv_s = self.scale.recip();
        let linear = Mat3A::from_diagonal(inv_s) * Mat3A::from_quat(inv_r);
        Affine3A {
            matrix3: linear,
            translation: linear * glam::Vec3A::from(-self.translation),
        }
    }

    /// The matrix that takes object-space normals to world space (the inverse transpose
    /// of the linear part: `R * S^-1`); its results need normalising.
    pub fn normal_matrix(&self) -> Mat3A {
        Mat3A::from_quat(self.rotation.normalize()) * Mat3A::from_diagonal(self.scale.recip())
    }

    /// What is wrong with the transform, if anything (finite parts, a unit rotation, scales
    /// in [`SCALE_RANGE`]).
    pub fn problem(&self) -> Option<String> {
        if !self.translation.is_finite() {
            return Some("translation is not finite".into());
        }
        let q = self.rotation;
        if !q.is_finite() || (q.length() - 1.0).abs() > 1e-3 {
            return Some(format!(
                "rotation {:?} is not a unit quaternion [x, y, z, w] (length within 1e-3 of 1)",
                q.to_array()
            ));
        }
        let (lo, hi) = SCALE_RANGE;
        if !self.scale.is_finite()
            || !(lo..=hi).contains(&self.scale.abs().min_element())
            || self.scale.abs().max_element() > hi
        {
            return Some(format!(
                "scale {:?}: each component must be finite with magnitude in [{lo:e}, {hi:e}]",
                self.scale.to_array()
            ));
        }
        None
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn object_from_world_inverts_world_from_object() {
        let t = Transform {
            translation: Vec3::new(1.0, -2.0, 3.5),
            rotation: Quat::from_axis_angle(Vec3::new(1.0, 2.0, 0.5).normalize(), 0.7),
            scale: Vec3::new(2.0, 0.5, -1.5),
        };
        let p = Vec3::new(0.3, -0.7, 1.1);
        let back = t
            .object_from_world()
            .transform_point3(t.world_from_object().transform_point3(p));
        assert!((back - p).abs().max_element() < 1e-5, "{back} vs {p}");
        // a normal stays perpendicular to a tangent through the transform
        let (tangent, normal) = (Vec3::new(1.0, 1.0, 0.0), Vec3::new(1.0, -1.0, 0.3));
        assert!(tangent.dot(normal).abs() < 1e-6);
        let wt = t.world_from_object().transform_vector3(tangent);
        let wn = t.normal_matrix() * normal;
        assert!(wt.dot(wn).abs() < 1e-5, "{}", wt.dot(wn));
    }

    #[test]
    fn bad_transforms_are_named() {
        let mut t = Transform::IDENTITY;
        assert!(t.problem().is_none());
        t.scale.y = 0.0;
        assert!(t.problem().unwrap().contains("scale"));
        t = Transform::IDENTITY;
        t.rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 2.0);
        assert!(t.problem().unwrap().contains("unit quaternion"));
        t = Transform::from_translation(Vec3::new(f32::NAN, 0.0, 0.0));
        assert!(t.problem().unwrap().contains("translation"));
    }
}
