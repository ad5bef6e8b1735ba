//! Wyman 2009's hierarchical emission on the device: the photon pyramid of one light view
//! plane traversed level by level under a memory limit (sections 3.2 and 4.3), recorded
//! once per frame with no wait on the device.
//!
//! **Levels.** Level `l` samples the plane on a `start_grid * 2^l` grid; level 0 holds
//! every cluster of the start grid, each deeper level a list of the clusters refined
//! into it ([`crate::math::photon_clusters`]). A level is taken in *passes* of at most
//! `pass_clusters` clusters ([`TraversalSizes`]): `dispatch_args` reads the list's length on the device and
//! writes the pass's launch shapes, `trace_photons` (`ADAPTIVE` variant) traces four
//! photons per live cluster into slots and `refine_clusters` discards, outputs or
//! refines each, appending children to the next level's list (both launched indirectly;
//! each bounds itself by the same length, so a backend without indirect dispatch
//! launches the recorded bound). Clusters that converged early (the error metric) are
//! output from fresh photons by a second trace and refinement of the pass. Output
//! photons go to a [`DepositTarget`]: deposited into CausticMap's atlas by
//! `refine_clusters` itself, or listed (world space) and deposited into Sspm's screen
//! photon map by `deposit_screen` in the same pass. The counts come back at the frame's
//! end ([`TraversalReadback`]).
//!
//! **Memory** (Wyman 2009, section 4.3, [`TraversalSettings::sizes`]). A level's list holds all
//! of its clusters when the byte limit allows; the passes take the rest of the limit. A
//! tighter limit caps the lists: a cluster whose children do not fit is output at its
//! level from fresh photons and counted (`clusters_overflowed`), never lost (which ones
//! overflow is the device atomics' order: such a frame is not bitwise reproducible). The pass
//! size changes nothing: a photon's jitter and Fresnel choices are keyed by its texel and
//! level, and the atlas sums are exact fixed-point, so any limit whose lists are whole
//! gives bitwise the same atlas.

use super::stats::AdaptiveStats;
use crate::backend::PassTime;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes, SceneArgs};
use crate::device::launch::DISPATCH_RECORD_WORDS;
use crate::device::layout::{
    cluster_count, counter, AtlasParams, AtlasTileTexel, DepositParams, GpuCamera, Photon,
    RefineParams, SeedParams, TraceParams,
};
use crate::frame::emission::light_view_plane::{LightViewPlane, ViewPlaneProjection};
use crate::frame::emission::view_planes::ViewPlanes;
use crate::frame::error::Error;
use crate::frame::pipeline::FrameBuilder;
use crate::frame::stats::FrameStats;
use crate::frame::submitted::{EndRead, FrameEnd};
use crate::kernels::{
    AtlasDeposit, ClusterBatch, DepositScreen, DispatchArgs, DispatchRecord, FusedDeposit,
    RefineClusters, ScreenDeposit, SeedClusters, TracePhotons, TraceVariant,
};
use crate::math::geometry::Aabb;
use crate::math::photon_clusters::{
    cluster_level_seed, cluster_metric, cluster_resample_seed, cluster_target,
};
use crate::recording::Recording;
use serde::{Deserialize, Serialize};

/// When a relevant cluster stops being refined (Wyman 2009, sections 3.2.1-2).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum AdaptiveMetric {
    /// Maximal traversal level: every cluster that met a caster is refined down to the
    /// finest level, where all its photons are output. The photons output are exactly the
    /// dense grid's over the clusters kept (the same seed and jitter), so the map differs
    /// from CausticMap's only where a coarse cluster missed a caster its finer photons
    /// would have met (never, with the `bounds` relevance). The default: with the bounds
    /// seed ([`ProbeLevels::Bounds`]) it traces one level, the finest, and on the built-in
    /// scenes fewer photons in less time than the error metric, whose coarse judged levels
    /// converge almost nothing up to 4096^2 (docs/adaptive-caustics.md).
    #[default]
    Level,
    /// Maximal caustic map error: from `error_from_grid` on, a cluster whose four photons
    /// all stored in one caustic-map texel is output at once (its photons carry their
    /// coarse texels' flux, the cluster's solid angle or area); the rest is refined, and
    /// output at the finest level (Wyman 2009's third condition). Its judged levels trace
    /// full paths (the test needs where the photons land).
    Error,
}

/// What keeps a traced cluster from being discarded (Wyman 2009, section 3.2's first
/// condition, and a conservative one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ClusterRelevance {
    /// A cluster is kept when one of its photons met a caster, or when its footprint on
    /// the view plane overlaps the projection of a caster's bounding box. No photon that
    /// can meet a caster is lost: the level metric outputs exactly the dense grid's
    /// photons (bitwise the same atlas), and a caster smaller than a start-grid cell is
    /// found. The default: Wyman 2009's own test lost 0.2 to 1.9% of the stored flux on the
    /// built-in scenes at 256^2 (`cornell` the most), at the casters' silhouettes.
    #[default]
    Bounds,
    /// Wyman 2009's test: kept when at least one of its four photons met a caster. Traces fewer
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

/// Device bytes per cluster of a pass: four 32-byte photon slots.
pub const SLOT_BYTES_PER_CLUSTER: u64 = 128;
/// Device bytes per entry of a level's cluster list, and of a pass's converged list.
pub const LIST_BYTES_PER_ENTRY: u64 = 4;
/// Most passes a level's list is taken in: a pass holds at least 1/64 of the largest
/// level's clusters (unless the device's largest buffer holds fewer clusters' slots), so
/// that a frame records a bounded number of dispatches.
pub const MAX_PASSES_PER_LEVEL: u64 = 64;

/// How the traversal judges its probe levels ([`TraversalSettings::is_probe_level`]).
/// Settings files name it (`"traced"`, `"first_segment"`, `"bounds"`); the boolean
/// `probe_coarse_levels` of earlier files still loads (`true`: `first_segment`, `false`:
/// `traced`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ProbeLevels {
    /// Every photon traced to its path's end, as at every other level (Wyman 2009).
    Traced,
    /// Each photon traced to its first surface only: whether a photon met a caster is
    /// decided by its first segment
    /// ([`photon_met_caster`](crate::math::photon_clusters::photon_met_caster)), so a
    /// level costs one segment's traversal instead of its longest path's (a glass ball's
    /// internal reflections).
    FirstSegment,
    /// Not traced at all where the casters' rectangles decide alone (the `bounds`
    /// relevance, whole lists): one `seed_clusters` launch lists the first judged level's
    /// clusters that overlap a caster's rectangle, which are exactly those the probe
    /// levels would pass down to be kept ([`crate::kernels::SeedClusters`]). Elsewhere
    /// (the `photons` relevance, or lists capped by the byte limit) as `first_segment`.
    /// The default.
    #[default]
    Bounds,
}

/// The traversal's parameters (`traversal` in AdaptiveCaustics' settings).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct TraversalSettings {
    /// The stop metric.
    pub metric: AdaptiveMetric,
    /// What keeps a cluster from being discarded: `bounds` (the default) or Wyman 2009's
    /// `photons`.
    pub relevance: ClusterRelevance,
    /// Texels a side of the start grid (Wyman 2009, section 4.2: 64, enough photons to
    /// keep a GPU busy from the first step; a power of two).
    pub start_grid: u32,
    /// Grid side from which the error metric is checked; coarser levels use the
    /// traversal-level metric (Wyman 2009, section 4.2: from 512^2 on, since coarse
    /// photons rarely converge).
    pub error_from_grid: u32,
    /// The error metric's tolerance (texels): a cluster converges when its four photons
    /// land in a square of at most this many caustic-map texels a side on one receiver,
    /// and its photons are then splatted over a window that size (Wyman 2009, section
    /// 3.2.2's alternative: "photon divergence greater than a single texel but less than a
    /// user-defined tolerance", with its multi-resolution map). 1 (the default) is the
    /// publication's metric, one texel, and a one-texel splat, taken on the atlas at the
    /// texel's centroid resolution: the four photons also in one of the texel's
    /// [`CONVERGENCE_CELLS`](crate::math::photon_clusters::CONVERGENCE_CELLS)^2 cells. At
    /// most 4; above 1 only with the atlas deposit.
    pub error_texels: u32,
    /// Device bytes the traversal may hold (Wyman 2009, section 4.3): the photon slots of
    /// a batch (128 bytes per cluster) and one cluster list per level (16 bytes per
    /// cluster of a batch each), plus the start grid's list. The batch size follows from
    /// it; the result is bitwise the same for any value. The screen deposit also holds a
    /// list of the batch's output photons (another 128 bytes per cluster). Where no
    /// traced level writes slots ([`TraversalSettings::writes_slots`]: the defaults),
    /// the lists alone, and each level is one pass.
    pub max_traversal_bytes: u64,
    /// How the *probe levels* are judged: the levels whose clusters are only refined or
    /// discarded, by whether a photon met a caster (below the finest, and below
    /// `error_from_grid` with the error metric; [`TraversalSettings::is_probe_level`]).
    /// Every choice gives bitwise the same atlas; see [`ProbeLevels`].
    pub probe_levels: ProbeLevels,
    /// The finest level's trace deposits its stored photons itself (`trace_photons`'
    /// adaptive variant with the fused deposit) instead of writing four slots a cluster
    /// for `refine_clusters`: every cluster there is output, and one that would be
    /// discarded holds no stored photon, so the map is bitwise the same either way. Its
    /// clusters then all count as output ([`super::AdaptiveStats::clusters_output`]).
    /// The default (`true`).
    pub fused_finest: bool,
}

impl Default for TraversalSettings {
    fn default() -> Self {
        TraversalSettings {
            metric: AdaptiveMetric::Level,
            relevance: ClusterRelevance::Bounds,
            start_grid: 64,
            error_from_grid: 512,
            error_texels: 1,
            max_traversal_bytes: 64 << 20,
            probe_levels: ProbeLevels::Bounds,
            fused_finest: true,
        }
    }
}

/// How the traversal's device memory is split (from [`TraversalSettings::sizes`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct TraversalSizes {
    /// Clusters one pass traces and judges (its photon slots, where it has them: else the
    /// level's whole list).
    pub pass_clusters: u32,
    /// Entries of the cluster list of each level `1 ..= finest` (index `level - 1`): the
    /// level's every cluster when the lists fit the byte limit beside the passes, else
    /// fewer (a multiple of 4), and what does not fit is output one level up.
    pub list_capacity: Vec<u32>,
    /// Whether some list holds fewer entries than its level has clusters.
    pub lists_capped: bool,
    /// Whether a pass holds photon slots (and a converged list, and the screen target's
    /// output photons): some traced level is judged from its slots
    /// ([`TraversalSettings::writes_slots`]). Without them a level is one pass of its
    /// whole list.
    pub slots: bool,
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

    /// Whether `level` of a pyramid down to `finest` is a probe level: its clusters are
    /// refined or discarded, never output with its own photons (below the finest level,
    /// and below the error metric's first level), so only whether a photon met a caster
    /// counts there.
    pub fn is_probe_level(&self, level: u32, finest: u32) -> bool {
        level < finest && !self.converges_at(level)
    }

    /// Whether clusters of `level` can converge (the error metric, from its first level).
    pub fn converges_at(&self, level: u32) -> bool {
        self.metric == AdaptiveMetric::Error && level >= self.error_from_level()
    }

    /// The level from which the traversal traces, when the bounds seed stands for the
    /// probe levels above it ([`ProbeLevels::Bounds`]) in a pyramid down to `finest`
    /// whose lists are whole (`lists_capped` false): the first level that is not a probe
    /// level, if it is not the start grid. `None`: every level is traced.
    pub fn seed_level(&self, finest: u32, lists_capped: bool) -> Option<u32> {
        if self.probe_levels != ProbeLevels::Bounds
            || self.relevance != ClusterRelevance::Bounds
            || lists_capped
        {
            return None;
        }
        (0..=finest)
            .find(|&l| !self.is_probe_level(l, finest))
            .filter(|&l| l > 0)
    }

    /// Whether a traced level of a pyramid down to `finest` writes photon slots for
    /// `refine_clusters` (with whole lists): every level but a fused finest one does, so
    /// none does where the bounds seed stands for every level above the finest (the
    /// level metric, or the error metric from the finest level on) and the finest level
    /// deposits itself ([`TraversalSettings::fused_finest`]). A plane of a smaller
    /// pyramid then traces its own finest level alone too.
    pub fn writes_slots(&self, finest: u32) -> bool {
        !(self.fused_finest && (finest == 0 || self.seed_level(finest, false) == Some(finest)))
    }

    /// Why no pass judges clusters from slots ([`TraversalSizes::slots`] false): the
    /// frame plan's reason for leaving `refine_clusters` (and the screen target's
    /// `deposit_screen`) out.
    pub const NO_SLOTS_REASON: &'static str =
        "every traced level deposits itself: the bounds seed stands for the levels above the \
         finest (or the start grid is the finest), whose trace deposits each stored photon \
         (fused_finest)";

    /// Clusters of the start grid.
    pub fn start_clusters(&self) -> u64 {
        (self.start_grid as u64 / 2).pow(2)
    }

    /// Clusters of level `level`'s whole grid.
    pub fn dense_clusters(&self, level: u32) -> u64 {
        ((self.start_grid as u64) << level).pow(2) / 4
    }

    /// Bytes of one cluster of a pass: its slots, its converged-list entry and (`screen`)
    /// its four output photons.
    fn pass_bytes_per_cluster(screen: bool) -> u64 {
        let outputs = if screen { SLOT_BYTES_PER_CLUSTER } else { 0 };
        SLOT_BYTES_PER_CLUSTER + LIST_BYTES_PER_ENTRY + outputs
    }

    /// Bytes of the lists of levels `1 ..= finest` holding every cluster of their level.
    pub fn full_list_bytes(&self, finest: u32) -> u64 {
        (1..=finest)
            .map(|l| LIST_BYTES_PER_ENTRY * self.dense_clusters(l))
            .sum()
    }

    /// The byte limit at which passes hold `clusters` clusters and every list is whole
    /// ([`TraversalSettings::sizes`] inverted).
    pub fn bytes_for_pass(&self, finest: u32, screen: bool, clusters: u64) -> u64 {
        4 * self.start_clusters()
            + self.full_list_bytes(finest)
            + clusters * Self::pass_bytes_per_cluster(screen)
    }

    /// The smallest limit the traversal runs under: one cluster a pass, four entries a
    /// list.
    pub fn min_bytes(&self, finest: u32, screen: bool) -> u64 {
        4 * self.start_clusters()
            + Self::pass_bytes_per_cluster(screen)
            + 4 * LIST_BYTES_PER_ENTRY * finest as u64
    }

    /// The split of `max_traversal_bytes` for pyramids down to level `finest`, on a device
    /// whose largest buffer holds `max_buffer_bytes` ([`crate::backend::Capabilities`]):
    /// whole lists when they fit beside passes of at least `1 / MAX_PASSES_PER_LEVEL` of
    /// the largest level, the passes then as large as the rest allows; else half of the
    /// limit for the passes and the other half shared by the lists. No pass's slots (nor
    /// the screen target's output photons) and no list outgrow the largest buffer: the
    /// passes are then smaller, and a level whose whole list would not fit one buffer
    /// caps its list.
    pub fn sizes(&self, finest: u32, screen: bool, max_buffer_bytes: u64) -> TraversalSizes {
        let largest = self.dense_clusters(finest).max(self.start_clusters());
        let fixed = 4 * self.start_clusters();
        let per = Self::pass_bytes_per_cluster(screen);
        let lists = self.full_list_bytes(finest);
        let budget = self.max_traversal_bytes;
        let cap = |c: u64| c.min(u32::MAX as u64 / 4) as u32;
        // the most clusters one buffer holds the slots of, and the most entries of a list
        let buffer_clusters = (max_buffer_bytes / SLOT_BYTES_PER_CLUSTER).max(1);
        let list_entries = (max_buffer_bytes / LIST_BYTES_PER_ENTRY / 4 * 4).max(4);
        let min_pass = largest.div_ceil(MAX_PASSES_PER_LEVEL).min(buffer_clusters);
        let lists_fit = self.dense_clusters(finest) <= list_entries;
        let whole = || (1..=finest).map(|l| cap(self.dense_clusters(l))).collect();
        // the finest level alone, deposited by its trace: a pass holds nothing per
        // cluster, so a level is one pass (the fewest launches)
        if !self.writes_slots(finest) && lists_fit && budget >= fixed + lists {
            return TraversalSizes {
                pass_clusters: cap(largest),
                list_capacity: whole(),
                lists_capped: false,
                slots: false,
            };
        }
        if lists_fit && budget >= fixed + lists + min_pass * per {
            let c = ((budget - fixed - lists) / per)
                .clamp(min_pass, largest)
                .min(buffer_clusters);
            return TraversalSizes {
                pass_clusters: cap(c),
                list_capacity: whole(),
                lists_capped: false,
                slots: true,
            };
        }
        let rest = budget.saturating_sub(fixed);
        let c = (rest / 2 / per)
            .clamp(min_pass.min(largest), largest)
            .min(buffer_clusters)
            .max(1);
        let share = rest.saturating_sub(c * per) / (LIST_BYTES_PER_ENTRY * finest.max(1) as u64);
        let list_capacity: Vec<u32> = (1..=finest)
            .map(|l| {
                let n = self
                    .dense_clusters(l)
                    .min(share)
                    .min(MAX_PASSES_PER_LEVEL * c)
                    .min(list_entries);
                cap((n / 4 * 4).max(4))
            })
            .collect();
        let lists_capped =
            (1..=finest).any(|l| (list_capacity[l as usize - 1] as u64) < self.dense_clusters(l));
        TraversalSizes {
            pass_clusters: cap(c),
            list_capacity,
            lists_capped,
            slots: true,
        }
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
    /// The atlas's centroid sums.
    pub centroids: Buf<u32>,
    /// The atlas's reach mask (one bit a scene triangle). Only the fused finest level's
    /// deposit sets bits (`refine_clusters` sets none), so the mask is partial and
    /// AdaptiveCaustics does not read it.
    pub triangle_reach: Buf<u32>,
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

/// Where the traversal's output photons go (Wyman 2009's "splat into the caustic map", for
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
    /// `dispersion_mode` of the kernels (`frame.dispersion`).
    pub dispersion_mode: u32,
    /// The casters' balls its first segment is tested against
    /// ([`crate::device::caster_spheres`]).
    pub caster_spheres: crate::device::caster_spheres::CasterSpheres,
}

/// One light view plane of a frame's traversal and its seeds.
#[derive(Clone, Copy, Debug)]
pub struct PlaneSeeds {
    /// The light's index in the scene.
    pub light: u32,
    /// The plane.
    pub plane: LightViewPlane,
    /// The pass's seed of the plane (its photons' random numbers).
    pub seed: u32,
    /// The first pass's seed of the plane, and this pass's stratum: the passes of an
    /// accumulation stratify each cell together (`TraceParams::jitter_seed`, `stratum`).
    pub jitter_seed: u32,
    /// See `jitter_seed`.
    pub stratum: u32,
}

/// The traversal's device buffers and sizes.
#[derive(Clone, Debug)]
pub struct Traversal {
    /// The stop metric, start grid and error level.
    pub settings: TraversalSettings,
    /// Deepest level any plane reaches.
    pub finest: u32,
    /// The lists' capacities and whether they are capped.
    pub sizes: TraversalSizes,
    level0: Buf<u32>,
    /// `[0]`: the start grid's clusters (level 0's list length).
    level0_length: Buf<u32>,
    /// The casters' bounding boxes (world space), one per caster object.
    caster_boxes: Vec<Aabb>,
    /// Their projections on the current plane ([`caster_rects`]).
    rects: Buf<[f32; 4]>,
    /// The cluster lists of levels `1 ..= finest`.
    lists: Vec<Buf<u32>>,
    /// Per plane of a frame, per level: [`cluster_count`] words (word 0: the next level's
    /// list length), read back at the frame's end (made with the traversal: a buffer
    /// is read back only after the recording that made it).
    counts: Vec<Vec<Buf<u32>>>,
    no_children: Buf<u32>,
    converged: Buf<u32>,
    converged_count: Buf<u32>,
    no_converged: Buf<u32>,
    no_converged_count: Buf<u32>,
    slots: Buf<Photon>,
    /// Per level, per pass: the pass's clusters at most and its `dispatch_args` rows (its
    /// trace, its refinement).
    tables: Vec<Vec<(u32, Buf<[u32; 4]>)>>,
    /// The rows of a pass over the converged clusters (from entry 0).
    converged_rows: Buf<[u32; 4]>,
    /// The records the passes' launches read (trace, refinement; then the converged
    /// clusters' trace and refinement).
    args: Buf<u32>,
    resample_args: Buf<u32>,
    /// Counters of the output (deposited) photons.
    pub output_counters: Buf<u32>,
    /// Counters of the probe levels' photons (their path ends after one segment).
    probe_counters: Buf<u32>,
    /// Per plane of a frame: counters of the fused finest level's photons (their path
    /// ends, and the deposit's accounting of the stored ones).
    fused_counters: Vec<Buf<u32>>,
    /// The screen target's output list (four slots per cluster of a pass; one unused
    /// entry with the atlas target or where no level writes slots) and its count.
    outputs: Buf<Photon>,
    output_count: Buf<u32>,
    /// Stand-ins for `refine_clusters`' atlas bindings with the screen target.
    no_atlas: Option<(Buf<u32>, Buf<AtlasTileTexel>, PhotonMapPlanes)>,
}

/// Photon counter words as read back ([`counter`]; missing ones 0), the 64-bit ones
/// (rays, stored flux) joined at their first word (the second then 0), so that
/// counters of several buffers add without a carry.
fn wide_counters(c: &[u32]) -> [u64; counter::WORDS] {
    let word = |i: usize| c.get(i).copied().unwrap_or(0);
    let mut w: [u64; counter::WORDS] = std::array::from_fn(|i| word(i) as u64);
    for i in [
        counter::RAYS,
        counter::STORED_FLUX,
        counter::STORED_FLUX + 2,
        counter::STORED_FLUX + 4,
    ] {
        w[i] = crate::math::fixed_point::join_u64([word(i), word(i + 1)]);
        w[i + 1] = 0;
    }
    w
}

/// The `dispatch_args` rows of a pass from list entry `first` of `bound` clusters: its
/// trace (four photons a cluster) and its refinement (one thread a cluster), both
/// reading the list length at word 0.
fn pass_rows(first: u32, bound: u32) -> [[u32; 4]; 2] {
    [[first, bound, 4, 0], [first, bound, 1, 0]]
}

/// One level of one plane's traversal as recorded: where its counts come back and what
/// bounds them.
#[derive(Clone, Debug)]
struct LevelRead {
    /// Index of the level's counts among the frame's readbacks.
    counts: usize,
    /// Clusters of the level's list: the start grid's at level 0, else the list's
    /// capacity (its length word may count appends past it).
    capacity: u64,
    /// Capacity of the next level's list (0 at the plane's finest).
    children_capacity: u64,
    /// A probe level the bounds seed stood for (nothing traced; the last one's `CHILDREN`
    /// word holds the seeded list's length).
    seeded: bool,
    /// Index of the plane's fused-level counters among the frame's readbacks, at a level
    /// whose trace deposited (no `refine_clusters`: its counts stay clear).
    fused: Option<usize>,
}

/// What a frame's traversal reads back at the frame's end and how it becomes
/// [`AdaptiveStats`] (a [`FrameEnd`]).
#[derive(Clone, Debug)]
pub struct TraversalReadback {
    planes: Vec<Vec<LevelRead>>,
    output_counters: usize,
    probe_counters: usize,
    flux_quantum: f32,
    pass_clusters: u64,
    dense_equivalent: u64,
    /// The traversal's kernels: (index among the frame's kernel steps, level, name).
    kernels: Vec<(usize, u32, &'static str)>,
}

impl FrameEnd for TraversalReadback {
    /// Puts the traversal's counts and the output photons' accounting into `stats`:
    /// stored, deposited and their flux are the output photons (the traced ones that
    /// were refined instead are not part of the map), emitted the photons traced. Call
    /// after the trace counters went in (`photons_traced_stored` takes their stored
    /// photons). A level's time is its kernels' when `times` holds them in order.
    fn apply(&self, readbacks: &[Vec<u8>], times: &[PassTime], stats: &mut FrameStats) {
        let words = |k: usize| -> Vec<u32> {
            readbacks
                .get(k)
                .map(|b| bytemuck::pod_collect_to_vec(b))
                .unwrap_or_default()
        };
        let mut a = AdaptiveStats {
            dense_equivalent_photons: self.dense_equivalent,
            ..Default::default()
        };
        let levels = self.planes.iter().map(Vec::len).max().unwrap_or(0);
        a.photons_per_level.resize(levels, 0);
        a.photons_output_per_level.resize(levels, 0);
        a.ms_per_level.resize(levels, 0.0);
        a.ms_per_level_kernel.resize(levels, Default::default());
        // the fused levels' counters (path ends and deposit of their stored photons)
        let mut fused = [0u64; counter::WORDS];
        for plane in &self.planes {
            let mut length = plane.first().map_or(0, |l| l.capacity);
            for l in plane.iter().enumerate() {
                let (level, read) = l;
                let c = words(read.counts);
                let w = |i: usize| c.get(i).copied().unwrap_or(0) as u64;
                if read.seeded {
                    a.levels_seeded += 1;
                    a.clusters_seeded += w(cluster_count::CHILDREN);
                    length = w(cluster_count::CHILDREN);
                    continue;
                }
                let taken = length.min(read.capacity);
                let resampled = w(cluster_count::CONVERGED) + w(cluster_count::OVERFLOW);
                let children = w(cluster_count::CHILDREN).min(read.children_capacity);
                a.clusters_refined += children / 4;
                a.clusters_output += w(cluster_count::OUTPUT);
                a.clusters_discarded += w(cluster_count::DISCARDED);
                a.clusters_converged += w(cluster_count::CONVERGED);
                a.clusters_overflowed += w(cluster_count::OVERFLOW);
                let traced = 4 * (taken + resampled);
                a.photons_processed += traced;
                a.photons_per_level[level] += traced;
                a.photons_output_per_level[level] += w(cluster_count::OUTPUT_PHOTONS);
                if let Some(f) = read.fused.map(|i| wide_counters(&words(i))) {
                    // no refinement: every traced cluster is output
                    a.clusters_output += taken;
                    a.photons_output_per_level[level] += f[counter::STORED];
                    fused.iter_mut().zip(f).for_each(|(s, w)| *s += w);
                }
                let passes = taken.div_ceil(self.pass_clusters.max(1))
                    + resampled.div_ceil(self.pass_clusters.max(1));
                a.steps += passes as u32;
                stats.batches += passes as u32;
                length = w(cluster_count::CHILDREN);
            }
        }
        let in_order = self
            .kernels
            .iter()
            .all(|&(i, _, name)| times.get(i).is_some_and(|t| t.kernel == name));
        if in_order {
            for &(i, level, name) in &self.kernels {
                let ms = times[i].seconds * 1e3;
                a.ms_per_level[level as usize] += ms;
                *a.ms_per_level_kernel[level as usize]
                    .entry(name.to_string())
                    .or_default() += ms;
            }
        }
        let o = words(self.output_counters);
        if o.len() >= counter::WORDS {
            // the output photons: refined clusters' and the fused levels'
            let mut out = wide_counters(&o);
            out.iter_mut().zip(fused).for_each(|(s, w)| *s += w);
            a.photons_traced_stored = stats.photons_stored + fused[counter::STORED];
            stats.photons_stored = out[counter::STORED];
            stats.photons_deposited = out[counter::DEPOSITED];
            stats.discarded.off_screen = out[counter::OFF_SCREEN];
            stats.discarded.depth_mismatch = out[counter::DEPTH_MISMATCH];
            stats.fixed_point_underflow = out[counter::UNDERFLOW];
            stats.fixed_point_saturated = out[counter::SATURATED];
            for ch in 0..3 {
                stats.stored_flux[ch] =
                    out[counter::STORED_FLUX + 2 * ch] as f64 * self.flux_quantum as f64;
            }
            // the fused levels' other path ends, as the trace counters' of other levels
            stats.discarded.no_specular += fused[counter::NO_SPECULAR];
            stats.discarded.escaped += fused[counter::ESCAPED];
            stats.discarded.negligible_power += fused[counter::NEGLIGIBLE];
            stats.discarded.bounce_limit += fused[counter::BOUNCE_LIMIT];
            stats.photon_splits += fused[counter::SPLITS];
            stats.photon_rays_traced += fused[counter::RAYS];
        }
        // probe photons: their misses are path ends like any other; those that met a
        // caster ended at their one segment (`probes_met_caster`)
        let p = words(self.probe_counters);
        if p.len() >= counter::WORDS {
            let w = |i: usize| p[i] as u64;
            stats.discarded.no_specular += w(counter::NO_SPECULAR);
            stats.discarded.escaped += w(counter::ESCAPED);
            stats.discarded.negligible_power += w(counter::NEGLIGIBLE);
            stats.photon_splits += w(counter::SPLITS);
            stats.photon_rays_traced +=
                crate::math::fixed_point::join_u64([p[counter::RAYS], p[counter::RAYS + 1]]);
            a.probes_met_caster = w(counter::BOUNCE_LIMIT) + w(counter::STORED);
        }
        stats.photons_emitted = a.photons_processed;
        a.put(stats);
    }
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

    /// Marks in `plan` the passes this traversal never launches: with no slots,
    /// `refine_clusters` and `deposit_screen` ([`TraversalSettings::NO_SLOTS_REASON`]).
    pub fn leave_out_unused_passes(&self, plan: &mut crate::frame::plan::FramePlan) {
        if self.sizes.slots {
            return;
        }
        for p in plan
            .passes
            .iter_mut()
            .filter(|p| p.runs && (p.name == "refine_clusters" || p.name == "deposit_screen"))
        {
            p.runs = false;
            p.reason = TraversalSettings::NO_SLOTS_REASON.into();
        }
    }

    /// Records the creation of the traversal's buffers for `planes` planes a frame down
    /// to level `finest`, for the atlas target or (`screen`) the screen target, on a
    /// device whose largest buffer holds `max_buffer_bytes`.
    pub fn record(
        rec: &mut Recording,
        settings: &TraversalSettings,
        (planes, finest): (usize, u32),
        caster_boxes: &[Aabb],
        (screen, max_buffer_bytes): (bool, u64),
    ) -> Traversal {
        let sizes = settings.sizes(finest, screen, max_buffer_bytes);
        let c = sizes.pass_clusters;
        // what a pass holds per cluster, where a level writes slots (else stand-ins)
        let per_cluster = |n: u32| if sizes.slots { n * c } else { 1 };
        let start = settings.start_clusters() as u32;
        let ids: Vec<u32> = (0..start).collect();
        // per level, per pass: its rows (the last pass of a level takes what is left of
        // the list's capacity, so that no pass reads past it)
        let tables: Vec<Vec<(u32, Buf<[u32; 4]>)>> = std::iter::once(start)
            .chain(sizes.list_capacity.iter().copied())
            .map(|n| {
                (0..n.div_ceil(c))
                    .map(|k| {
                        let bound = c.min(n - k * c);
                        let rows = pass_rows(k * c, bound);
                        (bound, rec.upload(&rows, "adaptive pass dispatch rows"))
                    })
                    .collect()
            })
            .collect();
        let converged_rows = rec.upload(&pass_rows(0, c), "adaptive converged dispatch rows");
        let records = 2 * DISPATCH_RECORD_WORDS as u32;
        Traversal {
            settings: *settings,
            finest,
            level0: rec.upload(&ids, "adaptive start-grid clusters"),
            level0_length: rec.upload(&[start], "adaptive start-grid length"),
            caster_boxes: caster_boxes.to_vec(),
            rects: rec.create(
                caster_boxes.len().max(1) as u32,
                "adaptive caster rectangles",
            ),
            lists: sizes
                .list_capacity
                .iter()
                .map(|&n| rec.create(n, "adaptive cluster list"))
                .collect(),
            counts: (0..planes.max(1))
                .map(|_| {
                    (0..=finest)
                        .map(|_| rec.create(cluster_count::WORDS as u32, "adaptive cluster counts"))
                        .collect()
                })
                .collect(),
            no_children: rec.create(1, "adaptive finest-level child list"),
            converged: rec.create(per_cluster(1), "adaptive converged clusters"),
            converged_count: rec.create(1, "adaptive converged count"),
            no_converged: rec.create(1, "adaptive resampled converged list"),
            no_converged_count: rec.create(1, "adaptive resampled converged count"),
            slots: rec.create(per_cluster(4), "adaptive photon slots"),
            tables,
            converged_rows,
            args: rec.create(records, "adaptive dispatch records"),
            resample_args: rec.create(records, "adaptive converged dispatch records"),
            output_counters: rec.create(counter::WORDS as u32, "adaptive output counters"),
            probe_counters: rec.create(counter::WORDS as u32, "adaptive probe counters"),
            fused_counters: (0..planes.max(1))
                .map(|_| rec.create(counter::WORDS as u32, "adaptive fused-level counters"))
                .collect(),
            outputs: rec.create(
                if screen { per_cluster(4) } else { 1 },
                "adaptive output photons",
            ),
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
            sizes,
        }
    }

    /// Records the traversal of every plane of a frame (`planes`: light, plane, seed)
    /// into `frame`, with no wait: each level's passes read their cluster counts on the
    /// device (`dispatch_args` and indirect launches), and the counts come back at the
    /// frame's end into [`AdaptiveStats`]. Each plane's `start_grid * 2^finest` side must
    /// lie in the traversal's pyramid. Output photons go into `target` (the target this
    /// traversal was recorded for).
    pub fn record_frame(
        &self,
        frame: &mut FrameBuilder,
        scene: SceneArgs,
        variant: TraceVariant,
        target: &DepositTarget,
        planes: &[PlaneSeeds],
        optics: PhotonOptics,
    ) -> Result<(), Error> {
        let s = self.settings;
        frame.rec().clear(self.output_counters);
        frame.rec().clear(self.probe_counters);
        let mut read = TraversalReadback {
            planes: Vec::new(),
            output_counters: 0,
            probe_counters: 0,
            flux_quantum: target.quanta().0,
            pass_clusters: self.sizes.pass_clusters as u64,
            dense_equivalent: 0,
            kernels: Vec::new(),
        };
        for (k, seeds) in planes.iter().enumerate() {
            let (light, plane, plane_seed) = (&seeds.light, &seeds.plane, &seeds.seed);
            let finest = (plane.resolution.0 / s.start_grid).max(1).ilog2();
            if finest > self.finest || (s.start_grid << finest) != plane.resolution.0 {
                return Err(Error::InvalidParameter(format!(
                    "adaptive plane of {}x{} texels outside the traversal's pyramid",
                    plane.resolution.0, plane.resolution.1
                )));
            }
            if k >= self.counts.len() {
                return Err(Error::InvalidParameter(format!(
                    "adaptive traversal made for {} planes, run for {}",
                    self.counts.len(),
                    planes.len()
                )));
            }
            read.dense_equivalent += plane.texels();
            let mut rects = caster_rects(plane, &self.caster_boxes);
            rects.resize(self.rects.len as usize, EMPTY_RECT);
            frame
                .rec()
                .update(self.rects, &rects, "adaptive caster rectangles")?;
            let mut levels = Vec::new();
            let seed_level = s.seed_level(finest, self.sizes.lists_capped);
            for level in 0..=finest {
                let counts = self.counts[k][level as usize];
                frame.rec().clear(counts);
                if let Some(p) = seed_level.filter(|&p| level < p) {
                    levels.push(LevelRead {
                        counts: frame.read_at_end(counts),
                        capacity: 0,
                        children_capacity: 0,
                        seeded: true,
                        fused: None,
                    });
                    if level + 1 == p {
                        self.record_seed(frame, p, counts, &rects, &mut read);
                    }
                    continue;
                }
                let (list, length, capacity) = match level {
                    0 => (self.level0, self.level0_length, s.start_clusters()),
                    l => (
                        self.lists[l as usize - 1],
                        self.counts[k][l as usize - 1],
                        self.sizes.list_capacity[l as usize - 1] as u64,
                    ),
                };
                let (children, children_capacity) = if level < finest {
                    let n = self.sizes.list_capacity[level as usize];
                    (self.lists[level as usize], n)
                } else {
                    (self.no_children, 0)
                };
                // the finest level outputs every cluster: its trace may deposit
                let fused = (s.fused_finest && level == finest).then_some(self.fused_counters[k]);
                if let Some(c) = fused {
                    frame.rec().clear(c);
                }
                levels.push(LevelRead {
                    counts: frame.read_at_end(counts),
                    capacity,
                    children_capacity: children_capacity as u64,
                    seeded: false,
                    fused: fused.map(|c| frame.read_at_end(c)),
                });
                let c = self.sizes.pass_clusters;
                // converged clusters (the error metric, from its level) and overflowed
                // ones (capped lists) are output at their level from fresh photons; no
                // pass is recorded where neither can occur
                let resample = level < finest && (s.converges_at(level) || self.sizes.lists_capped);
                let probe =
                    s.probe_levels != ProbeLevels::Traced && s.is_probe_level(level, finest);
                for (pass, &(bound, rows)) in self.tables[level as usize].iter().enumerate() {
                    let step = PassArgs {
                        level,
                        grid: s.start_grid << level,
                        seed: cluster_level_seed(*plane_seed, level, finest),
                        jitter_seed: cluster_level_seed(seeds.jitter_seed, level, finest),
                        stratum: seeds.stratum,
                        finest,
                        metric: s.metric as u32,
                        list: (list, length, pass as u32 * c),
                        bound,
                        rows,
                        args: self.args,
                        children: (children, children_capacity),
                        converged: (self.converged, self.converged_count),
                        counts,
                        probe,
                        fused,
                    };
                    if resample {
                        frame.rec().clear(self.converged_count);
                    }
                    self.record_pass(
                        frame,
                        scene,
                        variant,
                        target,
                        (*light, plane),
                        optics,
                        &step,
                        &mut read,
                    )?;
                    if resample {
                        let again = PassArgs {
                            seed: cluster_resample_seed(*plane_seed, level),
                            jitter_seed: cluster_resample_seed(seeds.jitter_seed, level),
                            finest: level,
                            metric: cluster_metric::LEVEL,
                            list: (self.converged, self.converged_count, 0),
                            bound: c,
                            rows: self.converged_rows,
                            args: self.resample_args,
                            children: (self.no_children, 0),
                            converged: (self.no_converged, self.no_converged_count),
                            probe: false,
                            fused: None,
                            ..step
                        };
                        self.record_pass(
                            frame,
                            scene,
                            variant,
                            target,
                            (*light, plane),
                            optics,
                            &again,
                            &mut read,
                        )?;
                    }
                }
            }
            read.planes.push(levels);
            frame.push(Recording::new(), plane.texels());
        }
        read.output_counters = frame.read_at_end(self.output_counters);
        read.probe_counters = frame.read_at_end(self.probe_counters);
        frame.end_read(EndRead::Own(std::sync::Arc::new(read)));
        Ok(())
    }
}

impl Traversal {
    /// Records the bounds seed of level `level`'s list ([`ProbeLevels::Bounds`]): its
    /// length is word `CHILDREN` of `length` (the level above's counts, cleared), its
    /// clusters those of the window of `rects` ([`seed_window`]) that overlap one; nothing
    /// is launched when no rectangle reaches the plane.
    fn record_seed(
        &self,
        frame: &mut FrameBuilder,
        level: u32,
        length: Buf<u32>,
        rects: &[[f32; 4]],
        read: &mut TraversalReadback,
    ) {
        let grid_w = self.settings.start_grid << level;
        let rects = &rects[..self.caster_boxes.len().min(rects.len())];
        let [first_x, first_y, window_w, window_h] = seed_window(rects, grid_w);
        if window_w == 0 || window_h == 0 {
            return;
        }
        read.kernels
            .push((frame.kernel_index(), level - 1, "seed_clusters"));
        frame.rec().kernel(SeedClusters {
            params: SeedParams {
                grid_w,
                first_x,
                first_y,
                window_w,
                window_h,
                rect_count: rects.len() as u32,
                capacity: self.sizes.list_capacity[level as usize - 1],
                _pad: 0,
            },
            caster_rects: self.rects,
            list: self.lists[level as usize - 1],
            list_length: length,
        });
    }
}

/// One pass's dispatch arguments.
#[derive(Clone, Copy)]
struct PassArgs {
    level: u32,
    grid: u32,
    seed: u32,
    /// The jitter's seed and stratum (an accumulation's passes stratify each cell
    /// together).
    jitter_seed: u32,
    stratum: u32,
    /// The level at which clusters are output (the plane's finest; the pass's own level
    /// when outputting converged clusters from fresh photons).
    finest: u32,
    metric: u32,
    /// The cluster list, the buffer whose word 0 is its length, and the pass's first
    /// entry.
    list: (Buf<u32>, Buf<u32>, u32),
    /// Most clusters the pass takes.
    bound: u32,
    /// The `dispatch_args` rows of the pass and the records they write.
    rows: Buf<[u32; 4]>,
    args: Buf<u32>,
    /// The child list and its capacity.
    children: (Buf<u32>, u32),
    /// The converged list and its count.
    converged: (Buf<u32>, Buf<u32>),
    /// The level's cluster counts.
    counts: Buf<u32>,
    /// Trace each photon's first segment only, into the probe counters.
    probe: bool,
    /// Deposit each stored photon in the trace, with these counters (a level whose
    /// every cluster is output), instead of slots and `refine_clusters`.
    fused: Option<Buf<u32>>,
}

impl Traversal {
    /// Records one pass: `dispatch_args` (the pass's live clusters on the device), then
    /// `trace_photons` and `refine_clusters` launched from its records (and, for the
    /// screen target, `deposit_screen` of the listed output photons).
    #[allow(clippy::too_many_arguments)]
    fn record_pass(
        &self,
        frame: &mut FrameBuilder,
        scene: SceneArgs,
        variant: TraceVariant,
        target: &DepositTarget,
        (light, plane): (u32, &LightViewPlane),
        optics: PhotonOptics,
        a: &PassArgs,
        read: &mut TraversalReadback,
    ) -> Result<(), Error> {
        let s = &self.settings;
        let at_level = LightViewPlane {
            resolution: (a.grid, a.grid),
            ..*plane
        };
        let (list, length, first) = a.list;
        let (children, capacity) = a.children;
        let c = a.bound;
        let (flux_quantum, hit_distance_quantum) = target.quanta();
        let (atlas_width, triangle_tiles, tiles, (atlas, centroids), camera, kind) =
            match (target, self.no_atlas) {
                (DepositTarget::Atlas(a), _) => (
                    a.atlas_width,
                    a.triangle_tiles,
                    a.tiles,
                    (a.sums, a.centroids),
                    GpuCamera::default(),
                    cluster_target::ATLAS,
                ),
                // the screen target binds no atlas: its centroids alias the counters
                (DepositTarget::Screen(sc), Some((tt, tl, planes))) => (
                    1,
                    tt,
                    tl,
                    (planes, self.output_counters),
                    sc.deposit.camera,
                    cluster_target::SCREEN,
                ),
                (DepositTarget::Screen(_), None) => {
                    return Err(Error::InvalidParameter(
                        "adaptive traversal recorded for the atlas, run for the screen".into(),
                    ))
                }
            };
        let mut kernel = |frame: &mut FrameBuilder, k: crate::kernels::Kernel| {
            read.kernels.push((frame.kernel_index(), a.level, k.name()));
            frame.rec().kernel(k);
        };
        kernel(
            frame,
            DispatchArgs {
                table: a.rows,
                counts: length,
                args: a.args,
            }
            .into(),
        );
        if let DepositTarget::Screen(_) = target {
            frame.rec().clear(self.output_count);
        }
        let record = |record| {
            Some(DispatchRecord {
                args: a.args,
                record,
            })
        };
        // the fused level's deposit: the target's sums, as the refinement adds them
        let deposit = a.fused.map(|_| match target {
            DepositTarget::Atlas(t) => FusedDeposit::Atlas(AtlasDeposit {
                params: AtlasParams {
                    width: t.atlas_width,
                    height: t.atlas_width,
                    flux_quantum,
                    hit_distance_quantum,
                    photon_capacity: 1,
                    gather_width: 1,
                    _pad: [0; 2],
                },
                triangle_tiles: t.triangle_tiles,
                tiles: t.tiles,
                triangle_reach: t.triangle_reach,
                sums: t.sums,
                centroids: t.centroids,
            }),
            DepositTarget::Screen(sc) => FusedDeposit::Screen(ScreenDeposit {
                params: sc.deposit,
                gbuffer: sc.gbuffer,
                photon_map: sc.photon_map,
            }),
        });
        kernel(
            frame,
            TracePhotons {
                scene,
                variant: TraceVariant {
                    fused_deposit: deposit.is_some(),
                    ..variant
                },
                params: TraceParams {
                    fresnel_model: optics.fresnel_model,
                    dispersion_mode: optics.dispersion_mode,
                    caster_sphere_count: optics.caster_spheres.count,
                    caster_spheres: optics.caster_spheres.spheres,
                    jitter_seed: a.jitter_seed,
                    stratum: a.stratum,
                    ..at_level.trace_params(
                        light,
                        (first, 4 * c),
                        a.seed,
                        if a.probe { 1 } else { optics.max_bounces },
                        optics.min_relative_power,
                        flux_quantum,
                    )
                },
                photons: self.slots,
                photon_count: length,
                counters: match (a.probe, a.fused) {
                    (true, _) => self.probe_counters,
                    (false, Some(c)) => c,
                    (false, None) => target.trace_counters(),
                },
                clusters: Some(ClusterBatch {
                    list,
                    dispatch: record(0),
                }),
                deposit,
            }
            .into(),
        );
        if a.fused.is_some() {
            return Ok(());
        }
        kernel(
            frame,
            RefineClusters {
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
                    count: c,
                    children_capacity: capacity,
                    relevance: s.relevance.kernel_value(),
                    rect_count: self.caster_boxes.len() as u32,
                    deposit_target: kind,
                    error_texels: s.error_texels,
                    _pad: 0,
                    camera,
                },
                clusters: list,
                list_length: length,
                caster_rects: self.rects,
                photons: self.slots,
                triangle_tiles,
                tiles,
                children,
                converged: a.converged.0,
                converged_count: a.converged.1,
                cluster_counts: a.counts,
                counters: self.output_counters,
                atlas,
                output_photons: self.outputs,
                output_count: self.output_count,
                dispatch: record(1),
                centroids,
            }
            .into(),
        );
        if let DepositTarget::Screen(sc) = target {
            kernel(
                frame,
                DepositScreen {
                    params: DepositParams {
                        photon_capacity: self.outputs.len,
                        ..sc.deposit
                    },
                    gbuffer: sc.gbuffer,
                    photons: self.outputs,
                    photon_count: self.output_count,
                    counters: self.output_counters,
                    photon_map: sc.photon_map,
                }
                .into(),
            );
        }
        Ok(())
    }
}

/// Fits the planes of `emission` to the pyramid: each plane's side becomes
/// `start_grid * 2^k` (the nearest such size to the dense plane's; a single plane's is
/// `photons_w` exactly, a cube face's `photons_w / sqrt 6` rounded to the pyramid), and
/// the flux quantum follows the coarsest photons that can be output (the error metric's
/// first level, else the finest), so that they cannot saturate the fixed point.
pub fn fit_planes(emission: &mut ViewPlanes, s: &TraversalSettings, dispersion_gain: f32) {
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
    emission.flux_quantum =
        ViewPlanes::quantum_for(&emission.planes, dispersion_gain, coarsest_output);
}

/// The window `[first_x, first_y, width, height]` (clusters) of a `grid_w` grid that
/// holds every cluster overlapping one of `rects`
/// ([`cluster_overlaps_rect`](crate::math::photon_clusters::cluster_overlaps_rect)), for
/// `seed_clusters`: the rectangles' bounds in cluster units, computed in f64 and widened
/// by a cluster on every side (the kernel's own test decides; the window only saves
/// threads). Empty (`width` 0) when no rectangle reaches the plane; the whole grid when a
/// bound is not a number.
pub fn seed_window(rects: &[[f32; 4]], grid_w: u32) -> [u32; 4] {
    let last = ((grid_w / 2).max(1) - 1) as f64;
    // a cluster (cx, cy) spans x in [cx, cx + 1] * 4 / grid_w - 1 and y in
    // 1 - [cy + 1, cy] * 4 / grid_w; it overlaps (x0, y0, x1, y1) when its x-span starts
    // at or before x1 and ends at or after x0 (and alike in y), whatever the corners' order
    let scale = grid_w as f64 / 4.0;
    let mut lo = [f64::INFINITY; 2];
    let mut hi = [f64::NEG_INFINITY; 2];
    for r in rects {
        let r = r.map(f64::from);
        if r.iter().any(|x| x.is_nan()) {
            return [0, 0, last as u32 + 1, last as u32 + 1];
        }
        let x = (
            ((r[0] + 1.0) * scale - 1.0).floor() - 1.0,
            ((r[2] + 1.0) * scale).ceil() + 1.0,
        );
        let y = (
            ((1.0 - r[3]) * scale - 1.0).floor() - 1.0,
            ((1.0 - r[1]) * scale).ceil() + 1.0,
        );
        let inside = |(a, b): (f64, f64)| a <= b && b >= 0.0 && a <= last;
        if inside(x) && inside(y) {
            lo = [lo[0].min(x.0), lo[1].min(y.0)];
            hi = [hi[0].max(x.1), hi[1].max(y.1)];
        }
    }
    if lo[0] > hi[0] {
        return [0, 0, 0, 0];
    }
    let clamp = |v: f64| v.clamp(0.0, last) as u32;
    let (x0, y0, x1, y1) = (clamp(lo[0]), clamp(lo[1]), clamp(hi[0]), clamp(hi[1]));
    [x0, y0, x1 - x0 + 1, y1 - y0 + 1]
}

/// A rectangle no cluster overlaps.
pub const EMPTY_RECT: [f32; 4] = [2.0, 2.0, -2.0, -2.0];

/// The projections of `boxes` on `plane`, as `(x0, y0, x1, y1)` in its normalised device
/// coordinates ([`crate::math::photon_clusters::cluster_overlaps_rect`]), conservative: a
/// photon whose ray meets a box starts inside the box's rectangle. Perspective: the
/// bounding rectangle of the corners' central projections, the whole plane when a corner
/// lies on or behind the light's side plane, nothing when every corner does;
/// orthographic: of their parallel projections, the whole plane when a corner lies behind
/// it, nothing when every corner does. Computed in f64 and widened by 1e-5 of the plane
/// and of the bounds (far above the rounding of the kernels' ray setup, ~1e-7) and by the
/// f32 rounding of positions as far from the origin as the light and the box (16 ulps of
/// the largest coordinate, seen from the nearest corner), so that a scene far from the
/// origin, whose rays and triangles the kernels place only to that resolution, loses no
/// photon that meets a caster: the bounds seed keeps only clusters that overlap.
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
            let mut z_min = f64::INFINITY;
            let mut reach = o.abs().max_element();
            for c in b.corners() {
                reach = reach.max(c.as_dvec3().abs().max_element());
                let d = c.as_dvec3() - o;
                let z = d.dot(w);
                if z <= 0.0 {
                    behind += 1;
                    continue;
                }
                z_min = z_min.min(z);
                let s = if perspective { z } else { 1.0 };
                let (x, y) = (d.dot(u) / (s * hx), d.dot(v) / (s * hy));
                r = [r[0].min(x), r[1].min(y), r[2].max(x), r[3].max(y)];
            }
            if behind == 8 {
                return EMPTY_RECT;
            }
            if behind > 0 {
                return [-1e30, -1e30, 1e30, 1e30];
            }
            // 16 ulps of the largest coordinate, in the plane's units at the nearest corner
            let rounding = 16.0 * f32::EPSILON as f64 * reach;
            let seen_at = if perspective { z_min } else { 1.0 };
            let absolute = rounding / (seen_at * hx.min(hy)).max(f64::MIN_POSITIVE);
            let pad = |x: f64| 1e-5 * (1.0 + x.abs()) + absolute;
            [
                (r[0] - pad(r[0])) as f32,
                (r[1] - pad(r[1])) as f32,
                (r[2] + pad(r[2])) as f32,
                (r[3] + pad(r[3])) as f32,
            ]
        })
        .collect()
}
