//! Every parameter of CausticMap, with its defaults and validation.

use crate::frame::error::Error;
use crate::frame::receivers::atlas::layout::DEFAULT_ATLAS_SIDE;
use crate::frame::settings::FrameSettings;
use crate::math::map_gather::DEFAULT_GATHER_WIDTH;
use serde::{Deserialize, Serialize};

/// How photons cross a dielectric (and a dispersive one).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FresnelSplit {
    /// Vanderstichelen 2021's intensity split: both the reflected (flux x R) and the refracted (x 1 - R)
    /// branch are traced, and the first dispersive surface sends three branches (three
    /// wavelengths stratified over the spectrum, or with `frame.dispersion` three bands
    /// one colour channel each), up to `split_budget` branches per photon (the stochastic
    /// choice beyond).
    /// It takes the noise of the Fresnel and channel choices out of the map (on the CPU,
    /// `docs/report-caustic-map`: about 8x less variance at the same photon count, for
    /// about 3x the time), but on the H200 it costs 3 to 6x the trace time (10 to 44 ms
    /// against 3 to 8 ms for 2048^2 photons, H200, 2026-12-01, `docs/caustic-map.md`):
    /// for offline quality, not the real-time default.
    Deterministic,
    /// Sspm's: reflect with probability R, else refract, flux kept; one wavelength (or,
    /// with three bands, one channel x3) per photon at the first dispersive surface. One stored photon per emitted photon, the
    /// same expectation as the split. The default, for the real-time budget (see above).
    #[default]
    Stochastic,
}

/// The reflectance of a dielectric interface, for photons and for the camera's chains.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum FresnelModel {
    /// The exact unpolarised Fresnel equations (the mean of the s and p reflectances).
    /// The default: it costs one square root more than Schlick per interface, the
    /// references and the other techniques use it, and Schlick's error is not small at
    /// the angles caustics come from: for glass (n = 1.5) it is off by up to 0.036 in
    /// absolute reflectance, from outside near grazing incidence (85 degrees: 0.647
    /// instead of 0.611) and from inside just below the critical angle (41.6 degrees),
    /// where internal reflections feed a ball's outer caustic ring
    /// (`fresnel_schlick_error_for_glass` in `math::optics` pins the bound).
    #[default]
    Exact,
    /// Vanderstichelen 2021's Schlick approximation, `R0 + (1 - R0)(1 - cos)^5` with the transmitted
    /// cosine when light goes into the lower index, total internal reflection included.
    Schlick,
}

impl FresnelModel {
    /// The kernels' `fresnel_model` value
    /// ([`fresnel_model`](crate::math::optics::fresnel_model)).
    pub fn kernel_value(self) -> u32 {
        match self {
            FresnelModel::Exact => crate::math::optics::fresnel_model::EXACT,
            FresnelModel::Schlick => crate::math::optics::fresnel_model::SCHLICK,
        }
    }
}

/// What each light's view plane covers (Vanderstichelen 2021, section 3.1 aims it at the casters).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum EmissionPlane {
    /// The cone (or, for a directional light, the rectangle) that bounds the casters:
    /// every texel's photon can meet one. The default.
    #[default]
    Casters,
    /// The light's whole cone: a spot light's outer cone, a point light's six cube faces
    /// (a directional light keeps its projection volume). The dense baseline of Wyman
    /// 2009's comparison, where adaptive emission can discard what misses the casters.
    LightCone,
}

impl EmissionPlane {
    /// The emission domain's aim.
    pub fn aim(self) -> crate::frame::emission::PointEmission {
        match self {
            EmissionPlane::Casters => crate::frame::emission::PointEmission::CasterCone,
            EmissionPlane::LightCone => crate::frame::emission::PointEmission::Sphere,
        }
    }
}

/// How the caustic map is filtered before the final pass reads it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum MapGather {
    /// Vanderstichelen 2021's N x N neighbour average (`gather_width`), normalised to keep the flux,
    /// inside each tile (`gather_caustic_map`). Not the default: it blurs a focused
    /// caustic at every photon budget, so that with the lookup's footprint rectangle the
    /// filtered image is worse than the raw map on `sphere` (relMSE 1.3e-3 against
    /// 8e-5 at 2048^2 photons, `docs/report-caustic-map`) and on `cornell` from
    /// 1024^2 photons on.
    Box,
    /// The density-adaptive, scatter-normalised gather Sspm filters its screen with
    /// (`crate::math::density_gather`), run on the atlas: a texel's radius follows the
    /// photons (`knn_photons` nearest, at most `max_radius_texels`), each source texel's
    /// kernel is normalised over the covered texels of its own tile, so the flux is kept
    /// and no tile border is crossed; a focused caustic where photons are dense is left
    /// as deposited. Flux deposited into a texel whose centre no UV triangle covers (at a
    /// UV island's edge), which the raw map has no area to show, is added to a covered
    /// neighbour of the same tile (its heir:
    /// `crate::math::density_gather::atlas_edge_texels`, `gather_footprint`); the box
    /// gather spreads it into covered neighbours. The default: below the raw map's error
    /// at every budget on `sphere`, `cornell` and `sphere-sun`, and converging to it
    /// (`docs/report-caustic-map`); it costs about 1.1 to 1.9 ms on the H200 at a
    /// 2048^2 atlas against the box's 0.25 ms, and 52 more bytes a texel.
    #[default]
    Density,
}

/// What the caustic atlas receiver is made with: the technique's shared block (outputs,
/// pruning, filter chain, accumulation, the camera's specular chains), its light view
/// planes' optics (the final pass's Fresnel) and the atlas block. CausticMap's and
/// AdaptiveCaustics' settings hold all three.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasConfig {
    /// The technique's shared block.
    pub frame: FrameSettings,
    /// The light view planes and the photons' optics.
    pub planes: PlaneSettings,
    /// The caustic atlas.
    pub atlas: AtlasSettings,
}

/// The light view planes photons start from, and the optics they follow (`planes` in
/// CausticMap's and AdaptiveCaustics' settings).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PlaneSettings {
    /// What the view plane covers: the casters (default) or the light's whole cone.
    pub emission_plane: EmissionPlane,
    /// Deterministic (Vanderstichelen 2021's) or stochastic Fresnel and dispersion splits.
    pub fresnel_split: FresnelSplit,
    /// Exact Fresnel (the default) or Vanderstichelen 2021's Schlick approximation, for
    /// the photons and for the final pass's camera chains alike.
    pub fresnel: FresnelModel,
    /// With the deterministic split: the most branches (stored photons) one emitted photon
    /// may split into (1..=32); a batch then traces `max_photons_per_batch / split_budget`
    /// photons so that its photon buffer cannot overflow.
    pub split_budget: u32,
}

impl Default for PlaneSettings {
    fn default() -> Self {
        PlaneSettings {
            emission_plane: EmissionPlane::Casters,
            fresnel_split: FresnelSplit::Stochastic,
            fresnel: FresnelModel::Exact,
            split_budget: 8,
        }
    }
}

/// The caustic atlas in the receivers' texture space (`atlas` in CausticMap's and
/// AdaptiveCaustics' settings).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AtlasSettings {
    /// Side of the caustic atlas (texels; Vanderstichelen 2021's map size, 2048).
    pub atlas_size: u32,
    /// The caustic map's filter: the density-adaptive gather (default) or the
    /// publication's N x N box.
    pub gather: MapGather,
    /// Width N of the flux-keeping N x N box gather (odd; the publication's 3; 1: no
    /// gather).
    pub gather_width: u32,
    /// Density gather: photons `k` whose nearest-neighbour window sets a texel's radius.
    pub knn_photons: u32,
    /// Density gather: largest radius (texels).
    pub max_radius_texels: u32,
    /// Device memory the atlas may take (bytes): its fixed-point sums (40 B a texel), its
    /// centroid sums (12 B), the gathered and raw maps (16 B each) and the texel table
    /// (8 B); with the density gather also its count table (4 B), edge texels and two
    /// passes' images (16 B each). A larger atlas is a typed out-of-memory error before
    /// any work (default 4 GiB: a 2048^2 atlas takes 576 MiB with the density gather, 368
    /// MiB with the box; 4096^2 2.25 GiB; 16384^2 36 GiB).
    pub max_atlas_bytes: u64,
}

impl Default for AtlasSettings {
    fn default() -> Self {
        AtlasSettings {
            atlas_size: DEFAULT_ATLAS_SIDE,
            gather: MapGather::Density,
            gather_width: DEFAULT_GATHER_WIDTH,
            knn_photons: 32,
            max_radius_texels: 16,
            max_atlas_bytes: 4 << 30,
        }
    }
}

/// Largest atlas side: 16384^2 texels (the sums alone are 10 GiB there; `max_atlas_bytes`
/// and the planned allocation refuse what the device cannot hold).
pub const MAX_ATLAS_SIZE: u32 = 16384;

/// Device bytes per atlas texel: sums (40), centroid sums (12), gathered map (16), raw
/// map (16), texel table (8).
pub const ATLAS_BYTES_PER_TEXEL: u64 = 92;

/// Device bytes per atlas texel the density gather adds: count table (4), edge texels
/// (16), the footprint and row-pass images (16 each).
pub const DENSITY_GATHER_BYTES_PER_TEXEL: u64 = 52;

impl AtlasSettings {
    /// Device bytes of the atlas at these settings (see [`ATLAS_BYTES_PER_TEXEL`] and
    /// [`DENSITY_GATHER_BYTES_PER_TEXEL`]).
    pub fn atlas_bytes(&self) -> u64 {
        let per_texel = match self.gather {
            MapGather::Box => ATLAS_BYTES_PER_TEXEL,
            MapGather::Density => ATLAS_BYTES_PER_TEXEL + DENSITY_GATHER_BYTES_PER_TEXEL,
        };
        (self.atlas_size as u64).pow(2) * per_texel
    }

    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: String| Err(Error::InvalidParameter(format!("atlas.{what}")));
        if self.atlas_size == 0 || self.atlas_size > MAX_ATLAS_SIZE {
            return bad(format!("atlas_size must be in 1..={MAX_ATLAS_SIZE}"));
        }
        if self.gather_width.is_multiple_of(2) || self.gather_width > 31 {
            return bad("gather_width must be odd and at most 31".into());
        }
        if self.knn_photons == 0 || self.knn_photons > 1024 {
            return bad("knn_photons must be in 1..=1024".into());
        }
        if self.max_radius_texels > 256 {
            return bad("max_radius_texels must be <= 256".into());
        }
        Ok(())
    }
}

impl PlaneSettings {
    /// Checks every field's range.
    pub fn validate(&self) -> Result<(), Error> {
        let max = crate::device::layout::MAX_SPLIT_BRANCHES;
        if !(1..=max).contains(&self.split_budget) {
            return Err(Error::InvalidParameter(format!(
                "planes.split_budget must be in 1..={max}"
            )));
        }
        Ok(())
    }
}
