//! Ray queries on the host: obvhs CWBVH traversal (its `traverse!` loop) over core's
//! flattened node array, with core's watertight `intersect_triangle` (its per-ray part `WatertightRay` set up once
//! per ray) as the leaf test (the same
//! function the shader ports mirror). Triangles are in BVH leaf order, so a leaf's
//! primitive index is the triangle.
//!
//! The node test is [`node_hits`], obvhs's `intersect_ray_basic` with one change: a child
//! box is entered when its exit distance is >= 0 (`CWBVH_T_MIN`), where obvhs clamps the
//! entry distance to its `EPSILON = 1e-4` and so culls every box closer than 1e-4 scene
//! units. That lost whole hits in scenes at 1e-4 scale (stiff case `scale-1e-4`,
//! docs/stability.md). The OpenCL and WGSL traversals (`cwbvh_node_hits`) make the same
//! test.

use caustica_core::backend::BackendError;
use caustica_core::device::layout::{surface_point, SurfacePoint};
use caustica_core::device::layout::{GpuLight, GpuMaterial, GpuTriangle, GpuVertex};
use caustica_core::math::geometry::WatertightRay;
// `UVec2`: named by obvhs's `traverse!` macro at its call site.
use caustica_core::device::acceleration::{
    culling_component, instance_flags, SINGLE_LEVEL_MARK, SINGLE_LEVEL_SLOT, SLOT_VEC4S,
};
use glam::{UVec2, Vec3, Vec3A};
use obvhs::cwbvh::node::extract_byte64;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::ray::Ray;

/// Smallest exit distance of a child box that is entered (scene units): 0, i.e. boxes
/// behind the ray origin are culled, and nothing else (obvhs: 1e-4).
pub const CWBVH_T_MIN: f32 = 0.0;

/// Depth of the traversal stack (the ports' `TRAVERSAL_STACK_SIZE`).
const TRAVERSAL_STACK_SIZE: usize = 32;

/// The (near, far) quantized bounds of one axis for a ray whose direction is negative
/// (`neg`) or not along it.
#[inline(always)]
fn axis<'a>(neg: bool, lo: &'a [u8; 8], hi: &'a [u8; 8]) -> (&'a [u8; 8], &'a [u8; 8]) {
    if neg {
        (hi, lo)
    } else {
        (lo, hi)
    }
}

/// Hit mask of `node`'s children for `ray` (obvhs's `CwBvhNode::intersect_ray_basic` with
/// the entry clamp [`CWBVH_T_MIN`]): inner children set a bit in the top byte at their
/// octant-ordered slot, leaves their unary primitive count in the low 24 bits.
/// `oct_inv4` is the ray's inverted octant replicated into each byte (obvhs's
/// `ray_get_octant_inv4`).
#[inline(always)]
pub fn node_hits(node: &CwBvhNode, ray: &Ray, oct_inv4: u32) -> u32 {
    let scale = node.compute_extent() * ray.inv_direction;
    let offset = (Vec3A::from(node.p) - ray.origin) * ray.inv_direction;
    // Per axis, the quantized child bounds the ray meets first (near) and last (far).
    let (near_x, far_x) = axis(ray.direction.x < 0.0, &node.child_min_x, &node.child_max_x);
    let (near_y, far_y) = axis(ray.direction.y < 0.0, &node.child_min_y, &node.child_max_y);
    let (near_z, far_z) = axis(ray.direction.z < 0.0, &node.child_min_z, &node.child_max_z);
    // The eight slab tests as straight-line array code (the compiler vectorises it);
    // the same operations, in the same order, as the OpenCL and WGSL `cwbvh_node_hits`.
    let mut entered = [false; 8];
    for child in 0..8 {
        let tmin = (near_x[child] as f32 * scale.x + offset.x)
            .max(near_y[child] as f32 * scale.y + offset.y)
            .max(near_z[child] as f32 * scale.z + offset.z)
            .max(CWBVH_T_MIN);
        let tmax = (far_x[child] as f32 * scale.x + offset.x)
            .min(far_y[child] as f32 * scale.y + offset.y)
            .min(far_z[child] as f32 * scale.z + offset.z)
            .min(ray.tmax);
        entered[child] = tmin <= tmax;
    }
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
    let mut hit_mask = 0;
    for (child, e) in entered.into_iter().enumerate() {
        if e {
            hit_mask |= extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
        }
    }
    hit_mask
}

/// Borrowed view of a prepared scene.
pub struct SceneView<'a> {
    /// Mesh vertices (world space: instances' vertices transformed).
    pub vertices: &'a [GpuVertex],
    /// Triangles, level after level, each level's in its BVH's leaf order.
    pub triangles: &'a [GpuTriangle],
    /// Material table.
    pub materials: &'a [GpuMaterial],
    /// Every light of the scene.
    pub lights: &'a [GpuLight],
    /// The node buffer as uploaded ([`caustica_core::device::acceleration`]): TLAS,
    /// instance records, BLASes and object-space positions, read in place.
    pub nodes: &'a [[u32; 4]],
}

/// Closest hit: distance, triangle and barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Distance along the unit ray (scene units).
    pub t: f32,
    /// Index of the triangle hit.
    pub triangle: u32,
    /// Barycentric weight of the triangle's vertex 1.
    pub u: f32,
    /// Barycentric weight of the triangle's vertex 2.
    pub v: f32,
}

/// Checks that the uploaded node array is a whole number of 80-byte nodes (the
/// traversal reads it in place).
pub fn check_nodes(nodes: &[[u32; 4]]) -> Result<(), BackendError> {
    if !nodes.len().is_multiple_of(SLOT_VEC4S) {
        return Err(BackendError::BadArgument(
            "BVH node buffer is not a whole number of 80-byte nodes".into(),
        ));
    }
    Ok(())
}

/// The obvhs ray for node culling: each direction component raised to at least
/// `CULLING_MIN_COMPONENT` in magnitude ([`culling_component`]) and its inverse taken
/// exactly. obvhs's `Ray::new` clamps the inverse of a component of at most 2^-23 to
/// 2^23 (`safe_inverse`), which culls boxes a ray from a distant light passes through.
/// Only node culling sees this ray; triangles are tested with the exact direction.
fn traversal_ray(origin: Vec3, dir: Vec3, t_max: f32) -> Ray {
    let direction = Vec3A::new(
        culling_component(dir.x),
        culling_component(dir.y),
        culling_component(dir.z),
    );
    Ray {
        origin: Vec3A::from(origin),
        direction,
        inv_direction: Vec3A::ONE / direction,
        tmin: 0.0,
        tmax: t_max,
    }
}

/// `row.xyz . p + row.w` in the order the ports write it (`x*r.x + y*r.y + z*r.z + r.w`,
/// each product rounded, never fused).
#[inline(always)]
fn affine_row(r: [u32; 4], p: Vec3, w: f32) -> f32 {
    let f = r.map(f32::from_bits);
    p.x * f[0] + p.y * f[1] + p.z * f[2] + w * f[3]
}

/// The ray as one level sees it: node-culling ray, its octant, its watertight form, and
/// `t_scale`, the factor from the ray's `t` to the culling ray's (1 in world space).
#[derive(Clone, Copy)]
struct LevelRay {
    ray: Ray,
    oct_inv4: u32,
    watertight: WatertightRay,
    t_scale: f32,
}

/// The power of two that brings `d`'s largest component into [1, 2) (1 where it is zero or
/// not finite): an object-space direction is `object_from_world` applied to a unit one, so
/// its length is about 1 / scale, and `CULLING_MIN_COMPONENT` is a floor for directions
/// of about unit size (the direction of an instance scaled by 2^64 would be floored
/// whole). Multiplying by a power of two is exact, so culling with `d * c` and `t / c`
/// decides as culling with `d` and `t` would with an unfloored inverse.
#[inline(always)]
fn culling_scale(d: Vec3) -> f32 {
    let e = (d.abs().max_element().to_bits() >> 23) & 0xff;
    if e == 0 || e >= 254 {
        return 1.0;
    }
    f32::from_bits((254 - e) << 23)
}

impl LevelRay {
    /// The world ray (unit direction; culled as before instances existed).
    fn world(origin: Vec3, dir: Vec3, t_max: f32) -> Option<LevelRay> {
        let ray = traversal_ray(origin, dir, t_max);
        Some(LevelRay {
            oct_inv4: ray_get_octant_inv4(&ray.direction),
            watertight: WatertightRay::new(origin, dir)?,
            ray,
            t_scale: 1.0,
        })
    }

    /// An instance's object-space ray (direction not normalised: `t` stays the world
    /// ray's), culled with its direction scaled by [`culling_scale`].
    fn object(origin: Vec3, dir: Vec3, t_max: f32) -> Option<LevelRay> {
        let c = culling_scale(dir);
        let ray = traversal_ray(origin, dir * c, t_max);
        Some(LevelRay {
            oct_inv4: ray_get_octant_inv4(&ray.direction),
            watertight: WatertightRay::new(origin, dir)?,
            ray,
            t_scale: 1.0 / c,
        })
    }
}

/// The ray's inverted octant in every byte (obvhs's private `ray_get_octant_inv4`; the
/// ports' `octant_inv4`).
#[inline(always)]
fn ray_get_octant_inv4(d: &Vec3A) -> u32 {
    (if d.x < 0.0 { 0 } else { 0x0404_0404 })
        | (if d.y < 0.0 { 0 } else { 0x0202_0202 })
        | (if d.z < 0.0 { 0 } else { 0x0101_0101 })
}

/// obvhs's `firstbithigh`.
#[inline(always)]
fn firstbithigh(x: u32) -> u32 {
    31 - x.leading_zeros()
}

impl SceneView<'_> {
    fn node(&self, i: u32) -> &CwBvhNode {
        let at = i as usize * SLOT_VEC4S;
        bytemuck::from_bytes(bytemuck::cast_slice(&self.nodes[at..at + SLOT_VEC4S]))
    }

    fn world_triangle(&self, i: u32) -> (Vec3, Vec3, Vec3) {
        let t = &self.triangles[i as usize];
        let p = |k: usize| Vec3::from(self.vertices[t.indices[k] as usize].position);
        (p(0), p(1), p(2))
    }

    /// An instance's triangle in object space: vertex index + `position_offset` is the
    /// position's vec4 in the node buffer.
    fn object_triangle(&self, i: u32, position_offset: u32) -> (Vec3, Vec3, Vec3) {
        let t = &self.triangles[i as usize];
        let p = |k: usize| {
            let v = self.nodes[t.indices[k].wrapping_add(position_offset) as usize];
            Vec3::new(
                f32::from_bits(v[0]),
                f32::from_bits(v[1]),
                f32::from_bits(v[2]),
            )
        };
        (p(0), p(1), p(2))
    }

    /// Closest intersection along the unit ray with `0 < t < t_max`.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_max: f32) -> Option<Hit> {
        self.traverse(origin, dir, t_max, false)
    }

    /// True when something lies on the ray before `t_max`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        self.traverse(origin, dir, t_max, true).is_some()
    }

    /// The closest hit in `0 < t < t_max`, or with `any_hit` the first one found (as the
    /// ports' `traverse_cwbvh`): obvhs's `traverse!` loop over two levels
    /// ([`caustica_core::device::acceleration`]). A TLAS leaf is an instance record: the
    /// TLAS's remaining work is pushed, the ray moves into the instance's object space
    /// (the static level keeps the world ray) and the instance's BLAS root becomes the
    /// current group; when the stack falls back to where it was on entry, the world ray
    /// returns. Popped groups with no inner-node bits are primitive groups (the TLAS's
    /// remaining instances).
    #[inline(always)]
    fn traverse(&self, origin: Vec3, dir: Vec3, t_max: f32, any_hit: bool) -> Option<Hit> {
        if self.nodes.len() < SLOT_VEC4S {
            return None;
        }
        crate::traversal_stats::ray_begins();
        let world = LevelRay::world(origin, dir, t_max)?;
        let mut level = world;
        let mut closest = t_max;
        let mut best: Option<Hit> = None;
        let mut stack = [UVec2::ZERO; TRAVERSAL_STACK_SIZE];
        let mut sp = 0usize;
        let mut current_group = UVec2::new(0, 0x8000_0000);
        let mut primitive_group = UVec2::ZERO;
        // in a BLAS: the stack depth on entry and the record's position offset
        let mut in_blas = false;
        let mut blas_sp = 0usize;
        let mut object_space = false;
        let mut position_offset = 0u32;
        // the static level alone: start at its BLAS root with the world ray
        if let Some(single) = self.nodes.get(SINGLE_LEVEL_SLOT * SLOT_VEC4S) {
            if single[0] == SINGLE_LEVEL_MARK {
                in_blas = true;
                position_offset = single[3];
                current_group = UVec2::new(single[1], 0x8000_0000);
            }
        }
        loop {
            while primitive_group.y != 0 {
                let bit = firstbithigh(primitive_group.y);
                primitive_group.y &= !(1u32 << bit);
                let prim = primitive_group.x + bit;
                if !in_blas {
                    // a TLAS leaf: enter the instance whose record is at slot 2 * prim
                    if primitive_group.y != 0 && sp < TRAVERSAL_STACK_SIZE {
                        stack[sp] = primitive_group;
                        crate::traversal_stats::stack_accessed();
                        sp += 1;
                    }
                    if current_group.y & 0xff00_0000 != 0 && sp < TRAVERSAL_STACK_SIZE {
                        stack[sp] = current_group;
                        crate::traversal_stats::stack_accessed();
                        sp += 1;
                    }
                    let r = &self.nodes[(2 * prim) as usize * SLOT_VEC4S..][..5];
                    let info = r[3];
                    object_space = info[1] & instance_flags::IDENTITY == 0;
                    if object_space {
                        let o = Vec3::new(
                            affine_row(r[0], origin, 1.0),
                            affine_row(r[1], origin, 1.0),
                            affine_row(r[2], origin, 1.0),
                        );
                        let d = Vec3::new(
                            affine_row(r[0], dir, 0.0),
                            affine_row(r[1], dir, 0.0),
                            affine_row(r[2], dir, 0.0),
                        );
                        match LevelRay::object(o, d, closest) {
                            Some(l) => level = l,
                            None => {
                                // a direction the transform cannot carry: skip the instance
                                current_group = UVec2::ZERO;
                                in_blas = true;
                                blas_sp = sp;
                                break;
                            }
                        }
                    }
                    position_offset = info[2];
                    in_blas = true;
                    blas_sp = sp;
                    current_group = UVec2::new(info[0], 0x8000_0000);
                    break;
                }
                let (a, b, c) = if object_space {
                    self.object_triangle(prim, position_offset)
                } else {
                    self.world_triangle(prim)
                };
                crate::traversal_stats::triangle_tested();
                if let Some(h) = level.watertight.intersect(a, b, c, 0.0, closest) {
                    closest = h.t;
                    best = Some(Hit {
                        t: h.t,
                        triangle: prim,
                        u: h.u,
                        v: h.v,
                    });
                    if any_hit {
                        return best;
                    }
                }
            }
            primitive_group = UVec2::ZERO;
            if current_group.y & 0xff00_0000 != 0 {
                let hits_imask = current_group.y;
                let child_index_offset = firstbithigh(hits_imask);
                let child_index_base = current_group.x;
                current_group.y &= !(1u32 << child_index_offset);
                if current_group.y & 0xff00_0000 != 0 && sp < TRAVERSAL_STACK_SIZE {
                    // a deeper tree than the stack (degenerate input) loses the group
                    // rather than writing out of bounds, as the ports do
                    stack[sp] = current_group;
                    crate::traversal_stats::stack_accessed();
                    sp += 1;
                }
                let slot_index = (child_index_offset - 24) ^ (level.oct_inv4 & 0xff);
                let relative_index = (hits_imask & !(0xffff_ffffu32 << slot_index)).count_ones();
                let node = self.node(child_index_base + relative_index);
                // `level` is the world ray outside a BLAS (t_scale 1: `closest` exactly)
                level.ray.tmax = closest * level.t_scale;
                crate::traversal_stats::node_visited();
                let hitmask = node_hits(node, &level.ray, level.oct_inv4);
                current_group = UVec2::new(
                    node.child_base_idx,
                    (hitmask & 0xff00_0000) | node.imask as u32,
                );
                primitive_group = UVec2::new(node.primitive_base_idx, hitmask & 0x00ff_ffff);
            } else {
                current_group = UVec2::ZERO;
            }
            if primitive_group.y == 0 && current_group.y & 0xff00_0000 == 0 {
                if in_blas && sp == blas_sp {
                    // the instance is done: back to the world ray and the TLAS
                    in_blas = false;
                    object_space = false;
                    level = world;
                }
                if sp == 0 {
                    break;
                }
                sp -= 1;
                let g = stack[sp];
                crate::traversal_stats::stack_accessed();
                if g.y & 0xff00_0000 != 0 {
                    current_group = g;
                } else {
                    primitive_group = g;
                }
            }
        }
        best
    }

    /// Surface at a hit.
    pub fn surface(&self, hit: &Hit) -> (SurfacePoint, &GpuMaterial) {
        let t = &self.triangles[hit.triangle as usize];
        let v = |k: usize| &self.vertices[t.indices[k] as usize];
        (
            surface_point(v(0), v(1), v(2), hit.u, hit.v),
            &self.materials[t.material as usize],
        )
    }
}
