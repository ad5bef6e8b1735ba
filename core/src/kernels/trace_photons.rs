//! `trace_photons`: emit, trace through specular chains, store.

use super::{
    bind, bytes, with_scene, Args, Binding, BindingKind::*, DispatchRecord, KernelDecl, KernelInfo,
};
use crate::device::error::BackendError;
use crate::device::handle::{Buf, GBufferPlanes, PhotonMapPlanes, SceneArgs};
use crate::device::layout::{AtlasParams, AtlasTileTexel, DepositParams, Photon, TraceParams};

/// Emits and traces photons `params.first .. first + count` of light `params.light`, in
/// the tile order of its photon grid (thread `i` traces grid photon
/// [`crate::math::sampling::tiled_photon_index`]`(first + i)`; the adaptive variant takes
/// its photons from clusters instead), from its emission domain (cone, rectangle or light
/// view plane) through specular chains
/// (mirror, Fresnel reflect/refract, total internal reflection, Beer-Lambert, Cauchy
/// dispersion as the variant allows); appends each photon that ends on a diffuse surface
/// after at least one specular interaction to `photons` at `photon_count[0]` (world-space
/// position, or uv and triangle with the variant's `surface_store`; flux in W per
/// channel; last segment length) and adds the photon accounting to `counters`
/// ([`crate::device::layout::counter`]). With the variant's `fused_deposit` the stored
/// photons are deposited where their paths end instead ([`TracePhotons::deposit`]: the
/// caustic atlas, or the camera's screen photon map).
#[derive(Clone, Copy, Debug)]
pub struct TracePhotons {
    /// The uploaded scene.
    pub scene: SceneArgs,
    /// The compiled variant to run (the frame plan's; it must cover every material
    /// feature of the scene).
    pub variant: TraceVariant,
    /// The batch: light, emission domain, photon range, seed, flux per photon.
    pub params: TraceParams,
    /// Output: stored photons, appended.
    pub photons: Buf<Photon>,
    /// `[0]`: next free slot in `photons`, incremented atomically (the caller clears it);
    /// with the `adaptive` variant, read only: the length of the cluster list (the batch
    /// traces its live clusters, [`crate::math::photon_clusters::live_clusters`] of
    /// `params.first` and `params.count / 4`).
    pub photon_count: Buf<u32>,
    /// Photon counters ([`crate::device::layout::counter`]) the kernel adds to.
    pub counters: Buf<u32>,
    /// With the `adaptive` variant: the level's cluster list
    /// ([`crate::math::photon_clusters`]); photon `i` of the batch is photon `i % 4` of
    /// cluster `clusters[params.first + i / 4]` of the `params.grid_w` grid, and is
    /// written to slot `i` of `photons` (`photon_store` says how), or deposited with the
    /// `fused_deposit` variant. Otherwise `None` (the binding then aliases the scene's
    /// triangles, read by nobody).
    pub clusters: Option<ClusterBatch>,
    /// With the `fused_deposit` variant: where each stored photon is deposited
    /// ([`FusedDeposit`]); `photons` is then neither read nor written, nor is
    /// `photon_count` but for the adaptive variant's list length. Otherwise `None` (the
    /// bindings then alias buffers of the kernel's other arguments, touched by nobody).
    pub deposit: Option<FusedDeposit>,
}

/// The adaptive variant's cluster list and, when its size is on the device, the launch's
/// shape (`params.count` is then the bound).
#[derive(Clone, Copy, Debug)]
pub struct ClusterBatch {
    /// The level's cluster list.
    pub list: Buf<u32>,
    /// The launch's record (`dispatch_args`), or `None` for a launch of `params.count`.
    pub dispatch: Option<DispatchRecord>,
}

/// Where the `fused_deposit` variant of [`TracePhotons`] deposits each stored photon.
#[derive(Clone, Copy, Debug)]
pub enum FusedDeposit {
    /// A texture-space photon (`surface_store`) into the caustic atlas (CausticMap).
    Atlas(AtlasDeposit),
    /// A world-space photon into the camera's screen photon map (Sspm).
    Screen(ScreenDeposit),
}

/// The screen photon map that the `fused_deposit` variant of [`TracePhotons`] (world
/// space) deposits into, as `deposit_screen` adds a photon: projected to its pixel, kept
/// where the pixel's G-buffer sees a receiver at a consistent depth from the side the
/// photon arrives on, added in fixed point.
#[derive(Clone, Copy, Debug)]
pub struct ScreenDeposit {
    /// Camera, quanta, depth tolerance (`photon_capacity` unused).
    pub params: DepositParams,
    /// The frame's G-buffer.
    pub gbuffer: GBufferPlanes,
    /// The screen photon map's fixed-point sums.
    pub photon_map: PhotonMapPlanes,
}

/// The caustic atlas that the `fused_deposit` variant of [`TracePhotons`] deposits into:
/// the atlas's sums and the buffers that address them.
#[derive(Clone, Copy, Debug)]
pub struct AtlasDeposit {
    /// Atlas size and quanta (`photon_capacity` unused).
    pub params: AtlasParams,
    /// Per scene triangle: its receiver's tile, or [`crate::device::layout::NO_TILE`].
    pub triangle_tiles: Buf<u32>,
    /// The atlas tiles.
    pub tiles: Buf<AtlasTileTexel>,
    /// One bit per scene triangle, or-ed with the bits of the stored photons' triangles.
    pub triangle_reach: Buf<u32>,
    /// The atlas's fixed-point sums.
    pub sums: PhotonMapPlanes,
    /// The atlas's centroid sums
    /// ([`CENTROID_WORDS`](crate::math::map_gather::CENTROID_WORDS) a texel: the photons'
    /// offsets inside their texel, [`centroid_offset`](crate::math::map_gather::centroid_offset),
    /// and their count).
    pub centroids: Buf<u32>,
}

const BINDINGS: [Binding; 25] = with_scene([
    bind("params", Params),
    bind("photons", ReadWrite),
    bind("photon_capacity", Count),
    bind("photon_count", ReadWrite),
    bind("counters", ReadWrite),
    bind("clusters", Read),
    bind("atlas_params", Params),
    bind("triangle_tiles", Read),
    bind("tiles", Read),
    bind("triangle_reach", ReadWrite),
    bind("photon_map0", ReadWrite),
    bind("photon_map1", ReadWrite),
    bind("photon_map2", ReadWrite),
    bind("deposit_params", Params),
    bind("gbuffer0", Read),
    bind("gbuffer1", Read),
    bind("gbuffer2", Read),
    bind("gbuffer3", Read),
    bind("centroids", ReadWrite),
]);

impl KernelDecl for TracePhotons {
    const INFO: KernelInfo = KernelInfo::traced(
        "trace_photons",
        &BINDINGS,
        &TraceVariant::SWITCHES,
        "Sspm, CausticMap",
    );

    fn scene(&self) -> Option<&SceneArgs> {
        Some(&self.scene)
    }

    fn lower(&self, a: &mut Args) -> Result<Option<u64>, BackendError> {
        let p = &self.params;
        if self.variant.fresnel_split
            && !(1..=crate::device::layout::MAX_SPLIT_BRANCHES).contains(&p.split_budget)
        {
            return Err(BackendError::BadArgument(format!(
                "trace_photons: split budget {} outside 1..={}",
                p.split_budget,
                crate::device::layout::MAX_SPLIT_BRANCHES
            )));
        }
        let per_photon = if self.variant.fresnel_split {
            p.split_budget as u64
        } else {
            1
        };
        let fits = match &self.deposit {
            None => !self.variant.fused_deposit,
            Some(FusedDeposit::Atlas(_)) => {
                self.variant.fused_deposit && self.variant.surface_store
            }
            Some(FusedDeposit::Screen(_)) => {
                self.variant.fused_deposit && !self.variant.surface_store
            }
        };
        if !fits {
            return Err(BackendError::BadArgument(
                "trace_photons: the fused_deposit variant goes with a deposit target, the \
                 atlas in texture space, the screen in world space"
                    .into(),
            ));
        }
        if !self.variant.fused_deposit && p.count as u64 * per_photon > self.photons.len as u64 {
            return Err(BackendError::BadArgument(format!(
                "photon buffer holds {} photons, the batch traces {} (x {per_photon} branches \
                 at most)",
                self.photons.len, p.count
            )));
        }
        if self.variant.adaptive {
            let Some(ClusterBatch { list: c, .. }) = self.clusters else {
                return Err(BackendError::BadArgument(
                    "trace_photons: the adaptive variant needs a cluster list".into(),
                ));
            };
            if self.variant.fresnel_split {
                return Err(BackendError::BadArgument(
                    "trace_photons: the adaptive variant stores one photon per slot (no \
                     deterministic split)"
                        .into(),
                ));
            }
            if !p.count.is_multiple_of(4)
                || p.first as u64 + p.count as u64 / 4 > c.len as u64
                || p.grid_w < 2
                || p.grid_w != p.grid_h
            {
                return Err(BackendError::BadArgument(format!(
                    "trace_photons: {} photons from cluster {} of a list of {} on a {}x{} grid",
                    p.count, p.first, c.len, p.grid_w, p.grid_h
                )));
            }
        }
        if p.light >= self.scene.lights.len {
            return Err(BackendError::BadArgument(
                "trace_photons: light index out of range".into(),
            ));
        }
        a.scene(&self.scene)?
            .params("params", p)?
            .buf("photons", self.photons, 0)?
            .count("photon_capacity", self.photons.len)?
            .buf("photon_count", self.photon_count, 4)?
            .buf("counters", self.counters, bytes::COUNTERS)?;
        match self.clusters {
            Some(c) => a.buf("clusters", c.list, 0)?.indirect(c.dispatch)?,
            None => a.buf("clusters", self.scene.triangles, 0)?,
        };
        let (atlas, screen) = match &self.deposit {
            Some(FusedDeposit::Atlas(d)) => (Some(d), None),
            Some(FusedDeposit::Screen(d)) => (None, Some(d)),
            None => (None, None),
        };
        // bindings of the target not deposited into are read by nobody: the scene's
        // triangles for the read-only ones, the counters for the read-write ones (a
        // buffer bound twice read-write is one usage on every backend)
        match atlas {
            Some(d) => {
                a.params("atlas_params", &d.params)?
                    .buf("triangle_tiles", d.triangle_tiles, 0)?
                    .buf("tiles", d.tiles, 0)?
                    .buf("triangle_reach", d.triangle_reach, 4)?;
            }
            None => {
                a.params("atlas_params", &AtlasParams::default())?
                    .buf("triangle_tiles", self.scene.triangles, 0)?
                    .buf("tiles", self.scene.triangles, 0)?
                    .buf("triangle_reach", self.counters, 0)?;
            }
        }
        match (atlas, screen) {
            (Some(d), _) => {
                a.photon_map(&d.sums, super::texels(d.params.width, d.params.height))?;
            }
            (None, Some(d)) => {
                a.photon_map(&d.photon_map, pixels(&d.params))?;
            }
            (None, None) => {
                for name in super::PHOTON_MAP_BINDINGS {
                    a.buf(name, self.counters, 0)?;
                }
            }
        }
        match screen {
            Some(d) => {
                a.params("deposit_params", &d.params)?
                    .gbuffer(&d.gbuffer, pixels(&d.params))?;
            }
            None => {
                a.params("deposit_params", &DepositParams::default())?;
                for name in super::GBUFFER_BINDINGS {
                    a.buf(name, self.scene.triangles, 0)?;
                }
            }
        }
        match atlas {
            Some(d) => {
                let texels = super::texels(d.params.width, d.params.height);
                let words = crate::math::map_gather::CENTROID_WORDS as u64;
                a.buf("centroids", d.centroids, 4 * words * texels)?
            }
            None => a.buf("centroids", self.counters, 0)?,
        };
        Ok(Some(p.count as u64))
    }

    fn switch_values(&self) -> Vec<u32> {
        self.variant.values().to_vec()
    }
}

/// The camera's pixels of a screen deposit.
fn pixels(p: &DepositParams) -> u64 {
    super::texels(p.camera.width, p.camera.height)
}

/// A compiled variant of `trace_photons` (feature variants are compiled, not
/// branched). Each switch removes a material feature from the kernel; the frame plan
/// turns on only what the scene's objects use. Backends compile it as WGSL
/// pipeline-overridable constants, Vulkan specialization constants (ids in
/// [`TraceVariant::SWITCHES`] order), OpenCL `-D` defines and CPU const generics, each
/// under the names of [`TraceVariant::SWITCHES`]. Switch values are `u32` so that small
/// enumerations (emission source, store policy) can join the flags.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, serde::Serialize)]
pub struct TraceVariant {
    /// Dielectric interfaces (Fresnel reflect/refract, total internal reflection).
    pub dielectric: bool,
    /// Dispersion: a photon takes a wavelength (or, with three bands, a colour channel)
    /// at its first dispersive hit and refracts with its index from then on
    /// (`math::spectrum::disperse`, `math::optics::dispersive_ior`).
    pub dispersion: bool,
    /// Beer-Lambert absorption inside dielectrics.
    pub absorption: bool,
    /// Stores photons in texture space (uv and triangle,
    /// [`photon_store::SURFACE`](crate::device::layout::photon_store::SURFACE)) for the
    /// caustic atlas, instead of world space (Sspm's screen deposit).
    pub surface_store: bool,
    /// Vanderstichelen 2021's deterministic splits: a dielectric sends both a reflected (flux x R) and
    /// a refracted (x (1 - R)) branch, and the first dispersive surface three branches
    /// (`math::spectrum::split_lane`), up to `TraceParams::split_budget` branches per emitted photon (beyond it,
    /// the stochastic choice); otherwise Sspm's stochastic Fresnel and channel choices.
    pub fresnel_split: bool,
    /// Wyman 2009's adaptive emission: photons come four by four from a cluster list, and
    /// each is written to its own slot (stored or not) for `refine_clusters` to judge;
    /// with `fused_deposit` too, each stored photon is deposited instead (a level whose
    /// every cluster is output: no slots and no `refine_clusters`).
    pub adaptive: bool,
    /// The fused pass: each stored photon is deposited where its path ends instead of
    /// into the photon buffer, into the caustic atlas with `surface_store` (CausticMap;
    /// [`AtlasDeposit`]: sums, counters and reach mask), into the camera's screen photon
    /// map without (Sspm; [`ScreenDeposit`]): no photon buffer and no second pass.
    pub fused_deposit: bool,
}

impl TraceVariant {
    /// Switch names, in specialization-constant id order.
    pub const SWITCHES: [&'static str; 7] = [
        "DIELECTRIC",
        "DISPERSION",
        "ABSORPTION",
        "SURFACE_STORE",
        "FRESNEL_SPLIT",
        "ADAPTIVE",
        "FUSED_DEPOSIT",
    ];

    /// Every feature compiled in (what a frame uses with pruning off).
    pub const ALL: TraceVariant = TraceVariant {
        dielectric: true,
        dispersion: true,
        absorption: true,
        surface_store: false,
        fresnel_split: false,
        adaptive: false,
        fused_deposit: false,
    };

    /// Switch values in [`TraceVariant::SWITCHES`] order.
    pub fn values(&self) -> [u32; 7] {
        [
            self.dielectric as u32,
            self.dispersion as u32,
            self.absorption as u32,
            self.surface_store as u32,
            self.fresnel_split as u32,
            self.adaptive as u32,
            self.fused_deposit as u32,
        ]
    }

    /// `(name, value)` of each switch, in specialization-constant id order.
    pub fn constants(&self) -> Vec<(&'static str, u32)> {
        Self::SWITCHES.iter().copied().zip(self.values()).collect()
    }
}
