//! AdaptiveCaustics' own frame statistics: the photon work of its traversal, per level,
//! as Wyman 2009's Table 1 counts it. A frame carries them in [`FrameStats::own`] under
//! [`AdaptiveStats::KEY`].

use crate::frame::stats::FrameStats;
use serde::{Deserialize, Serialize};

/// The photon work of one adaptive traversal (Wyman 2009, section 3.2, its Table 1's
/// "photons processed"), summed over the light view planes.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct AdaptiveStats {
    /// Every photon traced, at every level.
    pub photons_processed: u64,
    /// Photons the tracer stored, at every level (the output ones are `photons_stored`
    /// of the frame): with the frame's `discarded` path ends they add up to
    /// `photons_processed`.
    pub photons_traced_stored: u64,
    /// Photons the dense grid at the finest level would trace (its texels).
    pub dense_equivalent_photons: u64,
    /// Photons traced per level (index 0: the start grid).
    pub photons_per_level: Vec<u64>,
    /// Photons deposited (of output clusters), per level.
    pub photons_output_per_level: Vec<u64>,
    /// Time of each level's steps (`trace_photons` and `refine_clusters` of its batches
    /// and of its converged clusters' fresh photons), in ms of the frame's `timing`
    /// (device timestamps or host wall clock).
    pub ms_per_level: Vec<f64>,
    /// `ms_per_level` by kernel: per level, each kernel's time summed over its passes
    /// (`dispatch_args`, `trace_photons`, `refine_clusters`, `deposit_screen`; the bounds
    /// seed's `seed_clusters` under the last seeded level), in ms.
    #[serde(default)]
    pub ms_per_level_kernel: Vec<std::collections::BTreeMap<String, f64>>,
    /// Clusters whose photons were deposited (at a level whose trace deposits, every
    /// cluster traced there: [`TraversalSettings::fused_finest`](super::TraversalSettings)).
    pub clusters_output: u64,
    /// Clusters none of whose photons met a caster (judged by `refine_clusters`; none at
    /// a level whose trace deposits).
    pub clusters_discarded: u64,
    /// Clusters refined into four children.
    pub clusters_refined: u64,
    /// Clusters that converged before the finest level (the error metric), output from
    /// four fresh photons each (counted in `clusters_output` too).
    pub clusters_converged: u64,
    /// Clusters to be refined whose children did not fit the next level's list (the
    /// byte limit caps the lists): output at their level from four fresh photons each
    /// (counted in `clusters_output` too), so that no photon is lost.
    pub clusters_overflowed: u64,
    /// Photons of probe levels traced to their first segment
    /// ([`ProbeLevels::FirstSegment`](super::ProbeLevels))
    /// whose first segment met a caster, where their trace stopped: with
    /// `photons_traced_stored` and the frame's discarded path ends they add up to
    /// `photons_processed` (and the split branches).
    #[serde(default)]
    pub probes_met_caster: u64,
    /// Probe levels not traced, summed over the planes: the bounds seed listed the next
    /// level's clusters instead ([`ProbeLevels::Bounds`](super::ProbeLevels)).
    #[serde(default)]
    pub levels_seeded: u32,
    /// Clusters the bounds seed listed (those overlapping a caster's rectangle).
    #[serde(default)]
    pub clusters_seeded: u64,
    /// Traversal passes that had clusters (a trace and a refinement of one pass of one
    /// level, or of its converged clusters).
    pub steps: u32,
}

impl AdaptiveStats {
    /// The name of these statistics in [`FrameStats::own`] (and the frame's JSON form).
    pub const KEY: &'static str = "adaptive";

    /// The traversal's statistics of a frame: `None` for the other techniques and for
    /// frames without photon work.
    pub fn of(stats: &FrameStats) -> Option<AdaptiveStats> {
        stats.own_stats(Self::KEY)
    }

    /// Puts these statistics into the frame's.
    pub fn put(&self, stats: &mut FrameStats) {
        stats.put_own(Self::KEY, self);
    }
}
