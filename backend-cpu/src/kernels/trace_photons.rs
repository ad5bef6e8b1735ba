//! `trace_photons` (Kim 2019, sections 30.3.1.1-2): emits photon
//! `tiled_photon_index(first + i)` of the light's stratified grid (tile order: core's
//! `math::sampling`), traces it through mirrors and dielectrics and stores it where it first
//! meets a diffuse surface, provided it met at least one specular surface on the way.
//!
//! Per interaction: mirrors scale power by their reflectance; dielectrics reflect with
//! probability equal to the exact Fresnel reflectance and refract otherwise (power kept),
//! total internal reflection always reflects; Beer-Lambert attenuates power over segments
//! travelled inside a dielectric; at its first dispersive dielectric a photon takes a
//! wavelength and the colour of its power (core's `math::spectrum::disperse`: spectral, a
//! stratified wavelength with its CIE-matched sRGB weight, or the three-way split, one
//! channel x3) and refracts from then on with that wavelength's index (`dispersive_ior`:
//! Cauchy or the Abbe model).
//! Paths end at a diffuse surface, on escape, at `max_bounces` segments, or when the
//! largest channel drops below `min_relative_power` of the emitted flux.
//!
//! Emission: a cone (equal-area warp), a rectangle of parallel rays, or a light view plane
//! (Vanderstichelen 2021: the pinhole ray through a jittered point of the photon's texel, flux `I x`
//! the texel's solid angle). Store: world space (Sspm) or, with the variant's
//! `surface_store`, the hit's uv and triangle (CausticMap's atlas).
//!
//! Random dimensions: bounce 0 dims 0, 1 = grid jitter; bounce b dim 2 = Fresnel choice,
//! dim 3 = dispersion channel (three bands); the spectral wavelength is the photon's point
//! of the wavelength sequence (`spectral_sample(seed, index)`), no random dimension.
//!
//! Variants (compiled, not branched): the const generics `DIELECTRIC`, `DISPERSION` and `ABSORPTION`
//! compile the dielectric, Cauchy-dispersion and Beer-Lambert code in or out, as the
//! shader ports do with override constants, specialization constants and `-D` defines;
//! [`trace_photons`] picks the monomorphisation of core's [`TraceVariant`]. A variant
//! without a feature is only run on scenes without it (the frame plan's guarantee).

use super::{deposit_screen, Counters};
use crate::recording::reserve_temporary;
use crate::traversal::{Hit, SceneView};
use crate::{atlas_deposit, CpuBackend};
use caustica_core::backend::BackendError;
use caustica_core::device::device_scene::light_spot_falloff;
use caustica_core::device::layout::{
    counter, emission_kind, light_kind, material_kind, photon_store, Photon, SurfacePoint,
    TraceParams, MAX_SPLIT_BRANCHES,
};
use caustica_core::kernels::{AtlasDeposit, FusedDeposit, TracePhotons, TraceVariant};
use caustica_core::math::fixed_point::quantize;
use caustica_core::math::geometry::{offset_ray_origin, ray_meets_caster_spheres};
use caustica_core::math::optics::{
    beer_lambert, dielectric_scatter, dispersive_ior, fresnel_reflectance, reflect, refract,
};
use caustica_core::math::spectrum::{disperse, split_lane};
use caustica_core::math::packing::pack_unit_vector;
use caustica_core::math::photon_clusters::{
    cluster_photon_index, entry_cluster, live_clusters, photon_met_caster, NO_TRIANGLE,
};
use caustica_core::math::rng::{random_f32, stratum_jitter};
use caustica_core::math::sampling::{
    stratified_cell, tiled_photon_index, to_world, uniform_cone, view_plane_direction,
    view_plane_texel_weight,
};
use glam::{Vec2, Vec3};
use caustica_core::math::map_gather::CENTROID_WORDS;
use rayon::prelude::*;

/// Runs `trace_photons` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &TracePhotons) -> Result<(), BackendError> {
    let TracePhotons {
        scene,
        variant,
        params,
        photons,
        photon_count,
        counters,
        clusters,
        deposit,
    } = k;
    reserve_temporary::<Photon>(params.count as u64, "a photon batch")?;
    let result = match clusters.filter(|_| variant.adaptive) {
        Some(c) => {
            let list = cpu.get(c.list.id)?.as_slice::<u32>(c.list.len)?.to_vec();
            // the batch's live clusters: photon_count[0] is the list's length
            let length = cpu.get(photon_count.id)?.as_slice::<u32>(1)?[0];
            let live = live_clusters(length, params.first, params.count / 4);
            let p = TraceParams {
                count: 4 * live,
                ..*params
            };
            trace_cluster_slots(&cpu.view(scene)?, &p, *variant, &list)
        }
        None => trace_photons(&cpu.view(scene)?, params, *variant),
    };
    let fused = deposit.filter(|_| variant.fused_deposit);
    // the fused pass into the screen: the stored photons as deposit_screen
    // adds them
    let screen = match &fused {
        Some(FusedDeposit::Screen(d)) => {
            let g = cpu.gbuffer(&d.gbuffer)?;
            let atomics = cpu.map_atomics(&d.photon_map)?;
            Some(deposit_screen::deposit_screen(
                &d.params,
                g,
                &result.photons,
                atomics,
            ))
        }
        _ => None,
    };
    let words = cpu.get_mut(counters.id)?.as_mut_slice(counters.len)?;
    result.counters.add_to(words);
    if let Some(c) = screen {
        c.add_to(words);
        return Ok(());
    }
    if let Some(FusedDeposit::Atlas(d)) = fused {
        // the fused pass into the atlas, as atlas_deposit::deposit_atlas adds them
        return deposit_atlas_photons(cpu, &d, &result.photons, *counters);
    }
    if result.photons.len() > photons.len as usize {
        return Err(BackendError::BadArgument(format!(
            "photon buffer holds {} photons, batch stored {}",
            photons.len,
            result.photons.len()
        )));
    }
    cpu.get_mut(photons.id)?.write_prefix(&result.photons)?;
    if !variant.adaptive {
        cpu.get_mut(photon_count.id)?.as_mut_slice::<u32>(1)?[0] = result.photons.len() as u32;
    }
    Ok(())
}

/// The atlas deposit of texture-space photons `ph` into atlas `d`: the fixed-point sums,
/// the reach bits of their triangles and the deposit's counters (added to
/// `counters`). The fused `fused_deposit` trace's second half.
fn deposit_atlas_photons(
    cpu: &mut CpuBackend,
    d: &AtlasDeposit,
    ph: &[Photon],
    counters: caustica_core::device::handle::Buf<u32>,
) -> Result<(), BackendError> {
    let c = {
        let tt = cpu
            .get(d.triangle_tiles.id)?
            .as_slice(d.triangle_tiles.len)?;
        let tl = cpu.get(d.tiles.id)?.as_slice(d.tiles.len)?;
        let [a, b, c] = d.sums.planes;
        let atomics = [
            cpu.get(a.id)?.as_atomic_u64(a.bytes())?,
            cpu.get(b.id)?.as_atomic_u64(b.bytes())?,
            cpu.get(c.id)?.as_atomic_u64(c.bytes())?,
        ];
        let texels = d.params.width as u64 * d.params.height as u64;
        let centroids = cpu
            .get(d.centroids.id)?
            .as_atomic_u32(4 * CENTROID_WORDS as u64 * texels)?;
        atlas_deposit::deposit_atlas(&d.params, tt, tl, ph, atomics, centroids)
    };
    let reach = cpu
        .get_mut(d.triangle_reach.id)?
        .as_mut_slice::<u32>(d.triangle_reach.len)?;
    atlas_deposit::mark_triangle_reach(ph, reach);
    c.add_to(cpu.get_mut(counters.id)?.as_mut_slice(counters.len)?);
    Ok(())
}

/// Stored photons in photon order, plus the batch's counters.
pub struct TraceResult {
    /// Stored photons, in photon order.
    pub photons: Vec<Photon>,
    /// The batch's photon accounting.
    pub counters: Counters,
}

/// How one photon path ended.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PathEnd {
    /// Stored on a diffuse surface after at least one specular interaction.
    Stored(Photon),
    /// Reached a diffuse surface without a specular interaction (direct light).
    NoSpecular,
    /// Left the scene.
    Escaped,
    /// Power fell below the negligible threshold (or was zero at emission).
    Negligible,
    /// Still travelling after `max_bounces` segments.
    BounceLimit,
}

/// Traces the batch with the monomorphised variant `variant`.
pub fn trace_photons(scene: &SceneView, p: &TraceParams, variant: TraceVariant) -> TraceResult {
    let s = if variant.surface_store {
        photon_store::SURFACE
    } else {
        photon_store::WORLD
    };
    if variant.fresnel_split {
        return match (variant.dispersion, variant.absorption) {
            (false, false) => split_batch::<false, false>(scene, p, s),
            (false, true) => split_batch::<false, true>(scene, p, s),
            (true, false) => split_batch::<true, false>(scene, p, s),
            (true, true) => split_batch::<true, true>(scene, p, s),
        };
    }
    match (variant.dielectric, variant.dispersion, variant.absorption) {
        (false, false, false) => trace_batch::<false, false, false>(scene, p, s),
        (false, false, true) => trace_batch::<false, false, true>(scene, p, s),
        (false, true, false) => trace_batch::<false, true, false>(scene, p, s),
        (false, true, true) => trace_batch::<false, true, true>(scene, p, s),
        (true, false, false) => trace_batch::<true, false, false>(scene, p, s),
        (true, false, true) => trace_batch::<true, false, true>(scene, p, s),
        (true, true, false) => trace_batch::<true, true, false>(scene, p, s),
        (true, true, true) => trace_batch::<true, true, true>(scene, p, s),
    }
}

/// Counts one stored photon: `STORED` and its flux in quanta (`STORED_FLUX`).
pub fn count_stored(ph: &Photon, flux_quantum: f32, counters: &mut Counters) {
    counters.bump(counter::STORED);
    for ch in 0..3 {
        counters.words[counter::STORED_FLUX + 2 * ch] +=
            quantize(ph.flux[ch], flux_quantum).units as u64;
    }
}

/// Adds one path end to the batch's photons and counters.
fn count_end(end: PathEnd, p: &TraceParams, photons: &mut Vec<Photon>, counters: &mut Counters) {
    match end {
        PathEnd::Stored(ph) => {
            count_stored(&ph, p.flux_quantum, counters);
            photons.push(ph);
        }
        PathEnd::NoSpecular => counters.bump(counter::NO_SPECULAR),
        PathEnd::Escaped => counters.bump(counter::ESCAPED),
        PathEnd::Negligible => counters.bump(counter::NEGLIGIBLE),
        PathEnd::BounceLimit => counters.bump(counter::BOUNCE_LIMIT),
    }
}

/// Traces photons `first .. first + count` of the batch, in tile order
/// ([`tiled_photon_index`]), in parallel chunks of `chunk`:
/// `photon(index, on_end, counters)` traces one emitted photon, calling `on_end` for each
/// path end (one, or one per branch of a split) and adding its rays (and splits) to the
/// counters; stored photons come back in photon order.
fn batch(
    p: &TraceParams,
    chunk: u32,
    photon: impl Fn(u32, &mut dyn FnMut(PathEnd), &mut Counters) + Sync,
) -> TraceResult {
    let chunks = p.count.div_ceil(chunk);
    let parts: Vec<(Vec<Photon>, Counters)> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut photons = Vec::new();
            let mut counters = Counters::default();
            for i in c * chunk..((c + 1) * chunk).min(p.count) {
                let mut ends = Counters::default();
                crate::traversal_stats::photon_begins(i);
                photon(
                    tiled_photon_index(p.first + i, p.grid_w, p.grid_h),
                    &mut |end| count_end(end, p, &mut photons, &mut ends),
                    &mut counters,
                );
                crate::traversal_stats::photon_ends();
                counters = counters.merge(ends);
            }
            (photons, counters)
        })
        .collect();
    // thread i traces the i-th photon of the batch here as in the GPU ports
    crate::traversal_stats::report("trace_photons", p.count, None, |i| i);
    let mut photons = Vec::with_capacity(parts.iter().map(|p| p.0.len()).sum());
    let mut counters = Counters::default();
    for (ph, c) in parts {
        photons.extend(ph);
        counters = counters.merge(c);
    }
    TraceResult { photons, counters }
}

/// The batch with the deterministic splits ([`trace_photon_split`]).
fn split_batch<const DISPERSION: bool, const ABSORPTION: bool>(
    scene: &SceneView,
    p: &TraceParams,
    store: u32,
) -> TraceResult {
    batch(p, 1024, |index, on_end, counters| {
        let (rays, splits) =
            trace_photon_split::<DISPERSION, ABSORPTION>(scene, p, index, store, &mut |e| {
                on_end(e)
            });
        counters.words[counter::RAYS] += rays as u64;
        counters.words[counter::SPLITS] += splits as u64;
    })
}

/// A branch of a split photon: where it continues, its flux, the segments traced so far
/// and its wavelength (micrometres; 0 until its first dispersive surface).
#[derive(Clone, Copy, Debug)]
struct Branch {
    origin: Vec3,
    dir: Vec3,
    flux: Vec3,
    bounce: u32,
    wavelength: f32,
}

/// The photon a path stores at surface `s` of `hit` (world or texture space).
fn stored_photon(store: u32, s: &SurfacePoint, hit: &Hit, flux: Vec3, dir: Vec3) -> Photon {
    if store == photon_store::SURFACE {
        Photon {
            position: [s.uv.x, s.uv.y, 0.0],
            hit_distance: hit.t,
            flux: flux.to_array(),
            direction: hit.triangle,
        }
    } else {
        Photon {
            position: s.position.to_array(),
            hit_distance: hit.t,
            flux: flux.to_array(),
            direction: pack_unit_vector(dir),
        }
    }
}

/// One emitted photon with Vanderstichelen 2021's deterministic splits (the variant's `FRESNEL_SPLIT`):
/// at a dielectric both the reflected branch (flux x R, exact Fresnel) and the refracted
/// one (x (1 - R)) go on (total internal reflection: the reflected one with all the flux);
/// at the first dispersive surface three branches go on ([`split_lane`]: three
/// wavelengths stratified over the spectrum with a third of their weighted flux each, or,
/// with three bands, one per colour channel with that channel's flux), each with its
/// wavelength's index, and each then splits at this surface by its own Fresnel.
/// Branches are walked depth first (last pushed, first popped; children pushed reflected
/// first); once `split_budget` branches exist, further interactions make Sspm's stochastic
/// choice instead ([`disperse`]; same random dimensions: bounce b dim 2 Fresnel, dim 3
/// channel), so one photon stores at most `split_budget` photons. Calls `on_end` for every branch's end;
/// returns the ray segments traced and the branches added.
pub fn trace_photon_split<const DISPERSION: bool, const ABSORPTION: bool>(
    scene: &SceneView,
    p: &TraceParams,
    index: u32,
    store: u32,
    on_end: &mut impl FnMut(PathEnd),
) -> (u32, u32) {
    let (origin, dir, flux) = emit_photon(scene, p, index);
    let emitted_max = Vec3::from_slice(&p.photon_flux[..3]).max_element();
    let min_power = p.photon_flux[3] * emitted_max;
    if flux.max_element() <= 0.0 || flux.max_element() < min_power {
        on_end(PathEnd::Negligible);
        return (0, 0);
    }
    if !ray_meets_caster_spheres(origin, dir, &p.caster_spheres, p.caster_sphere_count) {
        // its first segment meets no caster ball, so no caster first (core's
        // device::caster_spheres): no ray traced
        on_end(PathEnd::NoSpecular);
        return (0, 0);
    }
    let budget = p.split_budget.clamp(1, MAX_SPLIT_BRANCHES);
    let mut stack = vec![Branch {
        origin,
        dir,
        flux,
        bounce: 0,
        wavelength: 0.0,
    }];
    let (mut rays, mut branches) = (0u32, 1u32);
    'branch: while let Some(mut b) = stack.pop() {
        loop {
            if b.bounce >= p.max_bounces {
                on_end(PathEnd::BounceLimit);
                continue 'branch;
            }
            rays += 1;
            let Some(hit) = scene.closest_hit(b.origin, b.dir, f32::INFINITY) else {
                on_end(PathEnd::Escaped);
                continue 'branch;
            };
            let (s, m) = scene.surface(&hit);
            let entering = b.dir.dot(s.geometric_normal) < 0.0;
            if ABSORPTION && m.kind == material_kind::DIELECTRIC && !entering {
                b.flux *= beer_lambert(Vec3::from_slice(&m.absorption[..3]), hit.t);
            }
            let bounce = b.bounce;
            b.bounce += 1;
            let facing = if s.shading_normal.dot(b.dir) > 0.0 {
                -s.shading_normal
            } else {
                s.shading_normal
            };
            match m.kind {
                material_kind::DIFFUSE => {
                    on_end(if bounce == 0 {
                        PathEnd::NoSpecular
                    } else {
                        PathEnd::Stored(stored_photon(store, &s, &hit, b.flux, b.dir))
                    });
                    continue 'branch;
                }
                material_kind::MIRROR => {
                    b.flux *= Vec3::from_slice(&m.color[..3]);
                    b.dir = reflect(b.dir, facing).normalize();
                    if b.flux.max_element() < min_power || b.flux.max_element() <= 0.0 {
                        on_end(PathEnd::Negligible);
                        continue 'branch;
                    }
                    let side = if b.dir.dot(s.geometric_normal) > 0.0 {
                        s.geometric_normal
                    } else {
                        -s.geometric_normal
                    };
                    b.origin = offset_ray_origin(s.position, side);
                }
                _ => {
                    // the branches this surface continues: three at the first dispersive
                    // surface (while the budget allows), else this one
                    let mut lanes = [b; 3];
                    let mut n_lanes = 1;
                    if DISPERSION && m.dispersion != 0.0 && b.wavelength == 0.0 {
                        if branches + 2 <= budget {
                            branches += 2;
                            n_lanes = 3;
                            for (k, lane) in lanes.iter_mut().enumerate() {
                                (lane.wavelength, lane.flux) =
                                    split_lane(b.flux, p.dispersion_mode, p.seed, index, k as u32);
                            }
                        } else {
                            let xi = random_f32(p.seed, index, bounce, 3);
                            (lanes[0].wavelength, lanes[0].flux) =
                                disperse(b.flux, p.dispersion_mode, p.seed, index, xi);
                        }
                    }
                    for lane in &lanes[..n_lanes] {
                        let ior = if DISPERSION && m.dispersion != 0.0 && lane.wavelength != 0.0 {
                            dispersive_ior(m.ior, m.dispersion, m.ior_model, lane.wavelength)
                        } else {
                            m.ior
                        };
                        let eta = if entering { 1.0 / ior } else { ior };
                        let f = fresnel_reflectance(-b.dir.dot(facing), eta, p.fresnel_model);
                        let reflected = reflect(b.dir, facing);
                        let mut children = [(reflected, lane.flux); 2];
                        let mut n_children = 1;
                        if let Some(t) = refract(b.dir, facing, eta) {
                            if branches < budget {
                                branches += 1;
                                children = [
                                    (reflected, lane.flux * f),
                                    (t.normalize(), lane.flux * (1.0 - f)),
                                ];
                                n_children = 2;
                            } else if random_f32(p.seed, index, bounce, 2) >= f {
                                children[0] = (t.normalize(), lane.flux);
                            }
                        }
                        for &(dir, flux) in &children[..n_children] {
                            if flux.max_element() < min_power || flux.max_element() <= 0.0 {
                                on_end(PathEnd::Negligible);
                                continue;
                            }
                            let side = if dir.dot(s.geometric_normal) > 0.0 {
                                s.geometric_normal
                            } else {
                                -s.geometric_normal
                            };
                            stack.push(Branch {
                                origin: offset_ray_origin(s.position, side),
                                dir,
                                flux,
                                bounce: b.bounce,
                                wavelength: lane.wavelength,
                            });
                        }
                    }
                    continue 'branch;
                }
            }
        }
    }
    (rays, branches - 1)
}

fn trace_batch<const DIELECTRIC: bool, const DISPERSION: bool, const ABSORPTION: bool>(
    scene: &SceneView,
    p: &TraceParams,
    store: u32,
) -> TraceResult {
    batch(p, 4096, |index, on_end, counters| {
        let (end, rays) = trace_photon_variant::<DIELECTRIC, DISPERSION, ABSORPTION>(
            scene,
            p,
            index,
            store,
            &mut |_, _| {},
        );
        counters.words[counter::RAYS] += rays as u64;
        on_end(end);
    })
}

/// The `ADAPTIVE` variant (Wyman 2009): photon `i` of the batch is photon `i % 4` of cluster
/// `clusters[p.first + i / 4]` of the `p.grid_w` grid
/// ([`cluster_photon_index`]), and goes to slot `i` whether it stored or not
/// (`photon_store`'s adaptive slot: an empty slot has zero flux, `direction` =
/// [`NO_TRIANGLE`] and `position.z` = 1 if the photon met a caster), in texture space
/// with `variant.surface_store` (the atlas target), else in world space (the screen
/// target). With `variant.fused_deposit` the result holds the stored photons alone, in
/// photon order, for the caller to deposit (a level whose every cluster is output).
pub fn trace_cluster_slots(
    scene: &SceneView,
    p: &TraceParams,
    variant: TraceVariant,
    clusters: &[u32],
) -> TraceResult {
    let store = if variant.surface_store {
        photon_store::SURFACE
    } else {
        photon_store::WORLD
    };
    let c = (clusters, store, variant.fused_deposit);
    match (variant.dielectric, variant.dispersion, variant.absorption) {
        (false, false, false) => cluster_batch::<false, false, false>(scene, p, c),
        (false, false, true) => cluster_batch::<false, false, true>(scene, p, c),
        (false, true, false) => cluster_batch::<false, true, false>(scene, p, c),
        (false, true, true) => cluster_batch::<false, true, true>(scene, p, c),
        (true, false, false) => cluster_batch::<true, false, false>(scene, p, c),
        (true, false, true) => cluster_batch::<true, false, true>(scene, p, c),
        (true, true, false) => cluster_batch::<true, true, false>(scene, p, c),
        (true, true, true) => cluster_batch::<true, true, true>(scene, p, c),
    }
}

/// The slot a traced cluster photon leaves (see [`trace_cluster_slots`]; `store` a
/// [`photon_store`] space).
pub fn cluster_slot(end: &PathEnd, rays: u32, store: u32) -> Photon {
    let (code, stored) = match end {
        PathEnd::Stored(ph) => (0, Some(*ph)),
        PathEnd::NoSpecular => (1, None),
        PathEnd::Escaped => (2, None),
        PathEnd::Negligible => (3, None),
        PathEnd::BounceLimit => (4, None),
    };
    match stored {
        Some(mut ph) => {
            if store == photon_store::SURFACE {
                ph.position[2] = 1.0;
            }
            ph
        }
        None => Photon {
            position: [0.0, 0.0, photon_met_caster(code, rays) as u32 as f32],
            direction: NO_TRIANGLE,
            ..Default::default()
        },
    }
}

/// Photons of an adaptive batch traced together: their per-photon results (about 200
/// bytes each with their counters) are held for one chunk at a time.
const CLUSTER_BATCH_CHUNK: u32 = 1 << 18;

fn cluster_batch<const DIELECTRIC: bool, const DISPERSION: bool, const ABSORPTION: bool>(
    scene: &SceneView,
    p: &TraceParams,
    (clusters, store, fused): (&[u32], u32, bool),
) -> TraceResult {
    // thread i: photon i % 4 of the batch's cluster i / 4
    let trace = |i: u32| -> (Option<Photon>, Counters) {
        let cluster = entry_cluster(clusters[(p.first + i / 4) as usize]);
        let index = cluster_photon_index(cluster, i % 4, p.grid_w);
        crate::traversal_stats::photon_begins(i);
        let (path_end, rays) = trace_photon_variant::<DIELECTRIC, DISPERSION, ABSORPTION>(
            scene,
            p,
            index,
            store,
            &mut |_, _| {},
        );
        crate::traversal_stats::photon_ends();
        let mut c = Counters::default();
        c.words[counter::RAYS] += rays as u64;
        let slot = match path_end {
            PathEnd::Stored(ph) if fused => Some(ph),
            _ if fused => None,
            _ => Some(cluster_slot(&path_end, rays, store)),
        };
        count_end(path_end, p, &mut Vec::new(), &mut c);
        (slot, c)
    };
    // in chunks, so that the per-photon results held at once stay bounded however many
    // clusters a pass takes (a level without slots is one pass); a slot stays at its
    // thread's index, a fused level keeps its stored photons in thread order
    let mut counters = Counters::default();
    let mut photons = Vec::with_capacity(if fused { 0 } else { p.count as usize });
    for first in (0..p.count).step_by(CLUSTER_BATCH_CHUNK as usize) {
        let last = p.count.min(first + CLUSTER_BATCH_CHUNK);
        let parts: Vec<(Option<Photon>, Counters)> =
            (first..last).into_par_iter().map(trace).collect();
        for (ph, c) in parts {
            photons.extend(ph);
            counters = counters.merge(c);
        }
    }
    // thread i traces photon i % 4 of the batch's cluster i / 4, as in the GPU ports
    crate::traversal_stats::report("trace_photons (adaptive)", p.count, None, |i| i);
    TraceResult { photons, counters }
}

/// The emitted ray and flux of photon `index` (global index in the light's grid).
pub fn emit_photon(scene: &SceneView, p: &TraceParams, index: u32) -> (Vec3, Vec3, Vec3) {
    let ix = index % p.grid_w;
    let iy = index / p.grid_w;
    let jitter = Vec2::new(
        stratum_jitter(p.jitter_seed, index, 0, p.stratum),
        stratum_jitter(p.jitter_seed, index, 1, p.stratum),
    );
    let u = stratified_cell(ix, iy, p.grid_w, p.grid_h, jitter);
    let flux = Vec3::from_slice(&p.photon_flux[..3]);
    let axis = Vec3::from_slice(&p.axis[..3]);
    if p.emission == emission_kind::RECTANGLE {
        let origin = Vec3::from_slice(&p.origin[..3])
            + u.x * Vec3::from_slice(&p.rect_u[..3])
            + u.y * Vec3::from_slice(&p.rect_v[..3]);
        return (origin, axis, flux);
    }
    let (dir, flux) = if p.emission == emission_kind::VIEW_PLANE {
        let dir = view_plane_direction(
            axis,
            Vec3::from_slice(&p.rect_u[..3]),
            Vec3::from_slice(&p.rect_v[..3]),
            u,
        );
        let w = view_plane_texel_weight(ix, iy, p.grid_w, p.grid_h, p.rect_u[3], p.rect_v[3]);
        (dir, flux * w)
    } else {
        (to_world(uniform_cone(u, p.origin[3], p.axis[3]), axis), flux)
    };
    let light = &scene.lights[p.light as usize];
    let falloff = if light.kind == light_kind::SPOT {
        light_spot_falloff(dir, light)
    } else {
        1.0
    };
    (Vec3::from_slice(&p.origin[..3]), dir, flux * falloff)
}

/// Traces one photon with every feature compiled in; returns how it ended and the number
/// of ray segments traced.
pub fn trace_photon(scene: &SceneView, p: &TraceParams, index: u32) -> (PathEnd, u32) {
    trace_photon_variant::<true, true, true>(scene, p, index, photon_store::WORLD, &mut |_, _| {})
}

/// [`trace_photon`] with every feature, calling `on_segment(origin, direction)` before each
/// ray segment is traced (the benchmark uses it to replay exactly the same rays through
/// raw obvhs).
pub fn trace_photon_observed(
    scene: &SceneView,
    p: &TraceParams,
    index: u32,
    on_segment: &mut impl FnMut(Vec3, Vec3),
) -> (PathEnd, u32) {
    trace_photon_variant::<true, true, true>(scene, p, index, photon_store::WORLD, on_segment)
}

/// One photon path of a compiled variant.
#[inline]
pub fn trace_photon_variant<
    const DIELECTRIC: bool,
    const DISPERSION: bool,
    const ABSORPTION: bool,
>(
    scene: &SceneView,
    p: &TraceParams,
    index: u32,
    store: u32,
    on_segment: &mut impl FnMut(Vec3, Vec3),
) -> (PathEnd, u32) {
    let (mut origin, mut dir, mut flux) = emit_photon(scene, p, index);
    let emitted_max = Vec3::from_slice(&p.photon_flux[..3]).max_element();
    let min_power = p.photon_flux[3] * emitted_max;
    if flux.max_element() <= 0.0 || flux.max_element() < min_power {
        return (PathEnd::Negligible, 0);
    }
    if !ray_meets_caster_spheres(origin, dir, &p.caster_spheres, p.caster_sphere_count) {
        // its first segment meets no caster ball, so no caster first (core's
        // device::caster_spheres): no ray traced
        return (PathEnd::NoSpecular, 0);
    }
    // the photon's wavelength (micrometres) from its first dispersive surface on
    let mut wavelength: Option<f32> = None;
    for bounce in 0..p.max_bounces {
        on_segment(origin, dir);
        let Some(hit) = scene.closest_hit(origin, dir, f32::INFINITY) else {
            return (PathEnd::Escaped, bounce + 1);
        };
        let (s, m) = scene.surface(&hit);
        let entering = dir.dot(s.geometric_normal) < 0.0;
        if ABSORPTION && m.kind == material_kind::DIELECTRIC && !entering {
            flux *= beer_lambert(Vec3::from_slice(&m.absorption[..3]), hit.t);
        }
        match m.kind {
            material_kind::DIFFUSE => {
                if bounce == 0 {
                    // every earlier segment ended at a mirror or dielectric, so bounce 0
                    // is the only path without a specular interaction
                    return (PathEnd::NoSpecular, bounce + 1);
                }
                let ph = stored_photon(store, &s, &hit, flux, dir);
                return (PathEnd::Stored(ph), bounce + 1);
            }
            material_kind::MIRROR => {
                flux *= Vec3::from_slice(&m.color[..3]);
                let n = if s.shading_normal.dot(dir) > 0.0 {
                    -s.shading_normal
                } else {
                    s.shading_normal
                };
                dir = reflect(dir, n).normalize();
            }
            _ if DIELECTRIC => {
                let mut ior = m.ior;
                if DISPERSION && m.dispersion != 0.0 {
                    let wl = match wavelength {
                        Some(wl) => wl,
                        None => {
                            // First dispersive surface: a wavelength and its colour; the
                            // expected flux per channel is unchanged.
                            let xi = random_f32(p.seed, index, bounce, 3);
                            let (wl, f) = disperse(flux, p.dispersion_mode, p.seed, index, xi);
                            flux = f;
                            wavelength = Some(wl);
                            wl
                        }
                    };
                    ior = dispersive_ior(m.ior, m.dispersion, m.ior_model, wl);
                }
                dir = dielectric_scatter(
                    dir,
                    s.shading_normal,
                    entering,
                    ior,
                    random_f32(p.seed, index, bounce, 2),
                    p.fresnel_model,
                )
                .direction;
            }
            // not compiled in: the plan never runs this variant on a dielectric
            _ => {}
        }
        if flux.max_element() < min_power || flux.max_element() <= 0.0 {
            return (PathEnd::Negligible, bounce + 1);
        }
        let side = if dir.dot(s.geometric_normal) > 0.0 {
            s.geometric_normal
        } else {
            -s.geometric_normal
        };
        origin = offset_ray_origin(s.position, side);
    }
    (PathEnd::BounceLimit, p.max_bounces)
}
