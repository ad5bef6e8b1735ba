//! `gather_footprint`: each pixel's density-adaptive gather radius and its flux
//! normalised for the row pass (see `crate::math::density_gather`).

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, ImageBuf, PhotonMapPlanes};
use crate::device::layout::GatherParams;
use crate::math::density_gather::source_index_len;

/// For every receiver pixel `i`: the radius `r_i` (pixels) of the smallest window holding
/// `params.knn_photons` photons (`footprint_radius` on the summed-area table), and the
/// pixel's deposited flux `F_i` (W per channel, from the photon map's fixed-point sums; on
/// the caustic atlas with the flux of the uncovered neighbours whose heir it is,
/// `math::density_gather::inherited_flux`) divided by its row normaliser
/// `W_i = sum_d footprint_weight(d, r_i) edge_weight(i, i+d)`
/// over the receivers of its row inside the image. Writes `(F_i / W_i, r_i)` to `out`
/// (other pixels get 0; a pixel without flux gets `(0, 0, 0, r_i)` without its normaliser
/// being computed). Receivers, depths and normals come from the edge texels
/// `photon_count_table` wrote. Every pixel it gives flux is entered into the row pass's
/// part of the source index (its reach into its tile's grid entry, its mask bit), which
/// the row pass's loops visit instead of every tap.
#[derive(Clone, Copy, Debug)]
pub struct GatherFootprint {
    /// Gather parameters (camera, `knn_photons`, `max_radius_px`, edge weights,
    /// `flux_quantum`).
    pub params: GatherParams,
    /// The screen-space photon map (flux sums).
    pub photon_map: PhotonMapPlanes,
    /// The summed-area table from `photon_count_table`.
    pub table: Buf<u32>,
    /// Per pixel `(F / W_row, radius)`: W per channel, pixels.
    pub out: ImageBuf,
    /// Per pixel the edge texel from `photon_count_table`.
    pub edge: ImageBuf,
    /// The source index (`math::density_gather::source_index_len` entries, zeroed
    /// before): the row pass's reach grid gets, per tile, the maximum `reach_grid_entry`
    /// of the pixels this kernel gives flux (atomic maxima), its source mask their bits
    /// (atomic ors).
    pub source_index: Buf<u32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("photon_map0", Read),
    bind("photon_map1", Read),
    bind("photon_map2", Read),
    bind("table", Read),
    bind("edge", Read),
    bind("out", ReadWrite),
    bind("source_index", ReadWrite),
];

impl KernelDecl for GatherFootprint {
    const INFO: KernelInfo = KernelInfo::compute("gather_footprint", BINDINGS, "Sspm");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let c = &self.params.camera;
        let n = texels(c.width, c.height);
        a.params("params", &self.params)?
            .photon_map(&self.photon_map, n)?
            .buf("table", self.table, n * 4)?
            .buf("edge", self.edge, n * bytes::IMAGE_TEXEL)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?
            .buf(
                "source_index",
                self.source_index,
                source_index_len(c.width, c.height) as u64 * 4,
            )?;
        Ok(Some(n))
    }
}
