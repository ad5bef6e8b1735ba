//! The screen receiver's parameters (deposit test, filter, temporal and A-Trous
//! passes, outputs), with their defaults and validation. Sspm's settings hold the same
//! fields at their top level; AdaptiveCaustics' screen target holds them as `screen`.

use crate::frame::error::Error;
use crate::frame::output::Outputs;
use crate::frame::screen::DirectLighting;
use crate::kernels::MAX_SPECULAR_DEPTH;
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
    /// The seed's edge-aware bilateral gather: radius `roughness` x the tile's mean hit
    /// distance (000 section 30.3.2), normalised per destination.
    Bilateral,
}

/// Every parameter of the screen receiver; defaults from Kim 2019 where it gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct ScreenSettings {
    /// The store test (condition 3): a photon is kept in the pixel it projects to when it
    /// lies on the surface that pixel's centre sees. `< 0` (default -0.01): within
    /// `|depth_tolerance| x depth` of the pixel's tangent plane (`layout::off_surface`);
    /// `> 0`: the seed's test, its view depth within `depth_tolerance x depth` of the
    /// pixel's. The default departs from the seed because the seed's test drops photons of
    /// surfaces seen at a grazing angle in coarse images, whose view depth varies across
    /// one pixel by more than 1%: on `rooms` at 160x90 the seed's 0.01 keeps 106953 of the
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
    /// Longest specular chain followed from a mirror/glass pixel in `direct_light`.
    pub max_specular_depth: u32,
    /// The images the caller wants; passes and buffers that no requested image needs are
    /// left out (see [`crate::frame::plan`]).
    pub outputs: Outputs,
    /// Leave out passes, kernel features, buffers and lights the scene and outputs do
    /// not need (default). Off: everything runs, the baseline pruning is checked against.
    pub prune: bool,
    /// Blends each frame's filtered caustics with the reprojected history of the earlier
    /// frames (Smal 2019, section 24.4.1's temporal accumulation, the shared
    /// `temporal_blend` pass with the chapter's constants: alpha 0.95 x depth and normal
    /// weights). Off by default: a frame is then a function of its seed alone. The history
    /// is forgotten when the lights, materials, settings or image size change.
    pub temporal: bool,
    /// Iterations of the edge-avoiding A-Trous filter with variance clipping of its
    /// detail coefficients (Smal 2019, section 24.4.2, the shared `atrous_filter` pass) run
    /// on the filtered (and, with `temporal`, blended) caustics: 0 (the default) runs
    /// none; the chapter runs 4. At most 8.
    pub atrous_iterations: u32,
    /// Standard deviations of the A-Trous kernel's values that a detail coefficient may
    /// keep (Eq. 18's bounds; the chapter gives no value: 1 by default). 0 keeps none (the
    /// smooth `s_n`); a large value keeps all (the unfiltered input).
    pub atrous_clip_sigmas: f32,
    /// Progressive accumulation: while the camera, lights, scene and settings stay, every
    /// frame adds its photons (traced with a new seed) to the photon map of the frames
    /// before, and the resolve and filter read the sum as one frame of all their photons
    /// (N frames of M photons: the estimate of one frame of N x M). Any change starts
    /// again from the next frame's photons. Off by default.
    pub accumulate: bool,
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
            max_specular_depth: 6,
            outputs: Outputs::default(),
            prune: true,
            temporal: false,
            atrous_iterations: 0,
            atrous_clip_sigmas: 1.0,
            accumulate: false,
        }
    }
}

impl ScreenSettings {
    /// How the direct image is lit: specular chains up to `max_specular_depth`, exact
    /// Fresnel, chains below 1e-3 of the pixel's weight stopped.
    pub fn direct_lighting(&self) -> DirectLighting {
        DirectLighting {
            max_specular_depth: self.max_specular_depth,
            min_weight: 1e-3,
            fresnel_model: crate::math::optics::fresnel_model::EXACT,
        }
    }

    /// Rejects parameters that cannot give a meaningful frame.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: &str| Err(Error::InvalidParameter(what.to_string()));
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
        if !(self.sigma_depth > 0.0 && self.sigma_depth.is_finite())
            || !(self.normal_power >= 0.0 && self.normal_power.is_finite())
        {
            return bad("sigma_depth must be > 0 and normal_power >= 0");
        }
        if self.tile_size == 0 || self.tile_size > 256 {
            return bad("tile_size must be in 1..=256");
        }
        self.outputs
            .check("the screen receiver", &super::ScreenReceiver::OUTPUTS)?;
        if self.atrous_iterations > 8 {
            return bad("atrous_iterations must be <= 8 (taps 128 pixels apart)");
        }
        if !(self.atrous_clip_sigmas >= 0.0 && self.atrous_clip_sigmas.is_finite()) {
            return bad("atrous_clip_sigmas must be >= 0");
        }
        if self.max_specular_depth > MAX_SPECULAR_DEPTH {
            return bad(&format!(
                "max_specular_depth must be <= {MAX_SPECULAR_DEPTH}"
            ));
        }
        Ok(())
    }
}
