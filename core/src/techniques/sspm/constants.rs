//! What Sspm's kernels are parameterised with, derived before any work.

use super::settings::SspmSettings;
use crate::device::caster_spheres::CasterSpheres;
use crate::device::device_scene::DeviceScene;
use crate::device::layout::*;
use crate::frame::emission::{emission_domain, unpruned_domain, EmissionDomain, NoEmission};
use crate::frame::plan::LightPlan;
use crate::frame::receivers::screen::ScreenQuanta;
use crate::math::fixed_point::power_of_two_quantum;
use crate::math::geometry::Aabb;
use crate::math::rng::pcg_hash;
use crate::scene::Scene;

/// What a frame's kernels are parameterised with, derived from the scene and settings
/// before any work: each light's emission domain (or why it emits nothing), the
/// fixed-point quanta and the gather's hit-distance clamp. [`Sspm`](super::Sspm) records its kernels
/// with these; tests that drive single kernels build the same parameters from them.
#[derive(Clone, Debug)]
pub struct FrameConstants {
    /// (light index, emission domain) of every light that emits photons.
    pub domains: Vec<(u32, EmissionDomain)>,
    /// Lights that emit no photons, and why.
    pub skipped_lights: Vec<(u32, NoEmission)>,
    /// Lights in `domains` that emit their whole domain only because pruning is off.
    pub unpruned: Vec<u32>,
    /// Flux of the brightest photon the frame can store (W, one channel): the largest
    /// per-photon emitted flux, times the gain of a dispersive surface
    /// ([`Dispersion::flux_gain`](crate::frame::settings::Dispersion::flux_gain)).
    pub max_photon_flux: f32,
    /// Flux per fixed-point unit (W), a power of two: the brightest photon of the frame
    /// (with the gain of a dispersive surface) is 2^24 to 2^25 units.
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units), a power of two: the scene diagonal
    /// is 2^24 to 2^25 units.
    pub hit_distance_quantum: f32,
    /// Lower clamp of the gather's hit distance (scene units; default 5% of the scene
    /// diagonal).
    pub hit_distance_min: f32,
    /// Upper clamp of the gather's hit distance (scene units; default 50% of the scene
    /// diagonal, never below `hit_distance_min`).
    pub hit_distance_max: f32,
    /// Balls around the casters that photons' first segments are tested against
    /// ([`crate::device::caster_spheres`]).
    pub caster_spheres: CasterSpheres,
}

impl FrameConstants {
    /// Derives the constants from the scene, its device scene and the settings.
    pub fn new(scene: &Scene, ds: &DeviceScene, settings: &SspmSettings) -> FrameConstants {
        Self::for_bounds(
            scene,
            ds.bounds,
            (ds.caster_bounds, ds.caster_spheres),
            ds.has_dispersion,
            settings,
        )
    }

    /// Refuses a light whose emitted flux is not finite or over
    /// [`crate::scene::limits::MAX_LIGHT_FLUX`] (a directional light's irradiance times a
    /// huge projection area), naming the light.
    pub fn check_light_flux(&self) -> Result<(), crate::frame::error::Error> {
        use crate::scene::limits::MAX_LIGHT_FLUX;
        for (i, d) in &self.domains {
            let f = d.flux.max_element();
            if !(f.is_finite() && f <= MAX_LIGHT_FLUX) {
                return Err(crate::frame::error::Error::InvalidScene(format!(
                    "lights[{i}]: emits {f:e} W per channel into its emission domain, over \
                     the bound {MAX_LIGHT_FLUX:e} W (2^100) that keeps a frame's flux finite"
                )));
            }
        }
        Ok(())
    }

    /// [`FrameConstants::new`] from the device scene's bounds (scene; casters' box and
    /// balls) and whether a material disperses: what a light update re-plans with.
    pub fn for_bounds(
        scene: &Scene,
        bounds: Aabb,
        (caster_bounds, caster_spheres): (Aabb, CasterSpheres),
        has_dispersion: bool,
        settings: &SspmSettings,
    ) -> FrameConstants {
        let mut domains = Vec::new();
        let mut skipped_lights = Vec::new();
        let mut unpruned = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            let i = i as u32;
            match emission_domain(l, caster_bounds, bounds, settings.point_emission) {
                Ok(domain) => domains.push((i, domain)),
                Err(why) => match unpruned_domain(l, bounds).filter(|_| !settings.frame.prune) {
                    Some(domain) => {
                        domains.push((i, domain));
                        unpruned.push(i);
                    }
                    None => skipped_lights.push((i, why)),
                },
            }
        }
        let photons_per_light = settings.frame.photons_w as f32 * settings.frame.photons_h as f32;
        let dispersion_gain = settings.frame.dispersion.flux_gain(has_dispersion);
        // Lights that emit only because pruning is off store no photon (that is why the
        // plan prunes them), so the quantum ignores them and stays the pruned frame's:
        // pruning on and off give the same fixed-point sums.
        let max_photon_flux = domains
            .iter()
            .filter(|(i, _)| !unpruned.contains(i))
            .map(|(_, d)| d.flux.max_element() / photons_per_light)
            .fold(0.0f32, f32::max)
            * dispersion_gain;
        let quanta = ScreenQuanta::new(
            bounds,
            power_of_two_quantum(max_photon_flux),
            &settings.screen,
        );
        FrameConstants {
            domains,
            skipped_lights,
            unpruned,
            max_photon_flux,
            flux_quantum: quanta.flux_quantum,
            hit_distance_quantum: quanta.hit_distance_quantum,
            hit_distance_min: quanta.hit_distance_min,
            hit_distance_max: quanta.hit_distance_max,
            caster_spheres,
        }
    }

    /// The screen receiver's quanta and hit-distance clamp.
    pub fn quanta(&self) -> ScreenQuanta {
        ScreenQuanta {
            flux_quantum: self.flux_quantum,
            hit_distance_quantum: self.hit_distance_quantum,
            hit_distance_min: self.hit_distance_min,
            hit_distance_max: self.hit_distance_max,
        }
    }

    /// `trace_photons` parameters for photons `first .. first + count` of light `light`
    /// with emission domain `d`: the light's seed is the frame seed hashed with its index.
    pub fn trace_params(
        &self,
        settings: &SspmSettings,
        light: u32,
        d: &EmissionDomain,
        first: u32,
        count: u32,
    ) -> TraceParams {
        let mut p = d.trace_params(
            light,
            (settings.frame.photons_w, settings.frame.photons_h),
            (first, count),
            settings.frame.seed ^ pcg_hash(light.wrapping_add(0x6c62_272e)),
            settings.trace.max_bounces,
            settings.trace.min_relative_power,
            self.flux_quantum,
        );
        self.caster_spheres.apply(&mut p);
        p.dispersion_mode = settings.frame.dispersion.kernel_value();
        p
    }

    /// `deposit_screen` / `resolve_caustics` parameters.
    pub fn deposit_params(
        &self,
        camera: GpuCamera,
        settings: &SspmSettings,
        photon_capacity: u32,
    ) -> DepositParams {
        self.quanta()
            .deposit_params(camera, &settings.screen, photon_capacity)
    }

    /// The gathers' parameters (`axis` 0: horizontal pass).
    pub fn gather_params(
        &self,
        camera: GpuCamera,
        settings: &SspmSettings,
        axis: u32,
    ) -> GatherParams {
        self.quanta().gather_params(camera, &settings.screen, axis)
    }

    /// `direct_light` parameters.
    pub fn direct_params(
        camera: GpuCamera,
        light_count: u32,
        settings: &SspmSettings,
    ) -> DirectParams {
        crate::frame::receivers::screen::direct_lighting(&settings.frame)
            .params(camera, light_count)
    }
}

/// The plan of every light of `constants`' emission (Kim 2019's projection volumes):
/// whether it emits and why.
pub fn volume_light_plans(constants: &FrameConstants) -> Vec<LightPlan> {
    let mut lights: Vec<LightPlan> = constants
        .domains
        .iter()
        .map(|(i, _)| LightPlan {
            light: *i,
            emits: true,
            reason: if constants.unpruned.contains(i) {
                "pruning off: emits its whole domain".into()
            } else {
                "its emission domain reaches a caustic caster".into()
            },
        })
        .collect();
    lights.extend(constants.skipped_lights.iter().map(|(i, why)| LightPlan {
        light: *i,
        emits: false,
        reason: why.reason().into(),
    }));
    lights.sort_by_key(|l| l.light);
    lights
}
