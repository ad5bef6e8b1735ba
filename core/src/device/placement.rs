//! An instance's vertices placed in the world: positions through `world_from_object`,
//! normals through its inverse transpose, renormalised. A build places each instance on
//! the host (the host's copy of the scene) and on the device; a move
//! ([`crate::device::device_scene::SceneInstances::move_instances`]) only bounds it on the
//! host ([`placed_bounds`]). The host's placement puts four vertices
//! at once, one per SIMD lane (`Vec4`), with the same operations in the same order in
//! each lane as [`placement`] does for one vertex, so the results are bitwise
//! [`placement`]'s (IEEE-754 rounds each operation by itself; shuffles move bits).
//!
//! A move places on the device: `place_vertices` ([`place_vertices`] is its definition,
//! the CPU backend's kernel) maps the object-space vertices the device keeps through the
//! [`PlacementParams`] of the instance's transform, and the host computes only what it
//! needs, the boxes ([`placed_bounds`], from the positions' coordinate columns).

use crate::device::layout::{GpuVertex, PlacementParams};
use crate::math::geometry::AabbA;
use crate::scene::{Aabb, Transform};
use glam::{Affine3A, BVec4A, Mat3A, Mat4, Vec3, Vec3A, Vec4};

/// Where `t` places an object-space vertex: its position through `world_from_object`, its
/// normal through the inverse transpose, renormalised (a normal of no length, or one whose
/// reciprocal length is not finite, becomes +Y). The definition the four-lane loop
/// ([`world_vertices`], [`placed_vertices`]) keeps bitwise.
pub fn placement(t: &Transform) -> impl Fn(&GpuVertex) -> GpuVertex {
    let m = t.world_from_object();
    let nm = t.normal_matrix();
    move |v| GpuVertex {
        position: Vec3::from(m.transform_point3a(Vec3A::from(v.position))).to_array(),
        normal: (nm * Vec3A::from(v.normal))
            .normalize_or(Vec3A::Y)
            .to_array(),
        ..*v
    }
}

/// The parameters that make `place_vertices` place `count` object-space vertices from
/// `object_first` by `t`'s [`placement`] into the world vertices from `world_first`.
pub fn placement_params(
    t: &Transform,
    object_first: u32,
    world_first: u32,
    count: u32,
) -> PlacementParams {
    let m = t.world_from_object();
    let nm = t.normal_matrix();
    let col = |c: Vec3A| c.extend(0.0).to_array();
    PlacementParams {
        axis_x: col(m.matrix3.x_axis),
        axis_y: col(m.matrix3.y_axis),
        axis_z: col(m.matrix3.z_axis),
        translation: col(m.translation),
        normal_x: col(nm.x_axis),
        normal_y: col(nm.y_axis),
        normal_z: col(nm.z_axis),
        object_first,
        world_first,
        count,
        _pad: 0,
    }
}

/// The placement and normal matrices `p` holds (the columns [`placement_params`] took,
/// bit for bit).
pub fn params_matrices(p: &PlacementParams) -> (Affine3A, Mat3A) {
    let col = |c: [f32; 4]| Vec3A::new(c[0], c[1], c[2]);
    (
        Affine3A::from_cols(
            col(p.axis_x),
            col(p.axis_y),
            col(p.axis_z),
            col(p.translation),
        ),
        Mat3A::from_cols(col(p.normal_x), col(p.normal_y), col(p.normal_z)),
    )
}

/// `place_vertices`' definition (the CPU backend's kernel; the ports mirror it): the run
/// `local` (the `count` object-space vertices from `object_first`) placed by `p`, each
/// vertex as [`placement`] of the transform `p` was made from places it: position
/// `x_axis x + y_axis y + z_axis z + translation`, normal `normal_x n.x + normal_y n.y +
/// normal_z n.z` times `1 / sqrt((x^2 + y^2) + z^2)` of itself where that is finite and
/// positive, else +Y, each operation rounded by itself in that order; u and v kept.
pub fn place_vertices(p: &PlacementParams, local: &[GpuVertex]) -> Vec<GpuVertex> {
    let (m, nm) = params_matrices(p);
    let mut placed = vec![[GpuVertex::default(); 4]; local.len().div_ceil(4)];
    place_run(&m, &nm, local, &[], &mut placed);
    let mut world: Vec<GpuVertex> = bytemuck::allocation::cast_vec(placed);
    world.truncate(local.len());
    world
}

/// Object-space positions by coordinate, in the order of the vertices they come from
/// (`SceneInstances::object_vertices`): what a move bounds ([`placed_bounds`]) without
/// placing, read four to a lane vector.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PositionColumns {
    /// x coordinates (object space, scene units).
    pub x: Vec<f32>,
    /// y coordinates.
    pub y: Vec<f32>,
    /// z coordinates.
    pub z: Vec<f32>,
}

impl PositionColumns {
    /// The columns of `vertices`' positions.
    pub fn of(vertices: &[GpuVertex]) -> PositionColumns {
        let column = |k: usize| vertices.iter().map(|v| v.position[k]).collect();
        PositionColumns {
            x: column(0),
            y: column(1),
            z: column(2),
        }
    }

    /// Replaces the positions from `first` with `vertices`'.
    pub fn set(&mut self, first: usize, vertices: &[GpuVertex]) {
        for (i, v) in vertices.iter().enumerate() {
            self.x[first + i] = v.position[0];
            self.y[first + i] = v.position[1];
            self.z[first + i] = v.position[2];
        }
    }
}

/// The boxes of an instance's vertices placed by `t` without placing them: `columns`'
/// positions in `range` (its object-space vertices), `unused` those its triangles leave
/// out (indices from the range's start, ascending). Returns the box of all of them and
/// of the used ones, bitwise [`placed_vertices`]' boxes: each coordinate is the same sum
/// of the same products in the same order, grown in four lanes as `place_run` grows them
/// (the unused vertices in lane boxes of their own), and in order where a bound is zero.
pub fn placed_bounds(
    t: &Transform,
    columns: &PositionColumns,
    range: std::ops::Range<usize>,
    unused: &[u32],
) -> (Aabb, Aabb) {
    let m = t.world_from_object();
    let (x, y, z) = (
        &columns.x[range.clone()],
        &columns.y[range.clone()],
        &columns.z[range],
    );
    let n = x.len();
    let place = |lx: Vec4, ly: Vec4, lz: Vec4| {
        let p = mul_lanes(
            &m.matrix3,
            &Lanes {
                x: lx,
                y: ly,
                z: lz,
            },
        );
        let t = m.translation;
        Lanes {
            x: p.x + t.x,
            y: p.y + t.y,
            z: p.z + t.z,
        }
    };
    let mut used = LaneBox::EMPTY;
    let mut unused_box = LaneBox::EMPTY;
    let mut next_unused = unused.iter().map(|&u| u as usize).peekable();
    let full = n / 4 * 4;
    for first in (0..full).step_by(4) {
        let p = place(
            Vec4::from_slice(&x[first..]),
            Vec4::from_slice(&y[first..]),
            Vec4::from_slice(&z[first..]),
        );
        if next_unused.peek().is_none_or(|&u| u >= first + 4) {
            used.grow(&p);
        } else {
            grow_split(
                &mut used,
                &mut unused_box,
                &p,
                first,
                first + 4,
                &mut next_unused,
            );
        }
    }
    if full < n {
        // the last block: its positions, the rest of the lanes masked out
        let lane = |c: &[f32]| {
            let mut v = [0.0f32; 4];
            v[..n - full].copy_from_slice(&c[full..]);
            Vec4::from_array(v)
        };
        let p = place(lane(x), lane(y), lane(z));
        grow_split(&mut used, &mut unused_box, &p, full, n, &mut next_unused);
    }
    let position = |i: usize| m.transform_point3a(Vec3A::new(x[i], y[i], z[i]));
    let mut all = used.union(&unused_box).aabb();
    if has_zero_bound(&all) {
        let mut g = AabbA::EMPTY;
        (0..n).for_each(|i| g.grow(position(i)));
        all = g.aabb();
    }
    let mut used = used.aabb();
    if has_zero_bound(&used) {
        let mut g = AabbA::EMPTY;
        let mut skip = unused.iter().map(|&u| u as usize).peekable();
        for i in 0..n {
            while skip.next_if(|&u| u < i).is_some() {}
            if skip.next_if(|&u| u == i).is_none() {
                g.grow(position(i));
            }
        }
        used = g.aabb();
    }
    (all, used)
}

/// Grows `used` with the lanes of vertices `first .. end` (a block of at most four) that
/// `next_unused` (ascending indices, repeats allowed) does not list, `unused` with those
/// it does, taking the listed indices below `end` off it.
fn grow_split(
    used: &mut LaneBox,
    unused: &mut LaneBox,
    p: &Lanes,
    first: usize,
    end: usize,
    next_unused: &mut std::iter::Peekable<impl Iterator<Item = usize>>,
) {
    let mut keep = [false; 4];
    keep[..end - first].fill(true);
    let mut skip = [false; 4];
    while let Some(u) = next_unused.next_if(|&u| u < end) {
        if u >= first {
            keep[u - first] = false;
            skip[u - first] = true;
        }
    }
    used.grow_where(p, BVec4A::from_array(keep));
    unused.grow_where(p, BVec4A::from_array(skip));
}

/// Four vertices' positions, one coordinate a vector (lane k: vertex k of a block).
struct Lanes {
    x: Vec4,
    y: Vec4,
    z: Vec4,
}

/// Lane-wise `m * p`: glam's `Mat3A * Vec3A` adds `x_axis * p.x`, `y_axis * p.y` and
/// `z_axis * p.z` in that order, and `Affine3A::transform_point3a` adds the translation
/// last.
#[inline(always)]
fn mul_lanes(m: &Mat3A, p: &Lanes) -> Lanes {
    let row = |k: usize| p.x * m.x_axis[k] + p.y * m.y_axis[k] + p.z * m.z_axis[k];
    Lanes {
        x: row(0),
        y: row(1),
        z: row(2),
    }
}

/// Four vertices placed as [`placement`] places each, and their world positions.
#[inline(always)]
fn place_block(m: &Affine3A, nm: &Mat3A, block: &[GpuVertex; 4]) -> ([GpuVertex; 4], Lanes) {
    let f: [f32; 32] = bytemuck::cast(*block);
    let col = |i: usize| Vec4::from_slice(&f[i..i + 4]);
    // columns (position, u) and (normal, v) of the four vertices, transposed to rows
    let a = Mat4::from_cols(col(0), col(8), col(16), col(24)).transpose();
    let b = Mat4::from_cols(col(4), col(12), col(20), col(28)).transpose();
    let p = mul_lanes(
        &m.matrix3,
        &Lanes {
            x: a.x_axis,
            y: a.y_axis,
            z: a.z_axis,
        },
    );
    let t = m.translation;
    let p = Lanes {
        x: p.x + t.x,
        y: p.y + t.y,
        z: p.z + t.z,
    };
    let n = mul_lanes(
        nm,
        &Lanes {
            x: b.x_axis,
            y: b.y_axis,
            z: b.z_axis,
        },
    );
    // glam's `Vec3A::normalize_or`: the reciprocal of the length's square root of
    // (x^2 + y^2) + z^2, used where finite and positive
    let rcp = Vec4::ONE / (n.x * n.x + n.y * n.y + n.z * n.z).sqrt();
    let ok: BVec4A = rcp.is_finite_mask() & rcp.cmpgt(Vec4::ZERO);
    let n = Lanes {
        x: Vec4::select(ok, n.x * rcp, Vec4::ZERO),
        y: Vec4::select(ok, n.y * rcp, Vec4::ONE),
        z: Vec4::select(ok, n.z * rcp, Vec4::ZERO),
    };
    let pa = Mat4::from_cols(p.x, p.y, p.z, a.w_axis).transpose();
    let na = Mat4::from_cols(n.x, n.y, n.z, b.w_axis).transpose();
    let mut out = [0.0f32; 32];
    for (k, (p, n)) in [
        (pa.x_axis, na.x_axis),
        (pa.y_axis, na.y_axis),
        (pa.z_axis, na.z_axis),
        (pa.w_axis, na.w_axis),
    ]
    .into_iter()
    .enumerate()
    {
        p.write_to_slice(&mut out[8 * k..8 * k + 4]);
        n.write_to_slice(&mut out[8 * k + 4..8 * k + 8]);
    }
    (bytemuck::cast(out), p)
}

/// A box grown in four lanes per coordinate: the lanes' bounds are the bounds of the
/// points each lane saw; [`LaneBox::aabb`] takes the extremes over the lanes.
struct LaneBox {
    min: Lanes,
    max: Lanes,
}

impl LaneBox {
    const EMPTY: LaneBox = LaneBox {
        min: Lanes {
            x: Vec4::INFINITY,
            y: Vec4::INFINITY,
            z: Vec4::INFINITY,
        },
        max: Lanes {
            x: Vec4::NEG_INFINITY,
            y: Vec4::NEG_INFINITY,
            z: Vec4::NEG_INFINITY,
        },
    };

    /// Grows every lane.
    #[inline(always)]
    fn grow(&mut self, p: &Lanes) {
        self.min.x = self.min.x.min(p.x);
        self.min.y = self.min.y.min(p.y);
        self.min.z = self.min.z.min(p.z);
        self.max.x = self.max.x.max(p.x);
        self.max.y = self.max.y.max(p.y);
        self.max.z = self.max.z.max(p.z);
    }

    /// Grows the lanes where `keep` holds.
    fn grow_where(&mut self, p: &Lanes, keep: BVec4A) {
        let lo = |v: Vec4| Vec4::select(keep, v, Vec4::INFINITY);
        let hi = |v: Vec4| Vec4::select(keep, v, Vec4::NEG_INFINITY);
        self.min.x = self.min.x.min(lo(p.x));
        self.min.y = self.min.y.min(lo(p.y));
        self.min.z = self.min.z.min(lo(p.z));
        self.max.x = self.max.x.max(hi(p.x));
        self.max.y = self.max.y.max(hi(p.y));
        self.max.z = self.max.z.max(hi(p.z));
    }

    /// Lane by lane, the box of both boxes' points.
    fn union(&self, o: &LaneBox) -> LaneBox {
        LaneBox {
            min: Lanes {
                x: self.min.x.min(o.min.x),
                y: self.min.y.min(o.min.y),
                z: self.min.z.min(o.min.z),
            },
            max: Lanes {
                x: self.max.x.max(o.max.x),
                y: self.max.y.max(o.max.y),
                z: self.max.z.max(o.max.z),
            },
        }
    }

    /// The box over all lanes. Bitwise the box [`AabbA`] grows over the same points in
    /// any order unless a bound is zero or a point is NaN: a bound is an extreme value,
    /// and equal values have equal bits but for the zeros' two signs. A scene's
    /// positions are never NaN: validation bounds coordinates (`scene::limits::
    /// MAX_COORDINATE`, 2^40) and scales (`scene::transform::SCALE_RANGE`, up to 2^20), so
    /// no product overflows and no sum is infinity minus infinity.
    fn aabb(&self) -> Aabb {
        Aabb {
            min: Vec3::new(
                self.min.x.min_element(),
                self.min.y.min_element(),
                self.min.z.min_element(),
            ),
            max: Vec3::new(
                self.max.x.max_element(),
                self.max.y.max_element(),
                self.max.z.max_element(),
            ),
        }
    }
}

/// Whether a bound of `b` is zero (of either sign), where the order of growth decides
/// its sign.
fn has_zero_bound(b: &Aabb) -> bool {
    b.min.cmpeq(Vec3::ZERO).any() || b.max.cmpeq(Vec3::ZERO).any()
}

/// The box [`AabbA`] grows over `vertices`' positions in order.
fn grown_in_order<'a>(vertices: impl Iterator<Item = &'a GpuVertex>) -> Aabb {
    let mut b = AabbA::EMPTY;
    for v in vertices {
        b.grow(Vec3A::from(v.position));
    }
    b.aabb()
}

/// An instance's world vertices ([`placement`] of each), with the box of all of them.
pub fn world_vertices(t: &Transform, local: &[GpuVertex]) -> (Vec<GpuVertex>, Aabb) {
    let (world, all, _) = placed_vertices(t, local, &[]);
    (world, all)
}

/// Places an instance's vertices `local` into `out` (its blocks of four, the last
/// padded; `unused`: the instance's unused vertex indices, ascending). Returns the lane
/// boxes of the used vertices and of the unused ones.
fn place_run(
    m: &Affine3A,
    nm: &Mat3A,
    local: &[GpuVertex],
    unused: &[u32],
    out: &mut [[GpuVertex; 4]],
) -> (LaneBox, LaneBox) {
    let (blocks, rest) = local.as_chunks::<4>();
    // the last block padded with default vertices (placed, then cut off; never in a box)
    let mut last = [GpuVertex::default(); 4];
    last[..rest.len()].copy_from_slice(rest);
    let last = (!rest.is_empty()).then_some(last);
    // the used vertices' box, and the box of the unused ones (few, if any)
    let mut used = LaneBox::EMPTY;
    let mut unused_box = LaneBox::EMPTY;
    let mut next_unused = unused.iter().map(|&u| u as usize).peekable();
    for ((k, block), o) in blocks.iter().chain(last.as_ref()).enumerate().zip(out) {
        let (w, p) = place_block(m, nm, block);
        *o = w;
        let (first, end) = (4 * k, local.len().min(4 * k + 4));
        if end == first + 4 && next_unused.peek().is_none_or(|&u| u >= end) {
            used.grow(&p);
            continue;
        }
        grow_split(&mut used, &mut unused_box, &p, first, end, &mut next_unused);
    }
    (used, unused_box)
}

/// An instance's world vertices ([`placement`] of each), with the box of all of them and
/// the box of those its triangles use, in one pass over the vertices (`unused`: the
/// vertices no triangle uses, as indices into `local`, ascending; a repeated or
/// out-of-range index changes nothing). Both boxes are bitwise
/// those [`AabbA`] grows over the same positions in order (a build's `world_vertices`
/// and `triangle_bounds`): the lanes' boxes equal them unless a bound is zero, and there
/// the box is grown again in order. One thread: on rayon's, in runs, the tight loop took
/// half the time but a host's frame loop, whose pool sleeps between frames, gained
/// nothing (docs/performance.md, "Dynamic scenes").
pub fn placed_vertices(
    t: &Transform,
    local: &[GpuVertex],
    unused: &[u32],
) -> (Vec<GpuVertex>, Aabb, Aabb) {
    let m = t.world_from_object();
    let nm = t.normal_matrix();
    let mut placed = vec![[GpuVertex::default(); 4]; local.len().div_ceil(4)];
    let (used, unused_box) = place_run(&m, &nm, local, unused, &mut placed);
    let mut world: Vec<GpuVertex> = bytemuck::allocation::cast_vec(placed);
    world.truncate(local.len());
    let all = used.union(&unused_box);
    let mut used = used.aabb();
    if has_zero_bound(&used) {
        let mut skip = unused.iter().map(|&u| u as usize).peekable();
        used = grown_in_order(
            world
                .iter()
                .enumerate()
                .filter(|(i, _)| {
                    while skip.next_if(|&u| u < *i).is_some() {}
                    skip.next_if(|&u| u == *i).is_none()
                })
                .map(|(_, v)| v),
        );
    }
    let mut all = all.aabb();
    if has_zero_bound(&all) {
        all = grown_in_order(world.iter());
    }
    (world, all, used)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;
    use proptest::prelude::*;

    /// Coordinates with zeros of both signs (often a box's bound), repeated values
    /// (ties), and values whose products overflow to infinities.
    fn coordinate() -> impl Strategy<Value = f32> {
        prop_oneof![
            Just(0.0f32),
            Just(-0.0f32),
            Just(0.5),
            -2.0f32..2.0,
            Just(3.0e38f32),
            Just(-3.0e38f32),
            Just(1.0e-30f32),
        ]
    }

    fn transform() -> impl Strategy<Value = Transform> {
        prop_oneof![
            Just(Transform::IDENTITY),
            // positions of zeros of both signs: x + y * 0 + z * 0 - 0 keeps -0 only
            // where every term is -0
            Just(Transform {
                translation: Vec3::splat(-0.0),
                ..Transform::IDENTITY
            }),
            (
                coordinate(),
                coordinate(),
                coordinate(),
                (-3.0f32..3.0, -3.0f32..3.0),
                (0.01f32..100.0, 0.01f32..100.0, 0.01f32..100.0),
            )
                .prop_map(|(x, y, z, (a, b), (sx, sy, sz))| Transform {
                    translation: Vec3::new(x, y, z),
                    rotation: Quat::from_rotation_y(a) * Quat::from_rotation_x(b),
                    scale: Vec3::new(sx, sy, sz),
                }),
        ]
    }

    fn vertex() -> impl Strategy<Value = GpuVertex> {
        let zero_or_one = || prop_oneof![Just(0.0f32), Just(-0.0f32), Just(-1.0f32)];
        let position = prop_oneof![
            [coordinate(), coordinate(), coordinate()],
            [zero_or_one(), zero_or_one(), zero_or_one()],
        ];
        (
            position,
            [coordinate(), coordinate(), coordinate()],
            any::<u32>(),
            any::<u32>(),
        )
            .prop_map(|(position, normal, u, v)| GpuVertex {
                position,
                u: f32::from_bits(u),
                normal,
                v: f32::from_bits(v),
            })
    }

    /// Whether the box of `positions` is NaN-free, as a placement's is (finite parts:
    /// an overflow gives an infinity of one sign, never infinity minus infinity)
    fn nan_free(world: &[GpuVertex]) -> bool {
        world.iter().all(|w| !Vec3::from(w.position).is_nan())
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(512))]

        /// The four-lane loop places every vertex bitwise as [`placement`] does (u and v
        /// of any bits carried over, normals of no length and overflows included), for
        /// any count (the padded last block), and its boxes are bitwise those grown in
        /// order over all and over the used vertices.
        #[test]
        fn the_lanes_place_and_bound_as_one_vertex_at_a_time(
            t in transform(),
            local in prop::collection::vec(vertex(), 0..23),
            unused_mask in prop::collection::vec(0u8..3, 23),
        ) {
            let one = placement(&t);
            let expected: Vec<GpuVertex> = local.iter().map(&one).collect();
            // unused vertices, some listed twice, and an index past the end
            let mut unused: Vec<u32> = (0..local.len() as u32)
                .flat_map(|i| std::iter::repeat_n(i, unused_mask[i as usize] as usize))
                .collect();
            unused.push(local.len() as u32 + 1);
            let (world, all, used) = placed_vertices(&t, &local, &unused);
            prop_assert!(
                bytemuck::cast_slice::<_, u32>(&world) == bytemuck::cast_slice::<_, u32>(&expected)
            );
            prop_assume!(nan_free(&expected));
            let bits = |b: Aabb| [b.min.to_array(), b.max.to_array()].map(|v| v.map(f32::to_bits));
            prop_assert_eq!(bits(all), bits(grown_in_order(expected.iter())));
            let used_in_order = grown_in_order(
                expected
                    .iter()
                    .enumerate()
                    .filter(|(i, _)| !unused.contains(&(*i as u32)))
                    .map(|(_, v)| v),
            );
            prop_assert_eq!(bits(used), bits(used_in_order));
            let (world2, all2) = world_vertices(&t, &local);
            prop_assert!(
                bytemuck::cast_slice::<_, u32>(&world2) == bytemuck::cast_slice::<_, u32>(&world)
            );
            prop_assert_eq!(bits(all2), bits(all));
            // the device's placement (its parameters, a run inside longer arrays) and the
            // host's boxes from the coordinate columns alone
            let mut padded = vec![GpuVertex::default(); 3];
            padded.extend_from_slice(&local);
            padded.push(GpuVertex::default());
            let p = placement_params(&t, 3, 7, local.len() as u32);
            let placed = place_vertices(&p, &padded[3..3 + local.len()]);
            prop_assert!(
                bytemuck::cast_slice::<_, u32>(&placed) == bytemuck::cast_slice::<_, u32>(&world)
            );
            let columns = PositionColumns::of(&padded);
            let (all3, used3) = placed_bounds(&t, &columns, 3..3 + local.len(), &unused);
            prop_assert_eq!(bits(all3), bits(all));
            prop_assert_eq!(bits(used3), bits(used));
        }
    }
}
