//! `refine_clusters` (Wyman 2009, section 3.2, AdaptiveCaustics): one step of the adaptive
//! traversal over a batch of traced clusters. The decisions are core's
//! `math::photon_clusters`; the atlas deposit is the fused trace's (`atlas_deposit::deposit_atlas_texel`), the screen target's
//! photons are `deposit_screen`'s input.

use super::deposit_screen::MapPlanes;
use super::trace_photons::count_stored;
use super::Counters;
use crate::atlas_deposit::{
    add_centroid, atlas_photon_texel, atlas_photon_tile, deposit_atlas_footprint,
    deposit_atlas_texel, CentroidSums,
};
use caustica_core::math::map_gather::{centroid_offset, CENTROID_WORDS};
use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{
    cluster_count, counter, project_to_pixel, AtlasTileTexel, Photon, RefineParams, NO_TILE,
};
use caustica_core::kernels::RefineClusters;
use caustica_core::math::photon_clusters::{
    cluster_entry, cluster_fate, cluster_overlaps_rects, cluster_photon_index, cluster_relevance,
    cluster_spread, cluster_target, convergence_cell, entry_cluster, entry_spread, live_clusters, slot_met_caster,
    slot_stored,
};
use rayon::prelude::*;

/// Runs `refine_clusters` on the host ([`super::run`]'s arm): its buffers read from `cpu`,
/// its results written back.
pub(crate) fn run(cpu: &mut CpuBackend, k: &RefineClusters) -> Result<(), BackendError> {
    let RefineClusters {
        params,
        clusters,
        list_length,
        caster_rects,
        photons,
        triangle_tiles,
        tiles,
        children,
        converged,
        converged_count,
        cluster_counts,
        counters,
        atlas,
        output_photons,
        output_count,
        dispatch: _,
        centroids,
    } = k;
    // the pass's live clusters: list_length[0] is its list's length
    let length = cpu.get(list_length.id)?.as_slice::<u32>(1)?[0];
    let live = live_clusters(length, params.first, params.count);
    let list = cpu.get(clusters.id)?.as_slice(clusters.len)?;
    let rects = cpu.get(caster_rects.id)?.as_slice(caster_rects.len)?;
    let ph = cpu.get(photons.id)?.as_slice(photons.len)?;
    let tt = cpu.get(triangle_tiles.id)?.as_slice(triangle_tiles.len)?;
    let tl = cpu.get(tiles.id)?.as_slice(tiles.len)?;
    let atomics = cpu.map_atomics(atlas)?;
    let centroid_bytes = if params.deposit_target == cluster_target::ATLAS {
        let texels = params.atlas_width as u64 * params.atlas_width as u64;
        4 * CENTROID_WORDS as u64 * texels
    } else {
        0
    };
    let centroids = cpu.get(centroids.id)?.as_atomic_u32(centroid_bytes)?;
    let r = refine_clusters(params, live, list, rects, ph, tt, tl, (atomics, centroids));
    r.counters
        .add_to(cpu.get_mut(counters.id)?.as_mut_slice(counters.len)?);
    let mut counts = cpu
        .get(cluster_counts.id)?
        .as_slice::<u32>(cluster_counts.len)?
        .to_vec();
    let mut conv = cpu
        .get(converged.id)?
        .as_slice::<u32>(converged.len)?
        .to_vec();
    let mut listed = cpu.get(converged_count.id)?.as_slice::<u32>(1)?[0];
    let kids = cpu.get_mut(children.id)?.as_mut_slice(children.len)?;
    append_refined(
        &r,
        (kids, params.children_capacity),
        (&mut conv, &mut listed),
        &mut counts,
    );
    cpu.get_mut(converged_count.id)?.as_mut_slice::<u32>(1)?[0] = listed;
    cpu.get_mut(converged.id)?
        .as_mut_slice::<u32>(converged.len)?
        .copy_from_slice(&conv);
    cpu.get_mut(cluster_counts.id)?
        .as_mut_slice::<u32>(cluster_counts.len)?
        .copy_from_slice(&counts);
    if !r.outputs.is_empty() {
        let mut n = cpu.get(output_count.id)?.as_slice::<u32>(1)?[0];
        let out = cpu
            .get_mut(output_photons.id)?
            .as_mut_slice(output_photons.len)?;
        append_outputs(&r, out, &mut n);
        cpu.get_mut(output_count.id)?.as_mut_slice::<u32>(1)?[0] = n;
    }
    Ok(())
}

/// What becomes of one cluster.
enum Step {
    Discarded,
    /// Deposited (or, with the screen target, its stored photons listed), with their
    /// accounting.
    Output(Counters, Vec<Photon>),
    /// Converged before the finest level: to be output from fresh photons.
    Converged(u32),
    /// Refined into four children (the cluster, its children).
    Refined(u32, [u32; 4]),
}

/// What a batch step produced: the lists appended (in cluster order: the GPU ports
/// append in arrival order, and every later result is independent of it), the cluster
/// counts and the photon counters of the output photons.
#[derive(Default)]
pub struct Refined {
    /// The refined clusters and their child cluster ids.
    pub children: Vec<(u32, [u32; 4])>,
    /// Clusters that converged before the finest level.
    pub converged: Vec<u32>,
    /// Clusters output.
    pub output: u32,
    /// Clusters discarded.
    pub discarded: u32,
    /// Photons deposited (the stored photons of output clusters).
    pub output_photons: u32,
    /// Photon accounting of the output photons.
    pub counters: Counters,
    /// The screen target's output photons (in cluster order).
    pub outputs: Vec<Photon>,
}

/// Judges the pass's `live` clusters and deposits the output ones (see core's
/// `RefineClusters`).
#[allow(clippy::too_many_arguments)]
pub fn refine_clusters(
    p: &RefineParams,
    live: u32,
    clusters: &[u32],
    caster_rects: &[[f32; 4]],
    photons: &[Photon],
    triangle_tiles: &[u32],
    tiles: &[AtlasTileTexel],
    (map, centroids): (MapPlanes, CentroidSums),
) -> Refined {
    let steps: Vec<Step> = (0..live)
        .into_par_iter()
        .map(|t| {
            let entry = clusters[(p.first + t) as usize];
            let cluster = entry_cluster(entry);
            let slots: [Photon; 4] = std::array::from_fn(|k| photons[4 * t as usize + k]);
            let screen = p.deposit_target == cluster_target::SCREEN;
            // the texel the error metric compares: the pixel or the atlas texel
            let texel_of = |ph: &Photon| {
                if screen {
                    project_to_pixel(&p.camera, glam::Vec3::from(ph.position))
                        .map_or(NO_TILE, |(x, y, _)| y * p.camera.width + x)
                } else {
                    atlas_photon_texel(triangle_tiles, tiles, ph, p.atlas_width)
                }
            };
            let texels = slots.map(|ph| slot_stored(ph.flux).then(|| texel_of(&ph)));
            // Wyman 2009's test (a photon met a caster), or the conservative one
            let relevant = slots
                .iter()
                .any(|ph| slot_met_caster(ph.flux, ph.position[2]))
                || (p.relevance == cluster_relevance::BOUNDS
                    && cluster_overlaps_rects(
                        cluster,
                        p.grid_w,
                        &caster_rects[..p.rect_count as usize],
                    ));
            // converged: all four in one square of at most error_texels a side, on one
            // receiver's tile (atlas) or on screen
            let width = if screen {
                p.camera.width
            } else {
                p.atlas_width
            };
            let tile = (!screen)
                .then(|| atlas_photon_tile(triangle_tiles, tiles, &slots[0]))
                .flatten();
            let inside = |t: u32| {
                t != NO_TILE
                    && (screen
                        || tile.is_some_and(|r| {
                            let (x, y) = (t % width, t / width);
                            x >= r[0] && x < r[0] + r[2] && y >= r[1] && y < r[1] + r[2]
                        }))
            };
            let all_in = texels.iter().all(|t| t.is_some_and(inside));
            let spread = if all_in {
                let xy = texels.map(|t| t.unwrap_or(0));
                cluster_spread(xy.map(|t| t % width), xy.map(|t| t / width))
            } else {
                u32::MAX
            };
            // with error_texels 1 on the atlas, the four also in one convergence cell of
            // their texel
            let one_cell = screen
                || p.error_texels > 1
                || !all_in
                || tile.is_none_or(|t| {
                    let cell = |ph: &Photon| {
                        let uv = glam::Vec2::new(ph.position[0], ph.position[1]);
                        convergence_cell(centroid_offset(t, uv))
                    };
                    slots.iter().all(|ph| cell(ph) == cell(&slots[0]))
                });
            let converged = spread <= p.error_texels.max(1) && one_cell;
            let fate = cluster_fate(
                relevant,
                converged,
                p.level,
                p.finest,
                p.metric,
                p.error_from_level,
            );
            use caustica_core::math::photon_clusters::cluster_fate::{DISCARDED, OUTPUT};
            match fate {
                DISCARDED => Step::Discarded,
                OUTPUT if p.level < p.finest => Step::Converged(cluster_entry(cluster, spread)),
                OUTPUT => {
                    let mut c = Counters::default();
                    let mut listed = Vec::new();
                    for (ph, texel) in slots.iter().zip(texels) {
                        let Some(texel) = texel else { continue };
                        count_stored(ph, p.flux_quantum, &mut c);
                        let quanta = (p.flux_quantum, p.hit_distance_quantum);
                        let own_tile = atlas_photon_tile(triangle_tiles, tiles, ph);
                        match (screen, own_tile) {
                            (true, _) => listed.push(*ph),
                            // a converged cluster's photon covers the cluster's footprint
                            (false, Some(tile)) if entry_spread(entry) > 1 => {
                                let at = (tile, p.atlas_width, texel, entry_spread(entry));
                                deposit_atlas_footprint((&map, centroids), at, ph, quanta, &mut c);
                            }
                            (false, tile) => {
                                deposit_atlas_texel(&map, texel, ph, quanta, &mut c);
                                if let (Some(tile), true) = (tile, texel != NO_TILE) {
                                    let uv = glam::Vec2::new(ph.position[0], ph.position[1]);
                                    let at = centroid_offset(tile, uv);
                                    add_centroid(centroids, texel, at, &mut c);
                                }
                            }
                        }
                    }
                    Step::Output(c, listed)
                }
                _ => Step::Refined(
                    cluster,
                    [0, 1, 2, 3].map(|s| cluster_photon_index(cluster, s, p.grid_w)),
                ),
            }
        })
        .collect();
    let mut r = Refined::default();
    for s in steps {
        match s {
            Step::Discarded => r.discarded += 1,
            Step::Output(c, listed) => {
                r.output += 1;
                r.output_photons += c.words[counter::STORED] as u32;
                r.counters = r.counters.merge(c);
                r.outputs.extend(listed);
            }
            Step::Converged(c) => r.converged.push(c),
            Step::Refined(cluster, ch) => r.children.push((cluster, ch)),
        }
    }
    r
}

/// Appends the screen target's output photons to `list` at `count[0]` (entries past the
/// list are counted, not written), as the GPU ports do.
pub fn append_outputs(r: &Refined, list: &mut [Photon], count: &mut u32) {
    for (k, ph) in r.outputs.iter().enumerate() {
        if let Some(slot) = list.get_mut(*count as usize + k) {
            *slot = *ph;
        }
    }
    *count = count.wrapping_add(r.outputs.len() as u32);
}

/// Adds a pass's results to the child and converged lists (`converged` and its count)
/// and the cluster counts, as the GPU ports' atomic appends do: a refined cluster's four
/// children go to the child list at `counts[CHILDREN]` (advanced by four either way)
/// when they all fit under `capacity`, else the cluster goes to the converged list
/// (output at its level) and counts as overflowed; converged entries past the list are
/// counted, not written.
pub fn append_refined(
    r: &Refined,
    (children, capacity): (&mut [u32], u32),
    (converged, listed): (&mut [u32], &mut u32),
    counts: &mut [u32],
) {
    let cap = capacity.min(children.len() as u32) as u64;
    let mut to_converged = r.converged.clone();
    for &(cluster, ch) in &r.children {
        let base = counts[cluster_count::CHILDREN];
        if base as u64 + 4 <= cap {
            children[base as usize..base as usize + 4].copy_from_slice(&ch);
        } else {
            to_converged.push(cluster_entry(cluster, 1));
            counts[cluster_count::OVERFLOW] = counts[cluster_count::OVERFLOW].wrapping_add(1);
        }
        counts[cluster_count::CHILDREN] = base.wrapping_add(4);
    }
    counts[cluster_count::CONVERGED] =
        counts[cluster_count::CONVERGED].wrapping_add(r.converged.len() as u32);
    for &e in &to_converged {
        if let Some(slot) = converged.get_mut(*listed as usize) {
            *slot = e;
        }
        *listed = listed.wrapping_add(1);
    }
    counts[cluster_count::OUTPUT] = counts[cluster_count::OUTPUT].wrapping_add(r.output);
    counts[cluster_count::DISCARDED] = counts[cluster_count::DISCARDED].wrapping_add(r.discarded);
    counts[cluster_count::OUTPUT_PHOTONS] =
        counts[cluster_count::OUTPUT_PHOTONS].wrapping_add(r.output_photons);
}
