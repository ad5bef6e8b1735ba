//! Scene model: triangle meshes (or procedural shapes tessellated into them), materials,
//! lights and a pinhole camera. All positions and lengths are in world space, in scene
//! units (the unit is the user's; built-in scenes use metres). Right-handed, y up.
//!
//! Radiometric units: point and spot light intensity in W/sr per RGB channel; directional
//! light irradiance in W/m^2 (per scene unit^2) on a surface facing the light; photon
//! flux in W; stored caustic and direct images are radiance in W/(sr m^2).

pub mod builtin;
pub mod format;
pub mod shapes;
mod validate;

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use crate::math::geometry::Aabb;
pub use validate::Problem;

/// A complete scene: what the file format holds and what built-in scenes produce.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name (used in output file names and reports).
    pub name: String,
    /// Free text: what the scene shows and its geometry.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    pub camera: Camera,
    /// Materials by name; objects refer to them by name.
    pub materials: BTreeMap<String, Material>,
    pub objects: Vec<Object>,
    pub lights: Vec<Light>,
}

/// Pinhole camera. `fov_y_deg` is the full vertical field of view in degrees; the
/// horizontal one follows from the aspect ratio `width / height` (pixels).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub position: Vec3,
    pub target: Vec3,
    #[serde(default = "default_up")]
    pub up: Vec3,
    pub fov_y_deg: f32,
    pub width: u32,
    pub height: u32,
}

fn default_up() -> Vec3 {
    Vec3::Y
}

/// Surface materials. Only `Diffuse` surfaces receive (store) photons; `Mirror` and
/// `Dielectric` are the specular caustic casters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Material {
    /// Lambertian reflector, BRDF `albedo / pi`; albedo per channel in [0, 1].
    Diffuse { albedo: Vec3 },
    /// Perfect specular reflector with per-channel reflectance in [0, 1].
    Mirror { reflectance: Vec3 },
    /// Smooth dielectric interface (glass, water). `ior` is the index of refraction at
    /// 550 nm relative to the surrounding medium (vacuum/air = 1); `cauchy_b` (um^2) makes
    /// it dispersive, `n(lambda) = A + B / lambda^2` with `A = ior - B / 0.55^2`;
    /// `absorption` is the Beer-Lambert coefficient per channel per scene unit inside
    /// the object.
    Dielectric {
        ior: f32,
        #[serde(default, skip_serializing_if = "is_zero")]
        cauchy_b: f32,
        #[serde(default, skip_serializing_if = "is_zero3")]
        absorption: Vec3,
    },
}

fn is_zero(x: &f32) -> bool {
    *x == 0.0
}
fn is_zero3(x: &Vec3) -> bool {
    *x == Vec3::ZERO
}

impl Material {
    /// True for mirrors and dielectrics (surfaces that cast caustics).
    pub fn is_specular(&self) -> bool {
        !matches!(self, Material::Diffuse { .. })
    }
}

/// A named shape with a material (by name in [`Scene::materials`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    pub name: String,
    pub material: String,
    pub shape: Shape,
}

/// Geometry. Procedural shapes are tessellated into triangles by [`shapes::tessellate`];
/// closed shapes have outward normals (required for dielectrics: the side a ray arrives
/// from tells inside from outside).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// Explicit triangle mesh; `normals` and `uvs` are per vertex and optional (flat
    /// normals and zero uvs when absent).
    Mesh {
        positions: Vec<Vec3>,
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        normals: Vec<Vec3>,
        #[serde(default, skip_serializing_if = "Vec::is_empty")]
        uvs: Vec<Vec2>,
        indices: Vec<[u32; 3]>,
    },
    /// UV sphere with smooth normals: `segments` around, `segments / 2` rings.
    Sphere {
        center: Vec3,
        radius: f32,
        #[serde(default = "default_segments")]
        segments: u32,
    },
    /// Parallelogram `center + s*u + t*v`, `s, t` in [-1, 1]; normal `u x v`.
    Quad { center: Vec3, u: Vec3, v: Vec3 },
    /// Axis-aligned box, outward normals.
    Cuboid { min: Vec3, max: Vec3 },
    /// Thick-walled vertical ring (a short tube) around `center`, inner radius `radius`,
    /// wall `thickness`, height `height`, standing on `center.y`.
    Ring {
        center: Vec3,
        radius: f32,
        thickness: f32,
        height: f32,
        #[serde(default = "default_segments")]
        segments: u32,
    },
    /// Prism with an equilateral triangular cross-section of side `side` in the xy plane,
    /// extruded along z by `length`, centred at `center`.
    Prism {
        center: Vec3,
        side: f32,
        length: f32,
    },
    /// Height field `y = center.y + sum of waves` over a `size.x` x `size.y` rectangle in
    /// xz, `resolution` quads per side; a single (open) surface with normals up.
    HeightField {
        center: Vec3,
        size: Vec2,
        resolution: u32,
        waves: Vec<Wave>,
    },
}

fn default_segments() -> u32 {
    96
}

/// One sinusoid of a height field: `amplitude * sin(2 pi (k . xz) / wavelength + phase)`
/// with `k = normalize(direction)`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Wave {
    pub amplitude: f32,
    pub wavelength: f32,
    pub direction: Vec2,
    #[serde(default)]
    pub phase: f32,
}

/// Light sources (all delta lights, as in seed 000).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Light {
    /// Isotropic point light, `intensity` in W/sr per channel; total flux `4 pi I`.
    Point { position: Vec3, intensity: Vec3 },
    /// Point light restricted to a cone around `direction`: full intensity inside
    /// `inner_angle_deg`, smoothstep falloff to zero at `outer_angle_deg` (half-angles).
    Spot {
        position: Vec3,
        direction: Vec3,
        intensity: Vec3,
        inner_angle_deg: f32,
        outer_angle_deg: f32,
    },
    /// Parallel light travelling along `direction` with `irradiance` W/m^2 on a surface
    /// facing it. Photons are emitted over the rectangle onto which `projection_volume`
    /// (a box around the caustic casters, seed 000 Fig. 30-2) projects; when absent, the
    /// box around every specular object is used.
    Directional {
        direction: Vec3,
        irradiance: Vec3,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        projection_volume: Option<Aabb>,
    },
}

/// A shape tessellated to triangles. Scene-wide bounds (all geometry, caustic casters)
/// are computed once, by `device_scene::DeviceScene::build`.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub uvs: Vec<Vec2>,
    pub indices: Vec<[u32; 3]>,
}

impl Scene {
    /// Checks every field for physical and structural validity; returns all problems
    /// found, each with the path of the offending field (e.g. `materials.glass.ior`).
    pub fn validate(&self) -> Result<(), Vec<Problem>> {
        validate::validate(self)
    }
}
