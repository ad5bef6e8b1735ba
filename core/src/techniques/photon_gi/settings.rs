//! Every parameter of PhotonGi, with its defaults (Smal 2019 where it gives them) and
//! validation.

use crate::backend::DeviceType;
use crate::frame::error::Error;
use crate::frame::settings::{FrameSettings, TechniqueSettings};
use crate::math::optics::fresnel_model;
use serde::{Deserialize, Serialize};

/// What the raw indirect image is made of.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IndirectEstimator {
    /// The chapter's ellipsoid splats of the packed photons (the technique).
    #[default]
    Splat,
    /// Every stored photon (as a float photon, the same paths) deposited into the one
    /// pixel it lands in (`deposit_screen`), no kernel: the quantity the splats estimate,
    /// whose mean over frames is the indirect reference.
    Deposit,
}

/// How the RSM's texels are chosen for the photons.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RsmSampling {
    /// By importance `luminance(flux x albedo)`, Clarberg's hierarchical warp (Smal 2019, section
    /// 24.2.1): the technique.
    #[default]
    Importance,
    /// Every texel that leaves flux equally likely, through the same warp: the same
    /// estimate in the mean at a higher variance (the unbiasedness test's comparison).
    Uniform,
}

impl RsmSampling {
    /// The value of `RsmParams::sampling` (`math::rsm::rsm_sampling`).
    pub fn code(self) -> u32 {
        match self {
            RsmSampling::Importance => crate::math::rsm::rsm_sampling::IMPORTANCE,
            RsmSampling::Uniform => crate::math::rsm::rsm_sampling::UNIFORM,
        }
    }
}

/// How `trace_indirect` runs its paths.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum IndirectSchedule {
    /// The faster of the two as measured on GPUs (Vulkan, wgpu and OpenCL alike, H100):
    /// `waves` from [`AUTO_WAVES_FROM_BOUNCES`] bounces on (Smal 2019's high setting,
    /// where a warp's longest path is many times its median) when a light's photons fit
    /// one chunk of the queues (`indirect_queue_paths`: several chunks each pay the
    /// waves' small last launches, which cost what they saved), `single_kernel`
    /// otherwise (short paths: the waves' launches and queue traffic cost more than the
    /// idle lanes they save), and always on the CPU backend (no lanes to idle). Where
    /// the waves run, a light whose photon count the host knows to be at most
    /// `auto_waves_above_photons` still takes the single kernel
    /// ([`PhotonGiSettings::light_waves`]). A pipeline resolves it by its device when it
    /// is made ([`PhotonGiSettings::schedule`]). The default.
    #[default]
    Auto,
    /// One launch: a thread follows its path from the RSM photon to its end.
    SingleKernel,
    /// Per-bounce waves: each launch traces one segment of every live path and queues
    /// the paths that go on (a compacted queue, its count on the device), the next wave
    /// launched from that count; the last wave traces the paths to their end. The same
    /// photons as the single launch, in another order: the same image, bit for bit.
    Waves,
    /// The waves with each queue taken in key order (the octant of the path's direction,
    /// then a coarse Morton code of its origin, `math::path_sort`), so that a warp's
    /// paths walk similar parts of the BVH: the queuing wave writes each path's key and
    /// rank, `sort_indirect_paths` orders them, the next wave reads its paths in that
    /// order. The same image, bit for bit.
    SortedWaves,
}

/// Bounces from which the `auto` schedule runs the waves.
pub const AUTO_WAVES_FROM_BOUNCES: u32 = 3;

/// Most chunks a light's photons take through the waves (`indirect_queue_paths` at
/// least this fraction of the photons): each chunk records its waves' launches.
pub const MAX_INDIRECT_CHUNKS: u64 = 64;

/// Every parameter of the technique.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct PhotonGiSettings {
    /// What every technique shares: photon grid (the photons of all lights, split by
    /// power), seed, accumulation, the temporal blend and A-Trous iterations (on by
    /// default: the chapter's), outputs, pruning, the camera's specular chains.
    pub frame: FrameSettings,
    /// Diffuse bounces of a path, the RSM's included (Smal 2019: 3 "high", 1 "low"): photons
    /// are stored at the hits after bounces 1 ..= `bounces`.
    pub bounces: u32,
    /// Most ray segments of a path (bounds mirror and glass chains).
    pub max_segments: u32,
    /// Texels per side of each RSM face (a power of two, 8..=2048).
    pub rsm_size: u32,
    /// Screen tile edge (pixels) of the splat's photon-density counts (Eqs. 3-6's `t`).
    pub tile_size: u32,
    /// Eq. 6's `n_tile`: photons expected to contribute to each pixel.
    pub photons_per_pixel: f32,
    /// Eq. 6's `r_min`, relative to the scene's bounding-box diagonal.
    pub density_radius_min: f32,
    /// Eq. 6's `r_max`, relative to the scene's bounding-box diagonal.
    pub density_radius_max: f32,
    /// Eq. 2's `l_max`, relative to the scene's diagonal (the chapter derives it from
    /// the bounding box).
    pub max_ray_length: f32,
    /// Smallest kernel scale in pixel footprints at the photon's depth (not in the chapter,
    /// whose rasterised splats cover whole pixels; see `photon_splat::min_splat_scale`).
    pub min_splat_px: f32,
    /// Compression of the kernel along the photon's normal (`s_n`, the listing's
    /// `KernelCompress`).
    pub normal_compression: f32,
    /// Largest stretch along the light direction (Eq. 7's `s_max`).
    pub max_stretch: f32,
    /// The raw indirect image's estimator (splats; or the raw deposit, for references).
    pub estimator: IndirectEstimator,
    /// How the RSM's texels are chosen (by importance; uniformly, for comparisons).
    pub rsm_sampling: RsmSampling,
    /// Most pixels from a splat's centre to its edge (a cost bound; larger splats are
    /// clipped and counted as saturated).
    pub max_splat_px: u32,
    /// Eq. 20's shading-normal correction (Smal 2019, section 24.4.3): the splats' power-weighted
    /// light direction against the shading normal instead of the geometric one. Runs only
    /// where the scene has vertex normals that depart from the geometric ones and with the
    /// splat estimator (the plan says why not).
    pub shading_normals: bool,
    /// Reflectance of dielectric interfaces ([`fresnel_model`]).
    pub fresnel_model: u32,
    /// How the indirect paths are traced (one launch, or per-bounce waves).
    pub indirect_schedule: IndirectSchedule,
    /// Waves of the `waves` schedule (1..=64): waves `0 .. n - 1` trace one segment each,
    /// the last one the rest of every path (at most `max_segments` waves run). Default 4:
    /// on the H100 at Smal 2019's high setting, with `rooms`' dim light in one launch,
    /// `trace_indirect` took 7.08 / 6.83 / 5.53 / 5.55 ms with 2 / 3 / 4 / 8 waves on
    /// OpenCL and 9.04 / 8.65 / 6.73 / 6.61 on Vulkan, and with every light in waves
    /// 6.16 ms with 4 against 6.54 with 8 on OpenCL (docs/photon-gi.md): past 4 waves a
    /// wave's launch and queue traffic cost what its shorter warps save.
    pub indirect_waves: u32,
    /// Most paths each of the waves' two queues holds (48 bytes each; a queue holds no
    /// more than a light's photons): a light's photons go through the waves in chunks of
    /// at most this many, so that no queue can overflow; the image is bitwise the same
    /// for any value. Default 2^22 (Smal 2019's high setting, 1732^2 photons, in one
    /// chunk: 288 MB for both queues; the default 1024^2 photons: 96 MiB); the
    /// `sorted_waves` schedule adds 12 bytes a path for its keys and order (36 MB at
    /// 1732^2).
    pub indirect_queue_paths: u32,
    /// Photons of a light above which the `auto` schedule's waves trace it; a light of
    /// at most this many (its count known on the host, from the frame after the plan is
    /// read back) takes the single kernel, whose program is built at its first use.
    /// Default 2^17, about 1.3 times what a large GPU runs at once (an H100 or H200, 132
    /// multiprocessors, workgroups of 64: 84,480 threads of `trace_indirect` at its 96
    /// registers, 101,376 at 80): a launch of no more photons has (nearly) every path
    /// resident from its start, so few warps wait for another's idle lanes, and the
    /// waves' own launches and queue traffic cost more than they save. On the H100
    /// (`rooms`, high setting, 8 waves) `trace_indirect` took 5.99 against 6.54 ms with
    /// every light in waves on OpenCL and 6.65 against 7.04 on Vulkan (docs/photon-gi.md);
    /// 0 traces every light in waves.
    pub auto_waves_above_photons: u32,
}

impl Default for PhotonGiSettings {
    fn default() -> Self {
        PhotonGiSettings {
            frame: FrameSettings {
                temporal: true,
                atrous_iterations: 4,
                max_specular_depth: 4,
                ..FrameSettings::seeded(1)
            },
            bounces: 3,
            max_segments: 16,
            rsm_size: 256,
            tile_size: 16,
            photons_per_pixel: 2.0,
            density_radius_min: 1e-4,
            density_radius_max: 0.05,
            max_ray_length: 0.5,
            min_splat_px: 1.5,
            normal_compression: 0.1,
            max_stretch: 4.0,
            estimator: IndirectEstimator::Splat,
            rsm_sampling: RsmSampling::Importance,
            max_splat_px: 48,
            shading_normals: true,
            fresnel_model: fresnel_model::EXACT,
            indirect_schedule: IndirectSchedule::Auto,
            indirect_waves: 4,
            indirect_queue_paths: 1 << 22,
            auto_waves_above_photons: 1 << 17,
        }
    }
}

impl TechniqueSettings for PhotonGiSettings {
    fn frame(&self) -> &FrameSettings {
        &self.frame
    }

    fn frame_mut(&mut self) -> &mut FrameSettings {
        &mut self.frame
    }
}

impl PhotonGiSettings {
    /// Initial photons per frame over all lights (`photons_w x photons_h`).
    pub fn total_photons(&self) -> u64 {
        self.frame.photons_w as u64 * self.frame.photons_h as u64
    }

    /// The schedule `indirect_schedule` runs on a device of type `device` (`auto`
    /// resolved by the bounces and the device).
    pub fn schedule(&self, device: DeviceType) -> IndirectSchedule {
        match self.indirect_schedule {
            IndirectSchedule::Auto
                if self.bounces >= AUTO_WAVES_FROM_BOUNCES
                    && device != DeviceType::Cpu
                    && self.total_photons() <= self.indirect_queue_paths as u64 =>
            {
                IndirectSchedule::Waves
            }
            IndirectSchedule::Auto => IndirectSchedule::SingleKernel,
            s => s,
        }
    }

    /// Launches of `trace_indirect` per light and chunk under `schedule` (resolved,
    /// [`PhotonGiSettings::schedule`]; `auto` counts as the single kernel): 1, or the
    /// waves (at most one a segment).
    pub fn waves(&self, schedule: IndirectSchedule) -> u32 {
        match schedule {
            IndirectSchedule::Auto | IndirectSchedule::SingleKernel => 1,
            IndirectSchedule::Waves | IndirectSchedule::SortedWaves => {
                self.indirect_waves.min(self.max_segments).max(1)
            }
        }
    }

    /// Launches of `trace_indirect` per chunk of a light's photons: [`Self::waves`],
    /// but 1 under the `auto` schedule for a light of `photons` (`None`: not known on the
    /// host, the device plan's count) at most `auto_waves_above_photons`.
    pub fn light_waves(&self, schedule: IndirectSchedule, photons: Option<u32>) -> u32 {
        match photons {
            Some(n)
                if self.indirect_schedule == IndirectSchedule::Auto
                    && n <= self.auto_waves_above_photons =>
            {
                1
            }
            _ => self.waves(schedule),
        }
    }

    /// Refuses values the kernels cannot run with, each by name.
    pub fn validate(&self) -> Result<(), Error> {
        let bad = |what: &str| Err(Error::InvalidParameter(format!("photon-gi: {what}")));
        self.frame.validate()?;
        self.frame.check_outputs("photon-gi", &super::OUTPUTS)?;
        let total = self.frame.photons();
        if total == 0 || total > (1 << 28) {
            return bad("photons_w x photons_h must be in 1..=2^28");
        }
        if self.bounces == 0 || self.bounces > 16 {
            return bad("bounces must be in 1..=16");
        }
        if self.max_segments == 0 || self.max_segments > 1024 {
            return bad("max_segments must be in 1..=1024");
        }
        if !self.rsm_size.is_power_of_two() || !(8..=2048).contains(&self.rsm_size) {
            return bad("rsm_size must be a power of two in 8..=2048");
        }
        if self.tile_size == 0 || self.tile_size > 256 {
            return bad("tile_size must be in 1..=256");
        }
        if self.max_splat_px == 0 || self.max_splat_px > 256 {
            return bad("max_splat_px must be in 1..=256");
        }
        for (name, v) in [
            ("photons_per_pixel", self.photons_per_pixel),
            ("density_radius_min", self.density_radius_min),
            ("density_radius_max", self.density_radius_max),
            ("max_ray_length", self.max_ray_length),
            ("normal_compression", self.normal_compression),
            ("min_splat_px", self.min_splat_px),
        ] {
            if !(v > 0.0 && v.is_finite()) {
                return bad(&format!("{name} must be > 0 and finite"));
            }
        }
        if self.density_radius_min > self.density_radius_max {
            return bad("density_radius_min must not exceed density_radius_max");
        }
        if !(self.max_stretch >= 1.0 && self.max_stretch.is_finite()) {
            return bad("max_stretch must be >= 1 and finite");
        }
        if self.indirect_waves == 0 || self.indirect_waves > 64 {
            return bad("indirect_waves must be in 1..=64");
        }
        if self.indirect_queue_paths == 0 || self.indirect_queue_paths > 1 << 28 {
            return bad("indirect_queue_paths must be in 1..=2^28");
        }
        if total.div_ceil(self.indirect_queue_paths as u64) > MAX_INDIRECT_CHUNKS {
            return bad(&format!(
                "indirect_queue_paths must hold at least 1/{MAX_INDIRECT_CHUNKS} of the photons \
                 (a light's photons in at most {MAX_INDIRECT_CHUNKS} chunks)"
            ));
        }
        if self.fresnel_model > fresnel_model::SCHLICK {
            return bad("fresnel_model must be 0 (exact) or 1 (Schlick)");
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `auto` runs the waves on a GPU from three bounces while a light's photons fit one
    /// chunk of the queues, the single kernel otherwise and on the CPU backend; a named
    /// schedule is kept.
    #[test]
    fn the_shared_atrous_clip_bounds_hold_here_too() {
        // 0 keeps no detail, as in every technique; negative or NaN is refused
        let mut s = PhotonGiSettings::default();
        s.frame.atrous_clip_sigmas = 0.0;
        s.validate().unwrap();
        for bad in [-1.0, f32::NAN, f32::INFINITY] {
            s.frame.atrous_clip_sigmas = bad;
            assert!(s.validate().is_err(), "{bad}");
        }
    }

    #[test]
    fn auto_resolves_by_bounces_device_and_queue() {
        let high = PhotonGiSettings {
            bounces: 3,
            ..Default::default()
        };
        let gpu = DeviceType::DiscreteGpu;
        assert_eq!(high.schedule(gpu), IndirectSchedule::Waves);
        assert_eq!(
            high.schedule(DeviceType::SoftwareGpu),
            IndirectSchedule::Waves
        );
        assert_eq!(
            high.schedule(DeviceType::Cpu),
            IndirectSchedule::SingleKernel
        );
        let low = PhotonGiSettings {
            bounces: 1,
            ..high.clone()
        };
        assert_eq!(low.schedule(gpu), IndirectSchedule::SingleKernel);
        let chunked = PhotonGiSettings {
            indirect_queue_paths: (high.total_photons() - 1) as u32,
            ..high.clone()
        };
        assert_eq!(chunked.schedule(gpu), IndirectSchedule::SingleKernel);
        for s in [
            IndirectSchedule::SingleKernel,
            IndirectSchedule::Waves,
            IndirectSchedule::SortedWaves,
        ] {
            let named = PhotonGiSettings {
                indirect_schedule: s,
                ..low.clone()
            };
            assert_eq!(named.schedule(DeviceType::Cpu), s);
        }
        let json: PhotonGiSettings =
            serde_json::from_value(serde_json::json!({ "indirect_schedule": "auto" })).unwrap();
        assert_eq!(json.indirect_schedule, IndirectSchedule::Auto);
    }

    /// Under `auto`'s waves a light of known photons up to `auto_waves_above_photons`
    /// takes the single kernel, an unknown count or a larger one the waves; a named
    /// schedule keeps its waves for every light.
    #[test]
    fn auto_traces_a_light_of_few_photons_in_one_launch() {
        let auto = PhotonGiSettings {
            indirect_waves: 8,
            ..Default::default()
        };
        let every_light = PhotonGiSettings {
            auto_waves_above_photons: 0,
            ..auto.clone()
        };
        let waves = auto.schedule(DeviceType::DiscreteGpu);
        assert_eq!(waves, IndirectSchedule::Waves);
        assert_eq!(every_light.light_waves(waves, Some(1)), 8);
        let above = auto.auto_waves_above_photons;
        assert_eq!(above, 1 << 17);
        assert_eq!(auto.light_waves(waves, Some(above)), 1);
        assert_eq!(auto.light_waves(waves, Some(0)), 1);
        assert_eq!(auto.light_waves(waves, Some(above + 1)), 8);
        assert_eq!(auto.light_waves(waves, None), 8);
        let single = auto.schedule(DeviceType::Cpu);
        assert_eq!(auto.light_waves(single, None), 1);
        let named = PhotonGiSettings {
            indirect_schedule: IndirectSchedule::SortedWaves,
            ..auto
        };
        let sorted = named.schedule(DeviceType::DiscreteGpu);
        assert_eq!(named.light_waves(sorted, Some(1)), 8);
    }
}
