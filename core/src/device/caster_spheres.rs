//! Caster spheres: world-space balls around the caustic casters (the mirror and dielectric
//! objects) that `trace_photons` tests a photon's first segment against before it
//! traverses the scene ([`crate::math::geometry::ray_meets_caster_spheres`]).
//!
//! Kim 2019's emission cone (30.3.1.1) bounds the casters' *box*; around a round caster
//! most of that cone misses it (on `sphere`, 68% of the photons: the cone holds the box's
//! circumscribed ball, radius `sqrt(3) r`, about three times the ball's solid angle). A
//! photon whose first segment meets no caster ball cannot meet a caster first: without
//! the test it would be traversed only to end on a diffuse surface (`NO_SPECULAR`) or in
//! the void (`ESCAPED`). With it, it ends as `NO_SPECULAR` with no ray traced. Stored
//! photons, hence images, are unchanged bitwise (each photon's random numbers depend on
//! its index alone); the counters move first-segment escapes to `no_specular` and count
//! fewer rays. This is caustica's own lever, not a seed's.
//!
//! One ball per caster object: the static level's specular objects each get the ball of
//! their world vertices, an instance the ball of its object-space vertices placed by its
//! transform ([`placed_ball`]). More than [`MAX_CASTER_SPHERES`] balls are merged
//! ([`CasterSpheres::from_balls`]).

use crate::device::layout::{TraceParams, MAX_CASTER_SPHERES};
use crate::math::geometry::{enclosing_ball, padded_ball};
use crate::scene::Transform;
use glam::Vec3;

/// At most [`MAX_CASTER_SPHERES`] balls (centre xyz, radius w; world space, scene units)
/// that hold every caster triangle, as `trace_photons` reads them.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CasterSpheres {
    /// The balls; the first `count` are used.
    pub spheres: [[f32; 4]; MAX_CASTER_SPHERES],
    /// How many balls hold the casters (0: no test).
    pub count: u32,
}

impl CasterSpheres {
    /// No test: every photon is traversed.
    pub const NONE: CasterSpheres = CasterSpheres {
        spheres: [[0.0; 4]; MAX_CASTER_SPHERES],
        count: 0,
    };

    /// The balls of `balls`, merged to at most [`MAX_CASTER_SPHERES`] when there are
    /// more: sorted along the axis on which their centres spread most and cut into that
    /// many runs of consecutive balls, each run replaced by a ball that encloses it
    /// ([`enclosing_ball`]). Deterministic (a stable sort on f32 keys, ties by position).
    pub fn from_balls(mut balls: Vec<[f32; 4]>) -> CasterSpheres {
        let mut out = CasterSpheres::NONE;
        if balls.len() > MAX_CASTER_SPHERES {
            let mut lo = Vec3::splat(f32::INFINITY);
            let mut hi = Vec3::splat(f32::NEG_INFINITY);
            for s in &balls {
                let c = Vec3::new(s[0], s[1], s[2]);
                lo = lo.min(c);
                hi = hi.max(c);
            }
            let spread = hi - lo;
            let axis = if spread.x >= spread.y && spread.x >= spread.z {
                0
            } else if spread.y >= spread.z {
                1
            } else {
                2
            };
            balls.sort_by(|a, b| a[axis].total_cmp(&b[axis]));
            let n = balls.len();
            balls = (0..MAX_CASTER_SPHERES)
                .filter_map(|k| {
                    let run = &balls[k * n / MAX_CASTER_SPHERES..(k + 1) * n / MAX_CASTER_SPHERES];
                    enclosing_ball(run)
                })
                .collect();
        }
        for (slot, b) in out.spheres.iter_mut().zip(&balls) {
            *slot = *b;
        }
        out.count = balls.len().min(MAX_CASTER_SPHERES) as u32;
        out
    }

    /// Sets `p`'s first-segment test to these balls.
    pub fn apply(&self, p: &mut TraceParams) {
        p.caster_spheres = self.spheres;
        p.caster_sphere_count = self.count;
    }
}

/// An instance's caster ball in world space: its object-space ball `object` (from
/// [`crate::math::geometry::bounding_sphere`] of its object-space vertices) placed by
/// `t`. The centre goes through `world_from_object`; the radius scales by the largest
/// scale magnitude (the rotation keeps lengths, so that is the transform's largest
/// stretch). The world vertices are computed in f32 from the same transform, and each
/// errs by a few ulps of `|s| (|c| + r) + |t|`; the margin of
/// [`padded_ball`] over that reach covers them.
pub fn placed_ball(t: &Transform, object: [f32; 4]) -> [f32; 4] {
    let c = Vec3::new(object[0], object[1], object[2]);
    let m = t.world_from_object();
    let wc = m.transform_point3(c);
    let stretch = t.scale.abs().max_element() as f64;
    let r = object[3] as f64 * stretch;
    let reach = stretch * (c.abs().max_element() as f64 + object[3] as f64)
        + t.translation.abs().max_element() as f64
        + wc.abs().max_element() as f64;
    padded_ball(wc, r, reach)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::geometry::{bounding_sphere, ray_meets_caster_spheres};
    use crate::math::rng::random_f32;
    use glam::Quat;

    fn points(seed: u32, n: u32, scale: f32, offset: Vec3) -> Vec<Vec3> {
        (0..n)
            .map(|i| {
                let r = |d| random_f32(seed, i, 0, d) - 0.5;
                offset + Vec3::new(r(0), r(1), r(2)) * scale
            })
            .collect()
    }

    #[test]
    fn a_bounding_sphere_holds_its_points_at_every_scale() {
        for (k, scale) in [1e-9f32, 1e-3, 1.0, 1e3, 1e9].into_iter().enumerate() {
            let offset = Vec3::new(3.0, -7.0, 11.0) * scale;
            let pts = points(k as u32, 500, scale, offset);
            let b = bounding_sphere(&pts).unwrap();
            let c = Vec3::new(b[0], b[1], b[2]).as_dvec3();
            for p in &pts {
                assert!((p.as_dvec3() - c).length() <= b[3] as f64, "{scale}: {p}");
            }
        }
        assert_eq!(bounding_sphere(&[]), None);
        assert_eq!(bounding_sphere(&[Vec3::new(f32::NAN, 0.0, 0.0)]), None);
    }

    #[test]
    fn a_placed_ball_holds_the_placed_points() {
        for k in 0..200u32 {
            let r = |d| random_f32(91, k, 0, d);
            let pts = points(k, 64, 0.5 + 3.0 * r(0), Vec3::new(r(1), r(2), r(3)) * 4.0);
            let t = Transform {
                translation: Vec3::new(r(4) - 0.5, r(5) - 0.5, r(6) - 0.5)
                    * 10f32.powi((k % 7) as i32),
                rotation: Quat::from_axis_angle(
                    Vec3::new(r(7) - 0.5, r(8) - 0.5, r(9) + 0.1).normalize(),
                    6.0 * r(10),
                ),
                scale: Vec3::new(0.1 + r(11), 0.1 + 4.0 * r(12), -(0.1 + r(13))),
            };
            let ball = placed_ball(&t, bounding_sphere(&pts).unwrap());
            let c = Vec3::new(ball[0], ball[1], ball[2]).as_dvec3();
            let m = t.world_from_object();
            for p in &pts {
                let w = m.transform_point3(*p).as_dvec3();
                assert!(
                    (w - c).length() <= ball[3] as f64,
                    "case {k}: {w} outside {ball:?}"
                );
            }
        }
    }

    #[test]
    fn merged_balls_hold_every_ball_and_rays_through_any_point_meet_them() {
        let balls: Vec<[f32; 4]> = (0..37u32)
            .map(|i| {
                let r = |d| random_f32(5, i, 0, d);
                [10.0 * r(0), 3.0 * r(1), -5.0 * r(2), 0.05 + 0.3 * r(3)]
            })
            .collect();
        let merged = CasterSpheres::from_balls(balls.clone());
        assert_eq!(merged.count as usize, MAX_CASTER_SPHERES);
        let used = &merged.spheres[..merged.count as usize];
        for b in &balls {
            let c = Vec3::new(b[0], b[1], b[2]).as_dvec3();
            assert!(
                used.iter().any(|m| {
                    (Vec3::new(m[0], m[1], m[2]).as_dvec3() - c).length() + b[3] as f64
                        <= m[3] as f64
                }),
                "{b:?} is in no merged ball"
            );
        }
        // a ray aimed at any point of any ball's surface is never refused
        let origin = Vec3::new(-20.0, 40.0, 7.0);
        for (i, b) in balls.iter().enumerate() {
            for d in 0..64u32 {
                let r = |k| random_f32(17, i as u32 * 64 + d, 0, k) - 0.5;
                let on =
                    Vec3::new(b[0], b[1], b[2]) + Vec3::new(r(0), r(1), r(2)).normalize() * b[3];
                let dir = (on - origin).normalize();
                assert!(ray_meets_caster_spheres(origin, dir, used, merged.count));
            }
        }
        // and a few balls stay as they are
        let few = CasterSpheres::from_balls(balls[..3].to_vec());
        assert_eq!(few.count, 3);
        assert_eq!(few.spheres[..3], balls[..3]);
        assert_eq!(CasterSpheres::from_balls(Vec::new()), CasterSpheres::NONE);
    }

    #[test]
    fn the_sphere_test_refuses_clear_misses_and_keeps_grazing_and_inside_rays() {
        use crate::math::geometry::ray_meets_sphere;
        for scale in [1e-9f32, 1.0, 1e9] {
            let s = [0.0, 1.0 * scale, 0.0, 0.5 * scale];
            let o = Vec3::new(0.0, 3.0, 0.0) * scale;
            let towards = |p: Vec3| (p * scale - o).normalize();
            // straight at it, tangent to its surface, and clear past it
            assert!(ray_meets_sphere(o, towards(Vec3::Y), s));
            let tangent = Vec3::new(
                0.5 * (1.0 - 0.25f32 / 4.0).sqrt(),
                1.0 + 0.5 * 0.5 / 2.0,
                0.0,
            );
            let d_t = towards(tangent);
            assert!(ray_meets_sphere(o, d_t, s));
            assert!(!ray_meets_sphere(o, towards(Vec3::new(0.8, 1.0, 0.0)), s));
            // away from it
            assert!(!ray_meets_sphere(o, Vec3::Y, s));
            // from inside, any direction
            assert!(ray_meets_sphere(
                Vec3::new(0.1, 1.2, 0.0) * scale,
                Vec3::Y,
                s
            ));
        }
    }
}
