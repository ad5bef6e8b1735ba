//! A scene flattened into the `Pod` arrays every backend uploads: vertices,
//! triangles, materials, lights and an obvhs compressed wide BVH (CWBVH, 80-byte nodes
//! uploaded as 5 x `[u32; 4]`). Triangles are reordered into BVH leaf order, so the
//! BVH's primitive index *is* the triangle index on every backend.

use crate::device::acceleration::{
    instance_blas_capacity, rebase_blas, tlas_capacity, top_level, Level, RECORD_SLOTS, SLOT_VEC4S,
    TRIANGLE_CORNER_VEC4S,
};
use crate::device::bvh_cache::{build_digest, BvhCache, KeptBuild};
use crate::device::caster_spheres::{placed_ball, CasterSpheres};
use crate::device::layout::{
    light_kind, material_kind, GpuLight, GpuMaterial, GpuTriangle, GpuVertex, PlacementParams,
};
use crate::device::placement::{place_vertices, placed_bounds, placement_params, PositionColumns};
pub use crate::device::placement::{placed_vertices, world_vertices};
use crate::math::geometry::bounding_sphere;
use crate::math::optics::ior_model;
use crate::math::sampling::{one_minus_cos_of_angle, NARROW_CONE};
use crate::scene::limits::{
    is_degenerate, tessellated_size, DEFAULT_MAX_TRIANGLES, MAX_COINCIDENT_TRIANGLES,
};
use crate::scene::{shapes::tessellate, Aabb, IorModel, Light, Material, Scene, Transform};
use glam::{Vec3, Vec3A};
use obvhs::cwbvh::{builder::build_cwbvh_from_tris, node::CwBvhNode};
use obvhs::triangle::Triangle;
use obvhs::BvhBuildParams;
use std::time::Duration;

/// Flattened scene arrays, ready for upload.
#[derive(Clone, Debug)]
pub struct DeviceScene {
    /// Vertices of every tessellated object (world space).
    pub vertices: Vec<GpuVertex>,
    /// Triangles in BVH leaf order (the BVH's primitive index is the triangle index).
    pub triangles: Vec<GpuTriangle>,
    /// Materials in name order (the scene's `BTreeMap`), indexed by `GpuTriangle::material`.
    pub materials: Vec<GpuMaterial>,
    /// Lights in scene order.
    pub lights: Vec<GpuLight>,
    /// CWBVH nodes, each 5 x `[u32; 4]` (80 bytes).
    pub bvh_nodes: Vec<[u32; 4]>,
    /// Bounds of all geometry (world space).
    pub bounds: Aabb,
    /// Bounds of the caustic casters, the mirror and dielectric objects (world space; empty
    /// when there are none).
    pub caster_bounds: Aabb,
    /// Balls around the caustic casters that photons' first segments are tested against
    /// ([`crate::device::caster_spheres`]).
    pub caster_spheres: CasterSpheres,
    /// True when some dielectric disperses (a non-zero Cauchy B, or the Abbe model).
    pub has_dispersion: bool,
    /// Triangles dropped because their area is zero in f32.
    pub degenerate_triangles: u64,
    /// Per triangle (in `triangles`' order): the index of the scene object it came from
    /// (host only: CausticMap's atlas assigns receivers' triangles to tiles with it).
    pub triangle_objects: Vec<u32>,
    /// The acceleration structure's levels and what moving an instance needs (host
    /// only).
    pub instances: SceneInstances,
}

/// The levels of a built scene ([`crate::device::acceleration`]) and the instances'
/// object-space vertices: what a technique keeps to move instances without the rest of
/// the [`DeviceScene`].
#[derive(Clone, Debug, PartialEq)]
pub struct SceneInstances {
    /// Static level first (if any object has no transform), then the instances in object
    /// order.
    pub levels: Vec<Level>,
    /// The instances' vertices in object space, level after level (the device keeps them
    /// too, `SceneArgs::object_vertices`, and places them: `place_vertices`).
    /// (Shared: a technique clones its `SceneInstances` on every move; only a
    /// deformation changes them.)
    pub object_vertices: std::sync::Arc<[GpuVertex]>,
    /// Their positions by coordinate: what a move bounds without placing
    /// ([`crate::device::placement::placed_bounds`]).
    pub columns: std::sync::Arc<PositionColumns>,
    /// vec4 index in the node buffer where the object-space positions start.
    positions_vec4: u32,
}

/// What moving instances changes ([`SceneInstances::move_instances`]).
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceMove {
    /// The moved instances' placements: `place_vertices` makes their world vertices on
    /// the device ([`SceneInstances::placed`] on the host, where one needs them).
    pub placements: Vec<PlacementParams>,
    /// The node buffer's new first vectors (TLAS and records).
    pub top_level: Vec<[u32; 4]>,
    /// The scene's new bounds and caster bounds (world space).
    pub bounds: Aabb,
    /// Its new caster bounds.
    pub caster_bounds: Aabb,
    /// Its new caster balls.
    pub caster_spheres: CasterSpheres,
}

/// What deforming an instance changes ([`SceneInstances::deform_instance`]): what a move
/// changes (its placement, the top level, the bounds), its object-space vertices, and its
/// triangles in the new BLAS's leaf order, its BLAS and its object-space positions.
#[derive(Clone, Debug, PartialEq)]
pub struct InstanceDeform {
    /// The placement, top level and bounds.
    pub moved: InstanceMove,
    /// Its first object vertex and its new object-space vertices (placed after they are
    /// written).
    pub object_vertices: (u32, Vec<GpuVertex>),
    /// The level's first triangle and its triangles in their new order.
    pub triangles: (u32, Vec<GpuTriangle>),
    /// Runs of the node buffer from their first vec4: the new BLAS (at the start of its
    /// region; the rest of the region is not read) and the object-space positions.
    pub nodes: Vec<(u32, Vec<[u32; 4]>)>,
}

/// An update of the instances: moved, or one deformed.
#[derive(Clone, Debug, PartialEq)]
pub enum InstanceUpdate {
    /// Instances moved ([`SceneInstances::move_instances`]).
    Moved(InstanceMove),
    /// An instance deformed ([`SceneInstances::deform_instance`]).
    Deformed(InstanceDeform),
}

impl InstanceUpdate {
    /// What it changes that a move changes too.
    pub fn moved(&self) -> &InstanceMove {
        match self {
            InstanceUpdate::Moved(m) => m,
            InstanceUpdate::Deformed(d) => &d.moved,
        }
    }
}

/// A tessellated mesh's vertices as the device holds them (object space for an
/// instance): normals normalised (`Y` for a zero normal).
pub fn mesh_vertices(m: &crate::scene::TriangleMesh) -> Vec<GpuVertex> {
    (0..m.positions.len())
        .map(|i| GpuVertex {
            position: m.positions[i].to_array(),
            u: m.uvs[i].x,
            normal: m.normals[i].normalize_or(Vec3::Y).to_array(),
            v: m.uvs[i].y,
        })
        .collect()
}

impl SceneInstances {
    /// Whether some level's triangles have smooth normals ([`Level::smooth_normals`]).
    pub fn smooth_normals(&self) -> bool {
        self.levels.iter().any(Level::smooth_normals)
    }

    /// The first object vertex of instance level `l` in [`SceneInstances::object_vertices`].
    fn object_first(&self, l: &Level) -> u32 {
        l.position_base - self.positions_vec4
    }

    /// `place_vertices`' parameters for every instance at its transform, in level order.
    pub fn placements(&self) -> Vec<PlacementParams> {
        self.levels
            .iter()
            .filter(|l| l.object.is_some())
            .map(|l| {
                placement_params(
                    &l.transform,
                    self.object_first(l),
                    l.vertex_base,
                    l.vertex_count,
                )
            })
            .collect()
    }

    /// The world vertices placement `p` makes ([`place_vertices`], `place_vertices`'
    /// definition), on the host: for the host's copy of a scene and for what the host
    /// follows (receivers of the atlas). Empty where `p` lies outside the object vertices.
    pub fn placed(&self, p: &PlacementParams) -> Vec<GpuVertex> {
        let first = p.object_first as usize;
        self.object_vertices
            .get(first..first + p.count as usize)
            .map_or_else(Vec::new, |local| place_vertices(p, local))
    }

    /// Moves instances (`(object index, transform)` pairs; the objects must have been
    /// built with a transform): their placements (the device places their world
    /// vertices), boxes, the scene's bounds, the TLAS and the records are recomputed with
    /// the functions the build uses, so the result equals a fresh build of the moved scene
    /// bitwise. No BLAS changes. On an error nothing changes.
    pub fn move_instances(
        &mut self,
        moves: &[(usize, Transform)],
    ) -> Result<InstanceMove, BuildError> {
        let mut levels = self.levels.clone();
        let mut moved = vec![false; levels.len()];
        for (object, transform) in moves {
            let path = format!("objects[{object}].transform");
            if let Some(reason) = transform.problem() {
                return Err(BuildError::Scene { path, reason });
            }
            let Some(k) = levels.iter().position(|l| l.object == Some(*object)) else {
                return Err(BuildError::Scene {
                    path,
                    reason: "the object has no transform in the scene it was built from, so it \
                             is part of the static level; give it one (identity will do) to \
                             move it"
                        .into(),
                });
            };
            let l = &mut levels[k];
            let mirrors = |t: &Transform| t.world_from_object().matrix3.determinant() < 0.0;
            if mirrors(&l.transform) != mirrors(transform) {
                return Err(BuildError::Scene {
                    path,
                    reason: "the new transform mirrors the object where the old one did not \
                             (or the reverse): its triangles' winding would change; build \
                             the scene anew"
                        .into(),
                });
            }
            l.transform = *transform;
            moved[k] = true;
        }
        let mut placements = Vec::new();
        for (l, _) in levels.iter_mut().zip(&moved).filter(|(_, m)| **m) {
            // the boxes alone: the device places the vertices (place_vertices)
            let first = self.object_first(l);
            let run = first as usize..(first + l.vertex_count) as usize;
            let (b, used) = placed_bounds(&l.transform, &self.columns, run, &l.unused_vertices);
            check_placed(l.object.unwrap_or(0), &b)?;
            l.caster_bounds = if l.caster_bounds.is_empty() {
                Aabb::EMPTY
            } else {
                b
            };
            l.world_bounds = b;
            l.caster_balls = placed_balls(l);
            l.triangle_bounds = used;
            placements.push(placement_params(
                &l.transform,
                first,
                l.vertex_base,
                l.vertex_count,
            ));
        }
        let top_level = top_level(&levels).map_err(|reason| BuildError::Scene {
            path: "objects".into(),
            reason,
        })?;
        let (bounds, caster_bounds) = level_bounds(&levels);
        let caster_spheres = level_caster_spheres(&levels);
        self.levels = levels;
        Ok(InstanceMove {
            placements,
            top_level,
            bounds,
            caster_bounds,
            caster_spheres,
        })
    }
}

impl SceneInstances {
    /// Deforms instance `object` (an object built with a transform): `local` are its new
    /// object-space vertices ([`mesh_vertices`] of its new shape: the same count, the same
    /// triangles). Its BLAS is rebuilt (the one BVH build: no other level's) into its
    /// reserved region, its triangles reordered as the new BLAS has them, its placement
    /// and boxes, the scene's bounds and the top level recomputed with the
    /// functions the build uses, so the result equals a fresh build of the deformed scene
    /// (the records' `geometry_version` aside). On an error nothing changes.
    pub fn deform_instance(
        &mut self,
        object: usize,
        local: Vec<GpuVertex>,
    ) -> Result<InstanceDeform, BuildError> {
        let path = format!("objects[{object}].shape");
        let bad = |reason: String| BuildError::Scene {
            path: path.clone(),
            reason,
        };
        let Some(k) = self.levels.iter().position(|l| l.object == Some(object)) else {
            return Err(bad(
                "the object has no transform in the scene it was built from, so it is part of \
                 the static level, whose BVH a deformation would rebuild; give it one \
                 (identity will do) to deform it"
                    .into(),
            ));
        };
        let mut levels = self.levels.clone();
        let l = &mut levels[k];
        if local.len() != l.vertex_count as usize {
            return Err(bad(format!(
                "{} vertices for an object of {}: a deformation keeps the mesh's vertices \
                 and triangles",
                local.len(),
                l.vertex_count
            )));
        }
        let (b, used_box) = placed_bounds(
            &l.transform,
            &PositionColumns::of(&local),
            0..local.len(),
            &l.unused_vertices,
        );
        check_placed(object, &b)?;
        let base = l.vertex_base;
        let tris: Vec<GpuTriangle> = l
            .triangle_indices
            .iter()
            .map(|&indices| GpuTriangle {
                indices,
                material: l.material,
            })
            .collect();
        let object_position = |i: u32| Vec3A::from(local[(i - base) as usize].position);
        let (ordered, mut nodes, _) =
            build_bvh(&object_position, tris, None, LevelBuild::Instance)?;
        let used = (nodes.len() / SLOT_VEC4S) as u32;
        if used > l.blas_capacity {
            return Err(bad(format!(
                "the deformed BLAS has {used} nodes, over the {} its region holds",
                l.blas_capacity
            )));
        }
        rebase_blas(&mut nodes, l.blas_root, l.triangle_base);
        let positions: Vec<[u32; 4]> = local.iter().map(|v| position_vec4(v.position)).collect();
        let corners = triangle_corners(&ordered, |i| local[(i - base) as usize].position);
        l.caster_bounds = if l.caster_bounds.is_empty() {
            Aabb::EMPTY
        } else {
            b
        };
        l.world_bounds = b;
        if l.object_ball.is_some() {
            l.object_ball = bounding_sphere(&vertex_positions(&local));
        }
        l.caster_balls = placed_balls(l);
        l.triangle_bounds = used_box;
        let run = |i: u32| local[(i - base) as usize];
        l.normal_departure = normal_departure(l.triangle_indices.iter().copied(), &run);
        l.geometry_version = l.geometry_version.wrapping_add(1);
        let (blas_root, triangle_base, position_base, corners_at) = (
            l.blas_root,
            l.triangle_base,
            l.position_base,
            l.triangle_corners + TRIANGLE_CORNER_VEC4S as u32 * l.triangle_base,
        );
        let top_level = top_level(&levels).map_err(|reason| BuildError::Scene {
            path: "objects".into(),
            reason,
        })?;
        let (bounds, caster_bounds) = level_bounds(&levels);
        let caster_spheres = level_caster_spheres(&levels);
        let first = (position_base - self.positions_vec4) as usize;
        let mut object_vertices = self.object_vertices.to_vec();
        object_vertices[first..first + local.len()].copy_from_slice(&local);
        let mut columns = (*self.columns).clone();
        columns.set(first, &local);
        let placement =
            placement_params(&levels[k].transform, first as u32, base, local.len() as u32);
        self.levels = levels;
        self.object_vertices = object_vertices.into();
        self.columns = columns.into();
        Ok(InstanceDeform {
            object_vertices: (first as u32, local),
            moved: InstanceMove {
                placements: vec![placement],
                top_level,
                bounds,
                caster_bounds,
                caster_spheres,
            },
            triangles: (triangle_base, ordered),
            nodes: vec![
                (blas_root * SLOT_VEC4S as u32, nodes),
                (position_base, positions),
                (corners_at, corners),
            ],
        })
    }
}

/// A vertex normal departs from its triangle's geometric normal where the two (unit)
/// differ by more than this on some axis, on either side ([`normal_departure`]).
pub const NORMAL_DEPARTURE: f32 = 1e-4;

/// The largest difference, per axis, between a vertex normal and its triangle's geometric
/// normal, on the nearer side (`n - ng` or `n + ng`), over `triangles`: 0 where every
/// vertex normal lies along its face's normal.
pub fn normal_departure(
    triangles: impl Iterator<Item = [u32; 3]>,
    vertex: &dyn VertexLookup,
) -> f32 {
    triangles.fold(0.0f32, |most, t| {
        let v = t.map(|i| vertex.vertex(i));
        let p = v.map(|v| Vec3::from(v.position));
        let ng = (p[1] - p[0]).cross(p[2] - p[0]).normalize_or_zero();
        v.iter().fold(most, |most, v| {
            let n = Vec3::from(v.normal).normalize_or_zero();
            let d = (n - ng)
                .abs()
                .max_element()
                .min((n + ng).abs().max_element());
            most.max(d)
        })
    })
}

/// The box of the vertices `used` (world-vertex indices); `vertices[i - base]` is vertex
/// `i` (all world vertices with `base` 0, or one instance's run from its first index).
fn triangle_bounds(used: &[u32], vertices: &[GpuVertex], base: u32) -> Aabb {
    let mut b = Aabb::EMPTY;
    for &i in used {
        b.grow(Vec3::from(vertices[(i - base) as usize].position));
    }
    b
}

/// The vertices `triangles` use, each once, ascending.
fn used_vertices(triangles: &[[u32; 3]]) -> Vec<u32> {
    let mut v: Vec<u32> = triangles.iter().flatten().copied().collect();
    v.sort_unstable();
    v.dedup();
    v
}

/// The vertices of an instance (`count` from world vertex `base`) that `used` (world-vertex
/// indices, ascending) leaves out, as indices from `base`, ascending.
fn unused_vertices(used: &[u32], base: u32, count: usize) -> Vec<u32> {
    let mut used = used.iter().map(|&i| (i - base) as usize).peekable();
    (0..count)
        .filter(|&i| {
            let is_used = used.peek() == Some(&i);
            if is_used {
                used.next();
            }
            !is_used
        })
        .map(|i| i as u32)
        .collect()
}

/// A world vertex by index (a slice of all, or one instance's run).
pub trait VertexLookup {
    /// Vertex `i`.
    fn vertex(&self, i: u32) -> GpuVertex;
}

impl VertexLookup for Vec<GpuVertex> {
    fn vertex(&self, i: u32) -> GpuVertex {
        self[i as usize]
    }
}

impl<F: Fn(u32) -> GpuVertex> VertexLookup for F {
    fn vertex(&self, i: u32) -> GpuVertex {
        self(i)
    }
}

/// The scene's bounds and caster bounds: unions of the levels' (min and max are exact, so
/// the union in any order equals growing a box vertex by vertex).
fn level_bounds(levels: &[Level]) -> (Aabb, Aabb) {
    levels.iter().fold((Aabb::EMPTY, Aabb::EMPTY), |(b, c), l| {
        (b.union(l.world_bounds), c.union(l.caster_bounds))
    })
}

/// A position as a node-buffer vec4: `(x, y, z, 1)` as f32 bits.
fn position_vec4([x, y, z]: [f32; 3]) -> [u32; 4] {
    [x.to_bits(), y.to_bits(), z.to_bits(), 1f32.to_bits()]
}

/// The corner vec4s of `tris` ([`TRIANGLE_CORNER_VEC4S`] each), `position(i)` the
/// position of vertex index `i` in the level's space.
fn triangle_corners(tris: &[GpuTriangle], position: impl Fn(u32) -> [f32; 3]) -> Vec<[u32; 4]> {
    tris.iter()
        .flat_map(|t| t.indices.map(|i| position_vec4(position(i))))
        .collect()
}

/// The levels' caster balls, merged to what `trace_photons` reads.
fn level_caster_spheres(levels: &[Level]) -> CasterSpheres {
    CasterSpheres::from_balls(
        levels
            .iter()
            .flat_map(|l| l.caster_balls.iter().copied())
            .collect(),
    )
}

/// An instance's world caster ball at its current transform (none when it is no caster).
fn placed_balls(l: &Level) -> Vec<[f32; 4]> {
    l.object_ball
        .map(|b| placed_ball(&l.transform, b))
        .into_iter()
        .collect()
}

/// The positions of `vertices`.
fn vertex_positions(vertices: &[GpuVertex]) -> Vec<Vec3> {
    vertices.iter().map(|v| Vec3::from(v.position)).collect()
}

/// An instance must stay inside the coordinate bound once transformed.
fn check_placed(object: usize, b: &Aabb) -> Result<(), BuildError> {
    let reach = b.min.abs().max(b.max.abs()).max_element();
    if !(reach <= crate::scene::limits::MAX_COORDINATE) {
        return Err(BuildError::Scene {
            path: format!("objects[{object}].transform"),
            reason: format!(
                "the transformed object reaches {reach:e} from the origin, beyond the \
                 coordinate bound {:e}",
                crate::scene::limits::MAX_COORDINATE
            ),
        });
    }
    Ok(())
}

/// `[u32; 4]` vectors per CWBVH node in `bvh_nodes` (80 bytes).
pub const BVH_NODE_VEC4S: usize = 5;

/// Why a scene could not be flattened: a problem of the scene (named by its field path)
/// or host memory that could not be reserved.
#[derive(Clone, Debug, thiserror::Error)]
pub enum BuildError {
    /// The scene is unusable as given (`path` names the field, as validation does).
    #[error("{path}: {reason}")]
    Scene {
        /// Field path, e.g. `objects[2].shape`.
        path: String,
        /// What is wrong.
        reason: String,
    },
    /// A host allocation failed (`try_reserve`).
    #[error("out of host memory allocating {bytes} bytes for {what}")]
    HostMemory {
        /// Size requested (bytes).
        bytes: u64,
        /// What the memory was for.
        what: String,
    },
}

/// Budgets of a scene build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BuildBudget {
    /// Most triangles the tessellated scene may have (default
    /// [`DEFAULT_MAX_TRIANGLES`]).
    pub max_triangles: u64,
}

impl Default for BuildBudget {
    fn default() -> Self {
        BuildBudget {
            max_triangles: DEFAULT_MAX_TRIANGLES,
        }
    }
}

impl DeviceScene {
    /// Tessellates, flattens and builds the BVH. The scene must have passed
    /// [`Scene::validate`]. Before anything is allocated, the triangle count (computed
    /// from the shapes) is checked against `budget`; triangles of zero area in f32 are
    /// dropped (counted in [`DeviceScene::degenerate_triangles`]); an object left with
    /// no triangle, or more than [`MAX_COINCIDENT_TRIANGLES`] triangles with one bounding
    /// box, is an error.
    pub fn build(scene: &Scene, budget: BuildBudget) -> Result<DeviceScene, BuildError> {
        Self::build_cached(scene, budget, &mut BvhCache::default())
    }

    /// [`DeviceScene::build`], with each level's BVH taken from `cache` where its input
    /// (its triangles' positions in its space) is one `cache` kept, built and kept
    /// otherwise; afterwards `cache` keeps this build's levels alone. The result equals
    /// [`DeviceScene::build`]'s bitwise: a build of the same input is the same BVH.
    pub fn build_cached(
        scene: &Scene,
        budget: BuildBudget,
        cache: &mut BvhCache,
    ) -> Result<DeviceScene, BuildError> {
        cache.begin_build();
        let names: Vec<&String> = scene.materials.keys().collect();
        let materials = scene.materials.values().map(gpu_material).collect();
        let (mut vertex_total, mut triangle_total) = (0u64, 0u64);
        for o in &scene.objects {
            let (v, t) = tessellated_size(&o.shape);
            vertex_total += v;
            triangle_total += t;
        }
        if triangle_total > budget.max_triangles {
            return Err(BuildError::Scene {
                path: "objects".into(),
                reason: format!(
                    "the scene tessellates to {triangle_total} triangles, over the budget of \
                     {} (setting max_triangles; about 200 bytes of host memory each)",
                    budget.max_triangles
                ),
            });
        }
        if vertex_total > u32::MAX as u64 {
            return Err(BuildError::Scene {
                path: "objects".into(),
                reason: format!("{vertex_total} vertices; at most 2^32 - 1 can be indexed"),
            });
        }
        let mut vertices: Vec<GpuVertex> = Vec::new();
        let mut static_tris: Vec<GpuTriangle> = Vec::new();
        reserve(&mut vertices, vertex_total, "scene vertices")?;
        reserve(&mut static_tris, triangle_total, "scene triangles")?;
        let mut degenerate_triangles = 0u64;
        let mut static_objects: Vec<u32> = Vec::new();
        reserve(&mut static_objects, triangle_total, "triangle objects")?;
        let mut static_level = Level {
            object: None,
            transform: Transform::IDENTITY,
            blas_root: 0,
            blas_capacity: 0,
            material: 0,
            geometry_version: 0,
            triangle_corners: 0,
            triangle_base: 0,
            triangle_count: 0,
            vertex_base: 0,
            vertex_count: 0,
            position_base: 0,
            world_bounds: Aabb::EMPTY,
            caster_bounds: Aabb::EMPTY,
            normal_departure: 0.0,
            triangle_indices: std::sync::Arc::from(Vec::new()),
            used_vertices: std::sync::Arc::from(Vec::new()),
            unused_vertices: std::sync::Arc::from(Vec::new()),
            triangle_bounds: Aabb::EMPTY,
            caster_balls: Vec::new(),
            object_ball: None,
        };
        // instances: (level, triangles, object-space vertices)
        let mut instances: Vec<(Level, Vec<GpuTriangle>)> = Vec::new();
        let mut object_vertices: Vec<GpuVertex> = Vec::new();
        for (k, o) in scene.objects.iter().enumerate() {
            let mat = names.iter().position(|n| **n == o.material).unwrap_or(0) as u32;
            let specular = scene.materials[&o.material].is_specular();
            let m = tessellate(&o.shape);
            let base = vertices.len() as u32;
            // a mirroring transform reverses the winding: swap two corners so that world
            // winding keeps agreeing with the (transformed) normals
            let mirrored = o
                .transform
                .is_some_and(|t| t.world_from_object().matrix3.determinant() < 0.0);
            let mut tris: Vec<GpuTriangle> = Vec::new();
            for t in &m.indices {
                if is_degenerate(&m, *t) {
                    degenerate_triangles += 1;
                } else {
                    let mut indices = t.map(|i| i + base);
                    if mirrored {
                        indices.swap(1, 2);
                    }
                    tris.push(GpuTriangle {
                        indices,
                        material: mat,
                    });
                }
            }
            if tris.is_empty() {
                return Err(BuildError::Scene {
                    path: format!("objects[{k}].shape"),
                    reason: format!(
                        "{} zero area in f32 (the shape collapses to a point or a line)",
                        match m.indices.len() {
                            1 => "its one triangle has".to_string(),
                            n => format!("all {n} triangles have"),
                        }
                    ),
                });
            }
            let local = mesh_vertices(&m);
            let mut world_bounds = Aabb::EMPTY;
            match o.transform {
                None => {
                    for v in &local {
                        world_bounds.grow(Vec3::from(v.position));
                    }
                    vertices.extend_from_slice(&local);
                    static_objects.extend(std::iter::repeat_n(k as u32, tris.len()));
                    static_tris.extend(tris);
                    static_level.world_bounds = static_level.world_bounds.union(world_bounds);
                    if specular {
                        static_level.caster_bounds = static_level.caster_bounds.union(world_bounds);
                        static_level
                            .caster_balls
                            .extend(bounding_sphere(&vertex_positions(&local)));
                    }
                    static_level.vertex_count = vertices.len() as u32;
                }
                Some(transform) => {
                    let (world, b) = world_vertices(&transform, &local);
                    world_bounds = b;
                    check_placed(k, &world_bounds)?;
                    vertices.extend_from_slice(&world);
                    let object_ball = if specular {
                        bounding_sphere(&vertex_positions(&local))
                    } else {
                        None
                    };
                    let used = used_vertices(&tris.iter().map(|t| t.indices).collect::<Vec<_>>());
                    let level = Level {
                        object: Some(k),
                        transform,
                        blas_root: 0,
                        blas_capacity: 0,
                        material: mat,
                        geometry_version: 0,
                        triangle_corners: 0,
                        triangle_base: 0,
                        triangle_count: tris.len() as u32,
                        vertex_base: base,
                        vertex_count: local.len() as u32,
                        position_base: object_vertices.len() as u32,
                        world_bounds,
                        caster_bounds: if specular { world_bounds } else { Aabb::EMPTY },
                        normal_departure: 0.0,
                        triangle_indices: tris.iter().map(|t| t.indices).collect(),
                        used_vertices: used.clone().into(),
                        unused_vertices: unused_vertices(&used, base, local.len()).into(),
                        triangle_bounds: Aabb::EMPTY,
                        caster_balls: object_ball
                            .map(|b| placed_ball(&transform, b))
                            .into_iter()
                            .collect(),
                        object_ball,
                    };
                    object_vertices.extend_from_slice(&local);
                    instances.push((level, tris));
                }
            }
        }
        let all: Vec<GpuTriangle> = static_tris
            .iter()
            .chain(instances.iter().flat_map(|(_, t)| t.iter()))
            .copied()
            .collect();
        check_coincident(scene, &vertices, &all)?;
        drop(all);
        let has_dispersion = scene.materials.values().any(Material::is_dispersive);
        let lights = scene.lights.iter().map(gpu_light).collect();

        // the levels' BLASes, static level first, then the instances in object order
        let world_positions = |i: u32| Vec3A::from(vertices[i as usize].position);
        let mut blases: Vec<(Level, BvhBuild, Vec<u32>)> = Vec::new();
        if !static_tris.is_empty() {
            static_level.triangle_count = static_tris.len() as u32;
            let build = build_bvh(
                &world_positions,
                static_tris,
                Some(&mut *cache),
                LevelBuild::Static,
            )?;
            blases.push((static_level, build, static_objects));
        }
        for (level, tris) in instances {
            let (base, first) = (level.vertex_base, level.position_base);
            let object_position =
                |i: u32| Vec3A::from(object_vertices[(i - base + first) as usize].position);
            let build = build_bvh(
                &object_position,
                tris,
                Some(&mut *cache),
                LevelBuild::Instance,
            )?;
            let k = level.object.unwrap_or(0) as u32;
            let objects = vec![k; build.0.len()];
            blases.push((level, build, objects));
        }
        let capacity = tlas_capacity(blases.len());
        let mut slot = capacity + RECORD_SLOTS * blases.len() as u32;
        let top_vec4s = slot as usize * SLOT_VEC4S;
        let mut triangle_base = 0u32;
        let mut triangles: Vec<GpuTriangle> = Vec::new();
        reserve(&mut triangles, triangle_total, "BVH-ordered triangles")?;
        let mut triangle_objects: Vec<u32> = Vec::new();
        reserve(&mut triangle_objects, triangle_total, "triangle objects")?;
        let mut blas_nodes: Vec<[u32; 4]> = Vec::new();
        let mut levels: Vec<Level> = Vec::new();
        for (mut level, (ordered, mut nodes, order), objects) in blases {
            rebase_blas(&mut nodes, slot, triangle_base);
            level.blas_root = slot;
            level.triangle_base = triangle_base;
            let used = (nodes.len() / SLOT_VEC4S) as u32;
            level.blas_capacity = if level.object.is_some() {
                instance_blas_capacity(level.triangle_count).max(used)
            } else {
                used
            };
            // object-space positions follow the BLASes (their vec4 index set below)
            slot += level.blas_capacity;
            triangle_base += ordered.len() as u32;
            triangle_objects.extend(order.iter().map(|&i| objects[i as usize]));
            triangles.extend(ordered);
            blas_nodes.extend(nodes);
            blas_nodes.resize(slot as usize * SLOT_VEC4S - top_vec4s, [0; 4]);
            levels.push(level);
        }
        for l in &mut levels {
            let range = l.triangle_base as usize..(l.triangle_base + l.triangle_count) as usize;
            let corners = triangles[range].iter().map(|t| t.indices);
            // an instance's in object space, which a move keeps (`Level::smooth_normals`
            // bounds what its transform makes of it)
            l.normal_departure = match l.object {
                None => normal_departure(corners, &vertices),
                Some(_) => {
                    let (base, first) = (l.vertex_base, l.position_base);
                    let local = |i: u32| object_vertices[(i - base + first) as usize];
                    normal_departure(corners, &local)
                }
            };
            l.triangle_bounds = triangle_bounds(&l.used_vertices, &vertices, 0);
        }
        let positions_vec4 = slot as usize * SLOT_VEC4S;
        let corners_vec4 = positions_vec4 + object_vertices.len();
        let total_vec4 =
            (corners_vec4 + TRIANGLE_CORNER_VEC4S * triangles.len()).next_multiple_of(SLOT_VEC4S);
        if total_vec4 > u32::MAX as usize {
            return Err(BuildError::Scene {
                path: "objects".into(),
                reason: format!(
                    "the node buffer would hold {total_vec4} vectors, over the 2^32 its u32 \
                     indices address: fewer triangles"
                ),
            });
        }
        for l in levels.iter_mut() {
            if l.object.is_some() {
                l.position_base += positions_vec4 as u32;
            }
            l.triangle_corners = corners_vec4 as u32;
        }
        let top = top_level(&levels).map_err(|reason| BuildError::Scene {
            path: "objects".into(),
            reason,
        })?;
        let mut bvh_nodes: Vec<[u32; 4]> = Vec::new();
        reserve(&mut bvh_nodes, total_vec4 as u64, "BVH nodes")?;
        bvh_nodes.extend(top);
        bvh_nodes.extend(blas_nodes);
        debug_assert_eq!(bvh_nodes.len(), positions_vec4);
        bvh_nodes.extend(object_vertices.iter().map(|v| position_vec4(v.position)));
        for l in &levels {
            let tris =
                &triangles[l.triangle_base as usize..(l.triangle_base + l.triangle_count) as usize];
            match l.object {
                None => bvh_nodes.extend(triangle_corners(tris, |i| vertices[i as usize].position)),
                Some(_) => {
                    let first = l.position_base as usize - positions_vec4;
                    let base = l.vertex_base;
                    bvh_nodes.extend(triangle_corners(tris, |i| {
                        object_vertices[first + (i - base) as usize].position
                    }))
                }
            }
        }
        bvh_nodes.resize(total_vec4, [0; 4]);
        let (bounds, caster_bounds) = level_bounds(&levels);
        cache.finish_build();
        Ok(DeviceScene {
            vertices,
            triangles,
            materials,
            lights,
            bvh_nodes,
            bounds,
            caster_bounds,
            caster_spheres: level_caster_spheres(&levels),
            has_dispersion,
            degenerate_triangles,
            triangle_objects,
            instances: SceneInstances {
                levels,
                columns: PositionColumns::of(&object_vertices).into(),
                object_vertices: object_vertices.into(),
                positions_vec4: positions_vec4 as u32,
            },
        })
    }

    /// Moves instances ([`SceneInstances::move_instances`]) and applies the move to these
    /// arrays: the result equals a fresh build of the moved scene.
    pub fn move_instances(&mut self, moves: &[(usize, Transform)]) -> Result<(), BuildError> {
        let m = self.instances.move_instances(moves)?;
        self.place(&m.placements);
        self.bvh_nodes[..m.top_level.len()].copy_from_slice(&m.top_level);
        self.bounds = m.bounds;
        self.caster_bounds = m.caster_bounds;
        self.caster_spheres = m.caster_spheres;
        Ok(())
    }

    /// Deforms an instance ([`SceneInstances::deform_instance`]) and applies it to these
    /// arrays: the result equals a fresh build of the deformed scene (the records'
    /// `geometry_version` aside).
    pub fn deform_instance(
        &mut self,
        object: usize,
        local: Vec<GpuVertex>,
    ) -> Result<(), BuildError> {
        let k = self
            .instances
            .levels
            .iter()
            .position(|l| l.object == Some(object));
        let d = self.instances.deform_instance(object, local)?;
        if let Some(l) = k.map(|k| &self.instances.levels[k]) {
            // the region as a fresh build leaves it: zero past the BLAS
            let region = l.blas_root as usize * SLOT_VEC4S
                ..(l.blas_root + l.blas_capacity) as usize * SLOT_VEC4S;
            self.bvh_nodes[region].fill([0; 4]);
        }
        self.place(&d.moved.placements);
        let (first, t) = &d.triangles;
        self.triangles[*first as usize..*first as usize + t.len()].copy_from_slice(t);
        for (first, n) in &d.nodes {
            self.bvh_nodes[*first as usize..*first as usize + n.len()].copy_from_slice(n);
        }
        let top = &d.moved.top_level;
        self.bvh_nodes[..top.len()].copy_from_slice(top);
        self.bounds = d.moved.bounds;
        self.caster_bounds = d.moved.caster_bounds;
        self.caster_spheres = d.moved.caster_spheres;
        Ok(())
    }

    /// Writes the world vertices of `placements` (the host's placement).
    fn place(&mut self, placements: &[PlacementParams]) {
        for p in placements {
            let world = self.instances.placed(p);
            let first = p.world_first as usize;
            self.vertices[first..first + world.len()].copy_from_slice(&world);
        }
    }

    /// Number of CWBVH nodes.
    pub fn bvh_node_count(&self) -> usize {
        self.bvh_nodes.len() / BVH_NODE_VEC4S
    }
}

/// Reserves room for `n` more elements, or says how much memory was missing.
fn reserve<T>(v: &mut Vec<T>, n: u64, what: &str) -> Result<(), BuildError> {
    let bytes = n.saturating_mul(std::mem::size_of::<T>() as u64);
    usize::try_from(n)
        .ok()
        .and_then(|n| v.try_reserve_exact(n).ok())
        .ok_or_else(|| BuildError::HostMemory {
            bytes,
            what: what.into(),
        })
}

/// Refuses more than [`MAX_COINCIDENT_TRIANGLES`] triangles with one bounding box (the
/// BVH build is quadratic in them). Boxes are compared through a 64-bit hash of their
/// six coordinates' bits, sorted; a hash collision could only make the check stricter.
fn check_coincident(
    scene: &Scene,
    vertices: &[GpuVertex],
    tris: &[GpuTriangle],
) -> Result<(), BuildError> {
    let mut keys: Vec<(u64, u32)> = Vec::new();
    reserve(&mut keys, tris.len() as u64, "coincident-triangle check")?;
    for (i, t) in tris.iter().enumerate() {
        let mut b = Aabb::EMPTY;
        for v in t.indices {
            b.grow(Vec3::from(vertices[v as usize].position));
        }
        let mut h = 0xcbf2_9ce4_8422_2325u64; // FNV-1a over the bits
        for x in b.min.to_array().into_iter().chain(b.max.to_array()) {
            h = (h ^ x.to_bits() as u64).wrapping_mul(0x0100_0000_01b3);
        }
        keys.push((h, i as u32));
    }
    keys.sort_unstable();
    let mut run = 1u32;
    for w in keys.windows(2) {
        run = if w[0].0 == w[1].0 { run + 1 } else { 1 };
        if run > MAX_COINCIDENT_TRIANGLES {
            // name the object owning the triangle (objects are contiguous, in order)
            let first = tris[w[1].1 as usize].indices[0] as u64;
            let mut end = 0u64;
            let mut object = 0;
            for (k, o) in scene.objects.iter().enumerate() {
                end += tessellated_size(&o.shape).0;
                if first < end {
                    object = k;
                    break;
                }
            }
            return Err(BuildError::Scene {
                path: format!("objects[{object}].shape"),
                reason: format!(
                    "more than {MAX_COINCIDENT_TRIANGLES} triangles share one bounding box \
                     (coincident geometry); the BVH build degrades quadratically on it"
                ),
            });
        }
    }
    Ok(())
}

/// The triangles in leaf order, the CWBVH nodes, and for each ordered triangle its index
/// in the input.
type BvhBuild = (Vec<GpuTriangle>, Vec<[u32; 4]>, Vec<u32>);

/// How a level's BVH is built: the static level once, when the scene is built, so with
/// more search for fewer node visits; an instance's as its deformation rebuilds it, every
/// frame it deforms (a build and a rebuild of one level must be the same build).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LevelBuild {
    /// The static level: [`STATIC_LEVEL_BUILD`].
    Static = 0,
    /// An instance: obvhs's `medium_build`.
    Instance = 1,
}

/// The static level's build: obvhs's `medium_build` with PLOC searching 24 nodes on each
/// side from its second pass on (`search_depth_threshold` 1), 128-bit sort keys, and
/// reinsertion over half the nodes (batch ratio 0.5). 2.8-3.9x the build time (obvhs
/// alone) for 1.6-9.2% fewer warp-steps on the built-in scenes, counted on the CPU
/// (feature `traversal-stats`; docs/performance.md, "What the kernels do for speed").
pub const STATIC_LEVEL_BUILD: BvhBuildParams = BvhBuildParams {
    ploc_search_distance: obvhs::ploc::PlocSearchDistance::High,
    search_depth_threshold: 1,
    reinsertion_batch_ratio: 0.5,
    sort_precision: obvhs::ploc::SortPrecision::U128,
    ..BvhBuildParams::medium_build()
};

impl LevelBuild {
    fn params(self) -> BvhBuildParams {
        match self {
            LevelBuild::Static => STATIC_LEVEL_BUILD,
            LevelBuild::Instance => BvhBuildParams::medium_build(),
        }
    }
}

fn build_bvh(
    p: &dyn Fn(u32) -> Vec3A,
    tris: Vec<GpuTriangle>,
    cache: Option<&mut BvhCache>,
    build: LevelBuild,
) -> Result<BvhBuild, BuildError> {
    let corners = |t: &GpuTriangle| t.indices.map(p);
    let kept = match cache {
        Some(c) => c.get_or_build(build_digest(build as u64, tris.iter().map(corners)), || {
            fresh_bvh(&tris, &corners, build)
        })?,
        None => std::sync::Arc::new(fresh_bvh(&tris, &corners, build)?),
    };
    // Reorder triangles into leaf order; leaf slots then index triangles directly.
    let mut ordered: Vec<GpuTriangle> = Vec::new();
    reserve(&mut ordered, tris.len() as u64, "BVH-ordered triangles")?;
    ordered.extend(kept.order.iter().map(|&i| tris[i as usize]));
    let mut out: Vec<[u32; 4]> = Vec::new();
    reserve(&mut out, kept.nodes.len() as u64, "BVH nodes")?;
    out.extend_from_slice(&kept.nodes);
    Ok((ordered, out, kept.order.clone()))
}

/// The CWBVH of `tris` (corners by `corners`) and its leaf order.
fn fresh_bvh(
    tris: &[GpuTriangle],
    corners: &dyn Fn(&GpuTriangle) -> [Vec3A; 3],
    build: LevelBuild,
) -> Result<KeptBuild, BuildError> {
    let mut obvhs_tris: Vec<Triangle> = Vec::new();
    reserve(&mut obvhs_tris, tris.len() as u64, "BVH build triangles")?;
    obvhs_tris.extend(tris.iter().map(|t| {
        let [v0, v1, v2] = corners(t);
        Triangle { v0, v1, v2 }
    }));
    let mut build_time = Duration::ZERO;
    let bvh = build_cwbvh_from_tris(&obvhs_tris, build.params(), &mut build_time);
    drop(obvhs_tris);
    let nodes: &[[u32; 4]] = bytemuck::cast_slice::<CwBvhNode, [u32; 4]>(&bvh.nodes);
    let mut out: Vec<[u32; 4]> = Vec::new();
    reserve(&mut out, nodes.len() as u64, "BVH nodes")?;
    out.extend_from_slice(nodes);
    Ok(KeptBuild {
        nodes: out,
        order: bvh.primitive_indices,
    })
}

/// A material as the kernels read it.
pub fn gpu_material(m: &Material) -> GpuMaterial {
    match m {
        Material::Diffuse { albedo } => GpuMaterial {
            kind: material_kind::DIFFUSE,
            color: albedo.extend(0.0).to_array(),
            ..Default::default()
        },
        Material::Mirror { reflectance } => GpuMaterial {
            kind: material_kind::MIRROR,
            color: reflectance.extend(0.0).to_array(),
            ..Default::default()
        },
        Material::Dielectric {
            ior,
            cauchy_b,
            absorption,
            ior_model,
        } => {
            let (dispersion, model) = match ior_model {
                IorModel::Cauchy => (*cauchy_b, ior_model::CAUCHY),
                IorModel::Abbe { abbe_number } => (*abbe_number, ior_model::ABBE),
            };
            GpuMaterial {
                kind: material_kind::DIELECTRIC,
                ior: *ior,
                dispersion,
                ior_model: model,
                color: [1.0; 4],
                absorption: absorption.extend(0.0).to_array(),
            }
        }
    }
}

/// A light as the kernels read it (intensity in W/sr or irradiance in W/m^2 per channel).
pub fn gpu_light(l: &Light) -> GpuLight {
    match l {
        Light::Point {
            position,
            intensity,
        } => GpuLight {
            kind: light_kind::POINT,
            cos_inner: -1.0,
            cos_outer: -1.0,
            one_minus_cos_outer: 2.0,
            position: position.extend(1.0).to_array(),
            intensity: intensity.extend(0.0).to_array(),
            ..Default::default()
        },
        Light::Spot {
            position,
            direction,
            intensity,
            inner_angle_deg,
            outer_angle_deg,
        } => GpuLight {
            kind: light_kind::SPOT,
            cos_inner: inner_angle_deg.to_radians().cos(),
            cos_outer: outer_angle_deg.to_radians().cos(),
            one_minus_cos_outer: one_minus_cos_of_angle(outer_angle_deg.to_radians()),
            position: position.extend(1.0).to_array(),
            direction: direction.normalize().extend(0.0).to_array(),
            intensity: intensity
                .extend(one_minus_cos_of_angle(inner_angle_deg.to_radians()))
                .to_array(),
        },
        Light::Directional {
            direction,
            irradiance,
            ..
        } => GpuLight {
            kind: light_kind::DIRECTIONAL,
            one_minus_cos_outer: 2.0,
            direction: direction.normalize().extend(0.0).to_array(),
            intensity: irradiance.extend(0.0).to_array(),
            ..Default::default()
        },
    }
}

/// Spot falloff: 1 inside the inner cone, 0 outside the outer, smoothstep between
/// (`cos_theta` is the cosine to the spot axis). Point lights pass `cos_outer = -1`.
#[inline]
pub fn spot_falloff(cos_theta: f32, cos_inner: f32, cos_outer: f32) -> f32 {
    if cos_theta >= cos_inner {
        return 1.0;
    }
    if cos_theta <= cos_outer {
        return 0.0;
    }
    let t = ((cos_theta - cos_outer) / (cos_inner - cos_outer)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// Spot light `l`'s falloff towards unit direction `dir` (world space): [`spot_falloff`]
/// of `dir . axis`, or for a spot narrower than [`NARROW_CONE`] (whose cosines round
/// towards 1, the smoothstep over a few f32 values, or none) the same smoothstep in
/// `h = 1 - cos`: `h = |dir - axis|^2 / 2` for unit vectors, without cancellation, against
/// the cone's `1 - cos` ([`GpuLight::one_minus_cos_outer`], `intensity[3]` for the inner
/// cone).
#[inline]
pub fn light_spot_falloff(dir: Vec3, l: &GpuLight) -> f32 {
    let axis = Vec3::from_slice(&l.direction[..3]);
    if l.one_minus_cos_outer < NARROW_CONE {
        let d = dir - axis;
        let h = 0.5 * (d.x * d.x + d.y * d.y + d.z * d.z);
        return spot_falloff_narrow(h, l.intensity[3], l.one_minus_cos_outer);
    }
    spot_falloff(dir.dot(axis), l.cos_inner, l.cos_outer)
}

/// [`spot_falloff`] in `h = 1 - cos` (`h_inner <= h_outer`): 1 inside the inner cone, 0
/// outside the outer, the smoothstep of `(h_outer - h) / (h_outer - h_inner)` between.
#[inline]
pub fn spot_falloff_narrow(h: f32, h_inner: f32, h_outer: f32) -> f32 {
    if h <= h_inner {
        return 1.0;
    }
    if h >= h_outer {
        return 0.0;
    }
    let t = ((h_outer - h) / (h_outer - h_inner)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::device::acceleration::{tlas_capacity, InstanceRecord};
    use crate::scene::builtin::builtin;
    use glam::Quat;

    /// `cornell` with both balls instances (re-centred, placed by translation).
    fn instanced_cornell() -> Scene {
        let mut s = builtin("cornell").unwrap();
        for o in s.objects.iter_mut().filter(|o| o.name.ends_with("ball")) {
            if let crate::scene::Shape::Sphere { center, .. } = &mut o.shape {
                o.transform = Some(Transform::from_translation(std::mem::replace(
                    center,
                    Vec3::ZERO,
                )));
            }
        }
        s
    }

    /// An instance's smooth-normal test bounds what its transform makes of its object-space
    /// departure: a quad whose vertex normals lean 5e-5 off its face passes for flat
    /// unscaled, but a scale of 100 along the face's normal leans them 5e-3 off in world
    /// space (measured on the placed vertices), which the test must not miss.
    #[test]
    fn a_stretched_instance_counts_its_normals_departure() {
        let mut scene = instanced_cornell();
        let lean = Vec3::new(5e-5, 1.0, 0.0).normalize();
        scene.objects[5].shape = crate::scene::Shape::Mesh {
            positions: vec![
                Vec3::new(-0.2, 0.0, -0.2),
                Vec3::new(0.2, 0.0, -0.2),
                Vec3::new(0.2, 0.0, 0.2),
                Vec3::new(-0.2, 0.0, 0.2),
            ]
            .into(),
            normals: vec![lean; 4].into(),
            uvs: Vec::new().into(),
            indices: vec![[0, 2, 1], [0, 3, 2]].into(),
        };
        let level = |ds: &DeviceScene| {
            ds.instances
                .levels
                .iter()
                .find(|l| l.object == Some(5))
                .unwrap()
                .clone()
        };
        let world_departure = |ds: &DeviceScene| {
            let l = level(ds);
            normal_departure(l.triangle_indices.iter().copied(), &ds.vertices)
        };
        let mut ds = DeviceScene::build(&scene, Default::default()).unwrap();
        assert!(world_departure(&ds) < NORMAL_DEPARTURE);
        assert!(!level(&ds).smooth_normals());
        let t = scene.objects[5].transform.unwrap();
        let stretched = Transform {
            scale: Vec3::new(1.0, 100.0, 1.0),
            ..t
        };
        ds.move_instances(&[(5, stretched)]).unwrap();
        assert!(world_departure(&ds) > 10.0 * NORMAL_DEPARTURE);
        assert!(level(&ds).smooth_normals());
        // normals along the face stay flat at any scale
        let crate::scene::Shape::Mesh { normals, .. } = &mut scene.objects[5].shape else {
            unreachable!()
        };
        *normals = vec![Vec3::Y; 4].into();
        scene.objects[5].transform = Some(stretched);
        let ds = DeviceScene::build(&scene, Default::default()).unwrap();
        assert!(!level(&ds).smooth_normals());
    }

    #[test]
    fn a_scene_without_transforms_has_one_static_level() {
        let ds = DeviceScene::build(&builtin("sphere").unwrap(), Default::default()).unwrap();
        assert_eq!(ds.instances.levels.len(), 1);
        let l = &ds.instances.levels[0];
        assert_eq!(l.object, None);
        assert_eq!(l.triangle_count as usize, ds.triangles.len());
        let r = InstanceRecord::decode(&ds.bvh_nodes[tlas_capacity(1) as usize * SLOT_VEC4S..]);
        assert_eq!(r, l.record());
        assert_eq!(
            r.flags,
            crate::device::acceleration::instance_flags::IDENTITY
        );
        // the traversal starts at the static level's BLAS root: the mark names its
        // record's root, corners and offset
        use crate::device::acceleration::{SINGLE_LEVEL_MARK, SINGLE_LEVEL_SLOT};
        assert_eq!(
            ds.bvh_nodes[SINGLE_LEVEL_SLOT * SLOT_VEC4S],
            [
                SINGLE_LEVEL_MARK,
                r.blas_root,
                r.triangle_corners,
                r.position_offset
            ]
        );
        // with instances the slot is the TLAS's (a node, or zero), never the mark
        let ds = DeviceScene::build(&instanced_cornell(), Default::default()).unwrap();
        assert_eq!(ds.instances.levels.len(), 3);
        assert_ne!(
            ds.bvh_nodes[SINGLE_LEVEL_SLOT * SLOT_VEC4S][0],
            SINGLE_LEVEL_MARK
        );
        assert!(f32::from_bits(SINGLE_LEVEL_MARK).is_nan());
    }

    #[test]
    fn moved_instances_equal_a_fresh_build_bitwise() {
        let scene = instanced_cornell();
        let mut ds = DeviceScene::build(&scene, Default::default()).unwrap();
        assert_eq!(ds.instances.levels.len(), 3, "static level and two balls");
        let moves = [
            (
                5,
                Transform {
                    translation: Vec3::new(-0.2, 0.6, 0.1),
                    rotation: Quat::from_rotation_y(0.7),
                    scale: Vec3::new(0.8, 1.1, 0.9),
                },
            ),
            (6, Transform::from_translation(Vec3::new(0.3, 0.4, -0.3))),
        ];
        ds.move_instances(&moves).unwrap();
        let mut moved = scene.clone();
        for (k, t) in moves {
            moved.objects[k].transform = Some(t);
        }
        let fresh = DeviceScene::build(&moved, Default::default()).unwrap();
        assert!(ds.vertices == fresh.vertices, "world vertices");
        assert!(ds.bvh_nodes == fresh.bvh_nodes, "node buffer");
        assert_eq!(ds.triangles, fresh.triangles);
        assert_eq!(ds.bounds, fresh.bounds);
        assert_eq!(ds.caster_bounds, fresh.caster_bounds);
        assert_eq!(ds.caster_spheres, fresh.caster_spheres);
        assert_eq!(ds.instances, fresh.instances);
    }

    /// A scene built again through the cache with one object's shape replaced (another
    /// triangle count, so every later level's triangles and vertices shift) builds that
    /// object's BVH alone and equals a fresh build bitwise; a static object's change
    /// builds the static level's.
    #[test]
    fn a_cached_build_builds_the_changed_level_alone_and_equals_a_fresh_build() {
        let scene = instanced_cornell();
        let mut cache = BvhCache::default();
        let first = DeviceScene::build_cached(&scene, Default::default(), &mut cache).unwrap();
        // the two balls are the same object-space input: one BVH
        assert_eq!((cache.built, cache.reused, cache.len()), (2, 1, 2));
        let same = |a: &DeviceScene, b: &DeviceScene| {
            assert!(a.vertices == b.vertices, "world vertices");
            assert!(a.bvh_nodes == b.bvh_nodes, "node buffer");
            assert_eq!(a.triangles, b.triangles);
            assert_eq!(a.triangle_objects, b.triangle_objects);
            assert_eq!(a.instances, b.instances);
            assert_eq!(a.caster_spheres, b.caster_spheres);
        };
        same(
            &first,
            &DeviceScene::build(&scene, Default::default()).unwrap(),
        );
        let mut changed = scene.clone();
        changed.objects[5].shape = crate::scene::Shape::Sphere {
            center: Vec3::ZERO,
            radius: 0.2,
            segments: 20,
        };
        let ds = DeviceScene::build_cached(&changed, Default::default(), &mut cache).unwrap();
        assert_eq!((cache.built, cache.reused, cache.len()), (3, 3, 3));
        assert_ne!(ds.triangles.len(), first.triangles.len());
        same(
            &ds,
            &DeviceScene::build(&changed, Default::default()).unwrap(),
        );
        // a static object: the static level's BVH alone
        let mut floor = changed.clone();
        let k = floor
            .objects
            .iter()
            .position(|o| o.transform.is_none())
            .unwrap();
        if let crate::scene::Shape::Quad { center, .. } = &mut floor.objects[k].shape {
            center.y += 0.01;
        }
        let ds = DeviceScene::build_cached(&floor, Default::default(), &mut cache).unwrap();
        assert_eq!((cache.built, cache.reused), (4, 5));
        same(
            &ds,
            &DeviceScene::build(&floor, Default::default()).unwrap(),
        );
    }

    #[test]
    fn a_deformed_instance_equals_a_fresh_build_but_for_its_version() {
        let scene = instanced_cornell();
        let mut ds = DeviceScene::build(&scene, Default::default()).unwrap();
        let before_nodes = ds.bvh_nodes.len();
        // ball 5 squashed and rippled (object space): a BVH of another shape
        let m = tessellate(&scene.objects[5].shape);
        let positions: Vec<Vec3> = m
            .positions
            .iter()
            .map(|p| Vec3::new(1.3 * p.x, 0.6 * p.y + 0.05 * (9.0 * p.x).sin(), p.z))
            .collect();
        let mut deformed = scene.clone();
        deformed.objects[5].shape = crate::scene::Shape::Mesh {
            positions: positions.into(),
            normals: Vec::new().into(),
            uvs: m.uvs.clone().into(),
            indices: m.indices.clone().into(),
        };
        let local = mesh_vertices(&tessellate(&deformed.objects[5].shape));
        ds.deform_instance(5, local).unwrap();
        let fresh = DeviceScene::build(&deformed, Default::default()).unwrap();
        assert_eq!(ds.bvh_nodes.len(), before_nodes, "deformed in place");
        assert!(ds.vertices == fresh.vertices, "world vertices");
        assert_eq!(ds.triangles, fresh.triangles);
        assert_eq!(ds.bounds, fresh.bounds);
        assert_eq!(ds.caster_bounds, fresh.caster_bounds);
        assert_eq!(ds.caster_spheres, fresh.caster_spheres);
        // the node buffer bitwise, but for the deformed level's record's version word
        let k = ds
            .instances
            .levels
            .iter()
            .position(|l| l.object == Some(5))
            .unwrap();
        assert_eq!(ds.instances.levels[k].geometry_version, 1);
        let mut nodes = ds.bvh_nodes.clone();
        let capacity = tlas_capacity(ds.instances.levels.len()) as usize;
        for p in 0..ds.instances.levels.len() {
            nodes[(capacity + 2 * p) * SLOT_VEC4S + 8][0] = 0;
        }
        assert!(nodes == fresh.bvh_nodes, "node buffer");
        let mut levels = ds.instances.levels.clone();
        levels[k].geometry_version = 0;
        assert_eq!(levels, fresh.instances.levels);
        assert_eq!(
            ds.instances.object_vertices,
            fresh.instances.object_vertices
        );
        // another vertex count, or a static object: refused, nothing changed
        let kept = ds.instances.clone();
        assert!(ds.instances.deform_instance(5, Vec::new()).is_err());
        assert!(ds.instances.deform_instance(0, Vec::new()).is_err());
        assert_eq!(ds.instances, kept);
    }

    #[test]
    fn triangle_corners_are_each_triangles_vertices_in_its_levels_space() {
        let mut ds = DeviceScene::build(&instanced_cornell(), Default::default()).unwrap();
        let check = |ds: &DeviceScene| {
            for l in &ds.instances.levels {
                let r = l.record();
                for i in r.triangle_base..r.triangle_base + r.triangle_count {
                    let t = ds.triangles[i as usize];
                    for (k, &v) in t.indices.iter().enumerate() {
                        let want = match l.object {
                            // world space
                            None => position_vec4(ds.vertices[v as usize].position),
                            // object space, where the CPU traversal reads it
                            Some(_) => ds.bvh_nodes[v.wrapping_add(r.position_offset) as usize],
                        };
                        let at =
                            r.triangle_corners as usize + TRIANGLE_CORNER_VEC4S * i as usize + k;
                        assert_eq!(ds.bvh_nodes[at], want, "triangle {i} corner {k}");
                    }
                }
            }
        };
        check(&ds);
        ds.move_instances(&[(5, Transform::from_translation(Vec3::new(0.1, 0.5, 0.0)))])
            .unwrap();
        check(&ds);
    }

    #[test]
    fn an_instance_blas_fits_its_region_for_any_shape() {
        // the bound of instance_blas_capacity on triangle soups of many sizes and shapes
        let mut seed = 7u32;
        let mut rnd = || {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            (seed >> 8) as f32 / (1 << 24) as f32
        };
        for n in [1u32, 2, 3, 5, 8, 17, 64, 300, 2000] {
            for spread in [1e-3f32, 1.0, 100.0] {
                let mut p = Vec::new();
                let mut tris = Vec::new();
                for t in 0..n {
                    let c = Vec3::new(rnd(), rnd(), rnd()) * spread;
                    for _ in 0..3 {
                        p.push(c + Vec3::new(rnd(), rnd(), rnd()) * 0.01);
                    }
                    tris.push(GpuTriangle {
                        indices: [3 * t, 3 * t + 1, 3 * t + 2],
                        material: 0,
                    });
                }
                let (_, nodes, _) = build_bvh(
                    &|i| Vec3A::from(p[i as usize]),
                    tris,
                    None,
                    LevelBuild::Instance,
                )
                .unwrap();
                let used = (nodes.len() / SLOT_VEC4S) as u32;
                assert!(
                    used <= instance_blas_capacity(n) && used <= n.max(2) - 1 + (n == 1) as u32,
                    "{n} triangles: {used} nodes"
                );
            }
        }
    }

    /// A spot wider than `NARROW_CONE` keeps the cosine smoothstep bit for bit; a narrow one
    /// (0.01 degrees, whose cosines are 1 in f32) falls off over its whole cone as the f64
    /// smoothstep in `1 - cos` does, within 1e-4.
    #[test]
    fn a_narrow_spot_falls_off_over_its_whole_cone() {
        let spot = |inner: f32, outer: f32| {
            gpu_light(&Light::Spot {
                position: Vec3::ZERO,
                direction: -Vec3::Y,
                intensity: Vec3::ONE,
                inner_angle_deg: inner,
                outer_angle_deg: outer,
            })
        };
        let towards = |theta: f64| Vec3::new(theta.sin() as f32, -(theta.cos() as f32), 0.0);
        let wide = spot(10.0, 30.0);
        for k in 0..=40 {
            let dir = towards((k as f64).to_radians());
            assert_eq!(
                light_spot_falloff(dir, &wide).to_bits(),
                spot_falloff(dir.dot(-Vec3::Y), wide.cos_inner, wide.cos_outer).to_bits()
            );
        }
        let narrow = spot(0.005, 0.01);
        assert_eq!((narrow.cos_inner, narrow.cos_outer), (1.0, 1.0));
        let (hi, ho) = (
            1.0 - 0.005f64.to_radians().cos(),
            1.0 - 0.01f64.to_radians().cos(),
        );
        let mut between = 0;
        for k in 0..=60 {
            let theta = (0.012 * k as f64 / 60.0).to_radians();
            let h = 2.0 * (0.5 * theta).sin().powi(2);
            let want = if h <= hi {
                1.0
            } else if h >= ho {
                0.0
            } else {
                between += 1;
                let t = (ho - h) / (ho - hi);
                t * t * (3.0 - 2.0 * t)
            };
            let got = light_spot_falloff(towards(theta), &narrow) as f64;
            assert!((got - want).abs() < 1e-4, "{theta:e} rad: {got} vs {want}");
        }
        assert!(between > 20);
    }

    #[test]
    fn static_objects_and_mirroring_moves_are_refused() {
        let scene = instanced_cornell();
        let mut ds = DeviceScene::build(&scene, Default::default()).unwrap();
        let before = ds.bvh_nodes.clone();
        let e = ds.move_instances(&[(0, Transform::IDENTITY)]).unwrap_err();
        assert!(e.to_string().contains("static level"), "{e}");
        let mirror = Transform {
            scale: Vec3::new(-1.0, 1.0, 1.0),
            ..Transform::IDENTITY
        };
        let e = ds.move_instances(&[(5, mirror)]).unwrap_err();
        assert!(e.to_string().contains("mirrors"), "{e}");
        assert!(ds.bvh_nodes == before, "a refused move changed the nodes");
        // beyond the coordinate bound: refused, naming the object
        let vertices = ds.vertices.clone();
        let far = Transform::from_translation(Vec3::splat(1e13));
        let e = ds.move_instances(&[(5, far)]).unwrap_err();
        assert!(e.to_string().contains("coordinate bound"), "{e}");
        assert!(e.to_string().starts_with("objects[5].transform"), "{e}");
        assert!(ds.bvh_nodes == before && ds.vertices == vertices);
    }

    #[test]
    fn a_mirrored_instance_keeps_its_winding_with_its_normals() {
        let mut scene = instanced_cornell();
        scene.objects[5].transform = Some(Transform {
            scale: Vec3::new(-1.0, 1.0, 1.0),
            ..scene.objects[5].transform.unwrap()
        });
        let ds = DeviceScene::build(&scene, Default::default()).unwrap();
        let l = ds
            .instances
            .levels
            .iter()
            .find(|l| l.object == Some(5))
            .unwrap();
        let tris = &ds.triangles[l.triangle_base as usize..][..l.triangle_count as usize];
        // the winding's normal agrees with the vertex normals (outward) on every triangle
        for t in tris {
            let v = t.indices.map(|i| ds.vertices[i as usize]);
            let p = v.map(|v| Vec3::from(v.position));
            let ng = (p[1] - p[0]).cross(p[2] - p[0]);
            let n = Vec3::from(v[0].normal) + Vec3::from(v[1].normal) + Vec3::from(v[2].normal);
            assert!(ng.dot(n) > 0.0, "a mirrored triangle faces inward");
        }
    }

    /// The boxes the host's placement grows in its one pass ([`placed_vertices`], against
    /// which a move's `placed_bounds` is proptested) are, bitwise, the box
    /// of every world vertex and the box of the used ones as a build grows them
    /// ([`world_vertices`], [`triangle_bounds`]), zero bounds of either sign included.
    mod placed {
        use super::*;
        use proptest::prelude::*;

        /// Coordinates with zeros of both signs, often a box's bound, and repeated values
        /// (ties).
        fn coordinate() -> impl Strategy<Value = f32> {
            prop_oneof![Just(0.0f32), Just(-0.0f32), Just(0.5), 0.0f32..2.0]
        }

        fn transform() -> impl Strategy<Value = Transform> {
            prop_oneof![
                Just(Transform::IDENTITY),
                (
                    coordinate(),
                    coordinate(),
                    coordinate(),
                    -3.0f32..3.0,
                    0.5f32..2.0
                )
                    .prop_map(|(x, y, z, angle, scale)| Transform {
                        translation: Vec3::new(x, y, z),
                        rotation: Quat::from_rotation_y(angle),
                        scale: Vec3::splat(scale),
                    }),
            ]
        }

        proptest! {
            #[test]
            fn placed_vertices_grow_the_boxes_a_build_grows(
                t in transform(),
                vertices in prop::collection::vec(
                    (coordinate(), coordinate(), coordinate(), any::<bool>()), 1..12),
            ) {
                let local: Vec<GpuVertex> = vertices
                    .iter()
                    .map(|&(x, y, z, _)| GpuVertex {
                        position: [x, y, z],
                        u: 0.0,
                        normal: [0.0, 1.0, 0.0],
                        v: 0.0,
                    })
                    .collect();
                let base = 7u32;
                let used: Vec<u32> = (0..local.len() as u32)
                    .filter(|&i| !vertices[i as usize].3)
                    .map(|i| i + base)
                    .collect();
                let unused = unused_vertices(&used, base, local.len());
                let (world, all) = world_vertices(&t, &local);
                let (placed, placed_all, placed_used) = placed_vertices(&t, &local, &unused);
                let bits = |b: Aabb| [b.min.to_array(), b.max.to_array()].map(|v| v.map(f32::to_bits));
                prop_assert!(bytemuck::cast_slice::<_, u32>(&placed) == bytemuck::cast_slice::<_, u32>(&world));
                prop_assert_eq!(bits(placed_all), bits(all));
                prop_assert_eq!(bits(placed_used), bits(triangle_bounds(&used, &world, base)));
            }
        }
    }
}
