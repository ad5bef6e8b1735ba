//! Photon emission domains (Kim 2019, section 30.3.1.1). Each light gets a domain whose
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
//! out removes no caustic photon (they would all be dropped as direct light). For the
//! same reason a spot light emits into the narrower of its outer cone and the caster
//! cone, and a spot light whose cone misses the casters' bounding sphere, or a
//! directional light whose projection volume misses the casters' box, emits nothing
//! ([`NoEmission::MissesCasters`]; the frame plan's light-frustum test). With pruning
//! off, [`unpruned_domain`] gives such lights their whole domain instead.

use crate::device::layout::emission_kind;
use crate::math::geometry::Aabb;
use crate::math::sampling::{cone_solid_angle, orthonormal_basis};
use crate::scene::Light;
use glam::Vec3;

/// Whether point lights emit over the whole sphere (as the source's pseudocode) or only
/// towards the caustic casters.
#[derive(Clone, Copy, Debug, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PointEmission {
    /// The whole sphere of directions, as the source's pseudocode.
    Sphere,
    /// The cone from the light that bounds the casters' bounding sphere (the whole sphere
    /// when the light is inside it).
    CasterCone,
}

/// Emission domain of one light, in the form of `TraceParams` fields.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct EmissionDomain {
    /// One of [`emission_kind`]: cone or rectangle.
    pub kind: u32,
    /// Cone apex (the light's position) or rectangle corner (world space).
    pub origin: Vec3,
    /// Unit cone axis, or the rays' direction for a rectangle (world space).
    pub axis: Vec3,
    /// Cosine of the cone's half-angle (-1: the whole sphere; 1 for rectangles).
    pub cos_max: f32,
    /// First rectangle edge (world space, scene units; zero for cones).
    pub rect_u: Vec3,
    /// Second rectangle edge (world space, scene units; zero for cones).
    pub rect_v: Vec3,
    /// Solid angle (cone, sr) or area (rectangle, scene units^2) covered by the domain.
    pub measure: f32,
    /// Flux of the whole domain (W per channel) before spot falloff.
    pub flux: Vec3,
}

impl EmissionDomain {
    /// Parameters of a `trace_photons` dispatch over photons `first .. first + count` (in
    /// tile order, [`crate::math::sampling::tiled_photon_index`]) of the `grid.0 x grid.1`
    /// grid of light `light`: flux per photon is the domain's flux
    /// over the grid (Kim 2019, Eqs. 1 and 3).
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
    ) -> crate::device::layout::TraceParams {
        let per_light = grid.0 as u64 * grid.1 as u64;
        crate::device::layout::TraceParams {
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
            split_budget: 1,
            fresnel_model: crate::math::optics::fresnel_model::EXACT,
            // no first-segment test until the technique adds its casters' balls
            // (`CasterSpheres::apply`)
            caster_sphere_count: 0,
            // a frame on its own: jitter from its seed (an accumulation sets its stratum)
            jitter_seed: seed,
            stratum: 0,
            // spectral, the default (a technique sets its `frame.dispersion`)
            dispersion_mode: crate::math::spectrum::dispersion_mode::SPECTRAL,
            _pad: 0,
            caster_spheres: [[0.0; 4]; crate::device::layout::MAX_CASTER_SPHERES],
        }
    }
}

/// Why a light emits no photons.
#[derive(Clone, Debug, PartialEq)]
pub enum NoEmission {
    /// The scene has no mirror or dielectric (nothing can cast a caustic).
    NoCasters,
    /// The light's intensity or irradiance is zero in every channel.
    ZeroPower,
    /// The light's frustum (spot cone, directional projection volume) misses every
    /// caster.
    MissesCasters,
    /// A directional light's projection volume is flat seen along its direction: the
    /// rectangle its photons cover has no area.
    FlatVolume,
}

impl NoEmission {
    /// The reason as the frame stats print it.
    pub fn reason(&self) -> &'static str {
        match self {
            NoEmission::NoCasters => "no specular surface (caustic caster) in the scene",
            NoEmission::ZeroPower => "light has zero power",
            NoEmission::MissesCasters => "light frustum misses every caustic caster",
            NoEmission::FlatVolume => {
                "projection volume flat seen along the light: its photons' rectangle has no area"
            }
        }
    }
}

/// Cone from `apex` that bounds the sphere around `casters` (axis, cosine of the half
/// angle), or `None` when `apex` is inside that sphere.
fn caster_cone(apex: Vec3, casters: Aabb) -> Option<(Vec3, f32)> {
    let c = casters.center();
    let r = 0.5 * casters.diagonal();
    let to = c - apex;
    let dist = to.length();
    (dist > r * 1.0001).then(|| (to / dist, (1.0 - (r / dist).powi(2)).max(0.0).sqrt()))
}

fn cone_domain(position: Vec3, intensity: Vec3, axis: Vec3, cos_max: f32) -> EmissionDomain {
    let omega = cone_solid_angle(cos_max);
    EmissionDomain {
        kind: emission_kind::CONE,
        origin: position,
        axis,
        cos_max,
        rect_u: Vec3::ZERO,
        rect_v: Vec3::ZERO,
        measure: omega,
        flux: intensity * omega,
    }
}

/// The rectangle domain of a directional light covering `volume` (Kim 2019, Eq. 3): the
/// projection of `volume` along `direction`, starting up-light of `scene` and `volume`.
fn rectangle_domain(
    direction: Vec3,
    irradiance: Vec3,
    volume: Aabb,
    scene: Aabb,
) -> EmissionDomain {
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
    EmissionDomain {
        kind: emission_kind::RECTANGLE,
        origin: t * s0 + b * u0 + d * h0,
        axis: d,
        cos_max: 1.0,
        rect_u,
        rect_v,
        measure: area,
        flux: irradiance * area,
    }
}

/// True when two boxes share a point (touching counts).
fn boxes_overlap(a: Aabb, b: Aabb) -> bool {
    a.min.cmple(b.max).all() && b.min.cmple(a.max).all()
}

/// The whole domain of a light, ignoring the casters (pruning off): a point light's
/// sphere, a spot light's outer cone, a directional light's projection volume (the scene
/// bounds when it has none). `None` only for a directional light in an empty scene.
pub fn unpruned_domain(light: &Light, scene: Aabb) -> Option<EmissionDomain> {
    match light {
        Light::Point {
            position,
            intensity,
        } => Some(cone_domain(*position, *intensity, Vec3::Z, -1.0)),
        Light::Spot {
            position,
            direction,
            intensity,
            outer_angle_deg,
            ..
        } => Some(cone_domain(
            *position,
            *intensity,
            direction.normalize(),
            outer_angle_deg.to_radians().cos(),
        )),
        Light::Directional {
            direction,
            irradiance,
            projection_volume,
        } => {
            let volume = projection_volume.unwrap_or(scene);
            (!volume.is_empty()).then(|| rectangle_domain(*direction, *irradiance, volume, scene))
        }
    }
}

/// The emission domain of `light` given the casters' and the scene's bounds, or why it
/// emits nothing.
pub fn emission_domain(
    light: &Light,
    casters: Aabb,
    scene: Aabb,
    point: PointEmission,
) -> Result<EmissionDomain, NoEmission> {
    let power = match light {
        Light::Point { intensity, .. } | Light::Spot { intensity, .. } => *intensity,
        Light::Directional { irradiance, .. } => *irradiance,
    };
    if power.max_element() <= 0.0 {
        return Err(NoEmission::ZeroPower);
    }
    if casters.is_empty() {
        return Err(NoEmission::NoCasters);
    }
    match light {
        Light::Point {
            position,
            intensity,
        } => Ok(match caster_cone(*position, casters) {
            Some((axis, cos_max)) if point == PointEmission::CasterCone => {
                cone_domain(*position, *intensity, axis, cos_max)
            }
            _ => cone_domain(*position, *intensity, Vec3::Z, -1.0),
        }),
        Light::Spot {
            position,
            direction,
            intensity,
            outer_angle_deg,
            ..
        } => {
            let spot_axis = direction.normalize();
            let cos_spot = outer_angle_deg.to_radians().cos();
            let Some((axis, cos_caster)) = caster_cone(*position, casters) else {
                // the light is among the casters: its whole cone may meet one
                return Ok(cone_domain(*position, *intensity, spot_axis, cos_spot));
            };
            // Cones miss when the angle between the axes exceeds the sum of the half
            // angles (with a 1e-3 rad margin for f32 acos; a near miss emits).
            let between = spot_axis.dot(axis).clamp(-1.0, 1.0).acos();
            if between > cos_spot.acos() + cos_caster.acos() + 1e-3 {
                return Err(NoEmission::MissesCasters);
            }
            // Both cones hold every photon that can meet a caster: use the narrower.
            Ok(
                if point == PointEmission::CasterCone && cos_caster > cos_spot {
                    cone_domain(*position, *intensity, axis, cos_caster)
                } else {
                    cone_domain(*position, *intensity, spot_axis, cos_spot)
                },
            )
        }
        Light::Directional {
            direction,
            irradiance,
            projection_volume,
        } => {
            let volume = projection_volume.unwrap_or(casters);
            if volume.is_empty() {
                return Err(NoEmission::NoCasters);
            }
            if !boxes_overlap(volume, casters) {
                return Err(NoEmission::MissesCasters);
            }
            let d = rectangle_domain(*direction, *irradiance, volume, scene);
            if !(d.measure > 0.0) {
                return Err(NoEmission::FlatVolume);
            }
            Ok(d)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn ball() -> Aabb {
        Aabb {
            min: Vec3::splat(-0.5),
            max: Vec3::splat(0.5),
        }
    }

    fn spot(direction: Vec3, outer_angle_deg: f32) -> Light {
        Light::Spot {
            position: Vec3::new(0.0, 4.0, 0.0),
            direction,
            intensity: Vec3::ONE,
            inner_angle_deg: 0.5 * outer_angle_deg,
            outer_angle_deg,
        }
    }

    #[test]
    fn spot_aimed_away_from_the_casters_emits_nothing() {
        let scene = ball().union(Aabb {
            min: Vec3::splat(-5.0),
            max: Vec3::splat(5.0),
        });
        let e = emission_domain(
            &spot(Vec3::Y, 30.0),
            ball(),
            scene,
            PointEmission::CasterCone,
        );
        assert_eq!(e, Err(NoEmission::MissesCasters));
        // with pruning off it emits its outer cone
        let d = unpruned_domain(&spot(Vec3::Y, 30.0), scene).unwrap();
        assert!((d.cos_max - 30f32.to_radians().cos()).abs() < 1e-6);
    }

    #[test]
    fn wide_spot_emits_only_into_the_caster_cone() {
        let scene = ball();
        let d = emission_domain(
            &spot(-Vec3::Y, 80.0),
            ball(),
            scene,
            PointEmission::CasterCone,
        )
        .unwrap();
        // caster sphere radius sqrt(3)/2 at distance 4
        let want = (1.0 - (0.75f32 / 16.0)).sqrt();
        assert!((d.cos_max - want).abs() < 1e-6, "{}", d.cos_max);
        assert!((d.flux.x - cone_solid_angle(want)).abs() < 1e-6);
        // a narrow spot keeps its own cone
        let d = emission_domain(
            &spot(-Vec3::Y, 5.0),
            ball(),
            scene,
            PointEmission::CasterCone,
        )
        .unwrap();
        assert!((d.cos_max - 5f32.to_radians().cos()).abs() < 1e-6);
    }

    #[test]
    fn projection_volume_away_from_the_casters_emits_nothing() {
        let light = Light::Directional {
            direction: -Vec3::Y,
            irradiance: Vec3::ONE,
            projection_volume: Some(Aabb {
                min: Vec3::splat(2.0),
                max: Vec3::splat(3.0),
            }),
        };
        let e = emission_domain(&light, ball(), ball(), PointEmission::CasterCone);
        assert_eq!(e, Err(NoEmission::MissesCasters));
    }

    /// At `scene::limits::MIN_INTENSITY` and the most photons a light may have (`photons_w x photons_h <=
    /// 2^32 - 1`), the quantum of the brightest emitted photon is a normal f32 with the
    /// full 2^24 units, for every light kind with a domain of at least 2^-10 (sr or
    /// unit^2), as `power_of_two_quantum` gets it (Sspm's `FrameConstants`).
    #[test]
    fn the_flux_quantum_at_the_bound_is_normal() {
        use crate::frame::emission::{emission_domain, unpruned_domain, PointEmission};
        use crate::math::fixed_point::{power_of_two_quantum, FLUX_QUANTA_PER_MAX_PHOTON};
        use crate::math::geometry::Aabb;
        use crate::scene::limits::MIN_INTENSITY;
        use crate::scene::Light;
        use glam::Vec3;
        // the most photons per light (FrameSettings::validate), as the frame counts them
        let (w, h) = (65_535u32, 65_537u32);
        assert_eq!(w as u64 * h as u64, u32::MAX as u64);
        let photons = w as f32 * h as f32;
        let quantum_of = |flux: f32| {
            let per_photon = flux / photons;
            let q = power_of_two_quantum(per_photon);
            assert!(q.is_normal() && q > 0.0, "flux {flux:e}: quantum {q:e}");
            assert!(
                per_photon / q >= FLUX_QUANTA_PER_MAX_PHOTON,
                "flux {flux:e}"
            );
            q
        };
        let i = Vec3::splat(MIN_INTENSITY);
        let casters = Aabb {
            min: Vec3::splat(-0.5),
            max: Vec3::splat(0.5),
        };
        let scene = casters.union(Aabb {
            min: Vec3::splat(-10.0),
            max: Vec3::splat(10.0),
        });
        // the whole sphere: 13 octaves above the smallest normal quantum
        let point = Light::Point {
            position: Vec3::new(0.0, 3.0, 0.0),
            intensity: i,
        };
        let d = unpruned_domain(&point, scene).unwrap();
        assert!(quantum_of(d.flux.max_element()) >= 2f32.powi(-113));
        // caster cones down to about 2^-10 sr (a caster sphere 57 radii away) ...
        let r = 0.5 * casters.diagonal();
        for dist in [1.5f32, 3.0, 10.0, 30.0, 56.0] {
            let light = Light::Point {
                position: Vec3::new(0.0, dist * r, 0.0),
                intensity: i,
            };
            let d = emission_domain(&light, casters, scene, PointEmission::CasterCone).unwrap();
            assert!(d.measure >= 2f32.powi(-10), "{dist}: {}", d.measure);
            quantum_of(d.flux.max_element());
        }
        // ... spot cones down to 1.02 degrees ...
        for outer in [1.02f32, 5.0, 45.0, 90.0, 180.0] {
            let light = Light::Spot {
                position: Vec3::new(0.0, 3.0, 0.0),
                direction: -Vec3::Y,
                intensity: i,
                inner_angle_deg: 0.0,
                outer_angle_deg: outer,
            };
            let d = unpruned_domain(&light, scene).unwrap();
            assert!(d.measure >= 2f32.powi(-10), "{outer}: {}", d.measure);
            quantum_of(d.flux.max_element());
        }
        // ... and directional rectangles down to 2^-10 unit^2
        for side in [2f32.powi(-5), 1.0, 20.0] {
            let light = Light::Directional {
                direction: -Vec3::Y,
                irradiance: i,
                projection_volume: Some(Aabb {
                    min: Vec3::splat(-0.5 * side),
                    max: Vec3::splat(0.5 * side),
                }),
            };
            let d = emission_domain(&light, casters, scene, PointEmission::CasterCone).unwrap();
            assert!(d.measure >= 2f32.powi(-10), "{side}: {}", d.measure);
            quantum_of(d.flux.max_element());
        }
    }
}
