//! The two-level acceleration structure every software traversal reads, laid out in the
//! scene's node buffer (`SceneArgs::bvh_nodes`, 80-byte slots of 5 x `[u32; 4]`):
//!
//! | slots                          | what                                                   |
//! |--------------------------------|--------------------------------------------------------|
//! | `0 .. C`                       | the top level (TLAS): a CWBVH over the levels' world boxes, root at slot 0, unused slots zero but for the [`SINGLE_LEVEL_MARK`] vector of a scene of the static level alone |
//! | `C .. C + 2N`                  | one [`InstanceRecord`] (2 slots) per level, in TLAS leaf order |
//! | then                           | each level's bottom-level CWBVH (BLAS), static level first, each in a region of [`Level::blas_capacity`] slots (an instance's: room for any BVH over its triangles, so that a deformed instance's BLAS is rebuilt in place) |
//! | then                           | the instances' object-space vertex positions, one `[f32; 4]` each (w = 1) |
//! | then                           | every triangle's corners in its level's space, [`TRIANGLE_CORNER_VEC4S`] `[f32; 4]` per triangle in triangle order (the records' `triangle_corners`), padded to whole slots |
//!
//! A *level* is the scene's static level (every object without a transform, in world
//! space: the single BVH that scenes had before instances) or one instance (an object with
//! a [`Transform`], its BLAS built once in object space). `C` (the TLAS capacity) is the
//! level count rounded up to even, enough for any CWBVH over that many boxes (its nodes
//! are the collapsed inner nodes of a binary tree: at most `max(1, N - 1)`), so moving
//! instances rewrites slots `0 .. C + 2N` in place and nothing else of the buffer.
//!
//! Node indices are absolute: each BLAS's child indices are rebased to where it lies and
//! its primitive indices to its first triangle; the TLAS's primitive indices are rebased
//! by `C / 2`, so that TLAS primitive `p` names the record at slot `2p`.
//!
//! Traversal (CPU `traversal.rs`, `traversal.wgsl`, `traversal.cl`): world ray through the
//! TLAS; at a TLAS leaf the ray moves into the level's object space (not at all for the
//! static level, flag [`instance_flags::IDENTITY`], so scenes without instances trace as
//! before, bitwise) and its BLAS is traversed, triangles tested in object space (the
//! instance's positions above; direction not normalised, so `t` is the world ray's). The
//! GPU ports read a tested triangle's corners from the corner region, the CPU through its
//! vertex indices: the same values (`device_scene`'s tests check the region). The
//! kernels then shade with the world-space vertices (`vertices`), which hold every
//! instance's vertices transformed: surfaces are interpolated from them with the hit's
//! barycentrics, which the affine map preserves. Vulkan builds its own BLAS per level from
//! the same records (static level from `vertices`, instances from their positions here)
//! and a TLAS of instances with the records' `world_from_object`.

use crate::math::geometry::Aabb;
use crate::scene::Transform;
use glam::{Affine3A, Vec3};

/// `[u32; 4]` vectors per 80-byte slot of the node buffer.
pub const SLOT_VEC4S: usize = 5;

/// Slots per [`InstanceRecord`].
pub const RECORD_SLOTS: u32 = 2;

/// Bits of [`InstanceRecord::flags`].
pub mod instance_flags {
    /// The level is in world space (the static level): rays enter its BLAS unchanged and
    /// its triangles are tested against `vertices`.
    pub const IDENTITY: u32 = 1;
}

/// First word of slot 1's first vector when the static level is the scene's only level:
/// `[SINGLE_LEVEL_MARK, blas_root, triangle_corners, position_offset]` (its record's),
/// so that a traversal starts at that BLAS's root with the world ray instead of visiting
/// the TLAS's root (a node test of every ray spent on one box) and entering the level.
/// The hits are the same: the TLAS's box only culls. Slot 1 lies inside the TLAS's
/// capacity (2 for one level) and is unused by its single node; with more levels it may
/// hold a TLAS node, whose first word is its box's minimum x, a finite float, never this
/// NaN's bits (a scene's vertices are finite: `Scene::validate`).
pub const SINGLE_LEVEL_MARK: u32 = 0x7fc0_5e1f;

/// Slot of the [`SINGLE_LEVEL_MARK`] vector.
pub const SINGLE_LEVEL_SLOT: usize = 1;

/// Smallest magnitude of a ray direction component in node culling (2^-64; a unit
/// direction in world space, in object space one whose largest component is in [1, 2)).
/// The slab test divides by each component, so a smaller one (a zero included, its sign
/// kept) is raised to this before its inverse is taken. The inverse is otherwise exact:
/// clamping it at 2^23, as a component of 2^-23 would give, culls boxes a ray from a
/// distant light passes through (its slab times along that axis are off by the factor
/// |c| 2^23). The floor bounds every slab value: a child's quantized bound (255 steps of
/// its node's power-of-two extent, at most 2^42 for boxes within the coordinate bound
/// `MAX_COORDINATE` = 2^40) or a distance (at most 2^41) times 2^64 stays below 2^107 in
/// world space; in an instance's object space (scales down to 2^-20) a ray's origin
/// reaches about 2^61 and a slab value 2^125, still finite. So no product overflows to
/// infinity and no `0 x inf` makes a NaN. What it
/// changes is below f32's resolution: the ray moves at most `t 2^-64` along that axis,
/// far less than the rounding `t 2^-24` of any point on it.
pub const CULLING_MIN_COMPONENT: f32 = 1.0 / 18_446_744_073_709_551_616.0;

/// A direction component as node culling sees it: at least [`CULLING_MIN_COMPONENT`] in
/// magnitude, sign kept (a zero's sign bit too, so the slab test's side choice matches
/// the inverse). Mirrored by the ports' `culling_component`.
#[inline(always)]
pub fn culling_component(c: f32) -> f32 {
    if c.abs() < CULLING_MIN_COMPONENT {
        CULLING_MIN_COMPONENT.copysign(c)
    } else {
        c
    }
}

/// One level as the traversal reads it: 10 x `[u32; 4]` (two node slots).
///
/// `[0..3]` rows of `object_from_world` (f32 bits; `x' = dot(row.xyz, p) + row.w`);
/// `[3]` = (`blas_root`, `flags`, `position_offset`, `triangle_base`);
/// `[4]` = (`triangle_count`, `vertex_base`, `vertex_count`, `position_base`);
/// `[5..8]` rows of `world_from_object` (Vulkan's instance transform); `[8]` =
/// (`geometry_version`, `triangle_corners`, 0, 0); `[9]` zero.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct InstanceRecord {
    /// World space to object space (3 rows of an affine 3x4 matrix).
    pub object_from_world: [[f32; 4]; 3],
    /// Object space to world space (3 rows).
    pub world_from_object: [[f32; 4]; 3],
    /// Slot of the level's BLAS root.
    pub blas_root: u32,
    /// [`instance_flags`].
    pub flags: u32,
    /// `position_base - vertex_base` (wrapping): a triangle's vertex index plus this is the
    /// vec4 index of its object-space position in the node buffer.
    pub position_offset: u32,
    /// First triangle of the level (triangles are contiguous per level).
    pub triangle_base: u32,
    /// Its triangle count.
    pub triangle_count: u32,
    /// First world vertex of the level's object (the static level: 0, unused).
    pub vertex_base: u32,
    /// Its vertex count (the static level: every vertex).
    pub vertex_count: u32,
    /// vec4 index of the first object-space position (the static level: 0, unused).
    pub position_base: u32,
    /// How many times the level's geometry was deformed since the build (Vulkan rebuilds
    /// a level's BLAS when it changes).
    pub geometry_version: u32,
    /// vec4 index in the node buffer of the triangle corners ([`TRIANGLE_CORNER_VEC4S`]
    /// per triangle, triangle `i` at `triangle_corners + 3 i`; the same for every level).
    pub triangle_corners: u32,
}

/// vec4s per triangle in the node buffer's corner region: its three corners, each
/// `(x, y, z, 1)` as f32 bits, in its level's space (world for the static level, object
/// space for an instance), in triangle (leaf) order. The GPU traversals read a triangle
/// here in one contiguous 48-byte run instead of through its three vertex indices (two
/// dependent loads); the values are the vertices' own, so hits are bitwise the same.
pub const TRIANGLE_CORNER_VEC4S: usize = 3;

fn rows(m: &Affine3A) -> [[f32; 4]; 3] {
    let c = m.to_cols_array_2d(); // 4 columns of 3
    std::array::from_fn(|r| [c[0][r], c[1][r], c[2][r], c[3][r]])
}

impl InstanceRecord {
    /// The record's ten vectors.
    pub fn encode(&self) -> [[u32; 4]; 10] {
        let f = |r: [f32; 4]| r.map(f32::to_bits);
        let z = [0u32; 4];
        [
            f(self.object_from_world[0]),
            f(self.object_from_world[1]),
            f(self.object_from_world[2]),
            [
                self.blas_root,
                self.flags,
                self.position_offset,
                self.triangle_base,
            ],
            [
                self.triangle_count,
                self.vertex_base,
                self.vertex_count,
                self.position_base,
            ],
            f(self.world_from_object[0]),
            f(self.world_from_object[1]),
            f(self.world_from_object[2]),
            [self.geometry_version, self.triangle_corners, 0, 0],
            z,
        ]
    }

    /// Reads a record back from its ten vectors.
    pub fn decode(v: &[[u32; 4]]) -> InstanceRecord {
        let f = |r: [u32; 4]| r.map(f32::from_bits);
        InstanceRecord {
            object_from_world: [f(v[0]), f(v[1]), f(v[2])],
            world_from_object: [f(v[5]), f(v[6]), f(v[7])],
            blas_root: v[3][0],
            flags: v[3][1],
            position_offset: v[3][2],
            triangle_base: v[3][3],
            triangle_count: v[4][0],
            vertex_base: v[4][1],
            vertex_count: v[4][2],
            position_base: v[4][3],
            geometry_version: v[8][0],
            triangle_corners: v[8][1],
        }
    }
}

/// One level on the host.
#[derive(Clone, Debug, PartialEq)]
pub struct Level {
    /// The scene object it is (an instance), or `None` for the static level.
    pub object: Option<usize>,
    /// Its placement (identity for the static level).
    pub transform: Transform,
    /// Slot of its BLAS root.
    pub blas_root: u32,
    /// Slots its BLAS region holds (the static level: its BLAS's nodes; an instance:
    /// [`instance_blas_capacity`]).
    pub blas_capacity: u32,
    /// The material index of its triangles (an instance is one object).
    pub material: u32,
    /// Deformations since the build ([`InstanceRecord::geometry_version`]).
    pub geometry_version: u32,
    /// [`InstanceRecord::triangle_corners`] (the node buffer's corner region).
    pub triangle_corners: u32,
    /// Its triangles: `triangle_base .. triangle_base + triangle_count`.
    pub triangle_base: u32,
    /// Its triangle count.
    pub triangle_count: u32,
    /// Its object's world vertices: `vertex_base .. vertex_base + vertex_count`.
    pub vertex_base: u32,
    /// Its vertex count.
    pub vertex_count: u32,
    /// vec4 index of its object-space positions in the node buffer (instances).
    pub position_base: u32,
    /// Box of its world vertices.
    pub world_bounds: Aabb,
    /// Box of its world vertices if its material is specular, else empty.
    pub caster_bounds: Aabb,
    /// How far its vertex normals depart from their faces' normals
    /// ([`crate::device::device_scene::normal_departure`]): the static level's in world
    /// space, an instance's in object space, which a move keeps ([`Level::smooth_normals`]).
    pub normal_departure: f32,
    /// An instance's triangles (world-vertex indices; empty for the static level): what
    /// `normal_departure` is recomputed over when it deforms.
    /// (Shared: levels are cloned on every move, their triangles never change.)
    pub triangle_indices: std::sync::Arc<[[u32; 3]]>,
    /// The world-vertex indices those triangles use, each once, ascending (what
    /// `triangle_bounds` is grown over: a third of the triangles' corners).
    pub used_vertices: std::sync::Arc<[u32]>,
    /// An instance's vertices its triangles leave unused, as indices from `vertex_base`,
    /// ascending (a move grows the box of the used ones in the pass that bounds them all:
    /// [`crate::device::placement::placed_bounds`]).
    pub unused_vertices: std::sync::Arc<[u32]>,
    /// An instance's box of the world vertices its triangles use (AdaptiveCaustics' caster
    /// box of the object: `adaptive_caustics::caster_boxes`); empty for the static level.
    pub triangle_bounds: Aabb,
    /// Balls around its caster objects (world space, centre xyz and radius w;
    /// [`crate::device::caster_spheres`]): one per specular object of the static level,
    /// one for a specular instance, none otherwise.
    pub caster_balls: Vec<[f32; 4]>,
    /// A specular instance's ball of its object-space vertices, which its world ball is
    /// placed from ([`crate::device::caster_spheres::placed_ball`]); `None` otherwise.
    pub object_ball: Option<[f32; 4]>,
}

impl Level {
    /// Whether a triangle of the level may have a vertex normal that departs from its
    /// geometric normal in world space by more than
    /// [`crate::device::device_scene::NORMAL_DEPARTURE`] (PhotonGi corrects shading
    /// normals where some level's do). An instance's departure `d` is measured in object
    /// space: its placement maps normals by the normal matrix `R S^-1` and renormalises
    /// them, which moves the difference of two unit normals by at most the condition
    /// number `kappa` (largest over smallest scale; the rotation keeps lengths) in length,
    /// to first order, and a per-axis difference lies within 1 and `sqrt(3)` of a length:
    /// the world departure is at most `sqrt(3) kappa d`, what is tested (the rounding of
    /// either normal, about 1e-7, is far below the threshold).
    pub fn smooth_normals(&self) -> bool {
        let stretch = match self.object {
            None => 1.0,
            Some(_) => {
                let s = self.transform.scale.abs();
                3f32.sqrt() * s.max_element() / s.min_element()
            }
        };
        self.normal_departure * stretch > crate::device::device_scene::NORMAL_DEPARTURE
    }

    /// The record the traversal reads.
    pub fn record(&self) -> InstanceRecord {
        let identity = self.object.is_none();
        InstanceRecord {
            object_from_world: rows(&self.transform.object_from_world()),
            world_from_object: rows(&self.transform.world_from_object()),
            blas_root: self.blas_root,
            flags: if identity {
                instance_flags::IDENTITY
            } else {
                0
            },
            position_offset: self.position_base.wrapping_sub(self.vertex_base),
            triangle_base: self.triangle_base,
            triangle_count: self.triangle_count,
            vertex_base: self.vertex_base,
            vertex_count: self.vertex_count,
            position_base: self.position_base,
            geometry_version: self.geometry_version,
            triangle_corners: self.triangle_corners,
        }
    }
}

/// Slots reserved for an instance's BLAS over `triangles` triangles: room for any CWBVH
/// over them. Every node but the root has at least two children and every leaf child at
/// least one triangle, so a CWBVH over `n` triangles has at most `max(1, n - 1)` nodes
/// (the TLAS's argument, [`tlas_capacity`]); `max(2, n)` leaves a margin. A deformed
/// instance's BLAS is rebuilt into this region in place (80 bytes a triangle of device
/// memory for instances; the static level is not reserved for, it never deforms).
pub fn instance_blas_capacity(triangles: u32) -> u32 {
    triangles.max(2)
}

/// TLAS capacity in slots for `levels` levels: the count rounded up to even, at least 2.
pub fn tlas_capacity(levels: usize) -> u32 {
    (levels.max(1) as u32).next_multiple_of(2)
}

/// The world box the TLAS culls a level with: its world vertices' box grown by
/// `2^-16 (extent + largest |coordinate|)` on every side. The margin covers the rounding
/// between the world vertices (`f32(M p)`) and the object-space triangles the ray meets
/// after its own transform into object space (a few ulps of those magnitudes each); it
/// only lets more rays into a BLAS, never changes which triangle is hit.
pub fn culling_box(b: &Aabb) -> obvhs::aabb::Aabb {
    let magnitude = b.min.abs().max(b.max.abs()).max_element();
    let pad = Vec3::splat(((b.max - b.min).max_element() + magnitude) * (1.0 / 65_536.0));
    obvhs::aabb::Aabb::new((b.min - pad).into(), (b.max + pad).into())
}

/// Slots `0 .. C + 2N` of the node buffer for `levels`: the TLAS built over their culling
/// boxes (obvhs, deterministic) and the records in its leaf order. Errors (never panics)
/// if the build made more nodes than the capacity.
pub fn top_level(levels: &[Level]) -> Result<Vec<[u32; 4]>, String> {
    let capacity = tlas_capacity(levels.len());
    let boxes: Vec<obvhs::aabb::Aabb> = levels
        .iter()
        .map(|l| culling_box(&l.world_bounds))
        .collect();
    let mut time = std::time::Duration::ZERO;
    let bvh = obvhs::cwbvh::builder::build_cwbvh(
        &boxes,
        obvhs::BvhBuildParams::medium_build(),
        &mut time,
    );
    if bvh.nodes.len() > capacity as usize {
        return Err(format!(
            "the top-level BVH over {} levels has {} nodes, over its capacity {capacity}",
            levels.len(),
            bvh.nodes.len()
        ));
    }
    let mut out =
        vec![[0u32; 4]; (capacity + RECORD_SLOTS * levels.len() as u32) as usize * SLOT_VEC4S];
    let nodes: &[[u32; 4]] = bytemuck::cast_slice(&bvh.nodes);
    out[..nodes.len()].copy_from_slice(nodes);
    for n in 0..bvh.nodes.len() {
        // TLAS primitive p (leaf order) -> record slot C + 2p = 2 (C/2 + p)
        out[n * SLOT_VEC4S + 1][1] += capacity / 2;
    }
    for (p, &l) in bvh.primitive_indices.iter().enumerate() {
        let at = (capacity as usize + 2 * p) * SLOT_VEC4S;
        out[at..at + 10].copy_from_slice(&levels[l as usize].record().encode());
    }
    if let [only] = levels {
        if only.object.is_none() && bvh.nodes.len() == 1 {
            let r = only.record();
            out[SINGLE_LEVEL_SLOT * SLOT_VEC4S] = [
                SINGLE_LEVEL_MARK,
                r.blas_root,
                r.triangle_corners,
                r.position_offset,
            ];
        }
    }
    Ok(out)
}

/// Rebases a BLAS's nodes to lie at slot `first_slot` with its triangles from
/// `first_triangle`.
pub fn rebase_blas(nodes: &mut [[u32; 4]], first_slot: u32, first_triangle: u32) {
    for n in nodes.chunks_exact_mut(SLOT_VEC4S) {
        n[1][0] += first_slot;
        n[1][1] += first_triangle;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn culling_component_floors_keeping_the_sign() {
        assert_eq!(CULLING_MIN_COMPONENT, 2f32.powi(-64));
        assert_eq!(culling_component(0.0), CULLING_MIN_COMPONENT);
        assert_eq!(culling_component(-0.0), -CULLING_MIN_COMPONENT);
        assert_eq!(culling_component(1e-30), CULLING_MIN_COMPONENT);
        assert_eq!(culling_component(-1e-30), -CULLING_MIN_COMPONENT);
        // components a clamped inverse would have changed keep their value
        for c in [2f32.powi(-64), 1e-7, 2f32.powi(-23), 0.5, -1e-7, -1.0] {
            assert_eq!(culling_component(c), c);
        }
    }

    #[test]
    fn slab_values_stay_finite_in_the_coordinate_bound() {
        // the largest power-of-two extent of a node within the coordinate bound (its 255
        // quantization steps span the box) and the longest distance, times the largest
        // inverse
        let span = 2.0 * crate::scene::limits::MAX_COORDINATE;
        let extent = 2f32.powi((span / 255.0).log2().ceil() as i32);
        let inv = 1.0 / CULLING_MIN_COMPONENT;
        let slab = 255.0 * extent * inv + span * inv;
        assert!(slab.is_finite() && slab < 2f32.powi(107), "{slab:e}");
        // in object space: a ray from the far side of the coordinate bound, seen by an
        // instance scaled by the smallest scale (its object coordinates within the bound)
        let min_scale = crate::scene::transform::SCALE_RANGE.0;
        let origin = span / min_scale;
        let slab = 255.0 * extent * inv + (origin + span) * inv;
        assert!(slab.is_finite() && slab < 2f32.powi(126), "{slab:e}");
    }
}
