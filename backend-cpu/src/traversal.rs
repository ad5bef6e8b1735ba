//! Ray queries on the host: obvhs CWBVH traversal (its `traverse!` loop) over core's
//! flattened node array, with core's watertight `intersect_triangle` (its per-ray part `WatertightRay` set up once
//! per ray) as the leaf test (the same
//! function the shader ports mirror). Triangles are in BVH leaf order, so a leaf's
//! primitive index is the triangle.
//!
//! The node test is [`node_hits`], obvhs's `intersect_ray_basic` with one change: a child
//! box is entered when its exit distance is >= 0 (`CWBVH_T_MIN`), where obvhs clamps the
//! entry distance to its `EPSILON = 1e-4` and so culls every box closer than 1e-4 scene
//! units. That lost whole hits in scenes at 1e-4 scale (issue 7, `scale-1e-4`). The
//! OpenCL and WGSL traversals (`cwbvh_node_hits`) make the same test.

use caustica_core::backend::BackendError;
use caustica_core::device::layout::{surface_point, SurfacePoint};
use caustica_core::device::layout::{GpuLight, GpuMaterial, GpuTriangle, GpuVertex};
use caustica_core::math::geometry::WatertightRay;
// `UVec2`: named by obvhs's `traverse!` macro at its call site.
use glam::{UVec2, Vec3, Vec3A};
use obvhs::cwbvh::node::extract_byte64;
use obvhs::cwbvh::{node::CwBvhNode, CwBvh};
use obvhs::ray::Ray;

/// Smallest exit distance of a child box that is entered (scene units): 0, i.e. boxes
/// behind the ray origin are culled, and nothing else (obvhs: 1e-4).
pub const CWBVH_T_MIN: f32 = 0.0;

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
    /// Mesh vertices (world space).
    pub vertices: &'a [GpuVertex],
    /// Triangles in BVH leaf order.
    pub triangles: &'a [GpuTriangle],
    /// Material table.
    pub materials: &'a [GpuMaterial],
    /// Every light of the scene.
    pub lights: &'a [GpuLight],
    /// The CWBVH adopted by `prepare_scene` (its leaves index `triangles` directly).
    pub bvh: &'a CwBvh,
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

/// Builds an obvhs `CwBvh` from the uploaded node array (5 x `[u32; 4]` per node).
pub fn adopt_bvh(nodes: &[[u32; 4]]) -> Result<CwBvh, BackendError> {
    if !nodes.len().is_multiple_of(5) {
        return Err(BackendError::BadArgument(
            "BVH node buffer is not a whole number of 80-byte nodes".into(),
        ));
    }
    let nodes: Vec<CwBvhNode> =
        bytemuck::pod_collect_to_vec(bytemuck::cast_slice::<[u32; 4], u8>(nodes));
    Ok(CwBvh {
        nodes,
        primitive_indices: Vec::new(),
        total_aabb: obvhs::aabb::Aabb::INVALID,
        exact_node_aabbs: None,
        uses_spatial_splits: false,
    })
}

/// The obvhs ray for a traversal. obvhs's `safe_inverse` maps a zero direction component
/// to +-1/EPSILON (8.4e6), which makes its slab test reject boxes for axis-aligned rays far
/// from the node origin (seen: a directional light straight down missed everything); a
/// zero component is replaced by +-1e-30 so its inverse is effectively infinite. Only
/// node culling sees this ray; triangles are tested with the exact direction.
fn traversal_ray(origin: Vec3, dir: Vec3, t_max: f32) -> Ray {
    let fix = |c: f32| if c == 0.0 { 1e-30f32.copysign(c) } else { c };
    Ray::new(
        Vec3A::from(origin),
        Vec3A::new(fix(dir.x), fix(dir.y), fix(dir.z)),
        0.0,
        t_max,
    )
}

impl SceneView<'_> {
    fn tri(&self, i: u32) -> (Vec3, Vec3, Vec3) {
        let t = &self.triangles[i as usize];
        let p = |k: usize| Vec3::from(self.vertices[t.indices[k] as usize].position);
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
    /// ports' `traverse_cwbvh`).
    #[inline(always)]
    fn traverse(&self, origin: Vec3, dir: Vec3, t_max: f32, any_hit: bool) -> Option<Hit> {
        if self.bvh.nodes.is_empty() {
            return None;
        }
        let watertight = WatertightRay::new(origin, dir)?;
        let mut ray = traversal_ray(origin, dir, t_max);
        let mut best: Option<Hit> = None;
        let mut state = self.bvh.new_traversal(ray.direction);
        let mut node;
        obvhs::traverse!(
            self.bvh,
            node,
            state,
            node_hits(node, &ray, state.oct_inv4),
            {
                let prim = state.primitive_id;
                let (a, b, c) = self.tri(prim);
                if let Some(h) = watertight.intersect(a, b, c, 0.0, ray.tmax) {
                    ray.tmax = h.t;
                    best = Some(Hit {
                        t: h.t,
                        triangle: prim,
                        u: h.u,
                        v: h.v,
                    });
                    if any_hit {
                        break;
                    }
                }
            }
        );
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
