//! A scene flattened into the `Pod` arrays every backend uploads: vertices,
//! triangles, materials, lights and an obvhs compressed wide BVH (CWBVH, 80-byte nodes
//! uploaded as 5 x `[u32; 4]`). Triangles are reordered into BVH leaf order, so the
//! BVH's primitive index *is* the triangle index on every backend.

use crate::device::layout::{
    light_kind, material_kind, GpuLight, GpuMaterial, GpuTriangle, GpuVertex,
};
use crate::scene::{shapes::tessellate, Aabb, Light, Material, Scene};
use glam::{Vec3, Vec3A};
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, node::CwBvhNode};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::time::Duration;

/// Flattened scene arrays, ready for upload.
#[derive(Clone, Debug)]
pub struct DeviceScene {
    /// Vertices of every tessellated object (world space).
    pub vertices: Vec<GpuVertex>,
    /// Triangles in BVH leaf order (the BVH's primitive index is the triangle index).
    pub triangles: Vec<GpuTriangle>,
    /// Materials in name order (the scene's `BTreeMap`), indexed by `GpuTriangle::material`.
    pub materials: Vec<GpuMaterial>,
    /// Lights in scene order.
    pub lights: Vec<GpuLight>,
    /// CWBVH nodes, each 5 x `[u32; 4]` (80 bytes).
    pub bvh_nodes: Vec<[u32; 4]>,
    /// Bounds of all geometry (world space).
    pub bounds: Aabb,
    /// Bounds of the caustic casters, the mirror and dielectric objects (world space; empty
    /// when there are none).
    pub caster_bounds: Aabb,
    /// True when some dielectric has a non-zero Cauchy B.
    pub has_dispersion: bool,
}

/// `[u32; 4]` vectors per CWBVH node in `bvh_nodes` (80 bytes).
pub const BVH_NODE_VEC4S: usize = 5;

impl DeviceScene {
    /// Tessellates, flattens and builds the BVH. The scene must have passed
    /// [`Scene::validate`].
    pub fn build(scene: &Scene) -> DeviceScene {
        let names: Vec<&String> = scene.materials.keys().collect();
        let materials = scene.materials.values().map(gpu_material).collect();
        let mut vertices = Vec::new();
        let mut tris = Vec::new();
        let mut bounds = Aabb::EMPTY;
        let mut caster_bounds = Aabb::EMPTY;
        for o in &scene.objects {
            let mat = names.iter().position(|n| **n == o.material).unwrap_or(0) as u32;
            let specular = scene.materials[&o.material].is_specular();
            let m = tessellate(&o.shape);
            let base = vertices.len() as u32;
            for i in 0..m.positions.len() {
                let p = m.positions[i];
                bounds.grow(p);
                if specular {
                    caster_bounds.grow(p);
                }
                vertices.push(GpuVertex {
                    position: p.to_array(),
                    u: m.uvs[i].x,
                    normal: m.normals[i].normalize_or(Vec3::Y).to_array(),
                    v: m.uvs[i].y,
                });
            }
            for t in &m.indices {
                tris.push(GpuTriangle {
                    indices: t.map(|i| i + base),
                    material: mat,
                });
            }
        }
        let has_dispersion = scene
            .materials
            .values()
            .any(|m| matches!(m, Material::Dielectric { cauchy_b, .. } if *cauchy_b != 0.0));
        let lights = scene.lights.iter().map(gpu_light).collect();
        let (triangles, bvh_nodes) = build_bvh(&vertices, tris);
        DeviceScene {
            vertices,
            triangles,
            materials,
            lights,
            bvh_nodes,
            bounds,
            caster_bounds,
            has_dispersion,
        }
    }

    /// Number of CWBVH nodes.
    pub fn bvh_node_count(&self) -> usize {
        self.bvh_nodes.len() / BVH_NODE_VEC4S
    }
}

fn build_bvh(vertices: &[GpuVertex], tris: Vec<GpuTriangle>) -> (Vec<GpuTriangle>, Vec<[u32; 4]>) {
    let p = |i: u32| Vec3A::from(vertices[i as usize].position);
    let obvhs_tris: Vec<Triangle> = tris
        .iter()
        .map(|t| Triangle {
            v0: p(t.indices[0]),
            v1: p(t.indices[1]),
            v2: p(t.indices[2]),
        })
        .collect();
    let mut build_time = Duration::ZERO;
    let bvh = build_cwbvh_from_tris(&obvhs_tris, BvhBuildParams::medium_build(), &mut build_time);
    // Reorder triangles into leaf order; leaf slots then index triangles directly.
    let ordered: Vec<GpuTriangle> = bvh
        .primitive_indices
        .iter()
        .map(|&i| tris[i as usize])
        .collect();
    let nodes: &[[u32; 4]] = bytemuck::cast_slice::<CwBvhNode, [u32; 4]>(&bvh.nodes);
    (ordered, nodes.to_vec())
}

fn gpu_material(m: &Material) -> GpuMaterial {
    match m {
        Material::Diffuse { albedo } => GpuMaterial {
            kind: material_kind::DIFFUSE,
            color: albedo.extend(0.0).to_array(),
            ..Default::default()
        },
        Material::Mirror { reflectance } => GpuMaterial {
            kind: material_kind::MIRROR,
            color: reflectance.extend(0.0).to_array(),
            ..Default::default()
        },
        Material::Dielectric {
            ior,
            cauchy_b,
            absorption,
        } => GpuMaterial {
            kind: material_kind::DIELECTRIC,
            ior: *ior,
            cauchy_b: *cauchy_b,
            color: [1.0; 4],
            absorption: absorption.extend(0.0).to_array(),
            ..Default::default()
        },
    }
}

/// A light as the kernels read it (intensity in W/sr or irradiance in W/m^2 per channel).
pub fn gpu_light(l: &Light) -> GpuLight {
    match l {
        Light::Point {
            position,
            intensity,
        } => GpuLight {
            kind: light_kind::POINT,
            cos_inner: -1.0,
            cos_outer: -1.0,
            position: position.extend(1.0).to_array(),
            intensity: intensity.extend(0.0).to_array(),
            ..Default::default()
        },
        Light::Spot {
            position,
            direction,
            intensity,
            inner_angle_deg,
            outer_angle_deg,
        } => GpuLight {
            kind: light_kind::SPOT,
            cos_inner: inner_angle_deg.to_radians().cos(),
            cos_outer: outer_angle_deg.to_radians().cos(),
            position: position.extend(1.0).to_array(),
            direction: direction.normalize().extend(0.0).to_array(),
            intensity: intensity.extend(0.0).to_array(),
            ..Default::default()
        },
        Light::Directional {
            direction,
            irradiance,
            ..
        } => GpuLight {
            kind: light_kind::DIRECTIONAL,
            direction: direction.normalize().extend(0.0).to_array(),
            intensity: irradiance.extend(0.0).to_array(),
            ..Default::default()
        },
    }
}

/// Spot falloff: 1 inside the inner cone, 0 outside the outer, smoothstep between
/// (`cos_theta` is the cosine to the spot axis). Point lights pass `cos_outer = -1`.
#[inline]
pub fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_theta >= cos_inner {
        return 1.0;
    }
    if cos_theta <= cos_outer {
        return 0.0;
    }
    let t = ((cos_theta - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}
