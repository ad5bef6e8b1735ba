//! `deposit_screen`: one photon -> one pixel (Kim 2019, section 30.3.1.3).

use super::{bind, bytes, texels, Args, Binding, BindingKind::*, KernelDecl, KernelInfo};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes};
use crate::device::layout::{DepositParams, Photon};

/// Projects each of the `photon_count[0]` stored photons to the screen and, when it lands
/// on a receiver pixel whose surface it lies on (`layout::off_surface`: within
/// `|params.depth_tolerance| x depth` of the pixel's tangent plane when the tolerance is
/// negative, Sspm's default; Kim 2019's relative view-depth match when positive),
/// adds its flux and hit distance in fixed point (`params.flux_quantum`,
/// `params.hit_distance_quantum`) to the screen-space photon map with integer atomics;
/// off-screen and depth-mismatched photons are counted in `counters`.
#[derive(Clone, Copy, Debug)]
pub struct DepositScreen {
    /// Camera, fixed-point quanta, depth tolerance and photon capacity.
    pub params: DepositParams,
    /// The frame's G-buffer planes (receiver flag, depth, normal per pixel).
    pub gbuffer: GBufferPlanes,
    /// The batch's stored photons.
    pub photons: Buf<Photon>,
    /// `[0]`: number of photons in `photons`.
    pub photon_count: Buf<u32>,
    /// Photon counters ([`crate::device::layout::counter`]) the kernel adds to.
    pub counters: Buf<u32>,
    /// Screen-space photon map planes, one texel per pixel, summed over the frame's
    /// batches.
    pub photon_map: PhotonMapPlanes,
}

const BINDINGS: &[Binding] = &[
    bind("params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("photons", Read),
    bind("photon_capacity", Count),
    bind("photon_count", Read),
    bind("counters", ReadWrite),
    bind("photon_map0", ReadWrite),
    bind("photon_map1", ReadWrite),
    bind("photon_map2", ReadWrite),
];

impl KernelDecl for DepositScreen {
    const INFO: KernelInfo = KernelInfo::compute("deposit_screen", BINDINGS, "Sspm");

    /// Its parameters may come partly from the device ([`crate::device::launch::ParamPatch`]).
    fn params_mut(&mut self) -> Option<&mut [u8]> {
        Some(bytemuck::bytes_of_mut(&mut self.params))
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let n = texels(self.params.camera.width, self.params.camera.height);
        a.params("params", &self.params)?
            .gbuffer(&self.gbuffer, n)?
            .buf(
                "photons",
                self.photons,
                self.photons.len as u64 * bytes::PHOTON,
            )?
            .count("photon_capacity", self.photons.len)?
            .buf("photon_count", self.photon_count, 4)?
            .buf("counters", self.counters, bytes::COUNTERS)?
            .photon_map(&self.photon_map, n)?;
        // one work-item per photon slot; the kernel reads how many are filled
        Ok(Some(self.photons.len as u64))
    }
}
