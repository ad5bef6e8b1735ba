//! Ray-geometry primitives shared by every backend: triangle intersection, robust ray
//! origins, bounding boxes. World space, scene units.

use glam::Vec3;
use serde::{Deserialize, Serialize};

/// Ray-triangle hit: distance `t` along the (unit) ray and barycentrics `(u, v)` of
/// vertices 1 and 2 (vertex 0 has weight `1 - u - v`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    /// Distance along the ray (scene units for a unit direction).
    pub t: f32,
    /// Barycentric weight of vertex 1.
    pub u: f32,
    /// Barycentric weight of vertex 2.
    pub v: f32,
}

/// Watertight ray-triangle intersection (Woop, Benthin and Wald, "Watertight
/// Ray/Triangle Intersection", JCGT 2013), two-sided. Returns a hit with
/// `t_min < t < t_max`.
///
/// The ray is made the +z axis of a sheared frame: `kz` is the direction's largest
/// component, `kx`, `ky` the next two (swapped when `dir[kz] < 0` to keep the winding),
/// and each vertex relative to the origin is sheared to `(x - Sx z, y - Sy z)` with
/// `Sx = dir[kx] / dir[kz]`, `Sy = dir[ky] / dir[kz]`. The 2-D edge functions `U, V, W` of
/// those points are the unnormalised barycentrics of `v0, v1, v2`; the ray hits when they
/// share a sign (zero counts as either). Two triangles sharing an edge compute that edge's
/// function from the same two sheared vertices with the operands swapped, so the values
/// are exact negations (no fused multiply-add anywhere, in Rust or in the ports) and no
/// ray passes between them: the property the Moller-Trumbore test lacked (a photon could
/// slip through a floor's diagonal). Zero-area triangles never hit (`U + V + W = 0`); the
/// paper's double-precision recomputation of zero edge functions is left out (WGSL has no
/// f64), so a ray exactly through an edge hits both triangles, which keeps it watertight.
#[inline]
pub fn intersect_triangle(
    origin: Vec3,
    dir: Vec3,
    v0: Vec3,
    v1: Vec3,
    v2: Vec3,
    t_min: f32,
    t_max: f32,
) -> Option<TriangleHit> {
    WatertightRay::new(origin, dir)?.intersect(v0, v1, v2, t_min, t_max)
}

/// The per-ray part of [`intersect_triangle`], computed once for every triangle a ray is
/// tested against (the CPU traversal): the permutation `(kx, ky, kz)` and the shear
/// `(Sx, Sy, Sz)`. Results are bitwise those of [`intersect_triangle`].
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: Vec3,
    k: [usize; 3],
    shear: [f32; 3],
}

/// Woop's 2D edge function of the sheared vertices `p`, `q`: `q.x p.y - q.y p.x`, evaluated
/// with the endpoints in a canonical (lexicographic) order and negated back, so that the
/// two triangles sharing an edge compute exactly opposite values. In Rust, which rounds
/// each product and never fuses them, that is bit for bit the plain expression (rounding
/// is symmetric); it matters in WGSL, which cannot forbid contracting `a * b - c * d` into
/// an FMA: NVIDIA's driver does, and rays through a shared edge then missed both
/// triangles (13 of 1024 texels of `sphere-sun`'s orthographic RSM face on the H200).
#[inline]
pub fn edge_function(p: [f32; 2], q: [f32; 2]) -> f32 {
    let swap = !(p[0] < q[0] || (p[0] == q[0] && p[1] < q[1]));
    let (lo, hi) = if swap { (q, p) } else { (p, q) };
    let e = hi[0] * lo[1] - hi[1] * lo[0];
    // `0 - e`, not `-e`: a zero stays +0, as the plain expression gives it
    if swap {
        0.0 - e
    } else {
        e
    }
}

impl WatertightRay {
    /// `None` for a zero (or NaN) direction, which hits nothing.
    #[inline]
    pub fn new(origin: Vec3, dir: Vec3) -> Option<WatertightRay> {
        let ad = dir.abs();
        let kz = if ad.x >= ad.y && ad.x >= ad.z {
            0
        } else if ad.y >= ad.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        let d = dir.to_array();
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        if !(d[kz] != 0.0) {
            return None;
        }
        Some(WatertightRay {
            origin,
            k: [kx, ky, kz],
            shear: [d[kx] / d[kz], d[ky] / d[kz], 1.0 / d[kz]],
        })
    }

    /// The hit with triangle `v0, v1, v2` in `t_min < t < t_max`, if any.
    #[inline]
    pub fn intersect(
        &self,
        v0: Vec3,
        v1: Vec3,
        v2: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<TriangleHit> {
        let [kx, ky, kz] = self.k;
        let [sx, sy, sz] = self.shear;
        let a = (v0 - self.origin).to_array();
        let b = (v1 - self.origin).to_array();
        let c = (v2 - self.origin).to_array();
        let ax = a[kx] - sx * a[kz];
        let ay = a[ky] - sy * a[kz];
        let bx = b[kx] - sx * b[kz];
        let by = b[ky] - sy * b[kz];
        let cx = c[kx] - sx * c[kz];
        let cy = c[ky] - sy * c[kz];
        let u = edge_function([bx, by], [cx, cy]);
        let v = edge_function([cx, cy], [ax, ay]);
        let w = edge_function([ax, ay], [bx, by]);
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let az = sz * a[kz];
        let bz = sz * b[kz];
        let cz = sz * c[kz];
        let inv_det = 1.0 / det;
        let t = (u * az + v * bz + w * cz) * inv_det;
        if t > t_min && t < t_max {
            Some(TriangleHit {
                t,
                u: v * inv_det,
                v: w * inv_det,
            })
        } else {
            None
        }
    }
}

/// Relative size of the ray origin offset: `2^-15` of the point's largest coordinate, i.e.
/// 256 ulps of it (`ulp(m) <= m 2^-23`).
pub const OFFSET_REL: f32 = 1.0 / 32768.0;

/// Smallest coordinate scale the offset uses (`2^-100`), so that a point exactly at the
/// origin still moves (by `2^-115`, a normal f32).
pub const OFFSET_MIN_SCALE: f32 = 7.888_609e-31;

/// Scale-aware ray origin offset: moves `p` off the surface with unit geometric normal `n`
/// (pointing to the side the new ray leaves from) by `OFFSET_REL * m`, where `m` is the
/// largest magnitude among `p`'s coordinates.
///
/// Why: a hit point interpolated from a triangle's vertices, or found by a ray from an
/// origin of similar magnitude, is off the surface by a few ulps of the coordinates
/// involved, i.e. a few `m 2^-23` in *every* component (the barycentrics' errors spread
/// along the edges). Waechter and Binder (Ray Tracing Gems ch. 6) offset each component by
/// 256 ulps of itself, but below a fixed `1/32` they switch to a fixed absolute `1/65536`:
/// that assumes unit-size scenes, and at 1e-4 units it moved origins by 30% of a 5e-5 ball
/// (stiff case `scale-1e-4`, docs/stability.md). Here the whole offset scales with the
/// point: rounding the sum `p + n d` errs by at most `ulp(m) / 2` per component, `< 2^-8 d`
/// along `n`, so the origin always leaves the surface by nearly `d`, at every scale from
/// 2^-100 to 2^127. The cost: on a surface far from the origin whose own coordinate is
/// small (a floor at y = 0.5 seen at x = 1e6) the offset is 256 ulps of the *large*
/// coordinate, more than that surface's own error needs; features smaller than `2^-15 |p|`
/// cannot be resolved there (f32 itself only resolves `2^-23 |p|`).
#[inline]
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    let m =
        p.x.abs()
            .max(p.y.abs())
            .max(p.z.abs().max(OFFSET_MIN_SCALE));
    let d = m * OFFSET_REL;
    p + n * d
}

/// `v / |v|`, computed as `w / |w|` with `w = v / max|v_i|` so that the squared length
/// neither underflows nor overflows; `fallback` for a zero, non-finite or subnormal-sized
/// `v`. The edge cross product of a triangle 1e-11 across is ~1e-22 per component and its
/// squared length ~1e-44, a subnormal that devices flushing subnormals to zero (NVIDIA's
/// Vulkan) turn into 0: the plain normalisation then fell back to +y on such devices only
/// (stiff case `near-plane`, docs/stability.md).
#[inline]
pub fn normalize_scaled(v: Vec3, fallback: Vec3) -> Vec3 {
    let scale = 1.0 / v.abs().max_element();
    if !(scale.is_finite() && scale > 0.0) {
        return fallback;
    }
    (v * scale).normalize_or(fallback)
}

/// Relative slack of [`ray_meets_sphere`]: a ray is refused only when its closest
/// approach to the centre exceeds the radius by more than `SPHERE_TEST_SLACK |oc|^2` in
/// the squared distance (`oc` = centre - origin). The f32 expression
/// `|oc|^2 - max(oc . d, 0)^2` errs by less than `16 eps |oc|^2 = 2^-20 |oc|^2`
/// (`eps = 2^-24`: the subtraction `c - o` per component, two 3-term dot products, one
/// square, one difference, and a direction whose length is 1 within 2 eps), so the slack
/// `2^-16` holds that bound 16 times over; contracted (fused) operations err less.
pub const SPHERE_TEST_SLACK: f32 = 1.0 / 65_536.0;

/// Whether the ray `origin + t dir`, `t >= 0` (`dir` unit, world space), may meet the ball
/// `sphere` (centre xyz, radius w; world space): false only when its closest point to the
/// centre lies outside the ball by more than the rounding of this test
/// ([`SPHERE_TEST_SLACK`]). The squared distance of the closest point is
/// `|oc|^2 - max(oc . dir, 0)^2` (the foot of the perpendicular, or the origin when the
/// centre is behind it). Mirrored by name in the shaders (`ray_meets_sphere`).
#[inline]
pub fn ray_meets_sphere(origin: Vec3, dir: Vec3, sphere: [f32; 4]) -> bool {
    let oc = Vec3::new(
        sphere[0] - origin.x,
        sphere[1] - origin.y,
        sphere[2] - origin.z,
    );
    let tca = (oc.x * dir.x + oc.y * dir.y + oc.z * dir.z).max(0.0);
    let oc2 = oc.x * oc.x + oc.y * oc.y + oc.z * oc.z;
    let r = sphere[3];
    !(oc2 - tca * tca > r * r + SPHERE_TEST_SLACK * oc2)
}

/// Whether the ray may meet one of the first `count` balls of `spheres`
/// ([`ray_meets_sphere`]); true when `count` is 0 (no test). Mirrored by name in the
/// shaders (`ray_meets_caster_spheres`).
#[inline]
pub fn ray_meets_caster_spheres(origin: Vec3, dir: Vec3, spheres: &[[f32; 4]], count: u32) -> bool {
    if count == 0 {
        return true;
    }
    spheres
        .iter()
        .take(count as usize)
        .any(|&s| ray_meets_sphere(origin, dir, s))
}

/// A ball (centre xyz, radius w) that holds every point of `points` with a margin: the
/// centre of their box, the largest distance to it (in f64) grown by 2^-12 of itself and
/// by 2^-16 of the largest coordinate magnitude, rounded up to f32. The margin covers the
/// rounding of any f32 point computed on a triangle of these vertices (a ray's hit
/// point) many times over. `None` for no points or a non-finite one.
pub fn bounding_sphere(points: &[Vec3]) -> Option<[f32; 4]> {
    let mut b = Aabb::EMPTY;
    for &p in points {
        b.grow(p);
    }
    if points.is_empty() || !(b.min.is_finite() && b.max.is_finite()) {
        return None;
    }
    let c = b.center();
    let r = points
        .iter()
        .map(|&p| (p - c).as_dvec3().length())
        .fold(0.0f64, f64::max);
    let reach = b.min.abs().max(b.max.abs()).max_element() as f64;
    Some(padded_ball(c, r, reach))
}

/// The ball `(c, r)` with the margin of [`bounding_sphere`] (`reach`: the largest coordinate
/// magnitude its points were computed from), radius rounded up to f32.
pub fn padded_ball(c: Vec3, r: f64, reach: f64) -> [f32; 4] {
    let padded = r * (1.0 + 1.0 / 4096.0) + reach / 65_536.0;
    [c.x, c.y, c.z, round_up_f32(padded)]
}

/// The smallest f32 not below `x` (x finite, non-negative).
fn round_up_f32(x: f64) -> f32 {
    let f = x as f32;
    if (f as f64) < x {
        // the next f32 up (f is finite and non-negative here)
        f32::from_bits(f.to_bits() + 1)
    } else {
        f
    }
}

/// A ball that holds every ball of `balls` (centre xyz, radius w): centred on the box of
/// their boxes, radius the largest `|c_i - c| + r_i` (in f64), grown by 2^-20 of the
/// reach and rounded up. `None` for none.
pub fn enclosing_ball(balls: &[[f32; 4]]) -> Option<[f32; 4]> {
    let mut b = Aabb::EMPTY;
    for s in balls {
        let c = Vec3::new(s[0], s[1], s[2]);
        b.grow(c - Vec3::splat(s[3]));
        b.grow(c + Vec3::splat(s[3]));
    }
    if balls.is_empty() || !(b.min.is_finite() && b.max.is_finite()) {
        return None;
    }
    let c = b.center();
    let r = balls
        .iter()
        .map(|s| (Vec3::new(s[0], s[1], s[2]) - c).as_dvec3().length() + s[3] as f64)
        .fold(0.0f64, f64::max);
    let reach = b.min.abs().max(b.max.abs()).max_element() as f64;
    Some([c.x, c.y, c.z, round_up_f32(r + reach / 1_048_576.0)])
}

/// An [`Aabb`] grown in SIMD lanes (`Vec3A`), for the loops that grow a box over many
/// points: bitwise the box [`Aabb::grow`] grows over the same points in the same order
/// (each lane keeps the bound where it is below, or above, the point, else takes the
/// point: `Vec3::min` and `Vec3::max`'s rule, ties and NaN included, on every glam
/// backend), in about half the time of `Vec3`'s lane-by-lane compares.
#[derive(Clone, Copy, Debug)]
pub struct AabbA {
    min: glam::Vec3A,
    max: glam::Vec3A,
}

impl AabbA {
    /// The empty box ([`Aabb::EMPTY`]).
    pub const EMPTY: AabbA = AabbA {
        min: glam::Vec3A::INFINITY,
        max: glam::Vec3A::NEG_INFINITY,
    };

    /// Grows the box to contain `p` (as [`Aabb::grow`]). On x86 `Vec3A::min` and `max`
    /// are MINPS and MAXPS (`a < b ? a : b` and `a > b ? a : b` per lane, the rule
    /// itself) or glam's scalar fallback (the rule again); elsewhere (NEON's and WASM's
    /// minimum order zeros and propagate NaN) the rule is written out as a select.
    #[inline(always)]
    pub fn grow(&mut self, p: glam::Vec3A) {
        #[cfg(any(target_arch = "x86", target_arch = "x86_64"))]
        {
            self.min = self.min.min(p);
            self.max = self.max.max(p);
        }
        #[cfg(not(any(target_arch = "x86", target_arch = "x86_64")))]
        {
            self.min = glam::Vec3A::select(self.min.cmplt(p), self.min, p);
            self.max = glam::Vec3A::select(self.max.cmpgt(p), self.max, p);
        }
    }

    /// The box as an [`Aabb`].
    pub fn aabb(self) -> Aabb {
        Aabb {
            min: self.min.into(),
            max: self.max.into(),
        }
    }
}

/// Axis-aligned box in world space.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Aabb {
    /// Minimum corner.
    pub min: Vec3,
    /// Maximum corner.
    pub max: Vec3,
}

impl Aabb {
    /// The empty box (min = +inf, max = -inf); grows with [`Aabb::grow`].
    pub const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    /// Grows the box to contain `p`.
    pub fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    /// The smallest box containing both boxes.
    pub fn union(self, o: Aabb) -> Aabb {
        Aabb {
            min: self.min.min(o.min),
            max: self.max.max(o.max),
        }
    }

    /// True when the box holds no point (`min` above `max` on some axis, or NaN).
    pub fn is_empty(&self) -> bool {
        !(self.min.x <= self.max.x && self.min.y <= self.max.y && self.min.z <= self.max.z)
    }

    /// The centre point.
    pub fn center(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    /// Length of the diagonal (scene units).
    pub fn diagonal(&self) -> f32 {
        (self.max - self.min).length()
    }

    /// The eight corners.
    pub fn corners(&self) -> [Vec3; 8] {
        let (a, b) = (self.min, self.max);
        [
            Vec3::new(a.x, a.y, a.z),
            Vec3::new(b.x, a.y, a.z),
            Vec3::new(a.x, b.y, a.z),
            Vec3::new(b.x, b.y, a.z),
            Vec3::new(a.x, a.y, b.z),
            Vec3::new(b.x, a.y, b.z),
            Vec3::new(a.x, b.y, b.z),
            Vec3::new(b.x, b.y, b.z),
        ]
    }

    /// True when `p` lies inside the box or on its boundary.
    pub fn contains(&self, p: Vec3) -> bool {
        p.cmpge(self.min).all() && p.cmple(self.max).all()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`AabbA::grow`] grows, bitwise, the box [`Aabb::grow`] grows over the same points
    /// in the same order: zeros of both signs, infinities and NaN included.
    #[test]
    fn a_box_grown_in_lanes_is_the_box_grown_by_vec3() {
        use proptest::prelude::*;
        let coordinate = prop_oneof![
            Just(0.0f32),
            Just(-0.0f32),
            Just(f32::NAN),
            Just(f32::INFINITY),
            Just(f32::NEG_INFINITY),
            Just(1.0f32),
            -2.0f32..2.0
        ];
        let points =
            prop::collection::vec((coordinate.clone(), coordinate.clone(), coordinate), 0..12);
        proptest!(|(points in points)| {
            let (mut a, mut b, mut s) = (Aabb::EMPTY, AabbA::EMPTY, AabbA::EMPTY);
            for (x, y, z) in points {
                a.grow(Vec3::new(x, y, z));
                let p = glam::Vec3A::new(x, y, z);
                b.grow(p);
                // the select written out for targets other than x86, checked here too
                s.min = glam::Vec3A::select(s.min.cmplt(p), s.min, p);
                s.max = glam::Vec3A::select(s.max.cmpgt(p), s.max, p);
            }
            let bits = |b: Aabb| [b.min.to_array(), b.max.to_array()].map(|v| v.map(f32::to_bits));
            prop_assert_eq!(bits(b.aabb()), bits(a));
            prop_assert_eq!(bits(s.aabb()), bits(a));
        });
    }

    #[test]
    fn edge_function_is_exactly_antisymmetric_and_the_plain_expression() {
        use crate::math::rng::random_f32;
        // exact zeros too: collinear with the origin
        assert_eq!(
            edge_function([2.0, 1.0], [4.0, 2.0]).to_bits(),
            0.0f32.to_bits()
        );
        assert_eq!(
            edge_function([4.0, 2.0], [2.0, 1.0]).to_bits(),
            0.0f32.to_bits()
        );
        for k in 0..20000u32 {
            let r = |d: u32| (random_f32(3, k, 0, d) - 0.5) * 10f32.powi((k % 9) as i32 - 4);
            let (p, q) = ([r(0), r(1)], [r(2), r(3)]);
            let e = edge_function(p, q);
            assert_eq!(e, -edge_function(q, p), "{p:?} {q:?}");
            assert_eq!(
                e.to_bits(),
                (q[0] * p[1] - q[1] * p[0]).to_bits(),
                "{p:?} {q:?}"
            );
        }
    }

    #[test]
    fn triangle_hit_and_miss() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let h =
            intersect_triangle(Vec3::new(0.25, 0.25, 1.0), -Vec3::Z, a, b, c, 0.0, 10.0).unwrap();
        assert!((h.t - 1.0).abs() < 1e-6 && (h.u - 0.25).abs() < 1e-6 && (h.v - 0.25).abs() < 1e-6);
        assert!(
            intersect_triangle(Vec3::new(0.8, 0.8, 1.0), -Vec3::Z, a, b, c, 0.0, 10.0).is_none()
        );
        // degenerate triangle
        assert!(
            intersect_triangle(Vec3::new(0.0, 0.0, 1.0), -Vec3::Z, a, a, c, 0.0, 10.0).is_none()
        );
    }

    #[test]
    fn offset_moves_to_the_normal_side_at_every_scale() {
        let n = Vec3::new(0.0, 0.6, 0.8);
        for &s in &[1e-30f32, 1e-4, 1.0, 1e5, 1e6, 1e30] {
            let p = Vec3::new(s, -s, 0.3 * s);
            let o = offset_ray_origin(p, n);
            let along = (o - p).dot(n);
            // Moves by the stated amount (within the sum's rounding), relative to the scale.
            assert!(along > 0.99 * OFFSET_REL * s, "scale {s}: {along}");
            assert!(along < 1.01 * OFFSET_REL * s, "scale {s}: {along}");
        }
        let o = offset_ray_origin(Vec3::ZERO, Vec3::Y);
        assert!(o.y > 0.0 && o.y.is_normal());
    }
}
