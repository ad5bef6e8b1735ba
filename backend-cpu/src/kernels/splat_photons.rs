//! `splat_photons` (PhotonGi, Smal 2019, section 24.3): the stored photons splatted into
//! the screen's irradiance. Method, units and sources in `caustica_core::math::photon_splat`
//! and the kernel's declaration.

use super::deposit_screen::{deposit_photon_texel, MapPlanes};
use super::Counters;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    counter, gbuffer_flags, gbuffer_pixel_area, project_to_pixel, splat_ray_may_hit, splat_rays,
    splat_screen_rect, GBufferView, SplatRays,
    GiPhoton, Photon, SplatParams,
};
use caustica_core::kernels::SplatPhotons;
use caustica_core::math::irradiance_filter::{light_direction_deposit, shading_normal_departs};
use caustica_core::math::packing::{unpack_rgb9e5, unpack_unit_vector};
use caustica_core::math::photon_splat::{
    density_scale, min_splat_scale, ray_length_scale, splat_irradiance, splat_kernel,
    SplatConstants, SplatKernel,
};
use glam::Vec3;
use rayon::prelude::*;

/// Runs `splat_photons` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &SplatPhotons) -> Result<(), BackendError> {
    let SplatPhotons {
        params,
        gbuffer,
        photons,
        photon_count,
        tile_counts,
        counters,
        photon_map,
        direction_map,
    } = k;
    let n = cpu.get(photon_count.id)?.as_slice::<u32>(1)?[0].min(photons.len);
    let ph = &cpu.get(photons.id)?.as_slice(photons.len)?[..n as usize];
    let tc = cpu.get(tile_counts.id)?.as_slice(tile_counts.len)?;
    let g = cpu.gbuffer(gbuffer)?;
    let atomics = cpu.map_atomics(photon_map)?;
    let directions = cpu.map_atomics(direction_map)?;
    let c = splat_photons(params, g, ph, tc, atomics, directions);
    c.add_to(cpu.get_mut(counters.id)?.as_mut_slice(counters.len)?);
    Ok(())
}

/// The chapter's kernel constants from the splat parameters.
pub fn splat_constants(p: &SplatParams) -> SplatConstants {
    SplatConstants {
        max_ray_length: p.max_ray_length,
        min_length_scale: p.min_length_scale,
        density_radius_min: p.density_radius_min,
        density_radius_max: p.density_radius_max,
        photons_per_pixel: p.photons_per_pixel,
        normal_compression: p.normal_compression,
        max_stretch: p.max_stretch,
    }
}

/// `splat_photons`: every photon's splat added to `map`; returns the counters.
pub fn splat_photons(
    p: &SplatParams,
    g: GBufferView,
    photons: &[GiPhoton],
    tile_counts: &[u32],
    map: MapPlanes,
    directions: MapPlanes,
) -> Counters {
    photons
        .par_chunks(256)
        .map(|chunk| {
            let mut c = Counters::default();
            for ph in chunk {
                splat_photon(p, &g, ph, tile_counts, (&map, &directions), &mut c);
            }
            c
        })
        .reduce(Counters::default, Counters::merge)
}

/// Half-width (pixels) of the square of pixels a splat with bounding radius `radius`
/// (scene units) around a point at view depth `z` can reach: its radius over the pixel
/// footprint at the sphere's nearest depth, plus one; `u32::MAX` when the sphere reaches
/// the camera plane.
pub fn splat_reach_px(p: &SplatParams, radius: f32, z: f32) -> u32 {
    let near = z - radius;
    if !(near > 0.0) {
        return u32::MAX;
    }
    let pixel = 2.0 * p.camera.tan_half_fov_y / p.camera.height as f32;
    let r = (radius / (near * pixel)).ceil() + 1.0;
    if r >= 4_194_304.0 {
        u32::MAX
    } else {
        r as u32
    }
}

/// What every pixel test of one splat reads (the GPU ports keep a workgroup's in shared
/// memory and walk their pixels together).
struct SplatSetup {
    ellipsoid: SplatKernel,
    centre: Vec3,
    normal: Vec3,
    to_light: Vec3,
    irradiance: Vec3,
    /// `[x0, x1, y0, y1]`, inclusive.
    rect: [i32; 4],
    /// The pixels' centre rays in the kernel's frame, tested before a pixel's G-buffer
    /// is read.
    rays: SplatRays,
}

/// A photon's kernel (Eqs. 2-8), irradiance (Eq. 9) and screen rectangle; `None` when it
/// packs to zero power or projects off screen. Counts a saturated splat.
fn splat_setup(
    p: &SplatParams,
    ph: &GiPhoton,
    tile_counts: &[u32],
    c: &mut Counters,
) -> Option<SplatSetup> {
    let power = unpack_rgb9e5(ph.power) * p.power_scale;
    if !(power.max_element() > 0.0) {
        return None;
    }
    let pos = Vec3::from(ph.position);
    let (px, py, z) = project_to_pixel(&p.camera, pos)?;
    let k = splat_constants(p);
    let n = unpack_unit_vector(ph.normal);
    let to_light = -unpack_unit_vector(ph.direction);
    let s = (ray_length_scale(ph.ray_length, &k)
        * density_scale(z, p.tile_constant, tile_counts[ph.tile as usize], &k))
    .max(min_splat_scale(
        z,
        p.camera.tan_half_fov_y,
        p.camera.height,
        p.min_splat_px,
    ));
    let kernel = splat_kernel(n, to_light, s, &k);
    let reach = splat_reach_px(p, kernel.axes.max_element(), z);
    if reach > p.max_splat_px {
        c.bump(counter::SATURATED);
    }
    let rect = splat_screen_rect(
        &p.camera,
        pos,
        &kernel,
        (px, py),
        reach.min(p.max_splat_px),
        p.scene_magnitude,
    );
    let rays = splat_rays(&p.camera, pos, &kernel, p.scene_magnitude);
    Some(SplatSetup {
        irradiance: splat_irradiance(power, &kernel),
        ellipsoid: kernel,
        centre: pos,
        normal: n,
        to_light,
        rect,
        rays,
    })
}

/// One pixel `q` of a splat's rectangle: if it is a receiver inside the kernel facing the
/// photon's side, `E` times its area goes to `map` (and Eq. 20's light direction to
/// `directions` with `p.light_direction`).
fn splat_pixel(
    p: &SplatParams,
    g: &GBufferView,
    s: &SplatSetup,
    q: u32,
    (map, directions): (&MapPlanes, &MapPlanes),
    c: &mut Counters,
) {
    let t = g.load_gbuffer(q as usize);
    // the GPU kernels' order: flags, containment, normal (each loads its plane)
    if t.flags & gbuffer_flags::RECEIVER == 0
        || !s.ellipsoid.contains(s.centre, Vec3::from(t.position))
        || Vec3::from(t.normal).dot(s.normal) <= 0.0
    {
        return;
    }
    let area = gbuffer_pixel_area(&p.camera, q, &t);
    let splat = Photon {
        flux: (s.irradiance * area).to_array(),
        ..Default::default()
    };
    deposit_photon_texel(map, q, &splat, p.flux_quantum, 1.0, c);
    if p.light_direction != 0
        && shading_normal_departs(Vec3::from(t.normal), unpack_unit_vector(t.geometric_normal))
    {
        // Eq. 20's power-weighted light direction, in the flux's quanta; its rounding is
        // not counted (the flux's own deposit counts it)
        let (d, w) = light_direction_deposit(s.irradiance * area, s.to_light);
        let dir = Photon {
            flux: d.to_array(),
            hit_distance: w,
            ..Default::default()
        };
        let mut uncounted = Counters::default();
        deposit_photon_texel(
            directions,
            q,
            &dir,
            p.flux_quantum,
            p.flux_quantum,
            &mut uncounted,
        );
    }
}

fn splat_photon(
    p: &SplatParams,
    g: &GBufferView,
    ph: &GiPhoton,
    tile_counts: &[u32],
    maps: (&MapPlanes, &MapPlanes),
    c: &mut Counters,
) {
    let Some(s) = splat_setup(p, ph, tile_counts, c) else {
        return;
    };
    let [x0, x1, y0, y1] = s.rect;
    let w = p.camera.width as i64;
    for qy in y0 as i64..=y1 as i64 {
        for qx in x0 as i64..=x1 as i64 {
            // a pixel whose centre ray misses the kernel's box is turned away before its
            // G-buffer is read (most of a rectangle's pixels)
            if splat_ray_may_hit(&s.rays, &p.camera, qx as u32, qy as u32) {
                splat_pixel(p, g, &s, (qy * w + qx) as u32, maps, c);
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustica_core::device::layout::{
        camera_ray, gbuffer_to_planes, GpuCamera, DEPOSIT_PLANES, DEPOSIT_PLANE_WORDS,
    };
    use caustica_core::math::packing::{pack_rgb9e5, pack_unit_vector};
    use caustica_core::math::rng::random_f32;
    use std::sync::atomic::{AtomicU64, Ordering};

    /// A camera `elevation` degrees above the plane y = 0 (90: straight down), at distance
    /// `dist` from the origin, the plane's G-buffer (misses where the ray goes up).
    fn plane_view(
        w: u32,
        h: u32,
        dist: f32,
        elevation: f32,
    ) -> (GpuCamera, Vec<caustica_core::device::layout::GBufferTexel>) {
        let e = elevation.to_radians();
        let forward = Vec3::new(0.0, -e.sin(), -e.cos());
        let right = Vec3::X;
        let up = right.cross(forward).normalize();
        let cam = GpuCamera {
            position: (-dist * forward).to_array(),
            tan_half_fov_x: 0.5 * w as f32 / h as f32,
            forward: forward.to_array(),
            tan_half_fov_y: 0.5,
            right: right.to_array(),
            width: w,
            up: (-up).to_array(),
            height: h,
        };
        let g = (0..w * h)
            .map(|i| {
                let d = camera_ray(&cam, i % w, i / w);
                let t = cam.position[1] / -d.y;
                if !(t > 0.0) {
                    return caustica_core::device::layout::GBufferTexel {
                        material: caustica_core::device::layout::NO_MATERIAL,
                        ..Default::default()
                    };
                }
                caustica_core::device::layout::GBufferTexel {
                    position: (Vec3::from(cam.position) + t * d).to_array(),
                    depth: t * d.dot(Vec3::from(cam.forward)),
                    normal: [0.0, 1.0, 0.0],
                    // a geometric normal 3 degrees off the shading one, so that Eq. 20's
                    // direction map is written
                    geometric_normal: caustica_core::math::packing::pack_unit_vector(
                        Vec3::new(0.05, 1.0, 0.0).normalize(),
                    ),
                    albedo: [1.0; 3],
                    material: 0,
                    uv: [0.0; 2],
                    view_distance: t,
                    flags: gbuffer_flags::RECEIVER,
                }
            })
            .collect();
        (cam, g)
    }

    /// On a flat receiver a splat's pixels sum to the photon's power (Eq. 9's kernel
    /// integrates to one), up to the pixel sampling of the ellipse: checked over many
    /// photons at random sub-pixel positions, oblique arrivals and kernel sizes, seen from
    /// above and at 30 and 12 degrees.
    #[test]
    fn splats_keep_the_photon_power_on_a_plane() {
        for elevation in [90.0f32, 30.0, 12.0] {
            splat_power_on_a_plane(elevation);
        }
    }

    fn splat_power_on_a_plane(elevation: f32) {
        let (w, h) = (160u32, 120u32);
        let (cam, g) = plane_view(w, h, 2.0, elevation);
        let planes = gbuffer_to_planes(&g);
        let view = GBufferView {
            planes: std::array::from_fn(|k| &planes[k][..]),
        };
        let p = SplatParams {
            camera: cam,
            tile_size: 16,
            power_scale: 1.0,
            flux_quantum: 1e-7,
            max_splat_px: 64,
            max_ray_length: 1.0,
            min_length_scale: 0.1,
            density_radius_min: 1e-3,
            density_radius_max: 0.2,
            photons_per_pixel: 2.0,
            normal_compression: 0.1,
            max_stretch: 4.0,
            tile_constant: 1e-3,
            min_splat_px: 1.5,
            light_direction: 1,
            scene_magnitude: 2.0,
            _pad: [0],
        };
        let photons: Vec<GiPhoton> = (0..4000u32)
            .map(|i| {
                let r = |k: u32| random_f32(9, i, 0, k);
                let dir = Vec3::new(r(0) - 0.5, -1.0, r(1) - 0.5).normalize();
                GiPhoton {
                    position: [(r(2) - 0.5) * 1.0, 0.0, (r(3) - 0.5) * 0.8],
                    power: pack_rgb9e5(Vec3::ONE),
                    normal: pack_unit_vector(Vec3::Y),
                    direction: pack_unit_vector(dir),
                    ray_length: 0.05 + r(4),
                    tile: (i % 30) * 2,
                }
            })
            .collect();
        let tiles = vec![40u32; 80];
        let n = (w * h) as usize;
        let words: [Vec<AtomicU64>; DEPOSIT_PLANES] = std::array::from_fn(|k| {
            (0..n * DEPOSIT_PLANE_WORDS[k] / 2)
                .map(|_| AtomicU64::new(0))
                .collect()
        });
        let map: MapPlanes = std::array::from_fn(|k| &words[k][..]);
        let direction_words: [Vec<AtomicU64>; DEPOSIT_PLANES] = std::array::from_fn(|k| {
            (0..n * DEPOSIT_PLANE_WORDS[k] / 2)
                .map(|_| AtomicU64::new(0))
                .collect()
        });
        let directions: MapPlanes = std::array::from_fn(|k| &direction_words[k][..]);
        let c = splat_photons(&p, view, &photons, &tiles, map, directions);
        // Eq. 20's direction map: per pixel the weights (hit-distance words: plane 1, the
        // second u64 of each pixel) are the luminance of the flux (white photons: the
        // red flux), within a quantum per splat; the mean direction points up, to the
        // photons' source
        let (mut weights, mut up) = (0.0f64, 0.0f64);
        for px in 0..n {
            let word = |k: usize, w: usize| {
                direction_words[k][px * DEPOSIT_PLANE_WORDS[k] / 2 + w].load(Ordering::Relaxed)
            };
            let w = word(1, 1) as f64;
            weights += w;
            // y sum: flux g (plane 0, second u64)
            up += 2.0 * word(0, 1) as f64 - w;
        }
        let red: f64 = words[0]
            .iter()
            .step_by(2)
            .map(|a| a.load(Ordering::Relaxed) as f64)
            .sum();
        assert!(
            (weights / red - 1.0).abs() < 1e-3,
            "direction weights {weights} vs flux {red}"
        );
        assert!(
            up > 0.5 * weights,
            "mean light direction not upwards: {up} of {weights}"
        );
        // red flux words: plane 0, words 0..2 of each pixel
        let sum: f64 = words[0]
            .iter()
            .step_by(2)
            .map(|a| a.load(Ordering::Relaxed) as f64)
            .sum::<f64>()
            * p.flux_quantum as f64;
        let expected = photons.len() as f64 * unpack_rgb9e5(pack_rgb9e5(Vec3::ONE)).x as f64;
        assert_eq!(c.words[counter::SATURATED], 0, "a splat was clipped");
        eprintln!(
            "elevation {elevation}: splats sum to {:.4} of the photons' power",
            sum / expected
        );
        // pixel sampling of the ellipses averages out over 4000 photons (within 0.2% seen
        // from above); at 12 degrees a kernel is a third of a pixel row tall on screen and
        // a pixel's patch a long trapezoid whose area the centre's obliquity misjudges to
        // second order (3.6% measured)
        let tol = if elevation < 20.0 { 0.05 } else { 0.01 };
        assert!(
            (sum / expected - 1.0).abs() < tol,
            "elevation {elevation}: splats sum to {sum}, photons carry {expected}"
        );
    }
}
