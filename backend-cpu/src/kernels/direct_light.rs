//! `direct_light`: radiance from the lights at each pixel, with shadow rays (glass and
//! mirrors cast shadows; the light they pass on arrives as caustics). Diffuse pixels are
//! shaded directly; mirror and glass pixels follow their specular chain (both Fresnel
//! branches, weights below `min_weight` cut, at most `max_specular_depth` surfaces, Beer
//! absorption inside dielectrics) to the diffuse surfaces they show. Background: black.
//! Output: radiance W/(sr m^2), alpha 1.

use crate::recording::reserve_temporary;
use crate::traversal::{Hit, SceneView};
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::device_scene::light_spot_falloff;
use caustica_core::device::layout::{
    camera_ray, light_kind, material_kind, DirectParams, GBufferView, GpuMaterial, SurfacePoint,
};
use caustica_core::kernels::DirectLight;
use caustica_core::math::geometry::offset_ray_origin;
use caustica_core::math::optics::{
    beer_lambert, fresnel_reflectance, reflect, refract, saturate_radiance, saturate_radiance3,
};
use glam::Vec3;
use rayon::prelude::*;
use std::f32::consts::PI;

/// Runs `direct_light` on the host ([`super::run`]'s arm): its buffers read from `cpu`, its
/// results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &DirectLight) -> Result<(), BackendError> {
    let DirectLight {
        scene,
        params,
        gbuffer,
        out,
    } = k;
    let g = cpu.gbuffer(gbuffer)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "the direct image")?;
    let img = direct_light(&cpu.view(scene)?, params, g);
    cpu.put(out.id, &img)
}

/// Direct radiance per pixel (W/(sr m^2) per channel), alpha 1: diffuse pixels shaded with
/// shadow rays, mirror and glass pixels through their specular chain, black where the
/// pixel sees nothing.
pub fn direct_light(scene: &SceneView, p: &DirectParams, gbuffer: GBufferView) -> Vec<[f32; 4]> {
    let w = p.camera.width;
    (0..gbuffer.len())
        .into_par_iter()
        .map(|i| {
            let g = &gbuffer.load_gbuffer(i);
            if g.depth <= 0.0 {
                return [0.0, 0.0, 0.0, 1.0];
            }
            let l = if g.flags & caustica_core::device::layout::gbuffer_flags::RECEIVER != 0 {
                // The G-buffer normal faces the camera; the geometric normal is not stored,
                // so the shadow ray starts from the shading normal's side.
                shade_diffuse(
                    scene,
                    Vec3::from(g.position),
                    Vec3::from(g.normal),
                    Vec3::from(g.normal),
                    Vec3::from(g.albedo),
                )
            } else {
                let i = i as u32;
                specular_chain(
                    scene,
                    p,
                    Vec3::from(p.camera.position),
                    camera_ray(&p.camera, i % w, i / w),
                )
            };
            let l = saturate_radiance3(l);
            [l.x, l.y, l.z, 1.0]
        })
        .collect()
}

/// Reflected radiance of a Lambertian surface at `pos` (shading normal `n` and geometric
/// normal `ng`, both on the viewer's side) lit by every light, with shadow rays.
pub fn shade_diffuse(scene: &SceneView, pos: Vec3, n: Vec3, ng: Vec3, albedo: Vec3) -> Vec3 {
    let mut e = Vec3::ZERO; // irradiance, W/m^2
    for light in scene.lights {
        let (wi, dist, scale) = match light.kind {
            light_kind::DIRECTIONAL => {
                (-Vec3::from_slice(&light.direction[..3]), f32::INFINITY, 1.0)
            }
            _ => {
                let to = Vec3::from_slice(&light.position[..3]) - pos;
                let d2 = to.length_squared();
                if d2 <= 0.0 {
                    continue;
                }
                let d = d2.sqrt();
                let wi = to / d;
                let falloff = if light.kind == light_kind::SPOT {
                    light_spot_falloff(-wi, light)
                } else {
                    1.0
                };
                (wi, d, saturate_radiance(falloff / d2))
            }
        };
        let cos = n.dot(wi);
        if cos <= 0.0 || scale <= 0.0 || ng.dot(wi) <= 0.0 {
            continue;
        }
        let origin = offset_ray_origin(pos, ng);
        let t_max = if dist.is_finite() {
            (origin - Vec3::from_slice(&light.position[..3])).length() * (1.0 - 1e-5)
        } else {
            f32::INFINITY
        };
        if scene.occluded(origin, wi, t_max) {
            continue;
        }
        e = saturate_radiance3(e + Vec3::from_slice(&light.intensity[..3]) * (scale * cos));
    }
    albedo / PI * e
}

/// Radiance arriving along a camera ray that meets mirrors and glass: the ray tree is
/// walked with an explicit stack.
fn specular_chain(scene: &SceneView, p: &DirectParams, origin: Vec3, dir: Vec3) -> Vec3 {
    specular_tree(
        scene,
        p.max_specular_depth,
        p.min_weight,
        p.fresnel_model,
        origin,
        dir,
        |_, s, m, n, ng_view, _, _, _| {
            shade_diffuse(
                scene,
                s.position,
                n,
                ng_view,
                Vec3::from_slice(&m.color[..3]),
            )
        },
    )
}

/// The specular ray tree from `origin` along `dir` (`direct_light` and
/// `caustic_map_lookup` walk it alike): depth first with an explicit stack (last pushed,
/// first popped), both Fresnel branches of a dielectric, mirrors scaled by their
/// reflectance, Beer-Lambert inside dielectrics (reflectance of `fresnel_model`, one of
/// `math::optics::fresnel_model`), branches below `min_weight` or past
/// `max_depth` specular surfaces cut. At every diffuse surface it meets, adds
/// `weight * diffuse_end(hit, surface, material, n, ng_view, distance, cos, dir)` (`n`
/// the shading normal and `ng_view` the geometric normal, both turned to the arriving ray;
/// `distance` the length of the path from `origin` to the surface, over all its segments;
/// `cos` the cosine between the arriving ray and `n`; `dir` the arriving ray's unit
/// direction).
pub fn specular_tree(
    scene: &SceneView,
    max_depth: u32,
    min_weight: f32,
    fresnel_model: u32,
    origin: Vec3,
    dir: Vec3,
    diffuse_end: impl Fn(&Hit, &SurfacePoint, &GpuMaterial, Vec3, Vec3, f32, f32, Vec3) -> Vec3,
) -> Vec3 {
    let mut l = Vec3::ZERO;
    let mut stack = vec![(origin, dir, Vec3::ONE, 0u32, 0.0f32)];
    while let Some((o, d, weight, depth, dist)) = stack.pop() {
        let Some(hit) = scene.closest_hit(o, d, f32::INFINITY) else {
            continue;
        };
        let (s, m) = scene.surface(&hit);
        let entering = d.dot(s.geometric_normal) < 0.0;
        let mut weight = weight;
        if m.kind == material_kind::DIELECTRIC && !entering {
            weight *= beer_lambert(Vec3::from_slice(&m.absorption[..3]), hit.t);
        }
        let ng_view = if entering {
            s.geometric_normal
        } else {
            -s.geometric_normal
        };
        match m.kind {
            material_kind::DIFFUSE => {
                let n = if s.shading_normal.dot(d) > 0.0 {
                    -s.shading_normal
                } else {
                    s.shading_normal
                };
                l += weight * diffuse_end(&hit, &s, m, n, ng_view, dist + hit.t, -d.dot(n), d);
            }
            _ if depth >= max_depth => {}
            material_kind::MIRROR => {
                let w = weight * Vec3::from_slice(&m.color[..3]);
                if w.max_element() >= min_weight {
                    let n = if s.shading_normal.dot(d) > 0.0 {
                        -s.shading_normal
                    } else {
                        s.shading_normal
                    };
                    stack.push((
                        offset_ray_origin(s.position, ng_view),
                        reflect(d, n),
                        w,
                        depth + 1,
                        dist + hit.t,
                    ));
                }
            }
            _ => {
                let facing = if s.shading_normal.dot(d) > 0.0 {
                    -s.shading_normal
                } else {
                    s.shading_normal
                };
                let eta = if entering { 1.0 / m.ior } else { m.ior };
                let f = fresnel_reflectance(-d.dot(facing), eta, fresnel_model);
                if weight.max_element() * f >= min_weight {
                    stack.push((
                        offset_ray_origin(s.position, ng_view),
                        reflect(d, facing),
                        weight * f,
                        depth + 1,
                        dist + hit.t,
                    ));
                }
                if let Some(t) = refract(d, facing, eta) {
                    if weight.max_element() * (1.0 - f) >= min_weight {
                        stack.push((
                            offset_ray_origin(s.position, -ng_view),
                            t.normalize(),
                            weight * (1.0 - f),
                            depth + 1,
                            dist + hit.t,
                        ));
                    }
                }
            }
        }
    }
    l
}
