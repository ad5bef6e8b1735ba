//! Scene builders shared by the stiff cases: small settings, the sphere scene at [`SIZE`],
//! glass, balls, and [`transform_scene`] (scale and offset a whole scene).

use super::SIZE;
use caustica_core::scene::builtin;
use caustica_core::scene::{Light, Material, Object, Scene, Shape};
use caustica_core::SspmSettings;
use caustica_core::TechniqueSettings;
use glam::Vec3;

pub(super) fn settings(n: u32) -> SspmSettings {
    SspmSettings::default().with_photons(n, n)
}

pub(super) fn sized(mut s: Scene, (w, h): (u32, u32)) -> Scene {
    s.camera.width = w;
    s.camera.height = h;
    s
}

pub(super) fn sphere_scene() -> Scene {
    sized(builtin::sphere(), SIZE)
}

pub(super) fn glass(ior: f32) -> Material {
    Material::Dielectric {
        ior,
        cauchy_b: 0.0,
        absorption: Vec3::ZERO,
        ior_model: Default::default(),
    }
}

pub(super) fn obj(name: &str, material: &str, shape: Shape) -> Object {
    Object {
        name: name.into(),
        material: material.into(),
        shape,
        transform: None,
    }
}

pub(super) fn ball(center: Vec3, radius: f32) -> Shape {
    Shape::Sphere {
        center,
        radius,
        segments: 96,
    }
}

/// `scene` with its sphere objects as instances: each re-centred at the object-space
/// origin and placed by a translation to its centre.
pub fn instanced_spheres(scene: &Scene) -> Scene {
    let mut t = scene.clone();
    for ob in &mut t.objects {
        if let Shape::Sphere { center, .. } = &mut ob.shape {
            ob.transform = Some(caustica_core::scene::Transform::from_translation(
                std::mem::replace(center, Vec3::ZERO),
            ));
        }
    }
    t
}

/// Scales every length of a scene about the origin by `s`, then offsets it by `o` (an
/// instance's transform scales and moves, its object-space shape stays); light
/// intensities scale by `s^2` (so radiances are unchanged), irradiances are kept.
pub fn transform_scene(scene: &Scene, s: f32, o: Vec3) -> Scene {
    let mut t = scene.clone();
    let p = |x: Vec3| x * s + o;
    t.camera.position = p(t.camera.position);
    t.camera.target = p(t.camera.target);
    for ob in &mut t.objects {
        if let Some(tr) = &mut ob.transform {
            // an instance: its placement scales, its object-space shape stays
            tr.translation = p(tr.translation);
            tr.scale *= s;
            continue;
        }
        match &mut ob.shape {
            Shape::Sphere { center, radius, .. } => {
                *center = p(*center);
                *radius *= s;
            }
            Shape::Quad { center, u, v } => {
                *center = p(*center);
                *u *= s;
                *v *= s;
            }
            Shape::Cuboid { min, max } => {
                *min = p(*min);
                *max = p(*max);
            }
            Shape::Mesh { positions, .. } => std::sync::Arc::make_mut(positions)
                .iter_mut()
                .for_each(|x| *x = p(*x)),
            _ => panic!("transform_scene: shape not supported"),
        }
    }
    for l in &mut t.lights {
        match l {
            Light::Point {
                position,
                intensity,
            }
            | Light::Spot {
                position,
                intensity,
                ..
            } => {
                *position = p(*position);
                *intensity *= s * s;
            }
            Light::Directional {
                projection_volume, ..
            } => {
                if let Some(b) = projection_volume {
                    b.min = p(b.min);
                    b.max = p(b.max);
                }
            }
        }
    }
    t
}
