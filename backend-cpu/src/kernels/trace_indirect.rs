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
    IndirectPath, IndirectTraceParams, Photon, RsmPhoton,
};
use caustica_core::kernels::{TraceIndirect, WaveKeys, VISIBLE_TOLERANCE};
use caustica_core::math::geometry::offset_ray_origin;
use caustica_core::math::gi_photon::{gi_store, screen_tile};
use caustica_core::math::optics::{beer_lambert, dielectric_scatter, dispersive_ior, reflect};
use caustica_core::math::path_sort::{path_sort_key, PathKey};
#[cfg(feature = "traversal-stats")]
use caustica_core::math::path_sort::PATH_SORT_BUCKETS;
use caustica_core::math::packing::{pack_rgb9e5, pack_unit_vector, unpack_unit_vector};
use caustica_core::math::rng::random_f32;
use caustica_core::math::rsm::{
    chunk_photons, coherent_sample_order, cosine_hemisphere, russian_roulette,
};
use caustica_core::math::spectrum::disperse;
use glam::{Vec2, Vec3};
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, Ordering};

/// The lanes of a persistent `trace_indirect` launch that the traversal statistics model:
/// an H200's 132 multiprocessors, each with four sub-partitions of 16,384 registers that
/// hold six warps at the OpenCL port's 80 registers a thread (its register cap), so 24
/// warps of 32 lanes a multiprocessor.
const PERSISTENT_LANES: u32 = 132 * 24 * 32;

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
        waves,
    } = k;
    let rsm = cpu
        .get(rsm_photons.id)?
        .as_slice::<RsmPhoton>(rsm_photons.len)?;
    let g = cpu.gbuffer(gbuffer)?;
    reserve_temporary::<[u32; 8]>(params.count as u64, "an indirect photon batch")?;
    let queued: Vec<IndirectPath>;
    let source = match waves {
        Some(w) if params.segment_first > 0 => {
            let live = cpu
                .get(w.path_counts.id)?
                .as_slice::<u32>(w.path_counts.len)?[params.segment_first as usize]
                .min(w.paths_out.len) as usize;
            let paths = cpu
                .get(w.paths_in.id)?
                .as_slice::<IndirectPath>(w.paths_in.len)?;
            queued = match w.keys.filter(|_| params.queue_order != 0) {
                // sorted: thread t continues path order[t] (sort_indirect_paths'); an
                // entry past the queue, which no sort writes, is no path, as on the GPU
                Some(keys) => {
                    let capacity = (w.paths_out.len as usize).min(paths.len());
                    cpu.get(keys.order.id)?
                        .as_slice::<u32>(keys.order.len)?[..live]
                        .iter()
                        .filter_map(|&s| paths[..capacity].get(s as usize).copied())
                        .collect()
                }
                None => paths[..live].to_vec(),
            };
            IndirectSource::Queue(&queued)
        }
        _ => IndirectSource::Rsm(rsm),
    };
    let r = trace_indirect(
        &cpu.view(scene)?,
        params,
        source,
        &g,
        tile_counts.len as usize,
    );
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
    if let (Some(w), false) = (waves, r.queued.is_empty()) {
        // the paths still going, appended from the queue's count (a slot past the queue's
        // end is not written, as on the GPU)
        let end = params.segment_end as usize;
        let counts = cpu
            .get_mut(w.path_counts.id)?
            .as_mut_slice::<u32>(w.path_counts.len)?;
        let first = counts[end] as usize;
        counts[end] = counts[end].wrapping_add(r.queued.len() as u32);
        let out = cpu
            .get_mut(w.paths_out.id)?
            .as_mut_slice::<IndirectPath>(w.paths_out.len)?;
        for (slot, path) in out.iter_mut().skip(first).zip(&r.queued) {
            *slot = *path;
        }
        if let Some(keys) = w.keys.filter(|_| params.queue_keys != 0) {
            queue_keys(cpu, params, keys, first, &r.queued)?;
        }
    }
    Ok(())
}

/// `queue_keys`: the sort key of each path queued from slot `first` on (below the
/// queue's end) and its rank among the queue's paths of that key (`buckets` counting
/// them, wrapping as the GPU's atomics), in queue order.
fn queue_keys(
    cpu: &mut CpuBackend,
    p: &IndirectTraceParams,
    keys: WaveKeys,
    first: usize,
    queued: &[IndirectPath],
) -> Result<(), BackendError> {
    let (lo, scale) = (Vec3::from(p.key_origin_min), Vec3::from(p.key_origin_scale));
    // the slots below the queue's end (`path_keys` is as long as the queue)
    let stored = queued.len().min((keys.path_keys.len as usize).saturating_sub(first));
    if stored == 0 {
        return Ok(());
    }
    let key_of: Vec<u32> = queued[..stored]
        .iter()
        .map(|q| path_sort_key(Vec3::from(q.origin), Vec3::from(q.direction), lo, scale))
        .collect();
    let buckets = cpu
        .get_mut(keys.buckets.id)?
        .as_mut_slice::<u32>(keys.buckets.len)?;
    let ranked: Vec<PathKey> = key_of
        .iter()
        .map(|&k| {
            let b = &mut buckets[k as usize];
            let rank = *b;
            *b = b.wrapping_add(1);
            [k, rank]
        })
        .collect();
    cpu.get_mut(keys.path_keys.id)?
        .as_mut_slice::<PathKey>(keys.path_keys.len)?[first..first + stored]
        .copy_from_slice(&ranked);
    #[cfg(feature = "traversal-stats")]
    crate::traversal_stats::sort_keys(p.segment_end, &key_of, PATH_SORT_BUCKETS as usize);
    Ok(())
}

/// Where a launch's paths come from.
#[derive(Clone, Copy)]
pub enum IndirectSource<'a> {
    /// The RSM photons `p.first .. p.first + p.count`, the launch's chunk of them
    /// (segment 0).
    Rsm(&'a [RsmPhoton]),
    /// The paths an earlier wave queued (thread `t` continues path `t`).
    Queue(&'a [IndirectPath]),
}

/// Photons `trace_indirect` stored (32-byte words, in photon order), the per-tile counts
/// it adds, its counters and the paths it queued.
pub struct IndirectResult {
    /// Stored photons (`GiPhoton` or `Photon` bytes as `p.store` says).
    pub photons: Vec<[u32; 8]>,
    /// Stored photons per screen tile.
    pub tile_counts: Vec<u32>,
    /// The launch's counters.
    pub counters: Counters,
    /// The paths still going after segment `p.segment_end - 1` (none when it is the
    /// last), in thread order.
    pub queued: Vec<IndirectPath>,
}

/// `trace_indirect` over segments `p.segment_first .. p.segment_end` of `source`'s paths.
pub fn trace_indirect(
    scene: &SceneView,
    p: &IndirectTraceParams,
    source: IndirectSource,
    gbuffer: &GBufferView,
    tiles: usize,
) -> IndirectResult {
    let tile_counts: Vec<AtomicU32> = (0..tiles).map(|_| AtomicU32::new(0)).collect();
    let threads = match source {
        IndirectSource::Rsm(_) => chunk_photons(p.count, p.chunk_first, p.chunk_size),
        IndirectSource::Queue(q) => q.len() as u32,
    };
    let parts: Vec<(Vec<[u32; 8]>, Counters, Vec<IndirectPath>)> = (0..threads.div_ceil(256))
        .into_par_iter()
        .map(|c| {
            let mut out = Vec::new();
            let mut queued = Vec::new();
            let mut counters = Counters::default();
            for i in c * 256..((c + 1) * 256).min(threads) {
                let path = match source {
                    IndirectSource::Rsm(rsm) => {
                        let index = p.first + p.chunk_first + i;
                        indirect_path_from_rsm(&rsm[index as usize], index, &mut counters)
                    }
                    IndirectSource::Queue(q) => Some(q[i as usize]),
                };
                let Some(mut path) = path else { continue };
                crate::traversal_stats::photon_begins(i);
                let going = trace_indirect_segments(
                    scene,
                    p,
                    &mut path,
                    gbuffer,
                    &mut |ph, tile| {
                        out.push(ph);
                        tile_counts[tile as usize].fetch_add(1, Ordering::Relaxed);
                    },
                    &mut counters,
                );
                crate::traversal_stats::photon_ends();
                if going {
                    if p.segment_end >= p.max_segments {
                        counters.bump(counter::BOUNCE_LIMIT);
                    } else {
                        queued.push(path);
                    }
                }
            }
            (out, counters, queued)
        })
        .collect();
    match source {
        // the GPU ports' thread t traces photon first + coherent_sample_order(t)
        IndirectSource::Rsm(_) if p.segment_end >= p.max_segments => {
            crate::traversal_stats::report("trace_indirect", threads, Some(PERSISTENT_LANES), |t| {
                coherent_sample_order(t, threads)
            })
        }
        IndirectSource::Rsm(_) => {
            crate::traversal_stats::report("trace_indirect wave 0", threads, Some(PERSISTENT_LANES), |t| {
                coherent_sample_order(t, threads)
            })
        }
        // (the GPU's queue is in arrival order; the CPU's in photon order)
        IndirectSource::Queue(_) => crate::traversal_stats::report(
            &format!("trace_indirect wave {}", p.segment_first),
            threads,
            Some(PERSISTENT_LANES),
            |t| t,
        ),
    }
    let mut photons = Vec::new();
    let mut queued = Vec::new();
    let mut counters = Counters::default();
    for (ph, c, q) in parts {
        photons.extend(ph);
        queued.extend(q);
        counters = counters.merge(c);
    }
    IndirectResult {
        photons,
        tile_counts: tile_counts.into_iter().map(|a| a.into_inner()).collect(),
        counters,
        queued,
    }
}

/// The path of RSM photon `index` before its first segment; `None` (counted negligible)
/// for a photon without flux.
pub fn indirect_path_from_rsm(r: &RsmPhoton, index: u32, c: &mut Counters) -> Option<IndirectPath> {
    if !(Vec3::from(r.flux).max_element() > 0.0) {
        c.bump(counter::NEGLIGIBLE);
        return None;
    }
    Some(IndirectPath {
        origin: r.origin,
        index,
        direction: unpack_unit_vector(r.direction).to_array(),
        bounces: r.bounces,
        flux: r.flux,
        wavelength: 0.0,
    })
}

/// Segments `p.segment_first .. p.segment_end` of `path` (the single launch: all of
/// them): calls `store(photon words, tile)` for every stored photon, counts into `c`,
/// and leaves in `path` what its next segment needs. Returns whether the path goes on
/// after the last of them (its end counted otherwise).
pub fn trace_indirect_segments(
    scene: &SceneView,
    p: &IndirectTraceParams,
    path: &mut IndirectPath,
    gbuffer: &GBufferView,
    store: &mut impl FnMut([u32; 8], u32),
    c: &mut Counters,
) -> bool {
    let index = path.index;
    let mut flux = Vec3::from(path.flux);
    let mut origin = Vec3::from(path.origin);
    let mut dir = Vec3::from(path.direction);
    let mut bounces = path.bounces;
    // the photon's wavelength (micrometres) from its first dispersive surface on (0: none
    // yet)
    let mut wavelength = path.wavelength;
    for segment in p.segment_first..p.segment_end {
        c.words[counter::RAYS] += 1;
        let Some(hit) = scene.closest_hit(origin, dir, f32::INFINITY) else {
            c.bump(counter::ESCAPED);
            return false;
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
                return false;
            }
            let xi = random_f32(p.seed, index, segment, 2);
            match russian_roulette(flux, Vec3::from_slice(&m.color[..3]), xi) {
                Some(f) => flux = f,
                None => {
                    c.bump(counter::NEGLIGIBLE);
                    return false;
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
                if wavelength == 0.0 {
                    // first dispersive surface: a wavelength and its colour (expectation
                    // kept; core's spectrum::disperse)
                    let xi = random_f32(p.seed, index, segment, 4);
                    let (wl, f) = disperse(flux, p.dispersion_mode, p.seed, index, xi);
                    flux = f;
                    wavelength = wl;
                }
                ior = dispersive_ior(m.ior, m.dispersion, m.ior_model, wavelength);
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
            return false;
        }
        let side = if dir.dot(s.geometric_normal) > 0.0 {
            s.geometric_normal
        } else {
            -s.geometric_normal
        };
        origin = offset_ray_origin(s.position, side);
    }
    *path = IndirectPath {
        origin: origin.to_array(),
        index,
        direction: dir.to_array(),
        bounces,
        flux: flux.to_array(),
        wavelength,
    };
    true
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
