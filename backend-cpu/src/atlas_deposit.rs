//! The atlas deposit of CausticMap (Vanderstichelen 2021): texture-space photons into the atlas's
//! fixed-point sums, as `trace_photons`' fused atlas deposit and `refine_clusters` add
//! them (the WGSL ports' `common/atlas_deposit.wgsl`). The math is core's
//! `math::map_gather`; these are loops over it.

use crate::kernels::deposit_screen::{
    add_photon_map_u64, deposit_photon_texel, photon_flux_units, MapPlanes,
};
use crate::kernels::Counters;
use caustica_core::device::layout::{
    counter, deposit_from_planes, AtlasParams, AtlasTileTexel, DepositTexel, Photon,
    DEPOSIT_PLANE_WORDS, NO_TILE,
};
use caustica_core::math::fixed_point::quantize;
use caustica_core::math::map_gather::{
    atlas_texel_index, centroid_offset, triangle_reach_bit, CENTROID_MAX_PHOTONS,
    CENTROID_SUBTEXELS, CENTROID_WORDS,
};
use caustica_core::math::photon_clusters::{footprint_share, footprint_window};
use glam::Vec2;
use rayon::prelude::*;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};

/// The atlas's centroid sums as the deposits add to them
/// ([`CENTROID_WORDS`] words a texel: offsets along x and y, photons).
pub type CentroidSums<'a> = &'a [AtomicU32];

/// Adds a photon at `offsets` ([`centroid_offset`]) inside texel `texel` to its centroid
/// sums; the add that takes the texel to [`CENTROID_MAX_PHOTONS`] photons is counted
/// saturated (its sums may wrap from there on, and the lookup reads it as uniform).
pub fn add_centroid(sums: CentroidSums, texel: u32, offsets: [u32; 2], c: &mut Counters) {
    let i = (texel * CENTROID_WORDS) as usize;
    sums[i].fetch_add(offsets[0], Ordering::Relaxed);
    sums[i + 1].fetch_add(offsets[1], Ordering::Relaxed);
    if sums[i + 2].fetch_add(1, Ordering::Relaxed) == CENTROID_MAX_PHOTONS - 1 {
        c.bump(counter::SATURATED);
    }
}

/// The offsets a photon spread over a footprint window adds to each of its texels: the
/// texel's middle (its flux is uniform there).
pub const CENTROID_MIDDLE: [u32; 2] = [CENTROID_SUBTEXELS / 2; 2];

/// Deposits every texture-space photon into the atlas sums (flux r, g, b in flux quanta,
/// hit distance in its quanta, a count) and its offset inside its texel into the centroid
/// sums, and returns the counters it adds to (off screen: the photon's triangle has no
/// tile; deposited; underflow; saturated).
pub fn deposit_atlas(
    p: &AtlasParams,
    triangle_tiles: &[u32],
    tiles: &[AtlasTileTexel],
    photons: &[Photon],
    map: MapPlanes,
    centroids: CentroidSums,
) -> Counters {
    photons
        .par_chunks(4096)
        .map(|chunk| {
            let mut c = Counters::default();
            for ph in chunk {
                let texel = atlas_photon_texel(triangle_tiles, tiles, ph, p.width);
                deposit_atlas_texel(
                    &map,
                    texel,
                    ph,
                    (p.flux_quantum, p.hit_distance_quantum),
                    &mut c,
                );
                if let (Some(tile), true) = (
                    atlas_photon_tile(triangle_tiles, tiles, ph),
                    texel != NO_TILE,
                ) {
                    let uv = Vec2::new(ph.position[0], ph.position[1]);
                    add_centroid(centroids, texel, centroid_offset(tile, uv), &mut c);
                }
            }
            c
        })
        .reduce(Counters::default, Counters::merge)
}

/// What [`deposit_atlas_fresh`] returns: the atlas sums, the counters in the device's
/// word layout ([`counter`]), the triangle reach mask, the centroid sums.
pub type AtlasDepositResult = (Vec<DepositTexel>, Vec<u32>, Vec<u32>, Vec<u32>);

/// [`deposit_atlas`] and [`mark_triangle_reach`] of `photons` into a fresh atlas of
/// `texels` texels and a fresh reach mask of `reach_words` words: the CPU's deposit of
/// photons another backend traced (conformance's check of the fused trace).
pub fn deposit_atlas_fresh(
    p: &AtlasParams,
    (triangle_tiles, tiles): (&[u32], &[AtlasTileTexel]),
    photons: &[Photon],
    texels: usize,
    reach_words: usize,
) -> AtlasDepositResult {
    let planes: [Vec<AtomicU64>; 3] = std::array::from_fn(|k| {
        (0..texels * DEPOSIT_PLANE_WORDS[k] / 2)
            .map(|_| AtomicU64::new(0))
            .collect()
    });
    let centroids: Vec<AtomicU32> = (0..texels * CENTROID_WORDS as usize)
        .map(|_| AtomicU32::new(0))
        .collect();
    let c = deposit_atlas(
        p,
        triangle_tiles,
        tiles,
        photons,
        [&planes[0], &planes[1], &planes[2]],
        &centroids,
    );
    // a u64 of the planes is the (lo, hi) pair of u32 words the devices hold
    let words = planes.map(|plane| {
        plane
            .into_iter()
            .flat_map(|a| {
                let v = a.into_inner();
                [v as u32, (v >> 32) as u32]
            })
            .collect::<Vec<u32>>()
    });
    let mut counters = vec![0u32; counter::WORDS];
    c.add_to(&mut counters);
    let mut reach = vec![0u32; reach_words];
    mark_triangle_reach(photons, &mut reach);
    (
        deposit_from_planes([&words[0], &words[1], &words[2]]),
        counters,
        reach,
        centroids.into_iter().map(AtomicU32::into_inner).collect(),
    )
}

/// Sets the reach bit of each texture-space photon's triangle (the atlas deposit; tile or
/// not, a triangle outside the mask is skipped).
pub fn mark_triangle_reach(photons: &[Photon], reach: &mut [u32]) {
    for ph in photons {
        let (word, bit) = triangle_reach_bit(ph.direction);
        if let Some(w) = reach.get_mut(word as usize) {
            *w |= bit;
        }
    }
}

/// Adds photon `ph` to atlas texel `texel` (fixed point, `(flux, hit distance)` quanta),
/// or counts it as off the atlas when `texel` is `NO_TILE` (its triangle has no tile):
/// the atlas deposit's and `refine_clusters`' deposit.
pub fn deposit_atlas_texel(
    map: &MapPlanes,
    texel: u32,
    ph: &Photon,
    (flux_quantum, hit_distance_quantum): (f32, f32),
    c: &mut Counters,
) {
    if texel == NO_TILE {
        c.bump(counter::OFF_SCREEN);
    } else {
        deposit_photon_texel(map, texel, ph, flux_quantum, hit_distance_quantum, c);
    }
}

/// Adds photon `ph` of a converged cluster to its footprint: the window
/// ([`footprint_window`]) of side `spread` around atlas texel `texel` in its tile, its flux
/// units split exactly over the window's texels ([`footprint_share`]), the hit distance
/// and a count on each, and the texels' middles to their centroid sums
/// ([`CENTROID_MIDDLE`]); one deposit counted.
pub fn deposit_atlas_footprint(
    (map, centroids): (&MapPlanes, CentroidSums),
    (tile, atlas_width, texel, spread): (AtlasTileTexel, u32, u32, u32),
    ph: &Photon,
    (flux_quantum, hit_distance_quantum): (f32, f32),
    c: &mut Counters,
) {
    let (x0, x1, y0, y1) = footprint_window(texel % atlas_width, texel / atlas_width, spread, tile);
    let n = (x1 - x0 + 1) * (y1 - y0 + 1);
    let hd = quantize(ph.hit_distance, hit_distance_quantum).units as u64;
    for (ch, units) in photon_flux_units(ph, flux_quantum, c)
        .into_iter()
        .enumerate()
    {
        if units == 0 {
            continue;
        }
        for (k, (x, y)) in (y0..=y1)
            .flat_map(|y| (x0..=x1).map(move |x| (x, y)))
            .enumerate()
        {
            let share = footprint_share(units, n, k as u32);
            if share != 0 {
                add_photon_map_u64(map, y * atlas_width + x, 2 * ch as u32, share as u64);
            }
        }
    }
    for y in y0..=y1 {
        for x in x0..=x1 {
            add_photon_map_u64(map, y * atlas_width + x, 6, hd);
            add_photon_map_u64(map, y * atlas_width + x, 8, 1);
            add_centroid(centroids, y * atlas_width + x, CENTROID_MIDDLE, c);
        }
    }
    c.bump(counter::DEPOSITED);
}

/// The tile of the receiver under texture-space photon `ph`, if its triangle has one.
pub fn atlas_photon_tile(
    triangle_tiles: &[u32],
    tiles: &[AtlasTileTexel],
    ph: &Photon,
) -> Option<AtlasTileTexel> {
    let tile = *triangle_tiles.get(ph.direction as usize)?;
    tiles.get(tile as usize).copied()
}

/// The atlas texel under texture-space photon `ph` (its uv on its triangle's receiver
/// tile), or `NO_TILE` when its triangle has no tile.
pub fn atlas_photon_texel(
    triangle_tiles: &[u32],
    tiles: &[AtlasTileTexel],
    ph: &Photon,
    width: u32,
) -> u32 {
    let tile = triangle_tiles
        .get(ph.direction as usize)
        .copied()
        .unwrap_or(NO_TILE);
    if tile == NO_TILE || tile as usize >= tiles.len() {
        return NO_TILE;
    }
    let uv = Vec2::new(ph.position[0], ph.position[1]);
    atlas_texel_index(tiles[tile as usize], uv, width)
}
