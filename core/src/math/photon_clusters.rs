//! Photon clusters of adaptive emission (Wyman 2009, section 3.2, AdaptiveCaustics): a
//! light view plane is sampled on a pyramid of grids, level `l` having `start * 2^l`
//! texels a side; a *cluster* at level `l` is a 2x2 block of that grid's texels (one
//! photon each), identified by its row-major index in the grid of `grid_w / 2` clusters a
//! side. Refining a cluster turns each of its four photons into a cluster of the next
//! level: the photon's texel `(x, y)` at level `l` is cluster `(x, y)` at level `l + 1`, so
//! a child cluster's id is its parent photon's index in the level grid.
//!
//! Every function here is mirrored by name in the WGSL (`common/photon_clusters.wgsl`),
//! OpenCL (`common/photon_clusters.cl`) and GLSL ports.

/// The traced photon's slot says nothing landed: `Photon::direction` of an empty slot.
pub const NO_TRIANGLE: u32 = u32::MAX;

/// How a cluster is judged after its photons are traced (Wyman 2009, sections 3.2.1-2).
pub mod cluster_metric {
    /// Maximal traversal level: a relevant cluster is refined until the finest level.
    pub const LEVEL: u32 = 0;
    /// Maximal caustic map error: a relevant cluster whose photons all landed in one
    /// caustic-map texel is output at once, others are refined (until the finest level).
    pub const ERROR: u32 = 1;
}

/// What becomes of a traced cluster.
pub mod cluster_fate {
    /// Every photon missed the caustic casters: nothing is output, nothing refined.
    pub const DISCARDED: u32 = 0;
    /// Its photons are deposited into the caustic map.
    pub const OUTPUT: u32 = 1;
    /// Four child clusters are traced at the next level instead.
    pub const REFINED: u32 = 2;
}

/// What keeps a traced cluster from being discarded.
pub mod cluster_relevance {
    /// Wyman 2009's test: at least one of its four photons met a caustic caster. Photons
    /// are samples: a cluster whose coarse photons all miss can still cover a caster's
    /// silhouette (or a caster smaller than its footprint), whose caustic is then lost.
    pub const PHOTONS: u32 = 0;
    /// Conservative: a photon met a caster, or the cluster's footprint on the view plane
    /// overlaps the projection of some caster's bounding box
    /// ([`cluster_overlaps_rect`]). No photon that could meet a caster is ever dropped,
    /// so the level metric outputs exactly the dense grid's stored photons.
    pub const BOUNDS: u32 = 1;
}

/// Where `refine_clusters` sends the photons of the clusters it outputs (Wyman 2009, section
/// 3.2's "splat into the caustic map", for either technique's map).
pub mod cluster_target {
    /// CausticMap's atlas: a photon's texel is the atlas texel under its uv (texture-space
    /// slots); output photons are deposited at once, as the fused trace does.
    pub const ATLAS: u32 = 0;
    /// Sspm's screen: a photon's texel is the pixel it projects to (world-space slots);
    /// output photons are appended to a list that `deposit_screen` then deposits.
    pub const SCREEN: u32 = 1;
}

/// Cells per atlas texel side in which the error metric's four photons must meet to
/// converge with `error_texels` 1 on the atlas (Wyman 2009's "one texel", taken at the
/// resolution of the texel's centroid sums, `math::map_gather::centroid_offset`): a
/// converged cluster is output from fresh photons at its coarse level, each standing for a
/// cell of that grid, and four photons in one texel do not say where in it their cells'
/// flux lands; in one sixteenth of it they do to that sixteenth. On `sphere` at 960x540
/// and 4096^2 photons (CPU, relMSE against the exact sphere): 1 cell (the texel, Wyman
/// 2009's) 2.01e-4, 2 cells 1.01e-4, 4 7.1e-5, 8 5.2e-5, 16 4.8e-5 (CausticMap's error), for
/// 9.46, 9.98, 10.42, 10.71 and 10.81 million photons traced (CausticMap: 16.8).
pub const CONVERGENCE_CELLS: u32 = 16;

/// The convergence cell (per axis, 0..[`CONVERGENCE_CELLS`]) of a photon at
/// `offset` ([`crate::math::map_gather::centroid_offset`]) inside its texel.
#[inline]
pub fn convergence_cell(offset: [u32; 2]) -> [u32; 2] {
    let per = crate::math::map_gather::CENTROID_SUBTEXELS / CONVERGENCE_CELLS;
    [offset[0] / per, offset[1] / per]
}

/// Largest `error_texels`: the side of a converged cluster's footprint travels in the top
/// two bits of its list entry ([`cluster_entry`]).
pub const MAX_ERROR_TEXELS: u32 = 4;
/// The cluster-id bits of a list entry (ids stay below 2^30: a level grid is at most 65536
/// texels a side, 2^30 clusters).
pub const CLUSTER_ID_MASK: u32 = (1 << 30) - 1;

/// A cluster list entry: cluster `cluster` and, for a converged cluster, the side
/// `spread` (texels, 1..=[`MAX_ERROR_TEXELS`]) of the square its photons landed in; other
/// entries carry 1.
#[inline]
pub fn cluster_entry(cluster: u32, spread: u32) -> u32 {
    (cluster & CLUSTER_ID_MASK) | ((spread.clamp(1, MAX_ERROR_TEXELS) - 1) << 30)
}

/// The cluster of list entry `entry` ([`cluster_entry`]).
#[inline]
pub fn entry_cluster(entry: u32) -> u32 {
    entry & CLUSTER_ID_MASK
}

/// The footprint side (texels) of list entry `entry` ([`cluster_entry`]).
#[inline]
pub fn entry_spread(entry: u32) -> u32 {
    (entry >> 30) + 1
}

/// The side (texels) of the smallest square of map texels that holds the texels
/// `(xs[k], ys[k])` of a cluster's four photons: 1 when all four landed in one texel
/// (Wyman 2009's convergence), more when they spread.
#[inline]
pub fn cluster_spread(xs: [u32; 4], ys: [u32; 4]) -> u32 {
    let span = |v: [u32; 4]| {
        let (mut lo, mut hi) = (v[0], v[0]);
        for x in v {
            lo = lo.min(x);
            hi = hi.max(x);
        }
        hi - lo
    };
    span(xs).max(span(ys)) + 1
}

/// The splat window of a photon of a cluster converged with footprint side `spread`
/// (Wyman 2009, section 3.2.2's multi-resolution map: a coarse photon covers its cluster's
/// footprint, not one texel): the odd square of side `2 * (spread / 2) + 1` centred on
/// its texel `(x, y)`, clipped to its receiver's tile `[x, y, side, _]`, as inclusive
/// `(x0, x1, y0, y1)`.
#[inline]
pub fn footprint_window(x: u32, y: u32, spread: u32, tile: [u32; 4]) -> (u32, u32, u32, u32) {
    let r = spread / 2;
    let (tx1, ty1) = (tile[0] + tile[2] - 1, tile[1] + tile[2] - 1);
    (
        x.saturating_sub(r).max(tile[0]),
        (x + r).min(tx1),
        y.saturating_sub(r).max(tile[1]),
        (y + r).min(ty1),
    )
}

/// Texel `k`'s share (of `n` texels) of `units` fixed-point units: `units / n`, plus one for
/// the first `units % n` texels, so the shares add up to `units` exactly.
#[inline]
pub fn footprint_share(units: u32, n: u32, k: u32) -> u32 {
    units / n + (k < units % n) as u32
}

/// Whether an adaptive photon slot holds a stored photon (in either space): a stored
/// photon carries flux in some channel (`trace_photons` drops a photon whose flux fell to
/// zero), an empty slot none.
#[inline]
pub fn slot_stored(flux: [f32; 3]) -> bool {
    flux[0] > 0.0 || flux[1] > 0.0 || flux[2] > 0.0
}

/// Whether an adaptive slot's photon met a caustic caster: it stored (only photons that
/// met a caster store), or its empty slot says so in `position.z`.
#[inline]
pub fn slot_met_caster(flux: [f32; 3], position_z: f32) -> bool {
    slot_stored(flux) || position_z != 0.0
}

/// Whether cluster `cluster` of a `grid_w` grid overlaps `rect` = `(x0, y0, x1, y1)`
/// (closed) in the view plane's normalised device coordinates: `x = 2 p.x - 1`,
/// `y = 1 - 2 p.y` of the plane point `p` in [0, 1]^2 (row 0 at the top, as
/// `LightViewPlane::texel_ndc`). The cluster covers its 2x2 texels; with `grid_w` a power
/// of two every bound is exact in f32, so all backends decide alike.
#[inline]
pub fn cluster_overlaps_rect(cluster: u32, grid_w: u32, rect: [f32; 4]) -> bool {
    let clusters_w = grid_w / 2;
    let cx = cluster % clusters_w;
    let cy = cluster / clusters_w;
    // 2 / grid_w, built from its exponent (exact, and no division a shader may round)
    let step = f32::from_bits((128 - grid_w.ilog2()) << 23);
    let x0 = (2 * cx) as f32 * step - 1.0;
    let x1 = (2 * cx + 2) as f32 * step - 1.0;
    let y1 = 1.0 - (2 * cy) as f32 * step;
    let y0 = 1.0 - (2 * cy + 2) as f32 * step;
    x0 <= rect[2] && rect[0] <= x1 && y0 <= rect[3] && rect[1] <= y1
}

/// Side of the tiles (clusters) in which `seed_clusters` takes its window: the seeded list
/// holds a window's clusters tile by tile, so that the 8 clusters of a trace warp (32
/// threads, four photons a cluster) are a 4 x 2 block of clusters, 8 x 4 photons, the
/// shape of the dense trace's warps ([`PHOTON_TILE`](crate::math::sampling::PHOTON_TILE)).
pub const SEED_TILE: u32 = 4;

/// The cluster thread `t` of a `seed_clusters` launch tests: the `t`-th of a window
/// `window_w` x `window_h` clusters from cluster column `first_x`, row `first_y` of a
/// `grid_w` grid (texels a side; clusters are 2x2 texels), in [`SEED_TILE`] tile order
/// ([`tiled_index`](crate::math::sampling::tiled_index)).
#[inline]
pub fn seed_cluster(
    t: u32,
    grid_w: u32,
    (first_x, first_y): (u32, u32),
    (window_w, window_h): (u32, u32),
) -> u32 {
    let i = crate::math::sampling::tiled_index(t, window_w, window_h, SEED_TILE);
    let cx = first_x + i % window_w;
    let cy = first_y + i / window_w;
    cy * (grid_w / 2) + cx
}

/// Whether cluster `cluster` of a `grid_w` grid overlaps one of `rects`
/// ([`cluster_overlaps_rect`]).
#[inline]
pub fn cluster_overlaps_rects(cluster: u32, grid_w: u32, rects: &[[f32; 4]]) -> bool {
    rects
        .iter()
        .any(|&r| cluster_overlaps_rect(cluster, grid_w, r))
}

/// Clusters a traversal pass takes from a list whose length (on the device) is
/// `list_length`: entries `first ..` of it, at most `bound` (the pass's recorded size).
/// A list's length may run past its capacity (appends that did not fit are counted, not
/// written); the passes recorded over a list never reach past its capacity, so the
/// entries taken are always written ones.
#[inline]
pub fn live_clusters(list_length: u32, first: u32, bound: u32) -> u32 {
    list_length.saturating_sub(first).min(bound)
}

/// Index, in the row-major level grid of `grid_w` texels a side, of photon `sub` (0..4:
/// x = `sub & 1`, y = `sub >> 1`) of cluster `cluster`. It is also the id of the child
/// cluster that photon becomes at the next level.
#[inline]
pub fn cluster_photon_index(cluster: u32, sub: u32, grid_w: u32) -> u32 {
    let clusters_w = grid_w / 2;
    let cx = cluster % clusters_w;
    let cy = cluster / clusters_w;
    (2 * cy + (sub >> 1)) * grid_w + 2 * cx + (sub & 1)
}

/// The seed of level `level` of a pyramid whose finest level is `finest`: the plane's own
/// seed at the finest level (so that the photons traced there are bitwise the dense
/// grid's), a hash of it and the level above.
#[inline]
pub fn cluster_level_seed(plane_seed: u32, level: u32, finest: u32) -> u32 {
    if level >= finest {
        plane_seed
    } else {
        crate::math::rng::pcg_hash(plane_seed ^ crate::math::rng::pcg_hash(0x4144_4150 + level))
    }
}

/// The seed of the fresh photons that output the clusters of `level` which converged
/// (the error metric): independent of every level's own photons, so that the decision to
/// stop (made on those) does not bias the flux output (see
/// `techniques::adaptive_caustics`).
#[inline]
pub fn cluster_resample_seed(plane_seed: u32, level: u32) -> u32 {
    crate::math::rng::pcg_hash(plane_seed ^ crate::math::rng::pcg_hash(0x5245_5341 + level))
}

/// Whether a photon met a caustic caster, from how its path ended (`trace_photons`'
/// path ends: 0 stored, 1 no specular, 2 escaped, 3 negligible, 4 bounce limit) and its
/// ray segments: it missed when its first segment reached a diffuse surface, left the
/// scene, or when it carried no flux at emission (outside a spot's cone).
#[inline]
pub fn photon_met_caster(end: u32, rays: u32) -> bool {
    !(end == 1 || (end == 2 && rays <= 1) || (end == 3 && rays == 0))
}

/// The fate of a cluster at `level` (0 = the start grid, `finest` = the last): discarded
/// when no photon met a caster (Wyman 2009, condition 1); output at the finest level (the
/// maximal traversal level, Wyman 2009, section 3.2.1, and the error metric's third
/// condition, section 3.2.2); output when the error metric applies at this level
/// (`level >= error_from_level`) and every photon landed in one caustic-map texel
/// (`converged`, section 3.2.2, condition 2); else refined.
#[inline]
pub fn cluster_fate(
    any_met_caster: bool,
    converged: bool,
    level: u32,
    finest: u32,
    metric: u32,
    error_from_level: u32,
) -> u32 {
    if !any_met_caster {
        cluster_fate::DISCARDED
    } else if level >= finest
        || (metric == cluster_metric::ERROR && level >= error_from_level && converged)
    {
        cluster_fate::OUTPUT
    } else {
        cluster_fate::REFINED
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_cluster_covers_its_two_by_two_texels() {
        // cluster 0 of an 8-grid: texels (0..2, 0..2), ndc x in [-1, -0.5], y in [0.5, 1]
        assert!(cluster_overlaps_rect(0, 8, [-0.6, 0.6, -0.55, 0.7]));
        assert!(cluster_overlaps_rect(0, 8, [-0.5, 0.5, -0.5, 0.5])); // a corner touches
        assert!(!cluster_overlaps_rect(0, 8, [-0.49, 0.6, 0.0, 0.7]));
        assert!(!cluster_overlaps_rect(0, 8, [-0.9, -0.2, -0.6, 0.49]));
        // the last cluster: x in [0.5, 1], y in [-1, -0.5]
        assert!(cluster_overlaps_rect(15, 8, [0.9, -0.9, 2.0, -0.8]));
        assert!(!cluster_overlaps_rect(15, 8, [0.9, -0.4, 2.0, 0.0]));
    }

    #[test]
    fn children_tile_the_next_level_once() {
        // every texel of the level-(l+1) grid belongs to exactly one child of one cluster
        let grid = 16u32;
        let mut seen = vec![0u32; (2 * grid * 2 * grid) as usize];
        for cluster in 0..(grid / 2) * (grid / 2) {
            for sub in 0..4 {
                let child = cluster_photon_index(cluster, sub, grid);
                assert!(child < grid * grid);
                for s2 in 0..4 {
                    seen[cluster_photon_index(child, s2, 2 * grid) as usize] += 1;
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1));
    }

    #[test]
    fn a_child_lies_under_its_parent_photon() {
        // photon (x, y) at grid g covers texels (2x..2x+1, 2y..2y+1) at grid 2g
        let g = 8u32;
        let parent = cluster_photon_index(5, 3, g);
        let (px, py) = (parent % g, parent / g);
        for sub in 0..4 {
            let c = cluster_photon_index(parent, sub, 2 * g);
            assert_eq!(((c % (2 * g)) / 2, (c / (2 * g)) / 2), (px, py));
        }
    }

    #[test]
    fn fates_follow_004() {
        use cluster_fate::*;
        use cluster_metric::*;
        assert_eq!(cluster_fate(false, true, 5, 5, ERROR, 0), DISCARDED);
        assert_eq!(cluster_fate(true, false, 5, 5, LEVEL, 0), OUTPUT);
        assert_eq!(cluster_fate(true, true, 2, 5, LEVEL, 0), REFINED);
        assert_eq!(cluster_fate(true, true, 2, 5, ERROR, 3), REFINED);
        assert_eq!(cluster_fate(true, true, 3, 5, ERROR, 3), OUTPUT);
        assert_eq!(cluster_fate(true, false, 3, 5, ERROR, 3), REFINED);
        assert!(!photon_met_caster(1, 1));
        assert!(!photon_met_caster(2, 1));
        assert!(photon_met_caster(2, 2));
        assert!(!photon_met_caster(3, 0));
        assert!(photon_met_caster(3, 1));
        assert!(photon_met_caster(0, 2));
        assert!(photon_met_caster(4, 12));
    }

    #[test]
    fn footprints_keep_every_unit_inside_the_tile() {
        assert_eq!(cluster_spread([3, 3, 3, 3], [7, 7, 7, 7]), 1);
        assert_eq!(cluster_spread([3, 4, 3, 5], [7, 7, 9, 8]), 3);
        for spread in 1..=MAX_ERROR_TEXELS {
            let e = cluster_entry(123_456_789 & CLUSTER_ID_MASK, spread);
            assert_eq!(
                (entry_cluster(e), entry_spread(e)),
                (123_456_789 & CLUSTER_ID_MASK, spread)
            );
        }
        // a texel at a tile corner keeps its window inside the tile
        let tile = [10, 20, 8, 0];
        assert_eq!(footprint_window(10, 27, 4, tile), (10, 12, 25, 27));
        assert_eq!(footprint_window(13, 23, 3, tile), (12, 14, 22, 24));
        assert_eq!(footprint_window(13, 23, 1, tile), (13, 13, 23, 23));
        for (units, n) in [(0u32, 1u32), (7, 9), (u32::MAX, 25), (100, 3)] {
            let sum: u64 = (0..n).map(|k| footprint_share(units, n, k) as u64).sum();
            assert_eq!(sum, units as u64);
        }
    }

    #[test]
    fn the_finest_level_keeps_the_plane_seed() {
        assert_ne!(cluster_resample_seed(77, 4), cluster_level_seed(77, 4, 4));
        assert_ne!(cluster_resample_seed(77, 3), cluster_level_seed(77, 3, 4));
        assert_eq!(cluster_level_seed(77, 4, 4), 77);
        assert_ne!(cluster_level_seed(77, 3, 4), 77);
        assert_ne!(cluster_level_seed(77, 3, 4), cluster_level_seed(77, 2, 4));
    }
}
