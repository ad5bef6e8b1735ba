//! `photon_count_table`: summed-area table of the photon counts (the density gather's
//! nearest-neighbour windows, see `crate::math::density_gather`).

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf, PhotonMapPlanes};
use crate::device::layout::{gather_surface, GatherParams};

/// One direction of the blocked summed-area table of per-pixel photon counts clamped at
/// `9 params.knn_photons` (`clamped_photon_count`), wrapping `u32` sums restarted at
/// every `params.table_block` pixels (`window_photons` reads it). `params.axis` 0:
/// `table[y][x] = sum count(x', y)` over `x'` from the block's left edge to `x`, from the
/// photon map; 1: the row sums become the table in place, `table[y][x] = sum table[y'][x]`
/// over `y'` from the block's top edge to `y`; axis 1 also writes every pixel's edge
/// texel (`math::density_gather::edge_texel`: the G-buffer's depth and normal, or the
/// not-a-receiver mark), which `gather_footprint` and `density_gather` read instead of
/// three G-buffer planes a tap. The GPU ports scan in workgroups
/// ([`count_table_threads`]); the sums are integers, so any order gives the same bits. With `params.surface` [`gather_surface::ATLAS`] the grid is the caustic atlas,
/// whose edge texels come with its layout: axis 1 only scans, and the G-buffer (any planes
/// of at least one texel) is bound but not read.
#[derive(Clone, Copy, Debug)]
pub struct PhotonCountTable {
    /// Gather parameters (camera size, `knn_photons`, `axis`).
    pub params: GatherParams,
    /// The screen-space photon map (its photon counts; read by axis 0 only).
    pub photon_map: PhotonMapPlanes,
    /// The table, one `u32` per pixel, row-major.
    pub table: Buf<u32>,
    /// The frame's G-buffer (receiver flag, depth, normal: planes 0, 1 and 3 are bound;
    /// read by axis 1 only).
    pub gbuffer: GBufferPlanes,
    /// Per pixel the edge texel `(view depth, world normal)` (scene units; depth -1: not a
    /// receiver); written by axis 1.
    pub edge: ImageBuf,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("photon_map0", Read),
    bind("photon_map1", Read),
    bind("photon_map2", Read),
    bind("table", ReadWrite),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer3", Read),
    bind("edge", ReadWrite),
];

/// Texels the bound G-buffer must hold: the screen's `n`, or one on the atlas (not read).
pub(super) fn gbuffer_texels(p: &GatherParams, n: u64) -> u64 {
    if p.surface == gather_surface::ATLAS {
        1
    } else {
        n
    }
}

/// Threads of a `photon_count_table` launch (workgroups of
/// [`SCAN_THREADS`](crate::math::density_gather::SCAN_THREADS)). Axis 0: a workgroup per
/// row and block, each thread on `table_block / 64` neighbouring pixels and a workgroup
/// scan between them (a thread per row and block walking its pixels was latency-bound on
/// an H200). Axis 1: a thread per pixel for the edge
/// texels, and a workgroup per `SCAN_COLUMNS` columns of a block, each column in
/// `COLUMN_CHUNKS` chunks.
pub fn count_table_threads(p: &GatherParams) -> u64 {
    use crate::math::density_gather::{SCAN_COLUMNS, SCAN_THREADS};
    let (w, h) = (p.camera.width as u64, p.camera.height as u64);
    let b = p.table_block.max(1) as u64;
    if p.axis == 0 {
        h * w.div_ceil(b) * SCAN_THREADS as u64
    } else {
        (w.div_ceil(SCAN_COLUMNS as u64) * h.div_ceil(b) * SCAN_THREADS as u64).max(w * h)
    }
}

impl KernelDecl for PhotonCountTable {
    const INFO: KernelInfo = KernelInfo::compute("photon_count_table", BINDINGS, "Sspm");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let c = &self.params.camera;
        let n = texels(c.width, c.height);
        a.params("params", &self.params)?
            .photon_map(&self.photon_map, n)?
            .buf("table", self.table, n * 4)?
            .gather_gbuffer(&self.gbuffer, gbuffer_texels(&self.params, n))?
            .buf("edge", self.edge, n * bytes::IMAGE_TEXEL)?;
        Ok(Some(count_table_threads(&self.params)))
    }
}

// The GPU scans assume a workgroup of SCAN_THREADS threads.
const _: () = assert!(crate::math::density_gather::SCAN_THREADS == super::DEFAULT_WORKGROUP_SIZE);
