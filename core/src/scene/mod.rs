//! Scene model: triangle meshes (or procedural shapes tessellated into them), materials,
//! lights and a pinhole camera. All positions and lengths are in world space, in scene
//! units (the unit is the user's; built-in scenes use metres). Right-handed, y up.
//!
//! Radiometric units: point and spot light intensity in W/sr per RGB channel; directional
//! light irradiance in W/m^2 (per scene unit^2) on a surface facing the light; photon
//! flux in W; stored caustic and direct images are radiance in W/(sr m^2).

pub mod builtin;
pub mod format;
pub mod limits;
pub mod shapes;
pub mod transform;
pub mod uv_charts;
mod validate;

use glam::{Vec2, Vec3};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

pub use crate::math::geometry::Aabb;
pub use transform::Transform;
pub use validate::{more_problems, Problem};

/// A complete scene: what the file format holds and what built-in scenes produce.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Short name (used in output file names and reports).
    pub name: String,
    /// Free text: what the scene shows and its geometry.
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub description: String,
    /// The viewpoint and the image size.
    pub camera: Camera,
    /// Materials by name; objects refer to them by name. A name given twice in a file is
    /// an error (not "the last one wins").
    #[serde(deserialize_with = "unique_keys")]
    pub materials: BTreeMap<String, Material>,
    /// The geometry, each shape with its material (at least one).
    pub objects: Vec<Object>,
    /// The light sources (at least one).
    pub lights: Vec<Light>,
}

/// Pinhole camera. `fov_y_deg` is the full vertical field of view in degrees; the
/// horizontal one follows from the aspect ratio `width / height` (pixels).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Eye position (world space).
    pub position: Vec3,
    /// Point the camera looks at (world space).
    pub target: Vec3,
    /// Approximate up direction (world space, default +y); must not be parallel to the view
    /// direction. The camera's frame is re-orthogonalised from it.
    #[serde(default = "default_up")]
    pub up: Vec3,
    /// Full vertical field of view (degrees, in (0, 179)).
    pub fov_y_deg: f32,
    /// Image width (pixels, 1..=16384).
    pub width: u32,
    /// Image height (pixels, 1..=16384).
    pub height: u32,
}

impl Camera {
    /// The camera a host holds as matrices: `view` maps world to view space (right-handed,
    /// looking down -z with +y up, as `Mat4::look_at_rh`), `projection` is a symmetric
    /// perspective projection (as `Mat4::perspective_rh`, `perspective_rh_gl` or an
    /// infinite one; a Vulkan-style flipped y is accepted) whose vertical field of view is
    /// `2 atan(1 / projection[1][1])`. Refused with the reason: an orthographic or
    /// off-centre projection (caustica's camera is a centred pinhole), a view that is not
    /// invertible, or an aspect ratio that disagrees with `width / height` by more than
    /// 0.1% (caustica's pixels are square).
    pub fn from_view_projection(
        view: glam::Mat4,
        projection: glam::Mat4,
        width: u32,
        height: u32,
    ) -> Result<Camera, String> {
        let p = projection;
        if p.w_axis.w != 0.0 || p.z_axis.w >= 0.0 {
            return Err("not a perspective projection (caustica's camera is a pinhole)".into());
        }
        if p.z_axis.x.abs() > 1e-6 || p.z_axis.y.abs() > 1e-6 {
            return Err("an off-centre projection: caustica's camera is a centred pinhole".into());
        }
        let fy = p.y_axis.y.abs();
        let fx = p.x_axis.x.abs();
        if !(fy.is_finite() && fy > 0.0 && fx.is_finite() && fx > 0.0) {
            return Err("the projection's focal terms are not finite and positive".into());
        }
        if width == 0 || height == 0 {
            return Err("the image has no pixel".into());
        }
        let aspect = fy / fx;
        let want = width as f32 / height as f32;
        if (aspect / want - 1.0).abs() > 1e-3 {
            return Err(format!(
                "the projection's aspect ratio {aspect} is not the image's {want} (pixels are square)"
            ));
        }
        if view.determinant().abs() < f32::MIN_POSITIVE || !view.is_finite() {
            return Err("the view matrix is not invertible".into());
        }
        let inv = view.inverse();
        let position = inv.w_axis.truncate();
        let forward = (-inv.z_axis.truncate()).normalize_or_zero();
        let up = inv.y_axis.truncate().normalize_or_zero();
        if forward == Vec3::ZERO || up == Vec3::ZERO {
            return Err("the view matrix has no forward or up direction".into());
        }
        Ok(Camera {
            position,
            target: position + forward,
            up,
            fov_y_deg: (2.0 * (1.0 / fy).atan()).to_degrees(),
            width,
            height,
        })
    }
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
    Diffuse {
        /// Diffuse reflectance per channel, in [0, 1].
        albedo: Vec3,
    },
    /// Perfect specular reflector with per-channel reflectance in [0, 1].
    Mirror {
        /// Reflectance per channel, in [0, 1].
        reflectance: Vec3,
    },
    /// Smooth dielectric interface (glass, water). `ior` is the index of refraction
    /// relative to the surrounding medium (vacuum/air = 1) at the reference wavelength of
    /// `ior_model`; `ior_model` says how it varies with wavelength: Cauchy's
    /// `n(lambda) = A + B / lambda^2` with `B = cauchy_b` (um^2) and `A = ior - B / 0.55^2`
    /// (the default), or the Abbe number of KHR_materials_dispersion ([`IorModel`]);
    /// `absorption` is the Beer-Lambert coefficient per channel per scene unit inside the
    /// object.
    Dielectric {
        /// Index of refraction relative to the surrounding medium (> 0): at 550 nm under
        /// the Cauchy model, at the d line (587.56 nm, `n_d`) under the Abbe model.
        ior: f32,
        /// Cauchy coefficient `B` (um^2) of the Cauchy model; 0 (the default) means no
        /// dispersion. Must be 0 under the Abbe model.
        #[serde(default, skip_serializing_if = "is_zero")]
        cauchy_b: f32,
        /// Beer-Lambert absorption coefficient per channel (1/scene unit, >= 0; default 0).
        #[serde(default, skip_serializing_if = "is_zero3")]
        absorption: Vec3,
        /// How the index varies with wavelength (default Cauchy, with `cauchy_b`).
        #[serde(default, skip_serializing_if = "IorModel::is_cauchy")]
        ior_model: IorModel,
    },
}

/// How a dielectric's index of refraction varies with wavelength (`ior_model` of
/// [`Material::Dielectric`]; JSON `{"type": "cauchy"}` or
/// `{"type": "abbe", "abbe_number": 64.2}`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum IorModel {
    /// Cauchy's equation `n(lambda) = A + B / lambda^2` (Vanderstichelen 2021), `ior` at
    /// 550 nm and `B` = `cauchy_b` ([`crate::math::optics::cauchy_ior`]).
    #[default]
    Cauchy,
    /// The Abbe-number model of KHR_materials_dispersion: `ior` is `n_d` at 587.56 nm and
    /// `n(lambda) = max(n_d + (n_d - 1) / V_d (523655 nm^2 / lambda^2 - 1.5168), 1)`
    /// ([`crate::math::optics::abbe_ior`]). glTF's `dispersion` is `20 / V_d`.
    Abbe {
        /// The Abbe number `V_d = (n_d - 1) / (n_F - n_C)` (> 0; crown glass ~60, flint
        /// ~30, rutile 9.8).
        abbe_number: f32,
    },
}

impl IorModel {
    /// True for the default (Cauchy) model.
    pub fn is_cauchy(&self) -> bool {
        *self == IorModel::Cauchy
    }
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

    /// True for a dielectric whose index varies with wavelength: a Cauchy `cauchy_b` other
    /// than 0, or the Abbe model.
    pub fn is_dispersive(&self) -> bool {
        match self {
            Material::Dielectric {
                cauchy_b,
                ior_model,
                ..
            } => *cauchy_b != 0.0 || !ior_model.is_cauchy(),
            _ => false,
        }
    }
}

/// A named shape with a material (by name in [`Scene::materials`]).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    /// Descriptive name of the object.
    pub name: String,
    /// Name of its material, a key of [`Scene::materials`].
    pub material: String,
    /// Its geometry: in world space, or in object space when `transform` is given.
    pub shape: Shape,
    /// With a transform the object is an instance ([`Transform`]): its shape is in object
    /// space, it has a bottom-level BVH of its own, and `set_object_transforms` moves it
    /// without a rebuild. Without one (the default) it belongs to the static level.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub transform: Option<Transform>,
}

/// A mesh's per-vertex or per-triangle data, shared: cloning a scene (every update of a
/// technique's scene does) copies no mesh. `vec.into()` makes one; `Arc::make_mut`
/// changes one in place.
pub type MeshData<T> = std::sync::Arc<Vec<T>>;

fn no_data<T>(v: &MeshData<T>) -> bool {
    v.is_empty()
}

/// Geometry. Procedural shapes are tessellated into triangles by [`shapes::tessellate`];
/// closed shapes have outward normals (required for dielectrics: the side a ray arrives
/// from tells inside from outside).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Shape {
    /// Explicit triangle mesh; `normals` and `uvs` are per vertex and optional (when
    /// absent: each vertex gets the area-weighted average of its faces' normals, uvs are
    /// zero, which a caustic map refuses; the scene loaders give a mesh without uvs
    /// generated charts, [`uv_charts::generate_missing_uvs`]).
    Mesh {
        /// Vertex positions (world space, scene units).
        positions: MeshData<Vec3>,
        /// Per-vertex shading normals (world space; normalised on upload), or empty.
        #[serde(default, skip_serializing_if = "no_data")]
        normals: MeshData<Vec3>,
        /// Per-vertex texture coordinates, or empty.
        #[serde(default, skip_serializing_if = "no_data")]
        uvs: MeshData<Vec2>,
        /// Triangles as triples of indices into `positions`.
        indices: MeshData<[u32; 3]>,
    },
    /// A triangle mesh in a Wavefront OBJ file (path relative to the scene file), loaded
    /// by the facade's scene loader (`caustica::scene_file`, the `obj` feature), which
    /// replaces it with a [`Shape::Mesh`] before validation: vertex positions in world
    /// space, its normals and UVs where the file has them, faces triangulated, `.mtl`
    /// materials not read (the object's `material` applies). A scene that still holds one
    /// fails validation.
    ObjFile {
        /// Path of the `.obj` file, relative to the scene file's directory.
        path: String,
    },
    /// UV sphere with smooth normals: `segments` around, `segments / 2` rings.
    Sphere {
        /// Centre (world space).
        center: Vec3,
        /// Radius (scene units, > 0).
        radius: f32,
        /// Subdivisions around the equator (3..=4096, default 96).
        #[serde(default = "default_segments")]
        segments: u32,
    },
    /// Parallelogram `center + s*u + t*v`, `s, t` in [-1, 1]; normal `u x v`.
    Quad {
        /// Centre (world space).
        center: Vec3,
        /// Half-edge vector along `s` (scene units).
        u: Vec3,
        /// Half-edge vector along `t` (scene units).
        v: Vec3,
    },
    /// Axis-aligned box, outward normals.
    Cuboid {
        /// Minimum corner (world space).
        min: Vec3,
        /// Maximum corner (world space), above `min` on every axis.
        max: Vec3,
    },
    /// Thick-walled vertical ring (a short tube) around `center`, inner radius `radius`,
    /// wall `thickness`, height `height`, standing on `center.y`.
    Ring {
        /// Centre of the ring's base circle (world space).
        center: Vec3,
        /// Inner radius (scene units, > 0).
        radius: f32,
        /// Wall thickness (scene units, > 0): the outer radius is `radius + thickness`.
        thickness: f32,
        /// Height along +y (scene units, > 0).
        height: f32,
        /// Subdivisions around the axis (3..=8192, default 96).
        #[serde(default = "default_segments")]
        segments: u32,
    },
    /// Prism with an equilateral triangular cross-section of side `side` in the xy plane,
    /// extruded along z by `length`, centred at `center`.
    Prism {
        /// Centroid of the prism (world space).
        center: Vec3,
        /// Side of the triangular cross-section (scene units, > 0).
        side: f32,
        /// Extent along z (scene units, > 0).
        length: f32,
    },
    /// Height field `y = center.y + sum of waves` over a `size.x` x `size.y` rectangle in
    /// xz, `resolution` quads per side; a single (open) surface with normals up.
    HeightField {
        /// Centre of the field (world space); wave heights are added to `center.y`.
        center: Vec3,
        /// Extent along x and z (scene units, > 0).
        size: Vec2,
        /// Quads per side (1..=4096).
        resolution: u32,
        /// The sinusoids summed into the height.
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
    /// Amplitude (scene units).
    pub amplitude: f32,
    /// Wavelength (scene units, > 0).
    pub wavelength: f32,
    /// Direction of travel in the xz plane (need not be unit length).
    pub direction: Vec2,
    /// Phase offset (radians, default 0).
    #[serde(default)]
    pub phase: f32,
}

/// Standard gravity (m/s^2): [`Wave::angular_frequency`]'s `g`.
pub const GRAVITY: f32 = 9.81;

impl Wave {
    /// Angular frequency (rad/s) of a gravity wave of this wavelength on deep water, where
    /// the dispersion relation is `omega^2 = g k` with `k = 2 pi / wavelength` (scene
    /// units taken as metres): a wave 0.5 long runs at 0.88 m/s, one 1 long at 1.25 m/s.
    pub fn angular_frequency(&self) -> f32 {
        (GRAVITY * std::f32::consts::TAU / self.wavelength).sqrt()
    }

    /// This wave `seconds` later: travelling along its direction, its phase falls by
    /// `omega t` (`sin(k . x - omega t + phase)`). A wavelength that is not positive and
    /// finite, or a time that is not finite, keeps its phase.
    pub fn advanced(&self, seconds: f32) -> Wave {
        let omega = self.angular_frequency();
        let phase = if omega.is_finite() && seconds.is_finite() && self.phase.is_finite() {
            // in f64, where `omega t` of any finite f32 time stays finite, wrapped to
            // [0, 2 pi) so that long animations keep the phase's precision
            (self.phase as f64 - omega as f64 * seconds as f64).rem_euclid(std::f64::consts::TAU)
                as f32
        } else {
            self.phase
        };
        Wave {
            phase,
            ..self.clone()
        }
    }
}

impl Shape {
    /// This shape `seconds` later: a height field with every wave [advanced](Wave::advanced),
    /// any other shape as it is. Its tessellation has the same vertex count and triangles,
    /// so a technique takes it with `Technique::set_object_vertices`.
    pub fn advanced(&self, seconds: f32) -> Shape {
        match self {
            Shape::HeightField {
                center,
                size,
                resolution,
                waves,
            } => Shape::HeightField {
                center: *center,
                size: *size,
                resolution: *resolution,
                waves: waves.iter().map(|w| w.advanced(seconds)).collect(),
            },
            other => other.clone(),
        }
    }
}

/// Light sources (all delta lights, as in Kim 2019).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Light {
    /// Isotropic point light, `intensity` in W/sr per channel; total flux `4 pi I`.
    Point {
        /// Position (world space).
        position: Vec3,
        /// Intensity (W/sr per channel, >= 0).
        intensity: Vec3,
    },
    /// Point light restricted to a cone around `direction`: full intensity inside
    /// `inner_angle_deg`, smoothstep falloff to zero at `outer_angle_deg` (half-angles).
    Spot {
        /// Position (world space).
        position: Vec3,
        /// Cone axis, the direction the light shines (world space; need not be unit length).
        direction: Vec3,
        /// Intensity on the axis (W/sr per channel, >= 0).
        intensity: Vec3,
        /// Half-angle of full intensity (degrees, in [0, `outer_angle_deg`]).
        inner_angle_deg: f32,
        /// Half-angle at which the intensity reaches zero (degrees, in (0, 180]).
        outer_angle_deg: f32,
    },
    /// Parallel light travelling along `direction` with `irradiance` W/m^2 on a surface
    /// facing it. Photons are emitted over the rectangle onto which `projection_volume`
    /// (a box around the caustic casters, Kim 2019, Fig. 30-2) projects; when absent, the
    /// box around every specular object is used.
    Directional {
        /// Direction the light travels (world space; need not be unit length).
        direction: Vec3,
        /// Irradiance on a surface facing the light (W/m^2 per channel, >= 0).
        irradiance: Vec3,
        /// Box (world space) whose projection along `direction` is the emission rectangle.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        projection_volume: Option<Aabb>,
    },
}

/// A shape tessellated to triangles. Scene-wide bounds (all geometry, caustic casters)
/// are computed once, by `device_scene::DeviceScene::build`.
#[derive(Clone, Debug, Default)]
pub struct TriangleMesh {
    /// Vertex positions (world space).
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals (outward for closed shapes).
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates.
    pub uvs: Vec<Vec2>,
    /// Triangles as triples of vertex indices.
    pub indices: Vec<[u32; 3]>,
}

impl Scene {
    /// Checks every field for physical and structural validity; returns all problems
    /// found, each with the path of the offending field (e.g. `materials.glass.ior`).
    pub fn validate(&self) -> Result<(), Vec<Problem>> {
        validate::validate(self)
    }

    /// [`Scene::validate`] but for the shapes' own fields (a mesh's every vertex): what a
    /// change that leaves every shape as it was needs to check (lights, camera, materials,
    /// transforms), in time independent of the meshes' size.
    pub fn validate_except_shapes(&self) -> Result<(), Vec<Problem>> {
        validate::validate_parts(self, false)
    }
}

/// Deserialises a map, refusing a key that appears twice (serde's maps keep the last).
fn unique_keys<'de, D, V>(d: D) -> Result<BTreeMap<String, V>, D::Error>
where
    D: serde::Deserializer<'de>,
    V: Deserialize<'de>,
{
    struct Unique<V>(std::marker::PhantomData<V>);
    impl<'de, V: Deserialize<'de>> serde::de::Visitor<'de> for Unique<V> {
        type Value = BTreeMap<String, V>;
        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            f.write_str("a map of materials by name")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(
            self,
            mut m: A,
        ) -> Result<Self::Value, A::Error> {
            let mut out = BTreeMap::new();
            while let Some((k, v)) = m.next_entry::<String, V>()? {
                if out.contains_key(&k) {
                    return Err(serde::de::Error::custom(format!(
                        "material '{k}' is defined twice"
                    )));
                }
                out.insert(k, v);
            }
            Ok(out)
        }
    }
    d.deserialize_map(Unique(std::marker::PhantomData))
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::camera::rh::proj::{directx, opengl};
    use glam::camera::rh::view::look_at_mat4;
    use glam::Mat4;

    #[test]
    fn projections_a_pinhole_cannot_take_are_refused() {
        let view = look_at_mat4(Vec3::new(0.0, 1.0, 3.0), Vec3::ZERO, Vec3::Y);
        let ortho = opengl::orthographic(-1.0, 1.0, -1.0, 1.0, 0.1, 10.0);
        assert!(Camera::from_view_projection(view, ortho, 64, 64).is_err());
        let skewed = opengl::frustum(-0.5, 1.0, -0.5, 0.5, 0.1, 10.0);
        assert!(Camera::from_view_projection(view, skewed, 64, 64).is_err());
        let wide = directx::perspective(1.0, 2.0, 0.1, 10.0);
        assert!(
            Camera::from_view_projection(view, wide, 64, 64).is_err(),
            "aspect"
        );
        assert!(Camera::from_view_projection(Mat4::ZERO, wide, 128, 64).is_err());
    }

    /// An update's validation (which leaves out the meshes' vertices) judges a moved
    /// shape as a new scene's does: a sphere moved where f32 no longer resolves it is
    /// refused by both, naming its shape; a small mesh far away loads as an instance as it
    /// does in the static level (meshes have no resolution test).
    #[test]
    fn a_moved_shape_is_judged_as_a_new_scenes() {
        let mut s = builtin::builtin("sphere").expect("sphere");
        let ball = s.objects[1].clone();
        s.objects[1].transform = Some(Transform::from_translation(Vec3::new(1e7, 0.0, 0.0)));
        let full = s.validate().expect_err("refused").remove(0);
        let update = s.validate_except_shapes().expect_err("refused").remove(0);
        assert_eq!(full.path, "objects[1].shape");
        assert_eq!(
            (update.path, update.reason),
            (full.path, full.reason.clone())
        );
        assert!(full.reason.contains("f32 resolution"), "{}", full.reason);
        // a 1 cm mesh 1000 units out: both accept it
        s.objects[1] = ball;
        s.objects.push(Object {
            name: "part".into(),
            material: s.objects[0].material.clone(),
            shape: Shape::Mesh {
                positions: vec![
                    Vec3::ZERO,
                    Vec3::new(0.01, 0.0, 0.0),
                    Vec3::new(0.0, 0.0, 0.01),
                ]
                .into(),
                normals: Vec::new().into(),
                uvs: Vec::new().into(),
                indices: vec![[0, 1, 2]].into(),
            },
            transform: Some(Transform::from_translation(Vec3::new(1e3, 0.0, 0.0))),
        });
        s.validate().expect("a small mesh far away");
        s.validate_except_shapes().expect("a small mesh far away");
    }
}
