//! `density_gather`: one direction of the scatter-normalised, density-adaptive caustic
//! gather (see `crate::math::density_gather`).

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf};
use crate::device::layout::GatherParams;
use crate::math::density_gather::{column_pass_threads, source_index_len};

/// One pass of the separable gather. Every receiver pixel `j` sums, over the receivers
/// `i` of its row (`params.axis` 0) or column (1) inside the image,
/// `input[i].rgb * footprint_weight(j - i, input[i].a) * edge_weight(i, j)`: the sources'
/// normalised flux spread with each source's own radius (a source without flux is
/// skipped before its weights are computed). Edge weights read the edge texels
/// `photon_count_table` wrote; pixel `j`'s own radius is `input[j].a`. The column pass
/// hands pixels to threads in 8 x 8 tiles (`math::density_gather::column_pass_pixel`).
///
/// - Axis 0 reads `gather_footprint`'s `(F / W_row, r)` and writes `(S_j / W_col(j), r_j)`,
///   where `W_col(j)` is pixel `j`'s normaliser over its column with its own radius: the
///   column pass's sources, already normalised.
/// - Axis 1 reads that and writes caustic radiance `L = (albedo / pi) S_j / A_j`
///   (W/(sr m^2) per channel, Kim 2019, Eq. 5 with the pixel's surface area `A_j`); alpha: the
///   pixel's gather radius (pixels) where it received flux, 0 elsewhere. On the caustic
///   atlas (`params.surface`
///   [`gather_surface::ATLAS`](crate::device::layout::gather_surface::ATLAS)) it writes
///   irradiance `E = S_j / A_j` (W/m^2 per channel) with `A_j` the texel's world area
///   from its edge texel (`math::density_gather::atlas_edge_texel`), and the G-buffer is
///   bound but not read.
///
/// Non-receiver pixels get 0. The loop visits only the sources the source index lists
/// within `R` of `j` (`math::density_gather::for_each_pass_source`, `R` from the reach
/// grid): the taps it leaves out have no flux or no weight, so the sum is the one over
/// `-max_radius_px..=max_radius_px`, bit for bit.
#[derive(Clone, Copy, Debug)]
pub struct DensityGather {
    /// Gather parameters; `axis` picks the pass.
    pub params: GatherParams,
    /// The frame's G-buffer (receiver flag, depth, normal, albedo).
    pub gbuffer: GBufferPlanes,
    /// Every pixel's edge texel from `photon_count_table` (view depth, world normal).
    pub edge: ImageBuf,
    /// Normalised flux and radius per pixel (W per channel; pixels).
    pub input: ImageBuf,
    /// Axis 0: normalised flux and radius; axis 1: caustic radiance and radius.
    pub out: ImageBuf,
    /// The source index: axis 0 reads the row pass's part (`gather_footprint` wrote it)
    /// and enters the pixels it gives flux into the column pass's (atomic maxima and ors,
    /// zeroed before); axis 1 reads the column pass's part.
    pub source_index: Buf<u32>,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("edge", Read),
    bind("input", Read),
    bind("out", ReadWrite),
    bind("source_index", ReadWrite),
];

impl KernelDecl for DensityGather {
    const INFO: KernelInfo = KernelInfo::compute("density_gather", BINDINGS, "Sspm");

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let c = &self.params.camera;
        let n = texels(c.width, c.height);
        a.params("params", &self.params)?
            .gbuffer(
                &self.gbuffer,
                super::photon_count_table::gbuffer_texels(&self.params, n),
            )?
            .buf("edge", self.edge, n * bytes::IMAGE_TEXEL)?
            .buf("input", self.input, n * bytes::IMAGE_TEXEL)?
            .buf("out", self.out, n * bytes::IMAGE_TEXEL)?
            .buf(
                "source_index",
                self.source_index,
                source_index_len(c.width, c.height) as u64 * 4,
            )?;
        Ok(Some(if self.params.axis == 1 {
            column_pass_threads(c.width, c.height)
        } else {
            n
        }))
    }
}
