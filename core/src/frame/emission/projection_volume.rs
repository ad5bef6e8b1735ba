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
use crate::math::sampling::{
    cone_one_minus_cos, cone_solid_angle, one_minus_cos_of_angle, orthonormal_basis, NARROW_CONE,
};
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
    /// `1 - cos_max` computed without cancellation (2 for the whole sphere, 0 for
    /// rectangles): what a narrow cone is sampled and measured from
    /// ([`NARROW_CONE`](crate::math::sampling::NARROW_CONE)).
    pub one_minus_cos: f32,
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
            axis: self.axis.extend(self.one_minus_cos).to_array(),
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

/// A cone's half-angle as its cosine and `1 - cos` computed without cancellation.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Cone {
    cos_max: f32,
    one_minus_cos: f32,
}

impl Cone {
    /// The whole sphere of directions.
    const SPHERE: Cone = Cone {
        cos_max: -1.0,
        one_minus_cos: 2.0,
    };

    /// A spot light's outer cone, `outer_angle_deg` its half-angle in degrees.
    fn spot(outer_angle_deg: f32) -> Cone {
        let a = outer_angle_deg.to_radians();
        Cone {
            cos_max: a.cos(),
            one_minus_cos: one_minus_cos_of_angle(a),
        }
    }

    /// The half-angle in radians: `acos(cos_max)`, or for a narrow cone, whose cosine
    /// has cancelled, `2 asin(sqrt(one_minus_cos / 2))`.
    fn half_angle(self) -> f32 {
        if self.one_minus_cos < NARROW_CONE {
            2.0 * (0.5 * self.one_minus_cos).sqrt().asin()
        } else {
            self.cos_max.acos()
        }
    }
}

/// Cone from `apex` that bounds the sphere around `casters` (axis, half-angle), or `None`
/// when `apex` is inside that sphere. Its `1 - cos` comes from the squared sine `(r /
/// d)^2`, exact where the cosine has cancelled (a far light, a small caster).
fn caster_cone(apex: Vec3, casters: Aabb) -> Option<(Vec3, Cone)> {
    let c = casters.center();
    let r = 0.5 * casters.diagonal();
    let to = c - apex;
    let dist = to.length();
    (dist > r * 1.0001).then(|| {
        let sin2 = (r / dist).powi(2);
        let cone = Cone {
            cos_max: (1.0 - sin2).max(0.0).sqrt(),
            one_minus_cos: cone_one_minus_cos(sin2),
        };
        (to / dist, cone)
    })
}

fn cone_domain(position: Vec3, intensity: Vec3, axis: Vec3, cone: Cone) -> EmissionDomain {
    let Cone {
        cos_max,
        one_minus_cos,
    } = cone;
    let omega = cone_solid_angle(cos_max, one_minus_cos);
    EmissionDomain {
        kind: emission_kind::CONE,
        origin: position,
        axis,
        cos_max,
        one_minus_cos,
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
        one_minus_cos: 0.0,
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
        } => Some(cone_domain(*position, *intensity, Vec3::Z, Cone::SPHERE)),
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
            Cone::spot(*outer_angle_deg),
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
            Some((axis, cone)) if point == PointEmission::CasterCone => {
                cone_domain(*position, *intensity, axis, cone)
            }
            _ => cone_domain(*position, *intensity, Vec3::Z, Cone::SPHERE),
        }),
        Light::Spot {
            position,
            direction,
            intensity,
            outer_angle_deg,
            ..
        } => {
            let spot_axis = direction.normalize();
            let spot = Cone::spot(*outer_angle_deg);
            let Some((axis, caster)) = caster_cone(*position, casters) else {
                // the light is among the casters: its whole cone may meet one
                return Ok(cone_domain(*position, *intensity, spot_axis, spot));
            };
            // Cones miss when the angle between the axes exceeds the sum of the half
            // angles (with a 1e-3 rad margin for f32 acos; a near miss emits).
            let between = spot_axis.dot(axis).clamp(-1.0, 1.0).acos();
            if between > spot.half_angle() + caster.half_angle() + 1e-3 {
                return Err(NoEmission::MissesCasters);
            }
            // Both cones hold every photon that can meet a caster: use the narrower (by
            // `1 - cos`, which tells narrow cones apart where both cosines round to 1).
            let caster_narrower = if spot.one_minus_cos.max(caster.one_minus_cos) < NARROW_CONE {
                caster.one_minus_cos < spot.one_minus_cos
            } else {
                caster.cos_max > spot.cos_max
            };
            Ok(if point == PointEmission::CasterCone && caster_narrower {
                cone_domain(*position, *intensity, axis, caster)
            } else {
                cone_domain(*position, *intensity, spot_axis, spot)
            })
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
        assert!((d.flux.x - cone_solid_angle(want, 1.0 - want)).abs() < 1e-6);
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

    /// A far point light whose intensity grows as `d^2` sends the same flux into the
    /// caster cone at every distance (`I Omega -> pi r^2 I / d^2`), within a few ulps of
    /// the f64 value, where `2 pi (1 - cos_max)` cancelled (+8% at `d = 1000` radii, x6 at
    /// 5000, zero from 20000); a caster a millionth of the unit four units away emits as
    /// the unit one does, scaled. The trace's parameters carry the same `1 - cos`.
    #[test]
    fn caster_cone_flux_of_a_far_light_falls_as_the_inverse_square() {
        let r = 0.5 * ball().diagonal();
        let exact = |d: f32, i: f32| {
            // the f32 distance and radius as the cone sees them, the rest in f64
            let x = (r as f64 / d as f64).powi(2);
            i as f64 * std::f64::consts::TAU * x / (1.0 + (1.0 - x).sqrt())
        };
        let far = std::f64::consts::PI * (r as f64).powi(2);
        for d in [40.0f32, 100.0, 1e3, 5e3, 2e4, 1e5, 1e6, 1e7, 1e9] {
            let i = d * d;
            let light = Light::Point {
                position: Vec3::new(0.0, d, 0.0),
                intensity: Vec3::splat(i),
            };
            let e = emission_domain(&light, ball(), ball(), PointEmission::CasterCone).unwrap();
            let f = e.flux.x as f64;
            let rel = (f - exact(d, i)).abs() / exact(d, i);
            assert!(
                rel < 6e-7,
                "d {d}: flux {f:e}, exact {:e}, rel {rel:e}",
                exact(d, i)
            );
            // the same flux at every distance: pi r^2 (times 1 + x/4 + ...)
            assert!(
                (f - far).abs() / far < 1e-3 * (40.0 / d as f64).powi(2) + 6e-7,
                "d {d}"
            );
            assert_eq!(e.axis, -Vec3::Y);
            let p = e.trace_params(0, (4, 4), (0, 16), 1, 1, 0.0, 1.0);
            assert_eq!(p.axis[3], e.one_minus_cos);
            assert_eq!(p.origin[3], e.cos_max);
        }
        let tiny = Aabb {
            min: Vec3::splat(-0.5e-6),
            max: Vec3::splat(0.5e-6),
        };
        let light = Light::Point {
            position: Vec3::new(0.0, 4.0, 0.0),
            intensity: Vec3::ONE,
        };
        let e = emission_domain(&light, tiny, ball(), PointEmission::CasterCone).unwrap();
        let x = (0.5 * tiny.diagonal() as f64 / 4.0).powi(2);
        let want = std::f64::consts::TAU * x / (1.0 + (1.0 - x).sqrt());
        assert!(
            ((e.flux.x as f64 - want) / want).abs() < 6e-7,
            "{e:?}, want {want:e}"
        );
    }

    /// Wide cones keep today's solid angle bit for bit; a spot narrower than 2.5 degrees
    /// gets its solid angle without cancellation and, aimed at a narrower caster cone,
    /// emits into the narrower one even where both cosines round to 1.
    #[test]
    fn narrow_cones_get_their_solid_angle_without_cancellation() {
        let wide = |d: &EmissionDomain| std::f32::consts::TAU * (1.0 - d.cos_max);
        let d = emission_domain(
            &spot(-Vec3::Y, 80.0),
            ball(),
            ball(),
            PointEmission::CasterCone,
        )
        .unwrap();
        assert_eq!(d.measure.to_bits(), wide(&d).to_bits());
        for outer in [20.0f32, 5.0, 180.0] {
            let d = unpruned_domain(&spot(-Vec3::Y, outer), ball()).unwrap();
            assert_eq!(d.measure.to_bits(), wide(&d).to_bits(), "{outer}");
        }
        let d = unpruned_domain(
            &Light::Point {
                position: Vec3::ZERO,
                intensity: Vec3::ONE,
            },
            ball(),
        )
        .unwrap();
        assert_eq!(d.measure, 2.0 * std::f32::consts::TAU);
        // narrow spots: 4 pi sin^2(theta / 2)
        for outer in [1.0f32, 0.1, 1e-3, 1e-5] {
            let d = unpruned_domain(&spot(-Vec3::Y, outer), ball()).unwrap();
            let t = (outer as f64).to_radians();
            let want = 2.0 * std::f64::consts::TAU * (0.5 * t).sin().powi(2);
            let rel = (d.measure as f64 - want).abs() / want;
            assert!(rel < 1e-6, "{outer} deg: {:e} vs {want:e}", d.measure);
        }
        // a 1e-3 degree spot on a ball 1e5 away (caster cone 5e-4 degrees): both cosines
        // are 1 in f32; the caster cone is the narrower
        let far_spot = |direction: Vec3| Light::Spot {
            position: Vec3::new(0.0, 1e5, 0.0),
            direction,
            intensity: Vec3::ONE,
            inner_angle_deg: 0.0,
            outer_angle_deg: 1e-3,
        };
        let d = emission_domain(
            &far_spot(-Vec3::Y),
            ball(),
            ball(),
            PointEmission::CasterCone,
        )
        .unwrap();
        assert_eq!(d.cos_max, 1.0);
        let x = (0.5 * ball().diagonal() as f64 / 1e5).powi(2);
        let want = std::f64::consts::TAU * x / (1.0 + (1.0 - x).sqrt());
        assert!(((d.measure as f64 - want) / want).abs() < 1e-6, "{d:?}");
        // and aimed 1 degree away it misses
        let aside = Vec3::new(1f32.to_radians().tan(), -1.0, 0.0);
        let e = emission_domain(&far_spot(aside), ball(), ball(), PointEmission::CasterCone);
        assert_eq!(e, Err(NoEmission::MissesCasters));
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
