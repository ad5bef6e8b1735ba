//! `primary_gbuffer`: one camera ray per pixel; writes the first hit's position, view
//! depth, shading normal (turned to the camera), albedo, geometric normal (packed, turned to the camera),
//! uv, material and the RECEIVER flag for diffuse surfaces. Misses get depth 0 and
//! material `NO_MATERIAL`.

use crate::traversal::SceneView;
use caustica_core::device::layout::{
    gbuffer_flags, material_kind, primary_ray, GBufferTexel, GpuCamera, NO_MATERIAL,
};
use caustica_core::math::packing::pack_unit_vector;
use glam::Vec3;
use rayon::prelude::*;

/// The G-buffer of `cam`: one texel per pixel, row-major from the top-left.
pub fn primary_gbuffer(scene: &SceneView, cam: &GpuCamera) -> Vec<GBufferTexel> {
    let (w, h) = (cam.width, cam.height);
    (0..w * h)
        .into_par_iter()
        .map(|i| gbuffer_texel(scene, cam, i % w, i / w))
        .collect()
}

fn gbuffer_texel(scene: &SceneView, cam: &GpuCamera, px: u32, py: u32) -> GBufferTexel {
    let (origin, dir) = primary_ray(cam, px, py);
    let Some(hit) = scene.closest_hit(origin, dir, f32::INFINITY) else {
        return GBufferTexel {
            material: NO_MATERIAL,
            ..Default::default()
        };
    };
    let (s, m) = scene.surface(&hit);
    let n = if s.shading_normal.dot(dir) > 0.0 {
        -s.shading_normal
    } else {
        s.shading_normal
    };
    let ng = if s.geometric_normal.dot(dir) > 0.0 {
        -s.geometric_normal
    } else {
        s.geometric_normal
    };
    let diffuse = m.kind == material_kind::DIFFUSE;
    let tri = &scene.triangles[hit.triangle as usize];
    GBufferTexel {
        position: s.position.to_array(),
        depth: hit.t * dir.dot(Vec3::from(cam.forward)),
        normal: n.to_array(),
        geometric_normal: pack_unit_vector(ng),
        albedo: [m.color[0], m.color[1], m.color[2]],
        material: tri.material,
        uv: s.uv.to_array(),
        view_distance: hit.t,
        flags: if diffuse { gbuffer_flags::RECEIVER } else { 0 },
    }
}
