//! Automatic UV charts for meshes that have none (glTF and OBJ files without texture
//! coordinates, meshes built in code). A caustic map addresses a receiver by its UVs
//! (`frame::receivers::atlas::layout`), which must not overlap; Sspm and PhotonGi need none.
//!
//! **How.** Each triangle is given the axis (+-x, +-y, +-z) its geometric normal leans
//! on most (box projection). A *chart* grows from a triangle over shared edges (vertices
//! welded by exact position) to triangles of the same axis, and takes a triangle only if
//! the triangle's projection along that axis overlaps no triangle already in the chart
//! (an exact 2D separating-axis test; triangles that only touch along an edge or at a
//! vertex do not overlap). Projected along its own axis a triangle keeps its orientation
//! (the projected area is the normal's component on that axis, at least `1/sqrt(3)` of
//! the whole), so inside a chart the UV map is an affine, orientation-preserving map of
//! each triangle, and charts are disjoint by construction. A plane is one chart; a box
//! six; a sphere six caps; a fold of the surface over itself (a spiral ramp) is split
//! where it would overlap.
//!
//! **Packing.** All charts share one scale (UV units per scene unit), so every chart gets
//! the same texel density; their projected bounding boxes are shelf-packed (tallest
//! first) into the unit square with a gutter of [`CHART_GUTTER`] of the square's side
//! between charts and around them. The gather of a caustic map does not cross a tile
//! (receiver) but does cross chart borders inside one, as at any UV seam: the gutter
//! keeps charts `CHART_GUTTER x side` texels apart (8 texels in a 2048-texel tile, 1 in
//! a 256-texel one).
//!
//! **Vertices.** Every vertex keeps its index (with the UV of the first chart that uses
//! it); a vertex shared by further charts gets a copy per chart, appended (same position
//! and normal); normals missing from the mesh are generated first, on the
//! mesh's own vertices, as the area-weighted face average (`shapes`), so the split does
//! not change the shading. Triangle order is kept: every technique traces the same
//! triangles as before, and triangles of zero area get their chart's corner.

use super::{Scene, Shape};
use glam::{Vec2, Vec3};
use std::collections::HashMap;

/// Gutter between charts and at the square's border, as a fraction of the UV square's
/// side (8 texels of a 2048-texel tile).
pub const CHART_GUTTER: f32 = 1.0 / 256.0;

/// A mesh whose vertices carry generated UVs ([`chart_mesh`]).
#[derive(Clone, Debug, PartialEq)]
pub struct ChartedMesh {
    /// Vertex positions (the input's, repeated where a vertex is split between charts).
    pub positions: Vec<Vec3>,
    /// Per-vertex normals (the input's, or generated as the area-weighted face average).
    pub normals: Vec<Vec3>,
    /// Per-vertex UVs in `[0, 1]^2`.
    pub uvs: Vec<Vec2>,
    /// The input's triangles, in the input's order, over the new vertices.
    pub indices: Vec<[u32; 3]>,
    /// Number of charts.
    pub charts: usize,
}

/// The projection axis a triangle's chart uses: `2 k + (n_k < 0)` for the component `k`
/// of the geometric normal `n` of largest magnitude; `None` for a triangle of zero (or
/// non-finite) area in f32.
fn chart_axis(p: [Vec3; 3]) -> Option<u8> {
    let n = (p[1] - p[0]).cross(p[2] - p[0]);
    if !n.is_finite() || n == Vec3::ZERO {
        return None;
    }
    let a = n.abs();
    let k = if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    };
    Some(2 * k as u8 + (n[k] < 0.0) as u8)
}

/// `p` projected along `axis` ([`chart_axis`]): the two other coordinates in cyclic order
/// (so the projected signed area is `n_k`), the first negated for a negative axis (so it
/// is `|n_k| > 0` for every triangle of the chart).
fn project(p: Vec3, axis: u8) -> Vec2 {
    let k = (axis / 2) as usize;
    let (u, v) = (p[(k + 1) % 3], p[(k + 2) % 3]);
    if axis & 1 == 1 {
        Vec2::new(-u, v)
    } else {
        Vec2::new(u, v)
    }
}

/// Whether some edge of the counter-clockwise triangle `a` has all of `b` on or outside
/// it. A shared edge's endpoints give exactly 0 (the same bits on both sides), so two
/// triangles meeting along an edge are separated by it.
fn separated(a: &[Vec2; 3], b: &[Vec2; 3]) -> bool {
    (0..3).any(|e| {
        let (p, q) = (a[e], a[(e + 1) % 3]);
        let d = q - p;
        b.iter().all(|&x| d.perp_dot(x - p) <= 0.0)
    })
}

/// Whether the interiors of two counter-clockwise 2D triangles overlap (separating axes:
/// the six edge normals).
fn interiors_overlap(a: &[Vec2; 3], b: &[Vec2; 3]) -> bool {
    !separated(a, b) && !separated(b, a)
}

/// The projected triangles of the chart being grown, for overlap queries: a loose grid of
/// levels, a triangle stored at the level whose cells are at least as large as its box
/// (cell `base 2^level`), under the cell of its box's lower corner.
struct ChartGrid {
    base: f32,
    cells: HashMap<(u8, i64, i64), Vec<u32>>,
    /// Per level: its triangles (scanned instead of the cells when there are fewer).
    levels: Vec<Vec<u32>>,
}

impl ChartGrid {
    fn new(base: f32) -> ChartGrid {
        ChartGrid {
            base,
            cells: HashMap::new(),
            levels: vec![Vec::new(); 64],
        }
    }

    fn clear(&mut self) {
        self.cells.clear();
        self.levels.iter_mut().for_each(Vec::clear);
    }

    fn level(&self, lo: Vec2, hi: Vec2) -> u8 {
        let e = (hi - lo).max_element() / self.base;
        if e <= 1.0 || !e.is_finite() {
            0
        } else {
            (e.log2().ceil() as u32).min(63) as u8
        }
    }

    fn cell(&self, level: u8, p: Vec2) -> (i64, i64) {
        let size = self.base * (level as f32).exp2();
        ((p.x / size).floor() as i64, (p.y / size).floor() as i64)
    }

    fn insert(&mut self, t: u32, lo: Vec2, hi: Vec2) {
        let l = self.level(lo, hi);
        let (x, y) = self.cell(l, lo);
        self.cells.entry((l, x, y)).or_default().push(t);
        self.levels[l as usize].push(t);
    }

    /// Calls `f` with every stored triangle whose box may overlap `[lo, hi]`, stopping at
    /// the first `true`.
    fn any(&self, lo: Vec2, hi: Vec2, mut f: impl FnMut(u32) -> bool) -> bool {
        for (l, list) in self.levels.iter().enumerate() {
            if list.is_empty() {
                continue;
            }
            let l = l as u8;
            // a stored box starts in its cell and is at most one cell long
            let (x0, y0) = self.cell(l, lo);
            let (x1, y1) = self.cell(l, hi);
            let (x0, y0) = (x0 - 1, y0 - 1);
            let cells = (x1 - x0 + 1).saturating_mul(y1 - y0 + 1);
            if cells < 0 || cells as u64 > list.len() as u64 {
                if list.iter().any(|&t| f(t)) {
                    return true;
                }
                continue;
            }
            for y in y0..=y1 {
                for x in x0..=x1 {
                    if let Some(ts) = self.cells.get(&(l, x, y)) {
                        if ts.iter().any(|&t| f(t)) {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// A chart: its projection axis and its triangles' projected bounds (scene units).
struct Chart {
    axis: u8,
    lo: Vec2,
    hi: Vec2,
}

/// Splits the triangles into charts (see the module doc): per triangle its chart, or
/// `u32::MAX` for a triangle of zero area.
fn grow_charts(positions: &[Vec3], indices: &[[u32; 3]]) -> (Vec<u32>, Vec<Chart>) {
    let n = indices.len();
    let corners = |t: usize| indices[t].map(|i| positions[i as usize]);
    let axis: Vec<Option<u8>> = (0..n).map(|t| chart_axis(corners(t))).collect();
    // vertices welded by exact position, so that split vertices still join their charts
    let mut weld: HashMap<[u32; 3], u32> = HashMap::with_capacity(positions.len());
    let welded: Vec<u32> = positions
        .iter()
        .map(|p| {
            let next = weld.len() as u32;
            *weld.entry(p.to_array().map(f32::to_bits)).or_insert(next)
        })
        .collect();
    // edges as (welded endpoints, triangle), sorted: equal keys are a shared edge
    let mut edges: Vec<(u64, u32)> = Vec::with_capacity(3 * n);
    for (t, tri) in indices.iter().enumerate() {
        if axis[t].is_none() {
            continue;
        }
        for e in 0..3 {
            let (a, b) = (welded[tri[e] as usize], welded[tri[(e + 1) % 3] as usize]);
            if a != b {
                edges.push((((a.min(b) as u64) << 32) | a.max(b) as u64, t as u32));
            }
        }
    }
    edges.sort_unstable();
    let mut neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
    for group in edges.chunk_by(|a, b| a.0 == b.0) {
        // a non-manifold edge of many triangles links them as a chain
        let all = group.len() <= 8;
        for (i, &(_, a)) in group.iter().enumerate() {
            for &(_, b) in &group[i + 1..] {
                neighbours[a as usize].push(b);
                neighbours[b as usize].push(a);
                if !all {
                    break;
                }
            }
        }
    }
    // the smallest triangle box: the finest level of the overlap grid
    let base = (0..n)
        .filter(|&t| axis[t].is_some())
        .map(|t| {
            let p = corners(t);
            (p[0].max(p[1]).max(p[2]) - p[0].min(p[1]).min(p[2])).max_element()
        })
        .filter(|e| *e > 0.0 && e.is_finite())
        .fold(f32::INFINITY, f32::min);
    let mut grid = ChartGrid::new(if base.is_finite() { base } else { 1.0 });
    let mut chart_of = vec![u32::MAX; n];
    let mut charts: Vec<Chart> = Vec::new();
    let mut queue = std::collections::VecDeque::new();
    for seed in 0..n {
        let Some(ax) = axis[seed] else { continue };
        if chart_of[seed] != u32::MAX {
            continue;
        }
        let c = charts.len() as u32;
        grid.clear();
        let mut chart = Chart {
            axis: ax,
            lo: Vec2::splat(f32::INFINITY),
            hi: Vec2::splat(f32::NEG_INFINITY),
        };
        let projected = |t: usize| corners(t).map(|p| project(p, ax));
        let take = |t: usize, grid: &mut ChartGrid, chart: &mut Chart| {
            let q = projected(t);
            let (lo, hi) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
            grid.insert(t as u32, lo, hi);
            chart.lo = chart.lo.min(lo);
            chart.hi = chart.hi.max(hi);
        };
        chart_of[seed] = c;
        take(seed, &mut grid, &mut chart);
        queue.push_back(seed as u32);
        while let Some(t) = queue.pop_front() {
            for &m in &neighbours[t as usize] {
                let m = m as usize;
                if chart_of[m] != u32::MAX || axis[m] != Some(ax) {
                    continue;
                }
                let q = projected(m);
                let (lo, hi) = (q[0].min(q[1]).min(q[2]), q[0].max(q[1]).max(q[2]));
                let overlaps = grid.any(lo, hi, |o| {
                    let r = projected(o as usize);
                    let (rlo, rhi) = (r[0].min(r[1]).min(r[2]), r[0].max(r[1]).max(r[2]));
                    lo.x < rhi.x
                        && rlo.x < hi.x
                        && lo.y < rhi.y
                        && rlo.y < hi.y
                        && interiors_overlap(&q, &r)
                });
                if overlaps {
                    continue; // left for a chart of its own
                }
                chart_of[m] = c;
                take(m, &mut grid, &mut chart);
                queue.push_back(m as u32);
            }
        }
        charts.push(chart);
    }
    (chart_of, charts)
}

/// Shelf-packs boxes of sizes `sizes` (tallest first, left to right in rows) with `gap`
/// between them and around them; returns each box's lower corner and the packing's side.
fn shelf_pack(sizes: &[Vec2], gap: f32) -> (Vec<Vec2>, f32) {
    let mut order: Vec<usize> = (0..sizes.len()).collect();
    order.sort_by(|&a, &b| sizes[b].y.total_cmp(&sizes[a].y).then(a.cmp(&b)));
    let area: f64 = sizes
        .iter()
        .map(|s| (s.x + gap) as f64 * (s.y + gap) as f64)
        .sum();
    let widest = sizes.iter().map(|s| s.x).fold(0.0f32, f32::max);
    let row_width = (area.sqrt() as f32).max(widest) + gap;
    let mut at = vec![Vec2::ZERO; sizes.len()];
    let (mut x, mut y, mut row_h, mut used_w) = (gap, gap, 0.0f32, 0.0f32);
    for &i in &order {
        let s = sizes[i];
        if x > gap && x + s.x + gap > row_width + gap {
            y += row_h + gap;
            x = gap;
            row_h = 0.0;
        }
        at[i] = Vec2::new(x, y);
        x += s.x + gap;
        row_h = row_h.max(s.y);
        used_w = used_w.max(x);
    }
    (at, used_w.max(y + row_h + gap))
}

/// UV charts for a mesh without UVs (see the module doc); `normals` may be empty (they
/// are then generated). `None` when an index is out of range (validation refuses such a
/// mesh) or the mesh has no triangle.
pub fn chart_mesh(
    positions: &[Vec3],
    normals: &[Vec3],
    indices: &[[u32; 3]],
) -> Option<ChartedMesh> {
    let nv = positions.len();
    if indices.is_empty() || indices.iter().flatten().any(|&i| i as usize >= nv) {
        return None;
    }
    let normals = if normals.len() == nv {
        normals.to_vec()
    } else {
        super::shapes::flat_vertex_normals(positions, indices)
    };
    let (chart_of, charts) = grow_charts(positions, indices);
    let sizes: Vec<Vec2> = charts
        .iter()
        .map(|c| (c.hi - c.lo).max(Vec2::ZERO))
        .collect();
    // the gutter is a fraction of the packing's side, which depends on the gutter: a few
    // rounds settle it
    let mut gap = CHART_GUTTER
        * (sizes
            .iter()
            .map(|s| s.x as f64 * s.y as f64)
            .sum::<f64>()
            .sqrt() as f32);
    let (mut at, mut side) = shelf_pack(&sizes, gap);
    for _ in 0..4 {
        let want = CHART_GUTTER * side;
        if !(want > 0.0) || (want - gap).abs() <= 0.01 * want {
            break;
        }
        gap = want;
        (at, side) = shelf_pack(&sizes, gap);
    }
    let scale = if side > 0.0 && side.is_finite() {
        1.0 / side
    } else {
        0.0
    };
    let uv_of = |t: usize, p: Vec3| -> Vec2 {
        match chart_of[t] {
            u32::MAX => Vec2::splat(0.5 * CHART_GUTTER),
            c => {
                let ch = &charts[c as usize];
                let q = project(p, ch.axis) - ch.lo + at[c as usize];
                (q * scale).clamp(Vec2::ZERO, Vec2::ONE)
            }
        }
    };
    // every vertex keeps its index, with the UV of the chart that first uses it; a copy
    // per further chart is appended
    let mut out = ChartedMesh {
        positions: positions.to_vec(),
        normals,
        uvs: vec![Vec2::splat(0.5 * CHART_GUTTER); nv],
        indices: Vec::with_capacity(indices.len()),
        charts: charts.len(),
    };
    let mut home = vec![None::<u32>; nv];
    let mut copies: HashMap<(u32, u32), u32> = HashMap::new();
    for (t, tri) in indices.iter().enumerate() {
        let c = chart_of[t];
        let new = tri.map(|i| {
            let p = positions[i as usize];
            match home[i as usize] {
                None => {
                    home[i as usize] = Some(c);
                    out.uvs[i as usize] = uv_of(t, p);
                    i
                }
                Some(h) if h == c => i,
                Some(_) => *copies.entry((c, i)).or_insert_with(|| {
                    out.positions.push(p);
                    out.normals.push(out.normals[i as usize]);
                    out.uvs.push(uv_of(t, p));
                    out.positions.len() as u32 - 1
                }),
            }
        });
        out.indices.push(new);
    }
    Some(out)
}

/// Gives every mesh object of `scene` that has no UVs generated UV charts
/// ([`chart_mesh`]); returns one line per object changed, for a loader's warnings.
pub fn generate_missing_uvs(scene: &mut Scene) -> Vec<String> {
    let mut notes = Vec::new();
    for (k, o) in scene.objects.iter_mut().enumerate() {
        let Shape::Mesh {
            positions,
            normals,
            uvs,
            indices,
        } = &mut o.shape
        else {
            continue;
        };
        if !uvs.is_empty() {
            continue;
        }
        let Some(m) = chart_mesh(positions, normals, indices) else {
            continue;
        };
        notes.push(format!(
            "objects[{k}] ('{}'): no UVs; generated {} UV chart{} ({} vertices from {}) for \
             caustic maps",
            o.name,
            m.charts,
            if m.charts == 1 { "" } else { "s" },
            m.positions.len(),
            positions.len()
        ));
        *positions = m.positions.into();
        *normals = m.normals.into();
        *uvs = m.uvs.into();
        *indices = m.indices.into();
    }
    notes
}

/// Meshes without UVs for the tests here and in `frame::receivers::atlas::layout` (welded, as a file
/// without texture coordinates has them).
#[cfg(test)]
pub(crate) mod test_meshes {
    use crate::scene::shapes::tessellate;
    use crate::scene::Shape;
    use glam::Vec3;
    use std::collections::HashMap;

    /// A tessellated shape with the copies of each position welded into one vertex.
    fn welded(shape: &Shape) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let m = tessellate(shape);
        let mut weld: HashMap<[u32; 3], u32> = HashMap::new();
        let mut positions = Vec::new();
        let map: Vec<u32> = m
            .positions
            .iter()
            .map(|p| {
                *weld
                    .entry(p.to_array().map(f32::to_bits))
                    .or_insert_with(|| {
                        positions.push(*p);
                        positions.len() as u32 - 1
                    })
            })
            .collect();
        let indices = m
            .indices
            .iter()
            .map(|t| t.map(|i| map[i as usize]))
            .collect();
        (positions, indices)
    }

    /// A UV sphere of `segments`, welded (its seam and poles do not weld exactly:
    /// sin(2 pi) != 0).
    pub fn sphere(segments: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        welded(&Shape::Sphere {
            center: Vec3::new(0.3, 1.0, -0.2),
            radius: 0.7,
            segments,
        })
    }

    /// A box of 8 shared corners (12 triangles).
    pub fn cuboid() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        welded(&Shape::Cuboid {
            min: Vec3::new(-2.0, -0.5, -1.0),
            max: Vec3::new(2.0, 0.0, 1.0),
        })
    }

    /// Two and a half turns of a ramp, every normal close to +y: one axis, one connected
    /// strip, overlapping itself in projection after each turn.
    pub fn spiral_ramp() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let (turns, steps) = (2.5f32, 120u32);
        let mut positions = Vec::new();
        for i in 0..=steps {
            let a = turns * std::f32::consts::TAU * i as f32 / steps as f32;
            let y = 0.05 * a;
            for r in [1.0f32, 2.0] {
                positions.push(Vec3::new(r * a.cos(), y, -r * a.sin()));
            }
        }
        let mut indices = Vec::new();
        for i in 0..steps {
            let (a, b, c, d) = (2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3);
            indices.push([a, b, d]);
            indices.push([a, d, c]);
        }
        (positions, indices)
    }

    /// A repeated index, three collinear points and a proper triangle.
    pub fn degenerate() -> (Vec<Vec3>, Vec<[u32; 3]>) {
        (
            vec![
                Vec3::ZERO,
                Vec3::X,
                Vec3::new(1.0, 0.0, 1.0),
                Vec3::new(2.0, 0.0, 0.0),
            ],
            vec![[0, 0, 1], [0, 1, 3], [0, 2, 1]],
        )
    }
}

#[cfg(test)]
mod tests {
    use super::test_meshes;
    use super::*;

    /// Charts for a mesh, checked: every input triangle keeps its corners and normals, and
    /// every UV lies in `[0, 1]^2`.
    fn checked(positions: &[Vec3], indices: &[[u32; 3]]) -> ChartedMesh {
        let m = chart_mesh(positions, &[], indices).expect("charts");
        let normals = crate::scene::shapes::flat_vertex_normals(positions, indices);
        assert_eq!(m.indices.len(), indices.len());
        for (a, b) in indices.iter().zip(&m.indices) {
            for k in 0..3 {
                assert_eq!(positions[a[k] as usize], m.positions[b[k] as usize]);
                assert_eq!(normals[a[k] as usize], m.normals[b[k] as usize]);
            }
        }
        for uv in &m.uvs {
            assert!(
                uv.cmpge(Vec2::ZERO).all() && uv.cmple(Vec2::ONE).all(),
                "{uv}"
            );
        }
        m
    }

    #[test]
    fn a_welded_box_gets_six_charts() {
        let (positions, indices) = test_meshes::cuboid();
        assert_eq!(positions.len(), 8);
        let m = checked(&positions, &indices);
        assert_eq!(m.charts, 6);
        assert_eq!(
            m.positions.len(),
            24,
            "each corner split between its three faces"
        );
    }

    #[test]
    fn a_sphere_gets_six_caps() {
        // (the seam splits two caps and the pole's copies cross each other by ~1e-8 and
        // become charts of a few triangles)
        let (positions, indices) = test_meshes::sphere(48);
        checked(&positions, &indices);
        let (chart_of, charts) = grow_charts(&positions, &indices);
        let mut count = vec![0usize; charts.len()];
        chart_of.iter().for_each(|&c| count[c as usize] += 1);
        let mut largest: Vec<usize> = (0..charts.len()).collect();
        largest.sort_by_key(|&c| std::cmp::Reverse(count[c]));
        let in_caps: usize = largest[..7].iter().map(|&c| count[c]).sum();
        assert!(in_caps * 100 > 95 * indices.len(), "{count:?}");
        let mut axes: Vec<u8> = largest[..7].iter().map(|&c| charts[c].axis).collect();
        axes.sort();
        axes.dedup();
        assert_eq!(axes, [0, 1, 2, 3, 4, 5], "one cap per axis");
    }

    #[test]
    fn a_spiral_ramp_is_split_where_it_would_overlap_itself() {
        let (positions, indices) = test_meshes::spiral_ramp();
        let m = checked(&positions, &indices);
        assert!(m.charts >= 3, "{} charts", m.charts);
    }

    #[test]
    fn degenerate_triangles_and_bad_indices_do_not_panic() {
        let (positions, indices) = test_meshes::degenerate();
        checked(&positions, &indices);
        assert!(chart_mesh(&positions, &[], &[[0, 1, 9]]).is_none());
        assert!(chart_mesh(&positions, &[], &[]).is_none());
    }

    #[test]
    fn meshes_with_uvs_are_left_alone_and_the_others_say_so() {
        let mut scene = crate::scene::builtin::builtin("sphere").unwrap();
        let (positions, indices) = test_meshes::sphere(16);
        scene.objects[0].shape = Shape::Mesh {
            positions: positions.into(),
            normals: Vec::new().into(),
            uvs: Vec::new().into(),
            indices: indices.into(),
        };
        let before = scene.clone();
        let notes = generate_missing_uvs(&mut scene);
        assert_eq!(notes.len(), 1, "{notes:?}");
        assert!(notes[0].starts_with("objects[0]") && notes[0].contains("UV charts"));
        assert_eq!(scene.objects[1..], before.objects[1..]);
        assert!(
            generate_missing_uvs(&mut scene).is_empty(),
            "UVs now present"
        );
        scene.validate().unwrap();
    }
}
