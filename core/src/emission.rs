//! Photon emission domains (seed 000 section 30.3.1.1). Each light gets a domain whose
//! photons all carry the same flux (stratified equal-area grid):
//!
//! - point light: the cone from the light that bounds the caustic casters' bounding
//!   sphere (or the whole sphere when the light is inside it, or when asked), flux per
//!   photon `I * Omega / (pw ph)` (Eq. 1 with `Omega = 4 pi` for the full sphere);
//! - spot light: its outer cone, `I * Omega_outer / (pw ph)`, times the spot falloff at the
//!   photon's direction (applied in the kernel);
//! - directional light: the rectangle `A` onto which the projection volume projects along
//!   the light direction, `E * a_l / (pw ph)` (Eq. 3), rays starting up-light of the scene.
//!
//! Photons outside the caster cone cannot meet a specular surface first, so leaving them
//! out removes no caustic photon (they would all be dropped as direct light).

use crate::geometry::Aabb;
use crate::gpu::emission_kind;
use crate::sampling::{cone_solid_angle, orthonormal_basis};
use crate::scene::Light;
use glam::Vec3;

/// Whether point lights emit over the whole sphere (as the source's pseudocode) or only
/// towards the caustic casters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointEmission {
    Sphere,
    CasterCone,
}

/// Emission domain of one light, in the form of `TraceParams` fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionDomain {
    pub kind: u32,
    pub origin: Vec3,
    pub axis: Vec3,
    pub cos_max: f32,
    pub rect_u: Vec3,
    pub rect_v: Vec3,
    /// Solid angle (cone) or area (rectangle) covered by the domain.
    pub measure: f32,
    /// Flux of the whole domain (W per channel) before spot falloff.
    pub flux: Vec3,
}

impl EmissionDomain {
    /// Parameters of a `trace_photons` dispatch over photons `first .. first + count` of
    /// the `grid.0 x grid.1` grid of light `light`: flux per photon is the domain's flux
    /// over the grid (000 Eqs. 1 and 3).
    #[allow(clippy::too_many_arguments)]
    pub fn trace_params(
        &self,
        light: u32,
        grid: (u32, u32),
        (first, count): (u32, u32),
        seed: u32,
        max_bounces: u32,
        min_relative_power: f32,
        flux_quantum: f32,
    ) -> crate::gpu::TraceParams {
        let per_light = grid.0 as u64 * grid.1 as u64;
        crate::gpu::TraceParams {
            light,
            emission: self.kind,
            grid_w: grid.0,
            grid_h: grid.1,
            first,
            count,
            seed,
            max_bounces,
            origin: self.origin.extend(self.cos_max).to_array(),
            axis: self.axis.extend(0.0).to_array(),
            rect_u: self.rect_u.extend(0.0).to_array(),
            rect_v: self.rect_v.extend(0.0).to_array(),
            photon_flux: (self.flux / per_light as f32)
                .extend(min_relative_power)
                .to_array(),
            flux_quantum,
            _pad: [0; 3],
        }
    }
}

/// Why a light emits no photons.
#[derive(Clone, Debug, PartialEq)]
pub enum NoEmission {
    NoCasters,
    ZeroPower,
}

/// The emission domain of `light` given the casters' and the scene's bounds.
pub fn emission_domain(
    light: &Light,
    casters: Aabb,
    scene: Aabb,
    point: PointEmission,
) -> Result<EmissionDomain, NoEmission> {
    match light {
        Light::Point {
            position,
            intensity,
        }
        | Light::Spot {
            position,
            intensity,
            ..
        } => {
            if intensity.max_element() <= 0.0 {
                return Err(NoEmission::ZeroPower);
            }
            if casters.is_empty() {
                return Err(NoEmission::NoCasters);
            }
            let (axis, cos_max) = if let Light::Spot {
                direction,
                outer_angle_deg,
                ..
            } = light
            {
                (direction.normalize(), outer_angle_deg.to_radians().cos())
            } else {
                let c = casters.center();
                let r = 0.5 * casters.diagonal();
                let to = c - *position;
                let dist = to.length();
                if point == PointEmission::CasterCone && dist > r * 1.0001 {
                    (to / dist, (1.0 - (r / dist).powi(2)).max(0.0).sqrt())
                } else {
                    (Vec3::Z, -1.0)
                }
            };
            let omega = cone_solid_angle(cos_max);
            Ok(EmissionDomain {
                kind: emission_kind::CONE,
                origin: *position,
                axis,
                cos_max,
                rect_u: Vec3::ZERO,
                rect_v: Vec3::ZERO,
                measure: omega,
                flux: *intensity * omega,
            })
        }
        Light::Directional {
            direction,
            irradiance,
            projection_volume,
        } => {
            if irradiance.max_element() <= 0.0 {
                return Err(NoEmission::ZeroPower);
            }
            let volume = projection_volume.unwrap_or(casters);
            if volume.is_empty() || casters.is_empty() {
                return Err(NoEmission::NoCasters);
            }
            let d = direction.normalize();
            let (t, b) = orthonormal_basis(d);
            let (mut s0, mut s1, mut u0, mut u1) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
            for c in volume.corners() {
                s0 = s0.min(c.dot(t));
                s1 = s1.max(c.dot(t));
                u0 = u0.min(c.dot(b));
                u1 = u1.max(c.dot(b));
            }
            // Start plane up-light of everything, so occluders above the volume count.
            let mut h0 = f32::MAX;
            for c in scene.union(volume).corners() {
                h0 = h0.min(c.dot(d));
            }
            let span = scene.union(volume).diagonal().max(f32::MIN_POSITIVE);
            h0 -= 1e-3 * span;
            let rect_u = t * (s1 - s0);
            let rect_v = b * (u1 - u0);
            let area = (s1 - s0) * (u1 - u0);
            Ok(EmissionDomain {
                kind: emission_kind::RECTANGLE,
                origin: t * s0 + b * u0 + d * h0,
                axis: d,
                cos_max: 1.0,
                rect_u,
                rect_v,
                measure: area,
                flux: *irradiance * area,
            })
        }
    }
}
