//! `trace_indirect` (PhotonGi, Smal 2019, section 24.2.2): the RSM photons' diffuse bounces,
//! stored where the camera sees them. Method, units and sources in
//! `caustica_core::math::gi_photon` and the kernel's declaration.

use super::Counters;
use crate::recording::reserve_temporary;
use crate::traversal::SceneView;
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    counter, gbuffer_flags, material_kind, off_surface, project_to_pixel, GBufferView, GiPhoton,
    IndirectTraceParams, Photon, RsmPhoton,
};
use caustica_core::kernels::{TraceIndirect, VISIBLE_TOLERANCE};
use caustica_core::math::geometry::offset_ray_origin;
use caustica_core::math::gi_photon::{gi_store, screen_tile};
use caustica_core::math::optics::{beer_lambert, dielectric_scatter, dispersive_ior, reflect};
use caustica_core::math::spectrum::disperse;
use caustica_core::math::packing::{pack_rgb9e5, pack_unit_vector, unpack_unit_vector};
use caustica_core::math::rng::random_f32;
use caustica_core::math::rsm::{coherent_sample_order, cosine_hemisphere, russian_roulette};
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// Runs `trace_indirect` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &TraceIndirect) -> Result<(), BackendError> {
    let TraceIndirect {
        scene,
        params,
        rsm_photons,
        photons,
        photon_count,
        tile_counts,
        counters,
        gbuffer,
        // the CPU has no launch grid: the kernel bounds itself by its count
        dispatch: _,
    } = k;
    let rsm = cpu
        .get(rsm_photons.id)?
        .as_slice::<RsmPhoton>(rsm_photons.len)?;
    let g = cpu.gbuffer(gbuffer)?;
    reserve_temporary::<[u32; 8]>(params.count as u64, "an indirect photon batch")?;
    let r = trace_indirect(&cpu.view(scene)?, params, rsm, &g, tile_counts.len as usize);
    let start = cpu.get(photon_count.id)?.as_slice::<u32>(1)?[0] as usize;
    if start + r.photons.len() > photons.len as usize {
        return Err(BackendError::BadArgument(format!(
            "indirect photon buffer holds {} photons, {} stored",
            photons.len,
            start + r.photons.len()
        )));
    }
    cpu.get_mut(photons.id)?
        .as_mut_slice::<[u32; 8]>(photons.len)?[start..start + r.photons.len()]
        .copy_from_slice(&r.photons);
    cpu.get_mut(photon_count.id)?.as_mut_slice::<u32>(1)?[0] = (start + r.photons.len()) as u32;
    for (t, n) in cpu
        .get_mut(tile_counts.id)?
        .as_mut_slice::<u32>(tile_counts.len)?
        .iter_mut()
        .zip(&r.tile_counts)
    {
        *t = t.wrapping_add(*n);
    }
    r.counters
        .add_to(cpu.get_mut(counters.id)?.as_mut_slice(counters.len)?);
    Ok(())
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
    // the photon's wavelength (micrometres) from its first dispersive surface on
    let mut wavelength: Option<f32> = None;
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
            if m.dispersion != 0.0 {
                let wl = *wavelength.get_or_insert_with(|| {
                    // first dispersive surface: a wavelength and its colour (expectation
                    // kept; core's spectrum::disperse)
                    let xi = random_f32(p.seed, index, segment, 4);
                    let (wl, f) = disperse(flux, p.dispersion_mode, p.seed, index, xi);
                    flux = f;
                    wl
                });
                ior = dispersive_ior(m.ior, m.dispersion, m.ior_model, wl);
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
