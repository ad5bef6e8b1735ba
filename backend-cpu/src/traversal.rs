//! Ray queries on the host: obvhs CWBVH traversal over core's flattened node array, with
//! core's `intersect_triangle` as the leaf test (the same function the shader ports
//! mirror). Triangles are in BVH leaf order, so a leaf's primitive index is the triangle.

use caustica_core::backend::BackendError;
use caustica_core::geometry::{intersect_triangle, surface_point, SurfacePoint};
use caustica_core::gpu::{GpuLight, GpuMaterial, GpuTriangle, GpuVertex};
use glam::{Vec3, Vec3A};
use obvhs::cwbvh::{node::CwBvhNode, CwBvh};
use obvhs::ray::{Ray, RayHit};

/// Borrowed view of a prepared scene.
pub struct SceneView<'a> {
    pub vertices: &'a [GpuVertex],
    pub triangles: &'a [GpuTriangle],
    pub materials: &'a [GpuMaterial],
    pub lights: &'a [GpuLight],
    pub bvh: &'a CwBvh,
}

/// Closest hit: distance, triangle and barycentrics.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
    pub u: f32,
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
        if self.bvh.nodes.is_empty() {
            return None;
        }
        let ray = traversal_ray(origin, dir, t_max);
        let mut hit = RayHit::none();
        let (mut u, mut v) = (0.0, 0.0);
        let found = self.bvh.ray_traverse(ray, &mut hit, |r, prim| {
            let (a, b, c) = self.tri(prim as u32);
            match intersect_triangle(origin, dir, a, b, c, 0.0, r.tmax) {
                Some(h) => {
                    u = h.u;
                    v = h.v;
                    h.t
                }
                None => f32::INFINITY,
            }
        });
        // `u, v` belong to the last accepted (closest) hit: obvhs only lowers tmax.
        found.then_some(Hit {
            t: hit.t,
            triangle: hit.primitive_id,
            u,
            v,
        })
    }

    /// True when something lies on the ray before `t_max`.
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        if self.bvh.nodes.is_empty() {
            return false;
        }
        let ray = traversal_ray(origin, dir, t_max);
        !self.bvh.ray_traverse_miss(ray, |r, prim| {
            let (a, b, c) = self.tri(prim as u32);
            intersect_triangle(origin, dir, a, b, c, 0.0, r.tmax).map_or(f32::INFINITY, |h| h.t)
        })
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
