//! CausticMap's emission (Vanderstichelen 2021, section 3.1): each light's view planes aimed at the
//! caustic casters, and the fixed-point quantum of the frame's flux.

use crate::device::caster_spheres::CasterSpheres;
use crate::frame::emission::light_view_plane::{light_view_planes, LightViewPlane};
use crate::frame::emission::NoEmission;
use crate::frame::receivers::atlas::settings::PlaneSettings;
use crate::frame::settings::FrameSettings;
use crate::math::fixed_point::power_of_two_quantum;
use crate::math::geometry::Aabb;
use crate::math::rng::pcg_hash;
use crate::scene::Scene;

/// The light view planes of a frame and what its fixed-point sums are scaled by.
#[derive(Clone, Debug)]
pub struct ViewPlanes {
    /// (light index, plane index of that light, plane) of every plane that emits.
    pub planes: Vec<(u32, u32, LightViewPlane)>,
    /// Lights that emit nothing, and why.
    pub skipped_lights: Vec<(u32, NoEmission)>,
    /// Flux per fixed-point unit (W), a power of two: the brightest photon (a plane's
    /// centre texel, times the gain of a dispersive surface,
    /// [`Dispersion::flux_gain`](crate::frame::settings::Dispersion::flux_gain)) is 2^24
    /// to 2^25 units.
    pub flux_quantum: f32,
    /// Hit distance per fixed-point unit (scene units): the scene diagonal is 2^24 to
    /// 2^25 units.
    pub hit_distance_quantum: f32,
    /// Balls around the casters that photons' first segments are tested against
    /// ([`crate::device::caster_spheres`]).
    pub caster_spheres: CasterSpheres,
}

impl ViewPlanes {
    /// The planes of every light of `scene` (bounded by `bounds`, casters in `casters`)
    /// at the settings' resolution: one plane of `photons_w x photons_h` texels, or six
    /// cube faces of `photons_w / sqrt 6 x photons_h / sqrt 6`.
    pub fn new(
        scene: &Scene,
        bounds: Aabb,
        casters: Aabb,
        caster_spheres: CasterSpheres,
        has_dispersion: bool,
        frame: &FrameSettings,
        view: &PlaneSettings,
    ) -> ViewPlanes {
        let mut planes = Vec::new();
        let mut skipped_lights = Vec::new();
        for (i, l) in scene.lights.iter().enumerate() {
            match light_view_planes(
                l,
                casters,
                bounds,
                frame.photons_w,
                view.emission_plane.aim(),
            ) {
                Ok(ps) => {
                    let cube = ps.len() > 1;
                    for (k, mut p) in ps.into_iter().enumerate() {
                        p.resolution = if cube {
                            let side = |n: u32| ((n as f64 / 6f64.sqrt()).round() as u32).max(1);
                            (side(frame.photons_w), side(frame.photons_h))
                        } else {
                            (frame.photons_w, frame.photons_h)
                        };
                        planes.push((i as u32, k as u32, p));
                    }
                }
                Err(why) => skipped_lights.push((i as u32, why)),
            }
        }
        let flux_quantum =
            Self::quantum_for(&planes, frame.dispersion.flux_gain(has_dispersion), |p| {
                p.resolution
            });
        ViewPlanes {
            planes,
            skipped_lights,
            flux_quantum,
            hit_distance_quantum: power_of_two_quantum(bounds.diagonal().max(f32::MIN_POSITIVE)),
            caster_spheres,
        }
    }

    /// `trace_photons` parameters for photons `first .. first + count` of `plane` (of
    /// light `light`): the plane's emission ([`LightViewPlane::trace_params`]) at the
    /// frame's flux quantum, with the casters' balls.
    pub fn trace_params(
        &self,
        plane: &LightViewPlane,
        light: u32,
        range: (u32, u32),
        seed: u32,
        max_bounces: u32,
        min_relative_power: f32,
    ) -> crate::device::layout::TraceParams {
        let mut p = plane.trace_params(
            light,
            range,
            seed,
            max_bounces,
            min_relative_power,
            self.flux_quantum,
        );
        self.caster_spheres.apply(&mut p);
        p
    }

    /// The flux quantum for photons of `planes` shot on grids of `resolution(plane)`
    /// texels: the brightest photon (a centre texel's, times `dispersion_gain`,
    /// [`Dispersion::flux_gain`](crate::frame::settings::Dispersion::flux_gain)) is 2^24
    /// to 2^25 units.
    pub fn quantum_for(
        planes: &[(u32, u32, LightViewPlane)],
        dispersion_gain: f32,
        resolution: impl Fn(&LightViewPlane) -> (u32, u32),
    ) -> f32 {
        let gain = dispersion_gain;
        let max_photon_flux = planes
            .iter()
            .map(|(_, _, p)| {
                let (hx, hy) = p.half_extent;
                let (w, h) = resolution(p);
                let texel = (2.0 * hx / w as f32) * (2.0 * hy / h as f32);
                p.power.max_element() * texel
            })
            .fold(0.0f32, f32::max)
            * gain;
        power_of_two_quantum(max_photon_flux)
    }

    /// Every light's plan: it emits when it has a plane (its view plane sees a caustic
    /// caster), else why not.
    pub fn light_plans(&self) -> Vec<crate::frame::plan::LightPlan> {
        use crate::frame::plan::LightPlan;
        let mut lights: Vec<LightPlan> = self
            .planes
            .iter()
            .filter(|(_, k, _)| *k == 0)
            .map(|(i, _, _)| LightPlan {
                light: *i,
                emits: true,
                reason: "its light view plane sees a caustic caster".into(),
            })
            .collect();
        lights.extend(self.skipped_lights.iter().map(|(i, why)| LightPlan {
            light: *i,
            emits: false,
            reason: why.reason().into(),
        }));
        lights.sort_by_key(|l| l.light);
        lights
    }

    /// The RNG seed of plane `plane` of light `light`: the frame seed hashed with both.
    pub fn plane_seed(seed: u32, light: u32, plane: u32) -> u32 {
        seed ^ pcg_hash(
            light
                .wrapping_mul(8)
                .wrapping_add(plane)
                .wrapping_add(0x4341_5553),
        )
    }

    /// Refuses a plane whose total flux is not finite or over
    /// [`crate::scene::limits::MAX_LIGHT_FLUX`], naming the light.
    pub fn check_light_flux(&self) -> Result<(), crate::frame::error::Error> {
        use crate::scene::limits::MAX_LIGHT_FLUX;
        for (i, _, p) in &self.planes {
            let f = (p.power.max_element() as f64 * p.plane_measure()) as f32;
            if !(f.is_finite() && f <= MAX_LIGHT_FLUX) {
                return Err(crate::frame::error::Error::InvalidScene(format!(
                    "lights[{i}]: emits {f:e} W per channel through its light view plane, over \
                     the bound {MAX_LIGHT_FLUX:e} W (2^100) that keeps a frame's flux finite"
                )));
            }
        }
        Ok(())
    }
}
