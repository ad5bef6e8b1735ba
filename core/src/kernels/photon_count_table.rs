//! `photon_count_table`: summed-area table of the photon counts (the density gather's
//! nearest-neighbour windows, see `crate::math::density_gather`).

use super::{bind, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, PhotonMapPlanes};
use crate::device::layout::GatherParams;

/// One direction of the blocked summed-area table of per-pixel photon counts clamped at
/// `9 params.knn_photons` (`clamped_photon_count`), wrapping `u32` sums restarted at
/// every `params.table_block` pixels (`window_photons` reads it). `params.axis` 0: one
/// thread per row and block writes `table[y][x] = sum count(x', y)` over `x'` from the
/// block's left edge to `x`, from the photon map; 1: one thread per column and block
/// turns the row sums into the table in place, `table[y][x] = sum table[y'][x]` over `y'`
/// from the block's top edge to `y`.
#[derive(Clone, Copy, Debug)]
pub struct PhotonCountTable {
    /// Gather parameters (camera size, `knn_photons`, `axis`).
    pub params: GatherParams,
    /// The screen-space photon map (its photon counts; read by axis 0 only).
    pub photon_map: PhotonMapPlanes,
    /// The table, one `u32` per pixel, row-major.
    pub table: Buf<u32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("photon_map0", Read),
    bind("photon_map1", Read),
    bind("photon_map2", Read),
    bind("table", ReadWrite),
];

impl KernelDecl for PhotonCountTable {
    const INFO: KernelInfo = KernelInfo::compute("photon_count_table", BINDINGS, "Sspm");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let c = &self.params.camera;
        let n = texels(c.width, c.height);
        a.params("params", &self.params)?
            .photon_map(&self.photon_map, n)?
            .buf("table", self.table, n * 4)?;
        let b = self.params.table_block.max(1);
        Ok(Some(if self.params.axis == 0 {
            c.height as u64 * c.width.div_ceil(b) as u64
        } else {
            c.width as u64 * c.height.div_ceil(b) as u64
        }))
    }
}
