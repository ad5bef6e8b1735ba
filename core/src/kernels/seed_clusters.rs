//! `seed_clusters`: AdaptiveCaustics' bounds seed, the cluster list of the first level the
//! traversal judges by its photons, made in one launch instead of the probe levels above it.

use super::{bind, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::Buf;
use crate::device::layout::SeedParams;

/// One thread per cluster of the window `params.window_w x params.window_h` from cluster
/// `(params.first_x, params.first_y)` of a `params.grid_w` grid
/// ([`seed_cluster`](crate::math::photon_clusters::seed_cluster)): a cluster whose
/// footprint overlaps one of the first `params.rect_count` of `caster_rects`
/// ([`cluster_overlaps_rect`](crate::math::photon_clusters::cluster_overlaps_rect)) is
/// appended to `list` at `list_length[0]` (an append at or past `params.capacity` is
/// counted, not written). The list's order is the device atomics' (no reader depends on it).
///
/// Why it may stand for the probe levels: with the `bounds` relevance a cluster is kept when
/// a photon met a caster or its footprint overlaps a caster's rectangle, and a photon that
/// meets a caster starts inside that caster's rectangle, so the rectangles alone decide. A
/// child's footprint lies inside its parent's, so a cluster overlaps a rectangle only if
/// every ancestor did: the clusters this lists are exactly those that overlap, and those the
/// probe levels pass down that do not overlap would be discarded where they are traced.
#[derive(Clone, Copy, Debug)]
pub struct SeedClusters {
    /// The grid, the window, the rectangle count and the list's capacity.
    pub params: SeedParams,
    /// The casters' bounding boxes projected on the plane: `(x0, y0, x1, y1)` in its
    /// normalised device coordinates.
    pub caster_rects: Buf<[f32; 4]>,
    /// The level's cluster list, appended to.
    pub list: Buf<u32>,
    /// `[0]`: the list's length, added to (the caller clears it).
    pub list_length: Buf<u32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("caster_rects", Read),
    bind("list", ReadWrite),
    bind("list_length", ReadWrite),
];

impl KernelDecl for SeedClusters {
    const INFO: KernelInfo = KernelInfo::compute("seed_clusters", BINDINGS, "AdaptiveCaustics");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        let clusters_w = p.grid_w / 2;
        if p.grid_w < 2
            || !p.grid_w.is_power_of_two()
            || p.first_x as u64 + p.window_w as u64 > clusters_w as u64
            || p.first_y as u64 + p.window_h as u64 > clusters_w as u64
            || p.rect_count > self.caster_rects.len
            || p.capacity > self.list.len
        {
            return Err(BackendError::BadArgument(format!(
                "seed_clusters: window {}x{} from ({}, {}) of a grid of {}, {} of {} \
                 rectangles, capacity {} of {}",
                p.window_w,
                p.window_h,
                p.first_x,
                p.first_y,
                p.grid_w,
                p.rect_count,
                self.caster_rects.len,
                p.capacity,
                self.list.len
            )));
        }
        a.params("params", p)?
            .buf("caster_rects", self.caster_rects, 16 * p.rect_count as u64)?
            .buf("list", self.list, 4 * p.capacity as u64)?
            .buf("list_length", self.list_length, 4)?;
        Ok(Some(p.window_w as u64 * p.window_h as u64))
    }
}
