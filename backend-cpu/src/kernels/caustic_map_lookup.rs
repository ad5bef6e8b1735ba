//! `caustic_map_lookup` (Vanderstichelen 2021): camera paths read the caustic map. The math is
//! core's `math::map_gather`; this is a loop over it.

use super::direct_light::specular_tree;
use crate::recording::reserve_temporary;
use crate::traversal::SceneView;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    camera_ray, AtlasTexel, AtlasTileTexel, MapLookupParams, NO_TILE,
};
use caustica_core::kernels::CausticMapLookup;
use caustica_core::math::map_gather::{
    atlas_texel_index, footprint_extent, footprint_texels, sample_caustic_map, texel_centroid,
    CENTROID_WORDS,
};
use caustica_core::math::optics::saturate_radiance3;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::f32::consts::PI;

/// Runs `caustic_map_lookup` on the host ([`super::run`]'s arm): its buffers read from
/// `cpu`, its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &CausticMapLookup) -> Result<(), BackendError> {
    let CausticMapLookup {
        scene,
        params,
        triangle_tiles,
        tiles,
        texels,
        map,
        out,
        centroids,
    } = k;
    let tt = cpu.get(triangle_tiles.id)?.as_slice(triangle_tiles.len)?;
    let tl = cpu.get(tiles.id)?.as_slice(tiles.len)?;
    let tx = cpu.get(texels.id)?.as_slice(texels.len)?;
    let m = cpu.get(map.id)?.as_slice(map.len)?;
    let cs = cpu
        .get(centroids.id)?
        .as_slice(map.len * CENTROID_WORDS)?;
    reserve_temporary::<[f32; 4]>(out.len as u64, "the caustics image")?;
    let img = caustic_map_lookup(&cpu.view(scene)?, params, tt, tl, tx, (m, cs));
    cpu.put(out.id, &img)
}

/// Caustic radiance per pixel (W/(sr m^2), alpha 1): the camera ray's specular tree
/// reading the caustic map at every diffuse end.
#[allow(clippy::too_many_arguments)]
pub fn caustic_map_lookup(
    scene: &SceneView,
    p: &MapLookupParams,
    triangle_tiles: &[u32],
    tiles: &[AtlasTileTexel],
    texels: &[AtlasTexel],
    (map, centroids): (&[[f32; 4]], &[u32]),
) -> Vec<[f32; 4]> {
    let cam = &p.camera;
    let (w, h) = (cam.width, cam.height);
    let pixel_angle = 2.0 * cam.tan_half_fov_y / h as f32;
    (0..w * h)
        .into_par_iter()
        .map(|i| {
            let l = specular_tree(
                scene,
                p.max_specular_depth,
                p.min_weight,
                p.fresnel_model,
                Vec3::from(cam.position),
                camera_ray(cam, i % w, i / w),
                |hit, s, m, _, _, distance, cos, dir| {
                    let tile = triangle_tiles[hit.triangle as usize];
                    if tile == NO_TILE {
                        return Vec3::ZERO;
                    }
                    let t = tiles[tile as usize];
                    let tri = &scene.triangles[hit.triangle as usize];
                    let v = tri.indices.map(|k| &scene.vertices[k as usize]);
                    let mut extent = footprint_extent(
                        dir,
                        Vec3::from(cam.right),
                        pixel_angle * distance,
                        v.map(|v| Vec3::from(v.position)),
                        v.map(|v| Vec2::new(v.u, v.v)),
                        t[2],
                    );
                    if extent.x < 0.0 {
                        // no UV Jacobian: the isotropic footprint
                        let texel = atlas_texel_index(t, s.uv, p.atlas_width);
                        extent = Vec2::splat(
                            0.5 * footprint_texels(
                                pixel_angle,
                                distance,
                                cos,
                                f32::from_bits(texels[texel as usize][0]),
                            ),
                        );
                    }
                    let e = sample_caustic_map(
                        t,
                        s.uv,
                        extent,
                        p.atlas_width,
                        |q| Vec3::from_slice(&map[q as usize][..3]),
                        |q| f32::from_bits(texels[q as usize][0]),
                        |q| {
                            let i = (q * CENTROID_WORDS) as usize;
                            texel_centroid(centroids[i], centroids[i + 1], centroids[i + 2])
                        },
                    );
                    Vec3::from_slice(&m.color[..3]) / PI * e
                },
            );
            let l = saturate_radiance3(l);
            [l.x, l.y, l.z, 1.0]
        })
        .collect()
}
