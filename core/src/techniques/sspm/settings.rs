//! Every parameter of Sspm, with its defaults and validation.

use crate::frame::emission::PointEmission;
use crate::frame::error::Error;
use crate::frame::output::Outputs;
use crate::frame::receivers::screen::{GatherFilter, ScreenSettings};
use serde::{Deserialize, Serialize};

/// Every parameter of the technique; defaults from Kim 2019 where it gives them.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct SspmSettings {
    /// Photon grid width per light (photons); each light emits `photons_w x photons_h`
    /// photons (Kim 2019: 2k x 2k in its figures).
    pub photons_w: u32,
    /// Photon grid height per light (photons).
    pub photons_h: u32,
    /// Maximum ray segments per photon path.
    pub max_bounces: u32,
    /// A photon whose largest channel falls below this fraction of its emitted flux is
    /// dropped as negligible (Kim 2019, condition 1).
    pub min_relative_power: f32,
    /// Point-light emission domain.
    pub point_emission: PointEmission,
    /// The screen receiver's [`ScreenSettings::depth_tolerance`].
    pub depth_tolerance: f32,
    /// The screen receiver's [`ScreenSettings::filter`].
    pub filter: GatherFilter,
    /// The screen receiver's [`ScreenSettings::knn_photons`].
    pub knn_photons: u32,
    /// The screen receiver's [`ScreenSettings::roughness`].
    pub roughness: f32,
    /// The screen receiver's [`ScreenSettings::hit_distance_min`].
    pub hit_distance_min: Option<f32>,
    /// The screen receiver's [`ScreenSettings::hit_distance_max`].
    pub hit_distance_max: Option<f32>,
    /// The screen receiver's [`ScreenSettings::max_radius_px`].
    pub max_radius_px: u32,
    /// The screen receiver's [`ScreenSettings::sigma_depth`].
    pub sigma_depth: f32,
    /// The screen receiver's [`ScreenSettings::normal_power`].
    pub normal_power: f32,
    /// The screen receiver's [`ScreenSettings::tile_size`].
    pub tile_size: u32,
    /// The screen receiver's [`ScreenSettings::max_specular_depth`].
    pub max_specular_depth: u32,
    /// Frame seed of the counter-based RNG.
    pub seed: u32,
    /// Memory limit: photons traced per batch (photon buffer = 32 bytes each; default
    /// [`crate::frame::allocation::DEFAULT_PHOTONS_PER_BATCH`], at most what the device's
    /// largest buffer holds).
    pub max_photons_per_batch: u32,
    /// The fused pass (default): `trace_photons` deposits each stored photon into the
    /// screen photon map where its path ends, as `deposit_screen` would (no photon buffer,
    /// no second pass; 0.1-0.4 ms less trace + deposit + gather on the H200, README). Off:
    /// the photons are stored (the buffer of [`crate::Sspm::photon_buffers`], for a caller
    /// that reads them) and `deposit_screen` deposits them. The CPU's image is bitwise the
    /// same either way; a GPU's within `deposit_screen`'s own agreement
    /// (`conformance`'s `sspm_fused_trace_deposits_what_its_trace_stores`).
    pub fused_deposit: bool,
    /// The screen receiver's [`ScreenSettings::outputs`].
    pub outputs: Outputs,
    /// The screen receiver's [`ScreenSettings::prune`].
    pub prune: bool,
    /// Most triangles the tessellated scene may have; checked before anything is
    /// allocated (default [`crate::scene::limits::DEFAULT_MAX_TRIANGLES`], 2^24).
    pub max_triangles: u64,
    /// The screen receiver's [`ScreenSettings::temporal`].
    pub temporal: bool,
    /// The screen receiver's [`ScreenSettings::atrous_iterations`].
    pub atrous_iterations: u32,
    /// The screen receiver's [`ScreenSettings::atrous_clip_sigmas`].
    pub atrous_clip_sigmas: f32,
    /// The screen receiver's [`ScreenSettings::accumulate`].
    pub accumulate: bool,
}

impl Default for SspmSettings {
    fn default() -> Self {
        SspmSettings {
            photons_w: 1024,
            photons_h: 1024,
            max_bounces: 12,
            min_relative_power: 1e-4,
            point_emission: PointEmission::CasterCone,
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
            seed: 0x5350_4d31,
            max_photons_per_batch: crate::frame::allocation::DEFAULT_PHOTONS_PER_BATCH,
            fused_deposit: true,
            outputs: Outputs::default(),
            prune: true,
            max_triangles: crate::scene::limits::DEFAULT_MAX_TRIANGLES,
            temporal: false,
            atrous_iterations: 0,
            atrous_clip_sigmas: 1.0,
            accumulate: false,
        }
    }
}

impl SspmSettings {
    /// Rejects parameters that cannot give a meaningful frame.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: &str| Err(Error::InvalidParameter(what.to_string()));
        let total = self.photons_w as u64 * self.photons_h as u64;
        if self.photons_w == 0 || self.photons_h == 0 || total > u32::MAX as u64 {
            return bad("photon grid must be at least 1x1 and at most 2^32 - 1 photons per light");
        }
        if self.max_triangles == 0 {
            return bad("max_triangles must be >= 1");
        }
        if self.max_bounces == 0 || self.max_bounces > 1024 {
            return bad("max_bounces must be in 1..=1024");
        }
        if !(self.min_relative_power >= 0.0 && self.min_relative_power < 1.0) {
            return bad("min_relative_power must be in [0, 1)");
        }
        if self.max_photons_per_batch == 0 {
            return bad("max_photons_per_batch must be >= 1");
        }
        self.screen().validate()
    }

    /// The screen receiver's fields.
    pub fn screen(&self) -> ScreenSettings {
        ScreenSettings {
            depth_tolerance: self.depth_tolerance,
            filter: self.filter,
            knn_photons: self.knn_photons,
            roughness: self.roughness,
            hit_distance_min: self.hit_distance_min,
            hit_distance_max: self.hit_distance_max,
            max_radius_px: self.max_radius_px,
            sigma_depth: self.sigma_depth,
            normal_power: self.normal_power,
            tile_size: self.tile_size,
            max_specular_depth: self.max_specular_depth,
            outputs: self.outputs,
            prune: self.prune,
            temporal: self.temporal,
            atrous_iterations: self.atrous_iterations,
            atrous_clip_sigmas: self.atrous_clip_sigmas,
            accumulate: self.accumulate,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_screen_fields_default_to_the_screen_receivers_defaults() {
        assert_eq!(SspmSettings::default().screen(), ScreenSettings::default());
    }
}
