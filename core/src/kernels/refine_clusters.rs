//! `refine_clusters`: Wyman 2009's traversal step, one thread per traced cluster.

use super::{bind, bytes, Args, Binding, BindingKind::*, DispatchRecord, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, PhotonMapPlanes};
use crate::device::layout::{cluster_count, AtlasTileTexel, Photon, RefineParams};

/// Judges each of the live clusters `clusters[params.first ..]` (at most `params.count`,
/// and no more than `list_length[0] - params.first`:
/// [`crate::math::photon_clusters::live_clusters`]) whose four
/// photons `trace_photons`' `ADAPTIVE` variant wrote to slots `4 t .. 4 t + 4` of
/// `photons` ([`crate::math::photon_clusters::cluster_fate`]): a cluster is discarded
/// when none of its photons met a caster and (with `params.relevance` BOUNDS) its
/// footprint overlaps none of `caster_rects`; a cluster output at the finest level
/// (`params.level >= params.finest`) deposits its stored photons into the atlas exactly
/// as the fused trace does (fixed point, order-free); one that converged earlier (the
/// error metric) is appended to `converged` at `converged_count[0]`, to be output
/// from fresh photons (see [`crate::techniques::adaptive_caustics::traversal`]); a refined one appends
/// its four children (the ids of its photons in the level grid) to `children` at
/// `cluster_counts[CHILDREN]`, or, when they do not fit under `params.children_capacity`,
/// is appended to `converged` like a converged one (output at its level, never lost) and
/// counted in `cluster_counts[OVERFLOW]`. Counts clusters output, discarded and converged
/// in `cluster_counts`, and the deposit's photon accounting (stored, stored flux,
/// deposited, off-atlas) in `counters`.
///
/// With `params.target` = [`cluster_target::SCREEN`](crate::math::photon_clusters::cluster_target)
/// the slots are world-space photons, a photon's "texel" (what the error metric compares)
/// is the pixel it projects to through `params.camera`, and an output cluster's stored
/// photons are appended to `output_photons` at `output_count[0]` (for `deposit_screen`,
/// which reads the same count) instead of being deposited; the atlas bindings are then
/// unused, and `output_photons` is unused with the atlas target.
#[derive(Clone, Copy, Debug)]
pub struct RefineClusters {
    /// The batch, level, metric and atlas quanta.
    pub params: RefineParams,
    /// The level's cluster list.
    pub clusters: Buf<u32>,
    /// `[0]`: the list's length (written by the step that appended to it).
    pub list_length: Buf<u32>,
    /// The casters' bounding boxes projected on the plane: `(x0, y0, x1, y1)` in its
    /// normalised device coordinates (`math::photon_clusters::cluster_overlaps_rect`).
    pub caster_rects: Buf<[f32; 4]>,
    /// The batch's photon slots (four per cluster).
    pub photons: Buf<Photon>,
    /// Per scene triangle: its receiver's tile, or [`crate::device::layout::NO_TILE`].
    pub triangle_tiles: Buf<u32>,
    /// The atlas tiles.
    pub tiles: Buf<AtlasTileTexel>,
    /// The next level's cluster list, appended to.
    pub children: Buf<u32>,
    /// The clusters that converged before the finest level or did not fit the child
    /// list, appended to (at most one per cluster: sized to `params.count`).
    pub converged: Buf<u32>,
    /// `[0]`: entries appended to `converged` (the caller clears it).
    pub converged_count: Buf<u32>,
    /// [`cluster_count`] words, added to.
    pub cluster_counts: Buf<u32>,
    /// Photon counters ([`crate::device::layout::counter`]) of the output photons.
    pub counters: Buf<u32>,
    /// The atlas's fixed-point sums.
    pub atlas: PhotonMapPlanes,
    /// The screen target's output photons (world space), appended to.
    pub output_photons: Buf<Photon>,
    /// `[0]`: photons in `output_photons` (entries past its length are counted, not
    /// written; the host sizes it to four per cluster of a batch).
    pub output_count: Buf<u32>,
    /// The launch's shape on the device (its `params.count` the bound), or `None`.
    pub dispatch: Option<DispatchRecord>,
    /// The atlas's centroid sums (the atlas target; `trace_photons`' `centroids`).
    pub centroids: Buf<u32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("clusters", Read),
    bind("list_length", Read),
    bind("caster_rects", Read),
    bind("photons", Read),
    bind("triangle_tiles", Read),
    bind("tiles", Read),
    bind("children", ReadWrite),
    bind("converged", ReadWrite),
    bind("converged_capacity", Count),
    bind("converged_count", ReadWrite),
    bind("cluster_counts", ReadWrite),
    bind("counters", ReadWrite),
    bind("photon_map0", ReadWrite),
    bind("photon_map1", ReadWrite),
    bind("photon_map2", ReadWrite),
    bind("output_photons", ReadWrite),
    bind("output_capacity", Count),
    bind("output_count", ReadWrite),
    bind("centroids", ReadWrite),
];

impl KernelDecl for RefineClusters {
    const INFO: KernelInfo = KernelInfo::compute("refine_clusters", BINDINGS, "AdaptiveCaustics");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        if p.first as u64 + p.count as u64 > self.clusters.len as u64
            || 4 * p.count as u64 > self.photons.len as u64
            || p.grid_w < 2
            || !p.grid_w.is_power_of_two()
        {
            return Err(BackendError::BadArgument(format!(
                "refine_clusters: clusters {}..+{} of {}, {} photon slots, grid {}",
                p.first, p.count, self.clusters.len, self.photons.len, p.grid_w
            )));
        }
        if p.rect_count > self.caster_rects.len {
            return Err(BackendError::BadArgument(
                "refine_clusters: rect_count over the rectangle buffer".into(),
            ));
        }
        // (children are appended four at a time, all or none: a capacity that is the
        // count's start plus a multiple of 4 leaves no unwritten entry below it)
        if p.children_capacity > self.children.len {
            return Err(BackendError::BadArgument(
                "refine_clusters: children_capacity over the child list".into(),
            ));
        }
        if p.level < p.finest && self.converged.len < p.count {
            return Err(BackendError::BadArgument(format!(
                "refine_clusters: a converged list of {} for {} clusters",
                self.converged.len, p.count
            )));
        }
        let n = super::texels(p.atlas_width, p.atlas_width);
        a.params("params", p)?
            .buf("clusters", self.clusters, 0)?
            .buf("list_length", self.list_length, 4)?
            .buf("caster_rects", self.caster_rects, 0)?
            .buf("photons", self.photons, 0)?
            .buf("triangle_tiles", self.triangle_tiles, 0)?
            .buf("tiles", self.tiles, 0)?
            .buf("children", self.children, 0)?
            .buf("converged", self.converged, 0)?
            .count("converged_capacity", self.converged.len)?
            .buf("converged_count", self.converged_count, 4)?
            .buf(
                "cluster_counts",
                self.cluster_counts,
                4 * cluster_count::WORDS as u64,
            )?
            .buf("counters", self.counters, bytes::COUNTERS)?
            .photon_map(&self.atlas, n)?
            .buf("output_photons", self.output_photons, 0)?
            .count("output_capacity", self.output_photons.len)?
            .buf("output_count", self.output_count, 4)?;
        let centroid_bytes =
            if p.deposit_target == crate::math::photon_clusters::cluster_target::ATLAS {
                4 * crate::math::map_gather::CENTROID_WORDS as u64 * n
            } else {
                0
            };
        a.buf("centroids", self.centroids, centroid_bytes)?
            .indirect(self.dispatch)?;
        Ok(Some(p.count as u64))
    }
}
