//! `primary_gbuffer`: one camera ray per pixel; writes the first hit's position, view
//! depth, shading normal (turned to the camera), albedo, geometric normal (packed, turned to the camera),
//! uv, material and the RECEIVER flag for diffuse surfaces. Misses get depth 0 and
//! material `NO_MATERIAL`.

use crate::recording::reserve_temporary;
use crate::traversal::SceneView;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    gbuffer_flags, material_kind, primary_ray, GBufferTexel, GpuCamera, NO_MATERIAL,
};
use caustica_core::kernels::PrimaryGbuffer;
use caustica_core::math::packing::pack_unit_vector;
use glam::Vec3;
use rayon::prelude::*;

/// Runs `primary_gbuffer` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &PrimaryGbuffer) -> Result<(), BackendError> {
    let PrimaryGbuffer {
        scene,
        camera,
        gbuffer,
    } = k;
    let pixels = camera.width as u64 * camera.height as u64;
    reserve_temporary::<GBufferTexel>(pixels, "the G-buffer")?;
    let out = primary_gbuffer(&cpu.view(scene)?, camera);
    // plane by plane, with no second copy of the G-buffer (8192^2: 4 GiB)
    for (k, b) in gbuffer.planes.iter().enumerate() {
        use rayon::prelude::*;
        let plane = cpu.get_mut(b.id)?.as_mut_slice(b.len)?;
        if plane.len() != out.len() {
            return Err(BackendError::BadArgument(
                "G-buffer plane and camera differ in size".into(),
            ));
        }
        plane
            .par_iter_mut()
            .zip(out.par_iter())
            .for_each(|(p, t): (&mut [u32; 4], _)| *p = t.to_planes()[k]);
    }
    Ok(())
}

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
