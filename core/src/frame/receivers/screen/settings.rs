//! The screen receiver's own parameters (the store test and the gather filter), with
//! their defaults and validation: `screen` in Sspm's settings and in AdaptiveCaustics'
//! screen deposit. What every technique shares (outputs, the temporal and A-Trous
//! passes, accumulation) is in [`crate::frame::settings::FrameSettings`].

use crate::frame::error::Error;
use serde::{Deserialize, Serialize};

/// The filter that turns the raw screen-space deposit into the technique's caustics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GatherFilter {
    /// Density-adaptive, scatter-normalised gather (the default): the radius follows the
    /// local photon density (k nearest photons), the flux of the raw deposit is kept by
    /// construction, and the filter fades to the identity as photons accumulate
    /// (`crate::math::density_gather`).
    #[default]
    Density,
    /// Kim 2019's edge-aware bilateral gather: radius `roughness` x the tile's mean hit
    /// distance (Kim 2019, section 30.3.2), normalised per destination.
    Bilateral,
}

/// Every parameter of the screen receiver; defaults from Kim 2019 where it gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScreenSettings {
    /// The store test (condition 3): a photon is kept in the pixel it projects to when it
    /// lies on the surface that pixel's centre sees. `< 0` (default -0.01): within
    /// `|depth_tolerance| x depth` of the pixel's tangent plane (`layout::off_surface`);
    /// `> 0`: Kim 2019's test, its view depth within `depth_tolerance x depth` of the
    /// pixel's. The default departs from Kim 2019 because Kim 2019's test drops photons of
    /// surfaces seen at a grazing angle in coarse images, whose view depth varies across
    /// one pixel by more than 1%: on `rooms` at 160x90 Kim 2019's 0.01 keeps 106953 of the
    /// 214497 photons the tangent-plane test keeps (at 480x270: 194472 of 194543), and
    /// Sspm's caustics were 20% (`cornell`) and 51% (`rooms`) too dark at 160x90. The
    /// caustic reference uses the same test (`caustica::reference::CAUSTIC_REFERENCE`).
    pub depth_tolerance: f32,
    /// The caustic filter between the raw deposit and the output.
    pub filter: GatherFilter,
    /// Density gather: photons `k` of a pixel's nearest-neighbour window; its kernel's
    /// support half-width is half the side of the square that holds `k` photons at the
    /// window's density, so pixels whose 3x3 window holds `k` photons per pixel are not
    /// filtered at all. 1..=1024; 32 (chosen on the built-in scenes: `k = 16` filters
    /// too little at 256^2 photons, 64 blurs the sparse tails more than it helps at
    /// 4096^2; see the README's report).
    pub knn_photons: u32,
    /// Bilateral gather: blur per unit hit distance (the source's denoiser "roughness",
    /// 0.07).
    pub roughness: f32,
    /// Lower hit-distance clamp (scene units); `None`: 5% of the scene's diagonal (the
    /// source clamps to [300, 2000] in its scene units and asks for a per-scene choice).
    pub hit_distance_min: Option<f32>,
    /// Upper hit-distance clamp (scene units); `None`: 50% of the scene's diagonal.
    pub hit_distance_max: Option<f32>,
    /// Largest gather radius in pixels (both filters).
    pub max_radius_px: u32,
    /// Bilateral depth weight `exp(-|dz| / (sigma_depth z))`.
    pub sigma_depth: f32,
    /// Bilateral normal weight exponent (0 disables it).
    pub normal_power: f32,
    /// Tile size (pixels) of the hit-distance tiles that set the gather radius.
    pub tile_size: u32,
}

impl Default for ScreenSettings {
    fn default() -> Self {
        ScreenSettings {
            depth_tolerance: -0.01,
            filter: GatherFilter::Density,
            knn_photons: 32,
            roughness: 0.07,
            hit_distance_min: None,
            hit_distance_max: None,
            max_radius_px: 16,
            sigma_depth: 0.02,
            normal_power: 8.0,
            tile_size: 8,
        }
    }
}

impl ScreenSettings {
    /// Rejects parameters that cannot give a meaningful frame.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: &str| Err(Error::InvalidParameter(format!("screen.{what}")));
        if !(self.depth_tolerance != 0.0 && self.depth_tolerance.is_finite()) {
            return bad(
                "depth_tolerance must be nonzero and finite (> 0: view-depth test; < 0: \
                 tangent-plane test)",
            );
        }
        if !(self.roughness >= 0.0 && self.roughness.is_finite()) {
            return bad("roughness must be >= 0");
        }
        for (name, v) in [
            ("hit_distance_min", self.hit_distance_min),
            ("hit_distance_max", self.hit_distance_max),
        ] {
            if let Some(v) = v {
                if !(v > 0.0 && v.is_finite()) {
                    return bad(&format!("{name} must be > 0"));
                }
            }
        }
        if let (Some(a), Some(b)) = (self.hit_distance_min, self.hit_distance_max) {
            if a > b {
                return bad("hit_distance_min exceeds hit_distance_max");
            }
        }
        if self.knn_photons == 0 || self.knn_photons > 1024 {
            return bad("knn_photons must be in 1..=1024");
        }
        if self.max_radius_px > 256 {
            return bad("max_radius_px must be <= 256");
        }
        if !(self.sigma_depth > 0.0 && self.sigma_depth.is_finite()) {
            return bad("sigma_depth must be > 0 and finite");
        }
        if !(self.normal_power >= 0.0 && self.normal_power.is_finite()) {
            return bad("normal_power must be >= 0 and finite");
        }
        if self.tile_size == 0 || self.tile_size > 256 {
            return bad("tile_size must be in 1..=256");
        }
        Ok(())
    }
}
