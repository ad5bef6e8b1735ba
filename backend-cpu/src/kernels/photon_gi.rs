//! PhotonGi's kernels (seed 003): `rsm_importance` and `sample_rsm` (section 24.2.1),
//! `trace_indirect` (24.2.2) and `splat_photons` (24.3). Method, units and sources in
//! `caustica_core::math::{rsm, gi_photon, photon_splat}` and the kernels' declarations.

use super::deposit_screen::{deposit_photon_texel, MapPlanes};
use super::Counters;
use crate::traversal::SceneView;
use caustica_core::device::device_scene::spot_falloff;
use caustica_core::device::layout::{
    camera_ray, counter, gbuffer_flags, gbuffer_pixel_area, light_kind, material_kind, off_surface,
    project_to_pixel, splat_screen_rect, CorrectionParams, GBufferView, GiPhoton, GpuLight,
    IndirectTraceParams, Photon, PhotonMapView, RsmParams, RsmPhoton, RsmTexel, SplatParams,
    NO_MATERIAL,
};
use caustica_core::kernels::VISIBLE_TOLERANCE;
use caustica_core::math::geometry::offset_ray_origin;
use caustica_core::math::gi_photon::{gi_store, screen_tile};
use caustica_core::math::irradiance_filter::{
    light_direction_deposit, mean_light_direction, shading_normal_departs, shading_normal_factor,
};
use caustica_core::math::map_gather::join_u64_f32;
use caustica_core::math::optics::{
    beer_lambert, cauchy_ior, dielectric_scatter, reflect, CHANNEL_WAVELENGTH_UM,
};
use caustica_core::math::packing::{
    pack_rgb9e5, pack_unit_vector, unpack_rgb9e5, unpack_unit_vector,
};
use caustica_core::math::photon_splat::{
    density_scale, min_splat_scale, ray_length_scale, splat_irradiance, splat_kernel,
    SplatConstants, SplatKernel,
};
use caustica_core::math::rng::random_f32;
use caustica_core::math::rsm::{
    coherent_sample_order, cosine_hemisphere, hammersley, level_offset, luminance, ortho_origin,
    ortho_texel_flux, pyramid_len, pyramid_sum, rsm_texel_kind, russian_roulette,
    texel_arriving_flux, warp_rsm,
};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// One RSM texel and its importance (`rsm_importance` level 0, texel `i` of the face).
pub fn rsm_texel(
    p: &RsmParams,
    light: &GpuLight,
    g: &caustica_core::device::layout::GBufferTexel,
    i: u32,
) -> (RsmTexel, f32) {
    let none = (RsmTexel::default(), 0.0);
    if g.material == NO_MATERIAL {
        return none;
    }
    let (x, y) = (i % p.side, i / p.side);
    let falloff = if light.kind == light_kind::SPOT {
        let dir = camera_ray(&p.face_camera, x, y);
        spot_falloff(
            dir.dot(Vec3::from_slice(&light.direction[..3])),
            light.cos_inner,
            light.cos_outer,
        )
    } else {
        1.0
    };
    let arriving = if light.kind == light_kind::DIRECTIONAL {
        ortho_texel_flux(
            Vec3::from_slice(&light.intensity[..3]),
            p.side,
            -p.face_camera.tan_half_fov_x,
        )
    } else {
        texel_arriving_flux(
            Vec3::from_slice(&light.intensity[..3]),
            falloff,
            x,
            y,
            p.side,
            p.face_camera.tan_half_fov_x,
        )
    };
    let albedo = Vec3::from(g.albedo);
    let importance = luminance(arriving * albedo);
    if !(importance > 0.0) || !importance.is_finite() {
        return none;
    }
    let diffuse = g.flags & gbuffer_flags::RECEIVER != 0;
    (
        RsmTexel {
            position: g.position,
            normal: pack_unit_vector(Vec3::from(g.normal)),
            flux: if diffuse { arriving * albedo } else { arriving }.to_array(),
            kind: if diffuse {
                rsm_texel_kind::DIFFUSE
            } else {
                rsm_texel_kind::SPECULAR
            },
        },
        caustica_core::math::rsm::pyramid_weight(p.sampling, importance),
    )
}

/// Level `p.level > 0` of `rsm_importance`: the 2x2 sums of level `p.level - 1` for
/// faces `0 ..= p.face`.
pub fn rsm_level(p: &RsmParams, pyramid: &mut [f32]) {
    let side = p.side;
    let plen = pyramid_len(side) as usize;
    let (below_off, off) = (
        level_offset(side, p.level - 1) as usize,
        level_offset(side, p.level) as usize,
    );
    let (s, sb) = ((side >> p.level) as usize, (side >> (p.level - 1)) as usize);
    for f in 0..=p.face as usize {
        let face = &mut pyramid[f * plen..(f + 1) * plen];
        let (below, rest) = face.split_at_mut(off);
        let below = &below[below_off..];
        for (i, v) in rest[..s * s].iter_mut().enumerate() {
            *v = pyramid_sum(
                |x, y| below[y as usize * sb + x as usize],
                (i % s) as u32,
                (i / s) as u32,
            );
        }
    }
}

/// `sample_rsm`: the light's photons (slot `i` of the returned vector is sample `i`).
pub fn sample_rsm(
    p: &RsmParams,
    light: &GpuLight,
    texels: &[RsmTexel],
    pyramid: &[f32],
) -> Vec<RsmPhoton> {
    (0..p.sample_count)
        .into_par_iter()
        .map(|i| rsm_photon(p, light, texels, pyramid, i))
        .collect()
}

/// Sample `i` of `sample_rsm`.
pub fn rsm_photon(
    p: &RsmParams,
    light: &GpuLight,
    texels: &[RsmTexel],
    pyramid: &[f32],
    i: u32,
) -> RsmPhoton {
    let shift = Vec2::new(
        random_f32(p.seed, p.light, 0, 0),
        random_f32(p.seed, p.light, 0, 1),
    );
    let u = hammersley(i, p.sample_count, shift);
    let plen = pyramid_len(p.side);
    let read = |f: u32, k: u32| pyramid[((p.face + f) * plen + k) as usize];
    let Some(c) = warp_rsm(read, p.face_count, p.side, u) else {
        return RsmPhoton::default();
    };
    let t =
        &texels[((p.face + c.face) * p.side * p.side + c.texel.1 * p.side + c.texel.0) as usize];
    let scale = 1.0 / (c.probability * p.sample_count as f32);
    let flux = Vec3::from(t.flux) * scale;
    if t.kind == rsm_texel_kind::DIFFUSE {
        let n = unpack_unit_vector(t.normal);
        RsmPhoton {
            origin: offset_ray_origin(Vec3::from(t.position), n).to_array(),
            direction: pack_unit_vector(cosine_hemisphere(c.within, n)),
            flux: flux.to_array(),
            bounces: 1,
        }
    } else if t.kind == rsm_texel_kind::SPECULAR {
        let origin = if light.kind == light_kind::DIRECTIONAL {
            ortho_origin(
                Vec3::from(t.position),
                Vec3::from(p.face_camera.position),
                Vec3::from(p.face_camera.forward),
            )
        } else {
            Vec3::from_slice(&light.position[..3])
        };
        RsmPhoton {
            origin: origin.to_array(),
            direction: pack_unit_vector((Vec3::from(t.position) - origin).normalize()),
            flux: flux.to_array(),
            bounces: 0,
        }
    } else {
        RsmPhoton::default()
    }
}

/// Photons `trace_indirect` stored (32-byte words, in photon order), the per-tile counts
/// it adds, and its counters.
pub struct IndirectResult {
    /// Stored photons (`GiPhoton` or `Photon` bytes as `p.store` says).
    pub photons: Vec<[u32; 8]>,
    /// Stored photons per screen tile.
    pub tile_counts: Vec<u32>,
    /// The launch's counters.
    pub counters: Counters,
}

/// `trace_indirect` over `rsm[p.first .. p.first + p.count]`.
pub fn trace_indirect(
    scene: &SceneView,
    p: &IndirectTraceParams,
    rsm: &[RsmPhoton],
    gbuffer: &GBufferView,
    tiles: usize,
) -> IndirectResult {
    let tile_counts: Vec<AtomicU32> = (0..tiles).map(|_| AtomicU32::new(0)).collect();
    let parts: Vec<(Vec<[u32; 8]>, Counters)> = (0..p.count.div_ceil(256))
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            let mut counters = Counters::default();
            for i in c * 256..((c + 1) * 256).min(p.count) {
                let index = p.first + i;
                crate::traversal_stats::photon_begins(i);
                trace_indirect_path(
                    scene,
                    p,
                    &rsm[index as usize],
                    index,
                    gbuffer,
                    &mut |ph, tile| {
                        out.push(ph);
                        tile_counts[tile as usize].fetch_add(1, Ordering::Relaxed);
                    },
                    &mut counters,
                );
                crate::traversal_stats::photon_ends();
            }
            (out, counters)
        })
        .collect();
    // the GPU ports' thread t traces photon first + coherent_sample_order(t)
    crate::traversal_stats::report("trace_indirect", p.count, |t| {
        coherent_sample_order(t, p.count)
    });
    let mut photons = Vec::new();
    let mut counters = Counters::default();
    for (ph, c) in parts {
        photons.extend(ph);
        counters = counters.merge(c);
    }
    IndirectResult {
        photons,
        tile_counts: tile_counts.into_iter().map(|a| a.into_inner()).collect(),
        counters,
    }
}

/// One path of `trace_indirect` (photon `index`): calls `store(photon words, tile)` for
/// every stored photon and counts into `c`.
pub fn trace_indirect_path(
    scene: &SceneView,
    p: &IndirectTraceParams,
    r: &RsmPhoton,
    index: u32,
    gbuffer: &GBufferView,
    store: &mut impl FnMut([u32; 8], u32),
    c: &mut Counters,
) {
    let mut flux = Vec3::from(r.flux);
    if !(flux.max_element() > 0.0) {
        c.bump(counter::NEGLIGIBLE);
        return;
    }
    let mut origin = Vec3::from(r.origin);
    let mut dir = unpack_unit_vector(r.direction);
    let mut bounces = r.bounces;
    let mut channel: Option<usize> = None;
    for segment in 0..p.max_segments {
        c.words[counter::RAYS] += 1;
        let Some(hit) = scene.closest_hit(origin, dir, f32::INFINITY) else {
            c.bump(counter::ESCAPED);
            return;
        };
        let (s, m) = scene.surface(&hit);
        let entering = dir.dot(s.geometric_normal) < 0.0;
        if m.kind == material_kind::DIELECTRIC && !entering {
            flux *= beer_lambert(Vec3::from_slice(&m.absorption[..3]), hit.t);
        }
        let facing = if s.shading_normal.dot(dir) > 0.0 {
            -s.shading_normal
        } else {
            s.shading_normal
        };
        if m.kind == material_kind::DIFFUSE {
            if bounces >= 1 {
                store_indirect(
                    p,
                    gbuffer,
                    &s.position,
                    s.geometric_normal,
                    dir,
                    hit.t,
                    flux,
                    store,
                    c,
                );
            }
            if bounces >= p.max_bounces {
                c.bump(counter::BOUNCE_LIMIT);
                return;
            }
            let xi = random_f32(p.seed, index, segment, 2);
            match russian_roulette(flux, Vec3::from_slice(&m.color[..3]), xi) {
                Some(f) => flux = f,
                None => {
                    c.bump(counter::NEGLIGIBLE);
                    return;
                }
            }
            let u = Vec2::new(
                random_f32(p.seed, index, segment, 0),
                random_f32(p.seed, index, segment, 1),
            );
            dir = cosine_hemisphere(u, facing);
            bounces += 1;
        } else if m.kind == material_kind::MIRROR {
            flux *= Vec3::from_slice(&m.color[..3]);
            dir = reflect(dir, facing).normalize();
        } else {
            let mut ior = m.ior;
            if m.cauchy_b != 0.0 {
                let ch = *channel.get_or_insert_with(|| {
                    // first dispersive surface: keep one channel, x3 (expectation kept)
                    let ch = ((random_f32(p.seed, index, segment, 4) * 3.0) as usize).min(2);
                    let mut one = [0.0; 3];
                    one[ch] = flux[ch] * 3.0;
                    flux = Vec3::from(one);
                    ch
                });
                ior = cauchy_ior(m.ior, m.cauchy_b, CHANNEL_WAVELENGTH_UM[ch]);
            }
            dir = dielectric_scatter(
                dir,
                s.shading_normal,
                entering,
                ior,
                random_f32(p.seed, index, segment, 3),
                p.fresnel_model,
            )
            .direction;
        }
        if !(flux.max_element() > 0.0) {
            c.bump(counter::NEGLIGIBLE);
            return;
        }
        let side = if dir.dot(s.geometric_normal) > 0.0 {
            s.geometric_normal
        } else {
            -s.geometric_normal
        };
        origin = offset_ray_origin(s.position, side);
    }
    c.bump(counter::BOUNCE_LIMIT);
}

/// Stores a photon at a diffuse hit if the camera sees its side and it projects into the
/// view (`trace_indirect`'s culling), counting it.
#[allow(clippy::too_many_arguments)]
fn store_indirect(
    p: &IndirectTraceParams,
    gbuffer: &GBufferView,
    position: &Vec3,
    geometric_normal: Vec3,
    dir: Vec3,
    ray_length: f32,
    flux: Vec3,
    store: &mut impl FnMut([u32; 8], u32),
    c: &mut Counters,
) {
    let n = if geometric_normal.dot(dir) > 0.0 {
        -geometric_normal
    } else {
        geometric_normal
    };
    if (Vec3::from(p.camera.position) - *position).dot(n) <= 0.0 {
        c.bump(counter::DEPTH_MISMATCH);
        return;
    }
    let Some((px, py, z)) = project_to_pixel(&p.camera, *position) else {
        c.bump(counter::OFF_SCREEN);
        return;
    };
    let g = gbuffer.load_gbuffer((py * p.camera.width + px) as usize);
    if g.flags & gbuffer_flags::RECEIVER == 0
        || off_surface(
            z,
            *position,
            Vec3::from(g.position),
            Vec3::from(g.normal),
            g.depth,
            VISIBLE_TOLERANCE,
        )
    {
        c.bump(counter::DEPTH_MISMATCH);
        return;
    }
    let tile = screen_tile(px, py, p.camera.width, p.tile_size);
    let words: [u32; 8] = if p.store == gi_store::FLOAT {
        bytemuck::cast(Photon {
            position: position.to_array(),
            hit_distance: ray_length,
            flux: flux.to_array(),
            direction: pack_unit_vector(dir),
        })
    } else {
        let power = pack_rgb9e5(flux / p.power_scale);
        if power & 0x07FF_FFFF == 0 {
            c.bump(counter::UNDERFLOW);
        }
        bytemuck::cast(GiPhoton {
            position: position.to_array(),
            power,
            normal: pack_unit_vector(n),
            direction: pack_unit_vector(dir),
            ray_length,
            tile,
        })
    };
    let stored = Photon {
        flux: flux.to_array(),
        ..Default::default()
    };
    super::trace_photons::count_stored(&stored, p.flux_quantum, c);
    store(words, tile);
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
    let rect = splat_screen_rect(&p.camera, pos, &kernel, (px, py), reach.min(p.max_splat_px));
    Some(SplatSetup {
        irradiance: splat_irradiance(power, &kernel),
        ellipsoid: kernel,
        centre: pos,
        normal: n,
        to_light,
        rect,
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
            splat_pixel(p, g, &s, (qy * w + qx) as u32, maps, c);
        }
    }
}

/// `shading_normal_correction` (003 Eq. 20): per receiver pixel with splats, the input
/// times `shading_normal_factor(w_i, n_s, n_g, s_max, eps)` with `w_i` the direction
/// map's mean light direction; other pixels keep the input.
pub fn shading_normal_correction(
    p: &CorrectionParams,
    g: GBufferView,
    directions: PhotonMapView,
    input: &[[f32; 4]],
) -> Vec<[f32; 4]> {
    (0..(p.width as usize * p.height as usize))
        .into_par_iter()
        .map(|i| {
            let v = input[i];
            let t = g.load_gbuffer(i);
            let d = directions.load(i);
            let w = join_u64_f32(d.hit_distance[0], d.hit_distance[1]);
            let (n_s, n_g) = (Vec3::from(t.normal), unpack_unit_vector(t.geometric_normal));
            if t.flags & gbuffer_flags::RECEIVER == 0
                || !(w > 0.0)
                || !shading_normal_departs(n_s, n_g)
            {
                return v;
            }
            let sums = Vec3::new(
                join_u64_f32(d.flux[0][0], d.flux[0][1]),
                join_u64_f32(d.flux[1][0], d.flux[1][1]),
                join_u64_f32(d.flux[2][0], d.flux[2][1]),
            );
            let w_i = mean_light_direction(sums, w);
            if w_i == Vec3::ZERO {
                return v;
            }
            let f = shading_normal_factor(w_i, n_s, n_g, p.max_stretch, p.epsilon);
            [v[0] * f, v[1] * f, v[2] * f, v[3]]
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use caustica_core::device::layout::{
        camera_ray, gbuffer_to_planes, GpuCamera, DEPOSIT_PLANES, DEPOSIT_PLANE_WORDS,
    };
    use std::sync::atomic::AtomicU64;

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

    /// The warped RSM photons are unbiased. Over 64 frame seeds, the
    /// mean flux the photons of each 4x4 block of two 16x16 faces carry equals that of
    /// uniform RSM sampling (texel uniformly at random, flux times the texel count), and
    /// both equal the block's leaving flux. Coloured, uneven texel fluxes (importance is
    /// the luminance, not each channel) and empty texels. Tolerance: a block's relative
    /// standard error over 64 x 2048 samples is below 2% for both estimators (the warp's
    /// is far smaller: its photons carry nearly equal luminance); 6% is three of them, on
    /// blocks holding at least 1% of the light. A pdf off by a power of the probability
    /// fails it by a factor of 20.
    #[test]
    fn warped_rsm_photons_are_unbiased_like_uniform_sampling() {
        let side = 16u32;
        let faces = 2u32;
        let n = (side * side) as usize;
        let mut texels = vec![RsmTexel::default(); faces as usize * n];
        let mut pyramid = vec![0.0f32; faces as usize * pyramid_len(side) as usize];
        for f in 0..faces as usize {
            for i in 0..n {
                let (x, y) = ((i % 16) as f32, (i / 16) as f32);
                let r = |k: u32| random_f32(5, (f * n + i) as u32, 0, k);
                let empty = r(3) < 0.2;
                let flux = if empty {
                    Vec3::ZERO
                } else {
                    Vec3::new(r(0), 0.5 * r(1), 2.0 * r(2)) * (1.0 + 4.0 * x / 16.0)
                };
                texels[f * n + i] = RsmTexel {
                    position: [100.0 * f as f32 + x + 0.5, y + 0.5, 0.0],
                    normal: pack_unit_vector(Vec3::Z),
                    flux: flux.to_array(),
                    kind: if empty {
                        rsm_texel_kind::NONE
                    } else {
                        rsm_texel_kind::DIFFUSE
                    },
                };
                pyramid[f * pyramid_len(side) as usize + i] = luminance(flux);
            }
        }
        for level in 1..caustica_core::math::rsm::level_count(side) {
            let p = RsmParams {
                side,
                level,
                face: faces - 1,
                ..Default::default()
            };
            rsm_level(&p, &mut pyramid);
        }
        let light = GpuLight::default();
        let block = |x: f32, y: f32, f: usize| f * 16 + (y as usize / 4) * 4 + x as usize / 4;
        let mut exact = [[0.0f64; 3]; 32];
        for f in 0..faces as usize {
            for i in 0..n {
                let t = &texels[f * n + i];
                let e = &mut exact[block((i % 16) as f32, (i / 16) as f32, f)];
                for (acc, v) in e.iter_mut().zip(t.flux) {
                    *acc += v as f64;
                }
            }
        }
        let (seeds, samples) = (64u32, 2048u32);
        let mut warped = [[0.0f64; 3]; 32];
        let mut uniform = [[0.0f64; 3]; 32];
        for seed in 0..seeds {
            let p = RsmParams {
                side,
                face: 0,
                face_count: faces,
                sample_count: samples,
                seed,
                ..Default::default()
            };
            for ph in sample_rsm(&p, &light, &texels, &pyramid) {
                if ph.flux == [0.0; 3] {
                    continue;
                }
                let f = (ph.origin[0] / 100.0) as usize;
                let b = block(ph.origin[0] - 100.0 * f as f32, ph.origin[1], f);
                for (acc, v) in warped[b].iter_mut().zip(ph.flux) {
                    *acc += v as f64 / seeds as f64;
                }
            }
            for k in 0..samples {
                let t =
                    (caustica_core::math::rng::random_u32(seed, k, 9, 0) as usize) % texels.len();
                let (f, i) = (t / n, t % n);
                let u = &mut uniform[block((i % 16) as f32, (i / 16) as f32, f)];
                for (acc, v) in u.iter_mut().zip(texels[t].flux) {
                    *acc += v as f64 * texels.len() as f64 / samples as f64 / seeds as f64;
                }
            }
        }
        let total: f64 = exact.iter().flatten().sum();
        let warped_total: f64 = warped.iter().flatten().sum();
        assert!(
            (warped_total / total - 1.0).abs() < 1e-3,
            "{warped_total} vs {total}"
        );
        for b in 0..32 {
            for c in 0..3 {
                let e = exact[b][c];
                if e < 0.01 * total / 3.0 {
                    continue;
                }
                let (w, u) = (warped[b][c], uniform[b][c]);
                assert!(
                    (w / e - 1.0).abs() < 0.06 && (u / e - 1.0).abs() < 0.06,
                    "block {b} channel {c}: warped {w}, uniform {u}, exact {e}"
                );
            }
        }
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
            _pad: [0; 2],
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
