//! Seed 004's hierarchical emission on the device: the photon pyramid of one light view
//! plane traversed in batches under a memory limit (sections 3.2 and 4.3).
//!
//! **Levels.** Level `l` samples the plane on a `start_grid * 2^l` grid; level 0 holds
//! every cluster of the start grid, each deeper level a list of the clusters refined
//! into it ([`crate::math::photon_clusters`]). One *step* takes a batch of at most
//! `batch_clusters` clusters of one level: `trace_photons` (`ADAPTIVE` variant) traces
//! their four photons each into slots, `refine_clusters` discards, outputs or refines
//! each, appending children to the next level's list, and the host reads the cluster
//! counts back (the stall of a step: the next step's size). Output photons go to a
//! [`DepositTarget`]: deposited into CausticMap's atlas by `refine_clusters` itself, or
//! listed (world space) and deposited into Sspm's screen photon map by `deposit_screen`
//! in the same step.
//!
//! **Batches** (004 section 4.3). The traversal always steps the deepest level with
//! clusters left, taking them from the end of its list; the level below is then empty,
//! so a step's children (at most four per cluster) always fit a list of
//! `4 * batch_clusters` entries, and no buffer grows with the photon count. The order
//! changes nothing: a photon's jitter and Fresnel choices are keyed by its texel and
//! level, and the atlas sums are exact fixed-point, so any memory limit gives bitwise
//! the same atlas.

use crate::backend::{read_buf, Backend};
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes, SceneArgs};
use crate::device::layout::{
    cluster_count, counter, AtlasTileTexel, DepositParams, GpuCamera, Photon, RefineParams,
    TraceParams,
};
use crate::frame::emission::light_view_plane::{LightViewPlane, ViewPlaneProjection};
use crate::frame::emission::view_planes::ViewPlanes;
use crate::frame::error::Error;
use crate::frame::stats::{AdaptiveStats, FrameStats};
use crate::kernels::{DepositScreen, RefineClusters, TracePhotons, TraceVariant};
use crate::math::geometry::Aabb;
use crate::math::photon_clusters::{
    cluster_level_seed, cluster_metric, cluster_resample_seed, cluster_target,
};
use crate::recording::Recording;
use serde::{Deserialize, Serialize};

/// When a relevant cluster stops being refined (seed 004 sections 3.2.1-2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdaptiveMetric {
    /// Maximal traversal level: every cluster that met a caster is refined down to the
    /// finest level, where all its photons are output. The photons output are exactly the
    /// dense grid's over the clusters kept (the same seed and jitter), so the map differs
    /// from CausticMap's only where a coarse cluster missed a caster its finer photons
    /// would have met.
    Level,
    /// Maximal caustic map error: from `error_from_grid` on, a cluster whose four photons
    /// all stored in one caustic-map texel is output at once (its photons carry their
    /// coarse texels' flux, the cluster's solid angle or area); the rest is refined, and
    /// output at the finest level (004's third condition). The default: it traces the
    /// fewest photons (004 Figure 7), and here both metrics cost one kernel per step.
    #[default]
    Error,
}

/// What keeps a traced cluster from being discarded (seed 004 section 3.2's first
/// condition, and a conservative one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClusterRelevance {
    /// A cluster is kept when one of its photons met a caster, or when its footprint on
    /// the view plane overlaps the projection of a caster's bounding box. No photon that
    /// can meet a caster is lost: the level metric outputs exactly the dense grid's
    /// photons (bitwise the same atlas), and a caster smaller than a start-grid cell is
    /// found. The default: 004's own test lost 0.2 to 1.9% of the stored flux on the
    /// built-in scenes at 256^2 (`cornell` the most), at the casters' silhouettes.
    #[default]
    Bounds,
    /// 004's test: kept when at least one of its four photons met a caster. Traces fewer
    /// photons; loses what the coarse photons straddle.
    Photons,
}

impl ClusterRelevance {
    /// The kernels' `relevance` value
    /// ([`cluster_relevance`](crate::math::photon_clusters::cluster_relevance)).
    pub fn kernel_value(self) -> u32 {
        match self {
            ClusterRelevance::Bounds => crate::math::photon_clusters::cluster_relevance::BOUNDS,
            ClusterRelevance::Photons => crate::math::photon_clusters::cluster_relevance::PHOTONS,
        }
    }
}

/// Device bytes per cluster of a batch: four 32-byte photon slots.
pub const SLOT_BYTES_PER_CLUSTER: u64 = 128;
/// Device bytes per cluster of a batch per level below the start grid: room for four
/// 4-byte children.
pub const LIST_BYTES_PER_CLUSTER: u64 = 16;

/// The traversal's parameters (AdaptiveCaustics' fields of the same names).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TraversalSettings {
    /// The stop metric.
    pub metric: AdaptiveMetric,
    /// What keeps a cluster from being discarded.
    pub relevance: ClusterRelevance,
    /// Texels a side of the start grid (a power of two; 004 section 4.2: 64).
    pub start_grid: u32,
    /// Grid side from which the error metric is checked (004 section 4.2: 512).
    pub error_from_grid: u32,
    /// The error metric's tolerance (texels a side).
    pub error_texels: u32,
    /// Device bytes the traversal may hold (004 section 4.3).
    pub max_traversal_bytes: u64,
}

impl TraversalSettings {
    /// The first level at which the error metric is checked.
    pub fn error_from_level(&self) -> u32 {
        let mut l = 0;
        while (self.start_grid as u64) << l < self.error_from_grid as u64 && l < 31 {
            l += 1;
        }
        l
    }

    /// Clusters of the start grid.
    pub fn start_clusters(&self) -> u64 {
        (self.start_grid as u64 / 2).pow(2)
    }

    /// The fixed bytes plus one cluster's of a traversal down to level `finest` (`screen`:
    /// with the screen target's output list).
    pub fn min_bytes(&self, finest: u32, screen: bool) -> u64 {
        let outputs = if screen { SLOT_BYTES_PER_CLUSTER } else { 0 };
        4 * self.start_clusters()
            + SLOT_BYTES_PER_CLUSTER
            + outputs
            + LIST_BYTES_PER_CLUSTER * finest as u64
    }

    /// Clusters per batch under `max_traversal_bytes`, at most what the finest level can
    /// need in one step (`dense_clusters`); the screen target (`screen`) also holds an
    /// output list of four photons per cluster.
    pub fn batch_clusters(&self, finest: u32, dense_clusters: u64, screen: bool) -> u32 {
        let fixed = 4 * self.start_clusters();
        let outputs = if screen { SLOT_BYTES_PER_CLUSTER } else { 0 };
        let per = SLOT_BYTES_PER_CLUSTER + outputs + LIST_BYTES_PER_CLUSTER * finest as u64;
        let c = self.max_traversal_bytes.saturating_sub(fixed) / per;
        c.clamp(1, dense_clusters.clamp(1, u32::MAX as u64 / 4)) as u32
    }
}

/// Where output photons go: CausticMap's atlas.
#[derive(Clone, Copy, Debug)]
pub struct AtlasTarget {
    /// Per scene triangle: its receiver's tile.
    pub triangle_tiles: Buf<u32>,
    /// The atlas tiles.
    pub tiles: Buf<AtlasTileTexel>,
    /// The atlas's fixed-point sums.
    pub sums: PhotonMapPlanes,
    /// Atlas side (texels).
    pub atlas_width: u32,
    /// Flux per fixed-point unit (W).
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units).
    pub hit_distance_quantum: f32,
    /// Counters of the photons traced (every level).
    pub trace_counters: Buf<u32>,
}

/// Where output photons go: Sspm's screen-space photon map.
#[derive(Clone, Copy, Debug)]
pub struct ScreenTarget {
    /// `deposit_screen`'s camera, quanta and depth tolerance (its `photon_capacity` is
    /// the traversal's output list's).
    pub deposit: DepositParams,
    /// The frame's G-buffer.
    pub gbuffer: GBufferPlanes,
    /// The screen photon map's fixed-point sums.
    pub photon_map: PhotonMapPlanes,
    /// Counters of the photons traced (every level).
    pub trace_counters: Buf<u32>,
}

/// Where the traversal's output photons go (seed 004's "splat into the caustic map", for
/// either technique's map).
#[derive(Clone, Copy, Debug)]
pub enum DepositTarget {
    /// CausticMap's atlas (texture-space photons, deposited by `refine_clusters`).
    Atlas(AtlasTarget),
    /// Sspm's screen (world-space photons, deposited by `deposit_screen`).
    Screen(ScreenTarget),
}

impl DepositTarget {
    /// (flux quantum, hit-distance quantum) of the target's fixed-point sums.
    fn quanta(&self) -> (f32, f32) {
        match self {
            DepositTarget::Atlas(a) => (a.flux_quantum, a.hit_distance_quantum),
            DepositTarget::Screen(s) => (s.deposit.flux_quantum, s.deposit.hit_distance_quantum),
        }
    }

    fn trace_counters(&self) -> Buf<u32> {
        match self {
            DepositTarget::Atlas(a) => a.trace_counters,
            DepositTarget::Screen(s) => s.trace_counters,
        }
    }
}

/// The optics of a traced photon.
#[derive(Clone, Copy, Debug)]
pub struct PhotonOptics {
    /// Longest path (segments).
    pub max_bounces: u32,
    /// Relative power below which a photon is dropped.
    pub min_relative_power: f32,
    /// `fresnel_model` of the kernels.
    pub fresnel_model: u32,
    /// The casters' balls its first segment is tested against
    /// ([`crate::device::caster_spheres`]).
    pub caster_spheres: crate::device::caster_spheres::CasterSpheres,
}

/// The traversal's device buffers and sizes.
#[derive(Clone, Debug)]
pub struct Traversal {
    /// The stop metric, start grid and error level.
    pub settings: TraversalSettings,
    /// Deepest level any plane reaches.
    pub finest: u32,
    /// Clusters per step.
    pub batch_clusters: u32,
    level0: Buf<u32>,
    /// The casters' bounding boxes (world space), one per caster object.
    caster_boxes: Vec<Aabb>,
    /// Their projections on the current plane ([`caster_rects`]).
    rects: Buf<[f32; 4]>,
    lists: Vec<Buf<u32>>,
    no_children: Buf<u32>,
    converged: Buf<u32>,
    no_converged: Buf<u32>,
    slots: Buf<Photon>,
    counts: Buf<u32>,
    /// Counters of the output (deposited) photons.
    pub output_counters: Buf<u32>,
    /// The screen target's output list (four slots per cluster of a batch; one unused
    /// entry with the atlas target) and its count.
    outputs: Buf<Photon>,
    output_count: Buf<u32>,
    /// Stand-ins for `refine_clusters`' atlas bindings with the screen target.
    no_atlas: Option<(Buf<u32>, Buf<AtlasTileTexel>, PhotonMapPlanes)>,
}

impl Traversal {
    /// Replaces the caster boxes (as many as before: moved instances,
    /// [`super::follow_moved_casters`]); the next frame's planes get their rectangles from
    /// them.
    pub fn set_caster_boxes(&mut self, boxes: &[Aabb]) {
        if boxes.len() == self.caster_boxes.len() {
            self.caster_boxes = boxes.to_vec();
        }
    }

    /// Records the creation of the traversal's buffers for planes down to level
    /// `finest`, for the atlas target or (`screen`) the screen target.
    pub fn record(
        rec: &mut Recording,
        settings: &TraversalSettings,
        finest: u32,
        caster_boxes: &[Aabb],
        screen: bool,
    ) -> Traversal {
        let dense_clusters = ((settings.start_grid as u64) << finest).pow(2) / 4;
        let c = settings.batch_clusters(finest, dense_clusters, screen);
        let ids: Vec<u32> = (0..settings.start_clusters() as u32).collect();
        Traversal {
            settings: *settings,
            finest,
            batch_clusters: c,
            level0: rec.upload(&ids, "adaptive start-grid clusters"),
            caster_boxes: caster_boxes.to_vec(),
            rects: rec.create(
                caster_boxes.len().max(1) as u32,
                "adaptive caster rectangles",
            ),
            lists: (1..=finest)
                .map(|_| rec.create(4 * c, "adaptive cluster list"))
                .collect(),
            no_children: rec.create(1, "adaptive finest-level child list"),
            converged: rec.create(c, "adaptive converged clusters"),
            no_converged: rec.create(1, "adaptive resampled converged list"),
            slots: rec.create(4 * c, "adaptive photon slots"),
            counts: rec.create(cluster_count::WORDS as u32, "adaptive cluster counts"),
            output_counters: rec.create(counter::WORDS as u32, "adaptive output counters"),
            outputs: rec.create(if screen { 4 * c } else { 1 }, "adaptive output photons"),
            output_count: rec.create(1, "adaptive output photon count"),
            no_atlas: screen.then(|| {
                let planes = rec.create_photon_map(1);
                rec.clear_photon_map(&planes);
                (
                    rec.upload(
                        &[crate::device::layout::NO_TILE],
                        "adaptive no triangle tiles",
                    ),
                    rec.upload(&[[0u32; 4]], "adaptive no atlas tiles"),
                    planes,
                )
            }),
        }
    }

    /// Traverses the pyramid of `plane` (its resolution the finest level's,
    /// `start_grid * 2^finest`) of light `light` with seed `plane_seed`: every step
    /// traced, judged and deposited into `target` (the target this traversal was
    /// recorded for). Adds to `adaptive` and the pass times
    /// of `stats`; calls `progress` with the photons traced so far after each step.
    #[allow(clippy::too_many_arguments)]
    pub fn run_plane(
        &self,
        backend: &mut dyn Backend,
        scene: SceneArgs,
        variant: TraceVariant,
        target: &DepositTarget,
        (light, plane, plane_seed): (u32, &LightViewPlane, u32),
        optics: PhotonOptics,
        stats: &mut FrameStats,
        adaptive: &mut AdaptiveStats,
        progress: &mut dyn FnMut(u64),
    ) -> Result<(), Error> {
        let s = &self.settings;
        let finest = (plane.resolution.0 / s.start_grid).max(1).ilog2();
        if finest > self.finest || (s.start_grid << finest) != plane.resolution.0 {
            return Err(Error::InvalidParameter(format!(
                "adaptive plane of {}x{} texels outside the traversal's pyramid",
                plane.resolution.0, plane.resolution.1
            )));
        }
        let levels = finest as usize + 1;
        if adaptive.photons_per_level.len() < levels {
            adaptive.photons_per_level.resize(levels, 0);
            adaptive.ms_per_level.resize(levels, 0.0);
            adaptive.photons_output_per_level.resize(levels, 0);
        }
        adaptive.dense_equivalent_photons += plane.texels();
        let start = s.start_clusters() as u32;
        // clusters left per level (level 0: from `cursor` to `start`)
        let mut left = vec![0u32; levels];
        let mut cursor = 0u32;
        let c = self.batch_clusters;
        let mut rects = caster_rects(plane, &self.caster_boxes);
        rects.resize(self.rects.len as usize, EMPTY_RECT);
        let mut rec = Recording::new();
        rec.update(self.rects, &rects, "adaptive caster rectangles")?;
        backend.execute(&rec)?;
        stats.host_waits += 1;
        loop {
            let level = match (1..levels).rev().find(|&l| left[l] > 0) {
                Some(l) => l,
                None if cursor < start => 0,
                None => break,
            };
            let (list, first, m) = if level == 0 {
                let m = c.min(start - cursor);
                (self.level0, cursor, m)
            } else {
                let m = c.min(left[level]);
                (self.lists[level - 1], left[level] - m, m)
            };
            let (children, capacity, before) = if level < finest as usize {
                let l = self.lists[level];
                (l, l.len, left[level + 1])
            } else {
                (self.no_children, 0, 0)
            };
            let grid = s.start_grid << level;
            let step = StepArgs {
                level: level as u32,
                grid,
                seed: cluster_level_seed(plane_seed, level as u32, finest),
                finest,
                metric: s.metric as u32,
                list: (list, first, m),
                children: (children, capacity, before),
                converged: self.converged,
            };
            adaptive.ms_per_level[level] += self.step(
                backend,
                scene,
                variant,
                target,
                (light, plane),
                optics,
                &step,
                stats,
            )?;
            let counts = read_buf(backend, self.counts)?;
            // the step ran and its counts came back: two waits
            stats.host_waits += 2;
            let kids = counts[cluster_count::CHILDREN];
            if kids > capacity || kids < before {
                return Err(Error::InvalidParameter(format!(
                    "adaptive traversal: level {} list overflowed ({kids} of {capacity})",
                    level + 1
                )));
            }
            if level < finest as usize {
                left[level + 1] = kids;
            }
            if level == 0 {
                cursor += m;
            } else {
                left[level] -= m;
            }
            let refined = (kids - before) as u64 / 4;
            adaptive.clusters_refined += refined;
            adaptive.clusters_output += counts[cluster_count::OUTPUT] as u64;
            adaptive.clusters_discarded += counts[cluster_count::DISCARDED] as u64;
            adaptive.photons_processed += 4 * m as u64;
            adaptive.photons_per_level[level] += 4 * m as u64;
            adaptive.photons_output_per_level[level] +=
                counts[cluster_count::OUTPUT_PHOTONS] as u64;
            adaptive.steps += 1;
            stats.batches += 1;
            let converged = counts[cluster_count::CONVERGED];
            if converged > 0 {
                // the converged clusters, output from fresh photons of their texels: the
                // decision to stop was made on the first four, so depositing those would
                // keep only the outcomes (Fresnel choices) that converge, a bias of
                // several percent (+3.6% on `sphere` at 1024^2)
                let resample = StepArgs {
                    level: level as u32,
                    grid,
                    seed: cluster_resample_seed(plane_seed, level as u32),
                    finest: level as u32,
                    metric: cluster_metric::LEVEL,
                    list: (self.converged, 0, converged),
                    children: (self.no_children, 0, 0),
                    converged: self.no_converged,
                };
                adaptive.ms_per_level[level] += self.step(
                    backend,
                    scene,
                    variant,
                    target,
                    (light, plane),
                    optics,
                    &resample,
                    stats,
                )?;
                let c = read_buf(backend, self.counts)?;
                stats.host_waits += 2;
                adaptive.clusters_converged += converged as u64;
                adaptive.clusters_output += c[cluster_count::OUTPUT] as u64;
                adaptive.clusters_discarded += c[cluster_count::DISCARDED] as u64;
                adaptive.photons_processed += 4 * converged as u64;
                adaptive.photons_per_level[level] += 4 * converged as u64;
                adaptive.photons_output_per_level[level] += c[cluster_count::OUTPUT_PHOTONS] as u64;
                adaptive.steps += 1;
                stats.batches += 1;
            }
            progress(adaptive.photons_processed);
        }
        Ok(())
    }
}

impl Traversal {
    /// Puts the output photons' accounting (read from `output_counters`) into `stats`
    /// after a frame's traversal: stored, deposited and their flux are the output photons
    /// (the traced ones that were refined instead are not part of the map), emitted the
    /// photons traced; `adaptive` (with the photons the trace stored) goes into
    /// `stats.adaptive`.
    pub fn output_stats(
        &self,
        backend: &mut dyn Backend,
        flux_quantum: f32,
        stats: &mut FrameStats,
        mut adaptive: AdaptiveStats,
    ) -> Result<(), Error> {
        let o = read_buf(backend, self.output_counters)?;
        stats.host_waits += 1;
        let o64 = |i: usize| crate::math::fixed_point::join_u64([o[i], o[i + 1]]);
        stats.photons_emitted = adaptive.photons_processed;
        adaptive.photons_traced_stored = stats.photons_stored;
        stats.photons_stored = o[counter::STORED] as u64;
        stats.photons_deposited = o[counter::DEPOSITED] as u64;
        stats.discarded.off_screen = o[counter::OFF_SCREEN] as u64;
        stats.discarded.depth_mismatch = o[counter::DEPTH_MISMATCH] as u64;
        stats.fixed_point_underflow = o[counter::UNDERFLOW] as u64;
        stats.fixed_point_saturated = o[counter::SATURATED] as u64;
        for ch in 0..3 {
            stats.stored_flux[ch] = o64(counter::STORED_FLUX + 2 * ch) as f64 * flux_quantum as f64;
        }
        stats.adaptive = Some(adaptive);
        Ok(())
    }
}

/// One traversal step's dispatch arguments.
struct StepArgs {
    level: u32,
    grid: u32,
    seed: u32,
    /// The level at which clusters are output (the plane's finest; the step's own level
    /// when outputting converged clusters from fresh photons).
    finest: u32,
    metric: u32,
    /// The cluster list, its first entry and the clusters to take.
    list: (Buf<u32>, u32, u32),
    /// The child list, its capacity and its entries before the step.
    children: (Buf<u32>, u32, u32),
    converged: Buf<u32>,
}

impl Traversal {
    /// Traces and judges one batch (`trace_photons`, `refine_clusters`), the cluster
    /// counts reset first (the child count to the entries already listed).
    #[allow(clippy::too_many_arguments)]
    fn step(
        &self,
        backend: &mut dyn Backend,
        scene: SceneArgs,
        variant: TraceVariant,
        target: &DepositTarget,
        (light, plane): (u32, &LightViewPlane),
        optics: PhotonOptics,
        a: &StepArgs,
        stats: &mut FrameStats,
    ) -> Result<f64, Error> {
        let s = &self.settings;
        let at_level = LightViewPlane {
            resolution: (a.grid, a.grid),
            ..*plane
        };
        let (list, first, m) = a.list;
        let (children, capacity, before) = a.children;
        let mut counts = [0u32; cluster_count::WORDS];
        counts[cluster_count::CHILDREN] = before;
        let (flux_quantum, hit_distance_quantum) = target.quanta();
        let mut rec = Recording::new();
        rec.update(self.counts, &counts, "adaptive cluster counts")?;
        if let DepositTarget::Screen(_) = target {
            rec.clear(self.output_count);
        }
        rec.kernel(TracePhotons {
            scene,
            variant,
            params: TraceParams {
                fresnel_model: optics.fresnel_model,
                caster_sphere_count: optics.caster_spheres.count,
                caster_spheres: optics.caster_spheres.spheres,
                ..at_level.trace_params(
                    light,
                    (first, 4 * m),
                    a.seed,
                    optics.max_bounces,
                    optics.min_relative_power,
                    flux_quantum,
                )
            },
            photons: self.slots,
            photon_count: self.counts,
            counters: target.trace_counters(),
            clusters: Some(list),
            deposit: None,
        });
        let (atlas_width, triangle_tiles, tiles, atlas, camera, kind) =
            match (target, self.no_atlas) {
                (DepositTarget::Atlas(a), _) => (
                    a.atlas_width,
                    a.triangle_tiles,
                    a.tiles,
                    a.sums,
                    GpuCamera::default(),
                    cluster_target::ATLAS,
                ),
                (DepositTarget::Screen(sc), Some((tt, tl, planes))) => {
                    (1, tt, tl, planes, sc.deposit.camera, cluster_target::SCREEN)
                }
                (DepositTarget::Screen(_), None) => {
                    return Err(Error::InvalidParameter(
                        "adaptive traversal recorded for the atlas, run for the screen".into(),
                    ))
                }
            };
        rec.kernel(RefineClusters {
            params: RefineParams {
                atlas_width,
                flux_quantum,
                hit_distance_quantum,
                level: a.level,
                finest: a.finest,
                metric: a.metric,
                error_from_level: s.error_from_level(),
                grid_w: a.grid,
                first,
                count: m,
                children_capacity: capacity,
                relevance: s.relevance.kernel_value(),
                rect_count: self.caster_boxes.len() as u32,
                deposit_target: kind,
                error_texels: s.error_texels,
                _pad: 0,
                camera,
            },
            clusters: list,
            caster_rects: self.rects,
            photons: self.slots,
            triangle_tiles,
            tiles,
            children,
            converged: a.converged,
            cluster_counts: self.counts,
            counters: self.output_counters,
            atlas,
            output_photons: self.outputs,
            output_count: self.output_count,
        });
        if let DepositTarget::Screen(sc) = target {
            rec.kernel(DepositScreen {
                params: DepositParams {
                    photon_capacity: self.outputs.len,
                    ..sc.deposit
                },
                gbuffer: sc.gbuffer,
                photons: self.outputs,
                photon_count: self.output_count,
                counters: self.output_counters,
                photon_map: sc.photon_map,
            });
        }
        let mut ms = 0.0;
        for t in backend.execute(&rec)? {
            stats.add_pass_time(t.kernel, t.seconds);
            ms += t.seconds * 1e3;
        }
        Ok(ms)
    }
}

/// Fits the planes of `emission` to the pyramid: each plane's side becomes
/// `start_grid * 2^k` (the nearest such size to the dense plane's; a single plane's is
/// `photons_w` exactly, a cube face's `photons_w / sqrt 6` rounded to the pyramid), and
/// the flux quantum follows the coarsest photons that can be output (the error metric's
/// first level, else the finest), so that they cannot saturate the fixed point.
pub fn fit_planes(emission: &mut ViewPlanes, s: &TraversalSettings, dispersion: bool) {
    let start = s.start_grid;
    for (_, _, p) in &mut emission.planes {
        let ratio = (p.resolution.0.max(1) as f64 / start as f64).max(1.0);
        let k = ratio.log2().round() as u32;
        p.resolution = (start << k, start << k);
    }
    let coarsest_output = |p: &LightViewPlane| {
        let finest = (p.resolution.0 / start).max(1).ilog2();
        let level = match s.metric {
            AdaptiveMetric::Level => finest,
            AdaptiveMetric::Error => s.error_from_level().min(finest),
        };
        (start << level, start << level)
    };
    emission.flux_quantum = ViewPlanes::quantum_for(&emission.planes, dispersion, coarsest_output);
}

/// A rectangle no cluster overlaps.
pub const EMPTY_RECT: [f32; 4] = [2.0, 2.0, -2.0, -2.0];

/// The projections of `boxes` on `plane`, as `(x0, y0, x1, y1)` in its normalised device
/// coordinates ([`crate::math::photon_clusters::cluster_overlaps_rect`]), conservative: a
/// photon whose ray meets a box starts inside the box's rectangle. Perspective: the
/// bounding rectangle of the corners' central projections, the whole plane when a corner
/// lies on or behind the light's side plane, nothing when every corner does;
/// orthographic: of their parallel projections, nothing when the box lies wholly behind
/// the plane. Computed in f64 and widened by 1e-5 of the plane and of the bounds (far
/// above the rounding of the kernels' ray setup, ~1e-7).
pub fn caster_rects(plane: &LightViewPlane, boxes: &[Aabb]) -> Vec<[f32; 4]> {
    let (o, u, v, w) = (
        plane.origin.as_dvec3(),
        plane.u.as_dvec3(),
        plane.v.as_dvec3(),
        plane.w.as_dvec3(),
    );
    let (hx, hy) = (plane.half_extent.0 as f64, plane.half_extent.1 as f64);
    let perspective = plane.projection == ViewPlaneProjection::Perspective;
    boxes
        .iter()
        .map(|b| {
            let mut r = [
                f64::INFINITY,
                f64::INFINITY,
                f64::NEG_INFINITY,
                f64::NEG_INFINITY,
            ];
            let mut behind = 0;
            for c in b.corners() {
                let d = c.as_dvec3() - o;
                let z = d.dot(w);
                if z <= 0.0 {
                    behind += 1;
                    continue;
                }
                let s = if perspective { z } else { 1.0 };
                let (x, y) = (d.dot(u) / (s * hx), d.dot(v) / (s * hy));
                r = [r[0].min(x), r[1].min(y), r[2].max(x), r[3].max(y)];
            }
            if behind == 8 {
                return EMPTY_RECT;
            }
            if perspective && behind > 0 {
                return [-1e30, -1e30, 1e30, 1e30];
            }
            let pad = |x: f64| 1e-5 * (1.0 + x.abs());
            [
                (r[0] - pad(r[0])) as f32,
                (r[1] - pad(r[1])) as f32,
                (r[2] + pad(r[2])) as f32,
                (r[3] + pad(r[3])) as f32,
            ]
        })
        .collect()
}
