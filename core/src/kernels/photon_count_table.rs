//! `photon_count_table`: summed-area table of the photon counts (the density gather's
//! nearest-neighbour windows, see `crate::math::density_gather`).

use super::{bind, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, PhotonMapPlanes};
use crate::device::layout::GatherParams;

/// One direction of the summed-area table of per-pixel photon counts clamped at
/// `params.knn_photons` (`clamped_photon_count`), wrapping `u32` sums. `params.axis` 0:
/// one thread per row writes `table[y][x] = sum_{x' <= x} count(x', y)` from the photon
/// map; 1: one thread per column turns the row sums into the full table in place,
/// `table[y][x] = sum_{y' <= y} table[y'][x]`.
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
        Ok(Some(if self.params.axis == 0 {
            c.height as u64
        } else {
            c.width as u64
        }))
    }
}
