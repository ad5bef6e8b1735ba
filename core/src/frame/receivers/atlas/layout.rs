//! The caustic atlas (Vanderstichelen 2021, section 3.2, "render caustic map"): one texture in which
//! every diffuse receiver owns a square tile, addressed by the receiver's UVs, so that a
//! photon landing on a receiver deposits into the texel under its hit's UV and any camera
//! path ending on that receiver reads it back (CausticMap's final pass, AdaptiveCaustics'
//! default deposit target).
//!
//! **Tile sizes.** Vanderstichelen 2021 gives every receiver its own map; one atlas (default 2048 x 2048,
//! the source's map size) holds them all here, each receiver's tile side proportional to
//! the square root of its world area, so that every receiver gets (about) the same *texel
//! density* `rho` (texels per scene unit^2). [`plan_atlas`] finds the largest `rho` whose
//! tiles, `side = max(1, floor(sqrt(rho A)))`, fit the atlas by shelf packing (tiles by
//! decreasing side, left to right in rows as tall as their first tile), by bisection on
//! `rho`; the plan states `rho` and each tile's own density `side^2 / A`.
//!
//! **Texel area.** A receiver's UVs in `[0, 1]^2` map onto its tile, `texel = corner +
//! uv * side`. On a triangle the map from UV to world is affine, so every texel inside
//! the triangle covers the same world area, `A_world / (A_uv side^2)` (the UV-to-world
//! Jacobian's determinant over the tile's texels per UV unit^2): [`texel_world_area`].
//! The map stores irradiance, a photon's flux over that area (W/m^2 per channel).
//!
//! **UVs must not overlap.** Two triangles sharing a texel would both deposit into it and
//! the caustic would be counted twice where either is seen. [`receiver_coverage`] tests
//! every texel centre of a tile against the receiver's UV triangles and refuses a receiver
//! whose UVs overlap, leave `[0, 1]^2`, or are missing (a triangle of zero UV area but
//! non-zero world area), naming it: a clear error, never a silently doubled caustic.
//! Meshes without UVs get generated ones where scenes are loaded (glTF, OBJ, scene files:
//! [`crate::scene::uv_charts`]); a scene built in code calls
//! [`crate::scene::uv_charts::generate_missing_uvs`] itself, as the error says.

use crate::device::device_scene::DeviceScene;
use crate::device::layout::{AtlasTexel, AtlasTileTexel, GpuVertex, NO_TILE};
use crate::math::map_gather::TILE_FULLY_COVERED;
use glam::{Vec2, Vec3};

/// Default atlas size (texels a side), the source's caustic map size.
pub const DEFAULT_ATLAS_SIDE: u32 = 2048;

/// One receiver's square tile in the atlas (texel coordinates).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AtlasTile {
    /// Index of the receiver in the list given to [`plan_atlas`].
    pub receiver: u32,
    /// Column of the tile's first texel.
    pub x: u32,
    /// Row of the tile's first texel.
    pub y: u32,
    /// Side (texels).
    pub side: u32,
}

/// Where every receiver's tile lies, and the texel density that sized them.
#[derive(Clone, Debug, PartialEq)]
pub struct AtlasPlan {
    /// Atlas width and height (texels).
    pub size: (u32, u32),
    /// One tile per receiver, in receiver order.
    pub tiles: Vec<AtlasTile>,
    /// The density the tiles were sized for (texels per scene unit^2); a tile's own
    /// density, `side^2 / area`, is at most this (the side is rounded down) and at least
    /// this for receivers so small that they get one texel.
    pub texels_per_unit_area: f64,
}

/// Why a set of receivers gets no atlas.
#[derive(Clone, Debug, PartialEq)]
pub enum AtlasError {
    /// The atlas has no texel, or a receiver's area is not a finite number > 0.
    BadInput(String),
    /// Even one texel per receiver does not fit (more receivers than texels).
    TooManyReceivers {
        /// Receivers asked for.
        receivers: usize,
        /// Texels in the atlas.
        texels: u64,
    },
    /// A receiver's world area is not a finite number > 0 (its triangles' areas are lost
    /// to f32 rounding, e.g. an instance scaled far down far from the origin).
    NoArea {
        /// Object index of the receiver.
        receiver: u32,
        /// Its world area (scene units^2).
        area: f64,
    },
    /// A receiver's UVs cannot address a caustic map (named, with the reason).
    BadUvs {
        /// Index of the receiver.
        receiver: u32,
        /// What is wrong.
        reason: String,
    },
}

impl std::fmt::Display for AtlasError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            AtlasError::BadInput(s) => write!(f, "caustic atlas: {s}"),
            AtlasError::TooManyReceivers { receivers, texels } => write!(
                f,
                "caustic atlas: {receivers} receivers do not fit {texels} texels, one each"
            ),
            AtlasError::BadUvs { receiver, reason } => {
                write!(f, "caustic atlas: receiver {receiver}: {reason}")
            }
            AtlasError::NoArea { receiver, area } => write!(
                f,
                "caustic atlas: receiver {receiver} has world area {area}, not a finite \
                 number > 0"
            ),
        }
    }
}

impl std::error::Error for AtlasError {}

/// Tile side for a receiver of world area `area` at density `rho`.
fn tile_side(area: f64, rho: f64, max_side: u32) -> u32 {
    ((rho * area).sqrt().floor() as u64).clamp(1, max_side as u64) as u32
}

/// Shelf-packs squares of the given sides (any order) into `size`; `None` if they do not
/// fit. Tiles go by decreasing side (ties by receiver), left to right, in shelves as tall
/// as their first tile.
fn shelf_pack(sides: &[u32], size: (u32, u32)) -> Option<Vec<AtlasTile>> {
    let mut order: Vec<usize> = (0..sides.len()).collect();
    order.sort_by_key(|&i| (std::cmp::Reverse(sides[i]), i));
    let mut tiles = vec![
        AtlasTile {
            receiver: 0,
            x: 0,
            y: 0,
            side: 0
        };
        sides.len()
    ];
    let (mut x, mut y, mut shelf) = (0u64, 0u64, 0u64);
    for i in order {
        let s = sides[i] as u64;
        if x + s > size.0 as u64 {
            // next shelf
            y += shelf;
            x = 0;
            shelf = 0;
        }
        if shelf == 0 {
            shelf = s;
        }
        if x + s > size.0 as u64 || y + s > size.1 as u64 {
            return None;
        }
        tiles[i] = AtlasTile {
            receiver: i as u32,
            x: x as u32,
            y: y as u32,
            side: s as u32,
        };
        x += s;
    }
    Some(tiles)
}

/// Plans an atlas of `size` texels for receivers of the given world areas (scene
/// units^2): the largest texel density whose tiles fit (see the module doc).
pub fn plan_atlas(areas: &[f64], size: (u32, u32)) -> Result<AtlasPlan, AtlasError> {
    if size.0 == 0 || size.1 == 0 {
        return Err(AtlasError::BadInput("the atlas has no texel".into()));
    }
    if areas.is_empty() {
        // no receiver (none reached): an atlas without tiles
        return Ok(AtlasPlan {
            size,
            tiles: Vec::new(),
            texels_per_unit_area: 0.0,
        });
    }
    if let Some(i) = areas.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
        return Err(AtlasError::BadInput(format!(
            "receiver {i} has world area {}, not a finite number > 0",
            areas[i]
        )));
    }
    let texels = size.0 as u64 * size.1 as u64;
    if areas.len() as u64 > texels {
        return Err(AtlasError::TooManyReceivers {
            receivers: areas.len(),
            texels,
        });
    }
    let max_side = size.0.min(size.1);
    let pack = |rho: f64| {
        let sides: Vec<u32> = areas.iter().map(|&a| tile_side(a, rho, max_side)).collect();
        shelf_pack(&sides, size)
    };
    // bisection on log rho between a density that fits (the tiles' total area a quarter
    // of the atlas, or else every tile one texel) and the density at which the smallest
    // receiver's tile would reach the atlas side (no tile grows beyond it)
    let total: f64 = areas.iter().sum();
    let min_area = areas.iter().cloned().fold(f64::INFINITY, f64::min);
    let (mut lo, mut hi) = (
        (0.25 * texels as f64 / total).max(f64::MIN_POSITIVE),
        1.01 * (max_side as f64).powi(2) / min_area,
    );
    if pack(lo).is_none() {
        lo = f64::MIN_POSITIVE; // every tile one texel: fits, as receivers <= texels
    }
    for _ in 0..200 {
        let mid = (lo * hi).sqrt();
        if !(mid > lo && mid < hi) {
            break;
        }
        if pack(mid).is_some() {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    let tiles = pack(lo).ok_or(AtlasError::TooManyReceivers {
        receivers: areas.len(),
        texels,
    })?;
    Ok(AtlasPlan {
        size,
        tiles,
        texels_per_unit_area: lo,
    })
}

/// World area (scene units^2) each texel of `tile_side` texels a side covers inside a
/// triangle with world corners `p` and UV corners `t`: `A_world / (A_uv side^2)`; `None`
/// where the triangle has no UV area.
pub fn texel_world_area(p: [Vec3; 3], t: [Vec2; 3], tile_side: u32) -> Option<f32> {
    let a_world = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
    let a_uv = 0.5 * (t[1] - t[0]).perp_dot(t[2] - t[0]).abs();
    let texels = a_uv * (tile_side as f32) * (tile_side as f32);
    (texels > 0.0).then(|| a_world / texels)
}

/// The texel of a tile under UV `uv` (clamped to the tile).
pub fn uv_texel(tile: &AtlasTile, uv: Vec2) -> (u32, u32) {
    let s = tile.side as f32;
    let cx = ((uv.x * s).floor().max(0.0) as u32).min(tile.side - 1);
    let cy = ((uv.y * s).floor().max(0.0) as u32).min(tile.side - 1);
    (tile.x + cx, tile.y + cy)
}

/// Which texels of a receiver's `side x side` tile its UV triangles cover (row-major,
/// `true` where a texel centre lies inside a triangle, edges included), or why its UVs
/// cannot address a caustic map: a UV outside `[0, 1]^2`, a triangle of zero UV area but
/// non-zero world area (missing UVs), or two triangles covering one texel centre (overlap).
pub fn receiver_coverage(
    receiver: u32,
    triangles: &[([Vec3; 3], [Vec2; 3])],
    side: u32,
) -> Result<Vec<bool>, AtlasError> {
    Ok(receiver_owners(receiver, triangles, side)?
        .into_iter()
        .map(|o| o != u32::MAX)
        .collect())
}

/// [`receiver_coverage`] naming the triangle (index into `triangles`) that covers each
/// texel centre, `u32::MAX` where none does.
pub fn receiver_owners(
    receiver: u32,
    triangles: &[([Vec3; 3], [Vec2; 3])],
    side: u32,
) -> Result<Vec<u32>, AtlasError> {
    let bad = |reason: String| AtlasError::BadUvs { receiver, reason };
    let mut owner = vec![u32::MAX; side as usize * side as usize];
    let s = side as f32;
    for (k, (p, t)) in triangles.iter().enumerate() {
        if t.iter()
            .any(|uv| !(uv.x >= 0.0 && uv.x <= 1.0 && uv.y >= 0.0 && uv.y <= 1.0))
        {
            return Err(bad(format!(
                "triangle {k} has a UV outside [0, 1]^2: {t:?}"
            )));
        }
        let a_world = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length();
        let twice_uv = (t[1] - t[0]).perp_dot(t[2] - t[0]);
        if twice_uv == 0.0 {
            if a_world > 0.0 {
                return Err(bad(format!(
                    "triangle {k} has no UV area (missing or degenerate UVs: give the \
                     mesh UVs that cover it, or none, for which the scene loaders and \
                     scene::uv_charts::generate_missing_uvs make UV charts)"
                )));
            }
            continue; // degenerate in the world too: covers nothing
        }
        // texel centres inside the triangle's UV box
        let lo = t[0].min(t[1]).min(t[2]) * s;
        let hi = t[0].max(t[1]).max(t[2]) * s;
        let (x0, y0) = (
            (lo.x - 0.5).ceil().max(0.0) as u32,
            (lo.y - 0.5).ceil().max(0.0) as u32,
        );
        let (x1, y1) = (
            ((hi.x - 0.5).floor().min(s - 1.0)).max(-1.0),
            ((hi.y - 0.5).floor().min(s - 1.0)).max(-1.0),
        );
        if x1 < 0.0 || y1 < 0.0 {
            continue;
        }
        for y in y0..=y1 as u32 {
            for x in x0..=x1 as u32 {
                let c = Vec2::new((x as f32 + 0.5) / s, (y as f32 + 0.5) / s);
                if inside_triangle(c, t, twice_uv) {
                    let o = &mut owner[(y * side + x) as usize];
                    if *o != u32::MAX {
                        return Err(bad(format!(
                            "UVs overlap: triangles {} and {k} both cover texel ({x}, {y}) \
                             of its {side}x{side} tile",
                            *o
                        )));
                    }
                    *o = k as u32;
                }
            }
        }
    }
    Ok(owner)
}

/// The atlas as the kernels read it (`trace_photons`' atlas deposit, `gather_caustic_map`,
/// `caustic_map_lookup`): the plan, each tile, each scene triangle's tile and each atlas
/// texel's world area and tile.
#[derive(Clone, Debug)]
pub struct AtlasLayout {
    /// Where the tiles lie and the texel density.
    pub plan: AtlasPlan,
    /// Scene object index of each receiver (receiver `i` owns tile `i`).
    pub receivers: Vec<u32>,
    /// Per tile: `[x, y, side, receiver object | TILE_FULLY_COVERED where every texel of
    /// the tile is covered]` ([`crate::math::map_gather::TILE_FULLY_COVERED`]).
    pub tiles: Vec<AtlasTileTexel>,
    /// Per scene triangle (device order): its tile, or [`NO_TILE`].
    pub triangle_tiles: Vec<u32>,
    /// Per atlas texel (row-major): `[world area bits, tile]` ([`AtlasTexel`]).
    pub texels: Vec<AtlasTexel>,
    /// Texels some UV triangle covers.
    pub covered_texels: u64,
}

/// Which scene objects get an atlas tile: one flag per object, true for diffuse
/// receivers (an object whose material is missing gets none; validation refuses it).
pub fn atlas_receivers(scene: &crate::scene::Scene) -> Vec<bool> {
    scene
        .objects
        .iter()
        .map(|o| {
            matches!(
                scene.materials.get(&o.material),
                Some(crate::scene::Material::Diffuse { .. })
            )
        })
        .collect()
}

/// A receiver's triangle: its scene index, world corners and UV corners.
type ReceiverTriangle = (usize, [Vec3; 3], [Vec2; 3]);

/// Lays out the atlas of `size` texels for the scene objects flagged in `receiver` (one
/// flag per scene object): [`AtlasReceivers::of`] then [`AtlasReceivers::layout`] with
/// every receiver included.
pub fn atlas_layout(
    ds: &DeviceScene,
    receiver: &[bool],
    size: (u32, u32),
) -> Result<AtlasLayout, AtlasError> {
    let r = AtlasReceivers::of(ds, receiver);
    r.layout(&vec![true; r.objects.len()], size)
}

/// The diffuse receivers' triangles, gathered once from the device scene, from which the
/// atlas is laid out for any subset of them: CausticMap lays its tiles out anew for the
/// receivers its photons reach ([`AtlasReceivers::reached`]) whenever that set changes.
#[derive(Clone, Debug)]
pub struct AtlasReceivers {
    /// Scene object index of each receiver.
    pub objects: Vec<u32>,
    /// Per receiver: its triangles (scene index, world corners, UV corners).
    triangles: Vec<Vec<ReceiverTriangle>>,
    /// Per receiver: its world area (scene units^2).
    areas: Vec<f64>,
    /// Per receiver: its triangles' world-vertex indices (to follow moved instances).
    indices: Vec<Vec<[u32; 3]>>,
    /// Triangles in the scene.
    scene_triangles: usize,
}

/// A receiver's world area: the sum of its triangles' areas (scene units^2). A triangle's
/// cross product is taken in f32 (the layout's bits) and again in f64 where its squared
/// length overflows f32 (edges beyond ~4e9 units, within the scene's coordinate bound).
fn world_area(ts: &[ReceiverTriangle]) -> f64 {
    ts.iter()
        .map(|(_, p, _)| {
            let a = 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() as f64;
            if a.is_finite() {
                return a;
            }
            let [p0, p1, p2] = p.map(|v| v.as_dvec3());
            0.5 * (p1 - p0).cross(p2 - p0).length()
        })
        .sum()
}

impl AtlasReceivers {
    /// The receivers among the scene objects flagged in `receiver` (one flag per scene
    /// object), with their triangles in device order.
    pub fn of(ds: &DeviceScene, receiver: &[bool]) -> AtlasReceivers {
        let objects: Vec<u32> = (0..receiver.len() as u32)
            .filter(|&o| receiver[o as usize])
            .collect();
        let mut slot_of = vec![None; receiver.len()];
        for (r, &o) in objects.iter().enumerate() {
            slot_of[o as usize] = Some(r);
        }
        let mut triangles: Vec<Vec<ReceiverTriangle>> = vec![Vec::new(); objects.len()];
        let mut indices: Vec<Vec<[u32; 3]>> = vec![Vec::new(); objects.len()];
        for (t, (tri, &o)) in ds.triangles.iter().zip(&ds.triangle_objects).enumerate() {
            if let Some(r) = slot_of.get(o as usize).copied().flatten() {
                let v = tri.indices.map(|i| ds.vertices[i as usize]);
                triangles[r].push((
                    t,
                    v.map(|v| Vec3::from(v.position)),
                    v.map(|v| Vec2::new(v.u, v.v)),
                ));
                indices[r].push(tri.indices);
            }
        }
        let areas = triangles.iter().map(|ts| world_area(ts)).collect();
        AtlasReceivers {
            objects,
            triangles,
            areas,
            indices,
            scene_triangles: ds.triangles.len(),
        }
    }

    /// Follows moved instances: `vertices` are runs of new world vertices from their first
    /// index (the receivers' instances placed on the host,
    /// [`crate::device::device_scene::SceneInstances::placed`]). The receivers whose
    /// triangles use them get their new corners and areas, computed as
    /// [`AtlasReceivers::of`] does, so the layout equals that of a fresh build of the moved
    /// scene. Returns whether any receiver moved.
    pub fn move_vertices(&mut self, vertices: &[(u32, Vec<GpuVertex>)]) -> bool {
        let lookup = |i: u32| {
            vertices.iter().find_map(|(first, v)| {
                i.checked_sub(*first)
                    .and_then(|k| v.get(k as usize))
                    .map(|v| Vec3::from(v.position))
            })
        };
        let mut any = false;
        for r in 0..self.objects.len() {
            let mut moved = false;
            for (tri, idx) in self.triangles[r].iter_mut().zip(&self.indices[r]) {
                for (corner, &i) in tri.1.iter_mut().zip(idx) {
                    if let Some(p) = lookup(i) {
                        *corner = p;
                        moved = true;
                    }
                }
            }
            if moved {
                self.areas[r] = world_area(&self.triangles[r]);
                any = true;
            }
        }
        any
    }

    /// Follows a deformed instance whose triangles from scene index `first` are now
    /// `ordered` (its new BLAS's leaf order, [`crate::device::device_scene::InstanceDeform`]):
    /// each receiver triangle in that range takes the vertex indices and UVs of the
    /// triangle now at its index (its corners follow with
    /// [`AtlasReceivers::move_vertices`]), so the layout equals that of a fresh build.
    pub fn reorder_triangles(
        &mut self,
        first: u32,
        ordered: &[crate::device::layout::GpuTriangle],
    ) {
        let range = first as usize..first as usize + ordered.len();
        // a deformation keeps every vertex's UV: read them off the triangles as they were
        let mut uv: std::collections::HashMap<u32, Vec2> = std::collections::HashMap::new();
        for (ts, is) in self.triangles.iter().zip(&self.indices) {
            for (tri, idx) in ts.iter().zip(is) {
                if range.contains(&tri.0) {
                    for (i, t) in idx.iter().zip(tri.2) {
                        uv.insert(*i, t);
                    }
                }
            }
        }
        if uv.is_empty() {
            return;
        }
        for (ts, is) in self.triangles.iter_mut().zip(self.indices.iter_mut()) {
            for (tri, idx) in ts.iter_mut().zip(is.iter_mut()) {
                if range.contains(&tri.0) {
                    let new = ordered[tri.0 - range.start].indices;
                    *idx = new;
                    tri.2 = new.map(|i| uv.get(&i).copied().unwrap_or(Vec2::ZERO));
                }
            }
        }
    }

    /// Per receiver: whether a triangle of it has its bit set in `reach`, a triangle
    /// reach mask ([`crate::math::map_gather::triangle_reach_bit`]).
    pub fn reached(&self, reach: &[u32]) -> Vec<bool> {
        self.triangles
            .iter()
            .map(|ts| {
                ts.iter().any(|(t, _, _)| {
                    let (word, bit) = crate::math::map_gather::triangle_reach_bit(*t as u32);
                    reach.get(word as usize).is_some_and(|w| w & bit != 0)
                })
            })
            .collect()
    }

    /// Lays out the atlas of `size` texels for the receivers flagged in `include` (one
    /// flag per receiver; the others get no tile, their triangles [`NO_TILE`]): tiles by
    /// world area ([`plan_atlas`]), every texel centre tested against the receiver's UV
    /// triangles ([`receiver_owners`]: overlapping, missing or out-of-range UVs are
    /// refused, naming the receiver by its object index), and each covered texel's world
    /// area from its triangle's UV-to-world Jacobian ([`texel_world_area`]).
    pub fn layout(&self, include: &[bool], size: (u32, u32)) -> Result<AtlasLayout, AtlasError> {
        let slots: Vec<usize> = (0..self.objects.len())
            .filter(|&r| include.get(r).copied().unwrap_or(false))
            .collect();
        let receivers: Vec<u32> = slots.iter().map(|&r| self.objects[r]).collect();
        if let Some(r) = receivers.iter().find(|&&r| r & TILE_FULLY_COVERED != 0) {
            // the tile's fourth word keeps the flag in its top bit
            return Err(AtlasError::BadInput(format!(
                "receiver object index {r} is past the atlas's 2^31 objects"
            )));
        }
        let areas: Vec<f64> = slots.iter().map(|&r| self.areas[r]).collect();
        if let Some(k) = areas.iter().position(|a| !(a.is_finite() && *a > 0.0)) {
            return Err(AtlasError::NoArea {
                receiver: receivers[k],
                area: areas[k],
            });
        }
        let plan = plan_atlas(&areas, size)?;
        let atlas_texels = size.0 as usize * size.1 as usize;
        let mut texels: Vec<AtlasTexel> = Vec::new();
        texels.try_reserve_exact(atlas_texels).map_err(|_| {
            AtlasError::BadInput(format!("no host memory for {atlas_texels} atlas texels"))
        })?;
        texels.resize(atlas_texels, [0, NO_TILE]);
        let mut triangle_tiles = vec![NO_TILE; self.scene_triangles];
        let mut tiles = Vec::with_capacity(plan.tiles.len());
        let mut covered_texels = 0u64;
        for (k, tile) in plan.tiles.iter().enumerate() {
            let tris = &self.triangles[slots[k]];
            let tile_covered_before = covered_texels;
            let local: Vec<([Vec3; 3], [Vec2; 3])> =
                tris.iter().map(|(_, p, t)| (*p, *t)).collect();
            let owners = receiver_owners(receivers[k], &local, tile.side)?;
            for (t, _, _) in tris {
                triangle_tiles[*t] = k as u32;
            }
            for ty in 0..tile.side {
                for tx in 0..tile.side {
                    let i = (tile.y + ty) as usize * size.0 as usize + (tile.x + tx) as usize;
                    let owner = owners[(ty * tile.side + tx) as usize];
                    let area = if owner == u32::MAX {
                        0.0
                    } else {
                        let (p, t) = &local[owner as usize];
                        texel_world_area(*p, *t, tile.side).unwrap_or(0.0)
                    };
                    covered_texels += (area > 0.0) as u64;
                    texels[i] = [area.to_bits(), k as u32];
                }
            }
            let full = covered_texels - tile_covered_before == tile.side as u64 * tile.side as u64;
            tiles.push([
                tile.x,
                tile.y,
                tile.side,
                receivers[k] | if full { TILE_FULLY_COVERED } else { 0 },
            ]);
        }
        Ok(AtlasLayout {
            plan,
            receivers,
            tiles,
            triangle_tiles,
            texels,
            covered_texels,
        })
    }
}

/// Whether `c` lies in UV triangle `t` (edges included, except the top-left rule: a point
/// on an edge shared by two triangles belongs to one of them only).
///
/// Watertight: each edge function is evaluated from the edge's endpoints in a canonical
/// order (the lexicographically smaller first) and then negated as the triangle's winding
/// needs, so the two triangles that share an edge compute exactly opposite values for
/// every point and no point near the edge can round to "inside" in both. (Evaluated from
/// each triangle's own start vertex, `(b - a) x (c - a)` and `(a - b) x (c - b)` are not
/// exact negatives in f32: on `rooms`' 8k-triangle grey ball, texel centres a rounding
/// error from a shared edge landed in both triangles and the atlas refused the ball.)
fn inside_triangle(c: Vec2, t: &[Vec2; 3], twice_area: f32) -> bool {
    let sign = twice_area.signum();
    let mut inside = true;
    for e in 0..3 {
        let (a, b) = (t[e], t[(e + 1) % 3]);
        let (p, q, flip) = if (a.x, a.y) < (b.x, b.y) {
            (a, b, 1.0)
        } else {
            (b, a, -1.0)
        };
        let w = (q - p).perp_dot(c - p) * flip * sign;
        // top-left rule on the oriented edge: on the edge counts only for edges whose
        // direction (in the triangle's winding) points down or left
        let d = (b - a) * sign;
        let owns_edge = d.y < 0.0 || (d.y == 0.0 && d.x > 0.0);
        inside &= w > 0.0 || (w == 0.0 && owns_edge);
    }
    inside
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_receivers_area_is_finite_where_f32_cross_products_overflow() {
        let tri = |s: f32| {
            (
                0,
                [Vec3::ZERO, Vec3::new(s, 0.0, 0.0), Vec3::new(0.0, 0.0, -s)],
                [Vec2::ZERO; 3],
            )
        };
        // the f32 path's bits where it is finite
        assert_eq!(world_area(&[tri(3.0)]), 4.5);
        assert_eq!(world_area(&[tri(1e10)]), 0.5 * 1e10f64 * 1e10f64);
    }

    #[test]
    fn triangles_sharing_an_edge_never_both_own_a_point() {
        use crate::math::rng::random_f32;
        let r = |k: u32, d: u32| random_f32(7, k, 0, d);
        for k in 0..2000u32 {
            // a quad a b c d split along a-c into (a, b, c) and (a, c, d), same winding
            let a = Vec2::new(r(k, 0) * 0.3, r(k, 1) * 0.3);
            let b = Vec2::new(0.7 + r(k, 2) * 0.3, r(k, 3) * 0.3);
            let c = Vec2::new(0.7 + r(k, 4) * 0.3, 0.7 + r(k, 5) * 0.3);
            let d = Vec2::new(r(k, 6) * 0.3, 0.7 + r(k, 7) * 0.3);
            let (t1, t2) = ([a, b, c], [a, c, d]);
            let area = |t: &[Vec2; 3]| (t[1] - t[0]).perp_dot(t[2] - t[0]);
            for j in 0..64u32 {
                // points on the shared edge, give or take a few ulps
                let s = random_f32(9, k, j, 0);
                let on = a + (c - a) * s;
                for (dx, dy) in [(0, 0), (1, 0), (0, 1), (-1, 0), (0, -1), (1, -1)] {
                    let bump = |v: f32, k: i32| f32::from_bits((v.to_bits() as i32 + k) as u32);
                    let p = Vec2::new(bump(on.x, dx), bump(on.y, dy));
                    let n = inside_triangle(p, &t1, area(&t1)) as u32
                        + inside_triangle(p, &t2, area(&t2)) as u32;
                    assert!(n <= 1, "quad {k}: {p:?} is inside both triangles");
                }
            }
        }
    }

    fn overlaps(a: &AtlasTile, b: &AtlasTile) -> bool {
        a.x < b.x + b.side && b.x < a.x + a.side && a.y < b.y + b.side && b.y < a.y + a.side
    }

    #[test]
    fn tiles_fit_without_overlap_and_follow_the_area() {
        let areas = [16.0, 4.0, 4.0, 1.0, 0.25, 9.0, 1e-6];
        let plan = plan_atlas(&areas, (256, 256)).unwrap();
        for (i, a) in plan.tiles.iter().enumerate() {
            assert_eq!(a.receiver, i as u32);
            assert!(a.x + a.side <= 256 && a.y + a.side <= 256);
            for b in &plan.tiles[i + 1..] {
                assert!(!overlaps(a, b), "{a:?} {b:?}");
            }
        }
        // side ~ sqrt(area): 16 -> 4x the side of 1
        let s = |i: usize| plan.tiles[i].side as f64;
        assert!((s(0) / s(3) - 4.0).abs() < 0.1, "{:?}", plan.tiles);
        assert!((s(1) - s(2)).abs() < 1.0);
        // the tiny receiver still gets one texel
        assert_eq!(plan.tiles[6].side, 1);
        // the density is the largest that fits: a little more does not
        let rho = plan.texels_per_unit_area;
        let sides: Vec<u32> = areas
            .iter()
            .map(|&a| tile_side(a, rho * 1.02, 256))
            .collect();
        assert!(shelf_pack(&sides, (256, 256)).is_none() || sides.iter().all(|&s| s == 256));
        // and fills a good part of the atlas
        let used: u64 = plan
            .tiles
            .iter()
            .map(|t| t.side as u64 * t.side as u64)
            .sum();
        assert!(used as f64 > 0.4 * 256.0 * 256.0, "used {used}");
    }

    #[test]
    fn bad_inputs_are_errors_not_panics() {
        assert!(matches!(
            plan_atlas(&[1.0], (0, 4)),
            Err(AtlasError::BadInput(_))
        ));
        assert!(matches!(
            plan_atlas(&[0.0], (4, 4)),
            Err(AtlasError::BadInput(_))
        ));
        assert!(matches!(
            plan_atlas(&[f64::NAN], (4, 4)),
            Err(AtlasError::BadInput(_))
        ));
        assert!(matches!(
            plan_atlas(&[1.0; 17], (4, 4)),
            Err(AtlasError::TooManyReceivers { .. })
        ));
        // exactly one texel each fits
        let p = plan_atlas(&[1.0; 16], (4, 4)).unwrap();
        assert!(p.tiles.iter().all(|t| t.side == 1));
        // a 1x1 atlas with one receiver
        assert_eq!(plan_atlas(&[3.0], (1, 1)).unwrap().tiles[0].side, 1);
    }

    /// A unit square in the world (z = 0) split into two triangles, UVs = xy.
    fn square() -> Vec<([Vec3; 3], [Vec2; 3])> {
        let p = |x: f32, y: f32| (Vec3::new(x, y, 0.0), Vec2::new(x, y));
        let q = [p(0.0, 0.0), p(1.0, 0.0), p(1.0, 1.0), p(0.0, 1.0)];
        vec![
            ([q[0].0, q[1].0, q[2].0], [q[0].1, q[1].1, q[2].1]),
            ([q[0].0, q[2].0, q[3].0], [q[0].1, q[2].1, q[3].1]),
        ]
    }

    #[test]
    fn a_square_covers_its_whole_tile_once() {
        for side in [1, 2, 7, 64] {
            let c = receiver_coverage(0, &square(), side).unwrap();
            assert!(c.iter().all(|&b| b), "side {side}");
        }
        // texel area: 1 m^2 over side^2 texels
        let (p, t) = square()[0];
        assert!((texel_world_area(p, t, 64).unwrap() - 1.0 / 4096.0).abs() < 1e-9);
        // scaled world: 3 m x 2 m on the same UVs
        let p3 = p.map(|v| v * Vec3::new(3.0, 2.0, 1.0));
        assert!((texel_world_area(p3, t, 64).unwrap() - 6.0 / 4096.0).abs() < 1e-8);
    }

    #[test]
    fn overlapping_missing_and_outside_uvs_are_refused() {
        let mut twice = square();
        twice.push(square()[0]);
        let e = receiver_coverage(3, &twice, 16).unwrap_err();
        assert!(matches!(e, AtlasError::BadUvs { receiver: 3, .. }), "{e}");
        assert!(e.to_string().contains("overlap"), "{e}");

        let mut flat = square();
        flat[1].1 = [Vec2::ZERO; 3];
        let e = receiver_coverage(0, &flat, 16).unwrap_err();
        assert!(e.to_string().contains("no UV area"), "{e}");

        let mut outside = square();
        outside[0].1[1] = Vec2::new(1.5, 0.0);
        let e = receiver_coverage(0, &outside, 16).unwrap_err();
        assert!(e.to_string().contains("outside"), "{e}");
    }

    #[test]
    fn every_built_in_receiver_has_uvs_that_address_a_caustic_map() {
        use crate::scene::builtin::{builtin, BUILTIN_SCENES};
        use crate::scene::shapes::tessellate;
        for name in BUILTIN_SCENES {
            let scene = builtin(name).unwrap();
            let mut areas = Vec::new();
            for (k, o) in scene.objects.iter().enumerate() {
                if scene.materials[&o.material].is_specular() {
                    continue;
                }
                let m = tessellate(&o.shape);
                let tris: Vec<([Vec3; 3], [Vec2; 3])> = m
                    .indices
                    .iter()
                    .map(|t| {
                        let i = t.map(|i| i as usize);
                        (i.map(|i| m.positions[i]), i.map(|i| m.uvs[i]))
                    })
                    .collect();
                for side in [1, 64, 256] {
                    if let Err(e) = receiver_coverage(k as u32, &tris, side) {
                        panic!("{name}: object '{}' at {side}^2: {e}", o.name);
                    }
                }
                areas.push(
                    tris.iter()
                        .map(|(p, _)| 0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length() as f64)
                        .sum::<f64>(),
                );
            }
            if !areas.is_empty() {
                let plan = plan_atlas(&areas, (DEFAULT_ATLAS_SIDE, DEFAULT_ATLAS_SIDE)).unwrap();
                assert_eq!(plan.tiles.len(), areas.len(), "{name}");
            }
        }
    }

    #[test]
    fn generated_uv_charts_never_overlap_and_cover_every_triangle() {
        use crate::scene::uv_charts::{chart_mesh, test_meshes};
        let meshes = [
            ("box", test_meshes::cuboid(), 64),
            ("sphere", test_meshes::sphere(48), 1024),
            ("spiral ramp", test_meshes::spiral_ramp(), 2048),
            ("degenerate", test_meshes::degenerate(), 64),
        ];
        for (what, (positions, indices), side) in meshes {
            let m = chart_mesh(&positions, &[], &indices).unwrap();
            let tris: Vec<([Vec3; 3], [Vec2; 3])> = m
                .indices
                .iter()
                .map(|t| {
                    (
                        t.map(|i| m.positions[i as usize]),
                        t.map(|i| m.uvs[i as usize]),
                    )
                })
                .collect();
            for s in [16, side] {
                receiver_owners(0, &tris, s).unwrap_or_else(|e| panic!("{what} at {s}: {e}"));
            }
            if what == "box" {
                let owners = receiver_owners(0, &tris, side).unwrap();
                for k in 0..tris.len() as u32 {
                    assert!(
                        owners.contains(&k),
                        "box: triangle {k} owns no texel at {side}"
                    );
                }
            }
        }
    }

    #[test]
    fn a_tile_is_flagged_fully_covered_exactly_when_every_texel_is() {
        use crate::device::device_scene::DeviceScene;
        use crate::math::map_gather::tile_receiver;
        use crate::scene::builtin::{builtin, BUILTIN_SCENES};
        let mut flagged = 0;
        for name in BUILTIN_SCENES {
            let scene = builtin(name).unwrap();
            let ds = DeviceScene::build(&scene, Default::default()).unwrap();
            let receiver = atlas_receivers(&scene);
            let Ok(l) = atlas_layout(&ds, &receiver, (256, 256)) else {
                continue;
            };
            for (k, t) in l.tiles.iter().enumerate() {
                let all = (0..t[2] * t[2]).all(|i| {
                    let at = (t[1] + i / t[2]) as usize * 256 + (t[0] + i % t[2]) as usize;
                    f32::from_bits(l.texels[at][0]) > 0.0
                });
                assert_eq!(t[3] & TILE_FULLY_COVERED != 0, all, "{name} tile {k}");
                assert_eq!(tile_receiver(t[3]), l.receivers[k], "{name} tile {k}");
                flagged += all as u32;
            }
        }
        // the quads of the built-in scenes fill their tiles
        assert!(flagged > 0);
    }

    #[test]
    fn uv_texels_stay_in_their_tile() {
        let t = AtlasTile {
            receiver: 0,
            x: 10,
            y: 20,
            side: 8,
        };
        assert_eq!(uv_texel(&t, Vec2::ZERO), (10, 20));
        assert_eq!(uv_texel(&t, Vec2::ONE), (17, 27));
        assert_eq!(uv_texel(&t, Vec2::new(0.5, 0.124)), (14, 20));
        assert_eq!(uv_texel(&t, Vec2::new(-1.0, 2.0)), (10, 27));
    }
}
