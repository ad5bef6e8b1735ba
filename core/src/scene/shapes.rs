//! Tessellation of the procedural shapes into triangle meshes with per-vertex normals
//! (outward for closed shapes) and uvs in [0, 1]^2.

use super::{Shape, TriangleMesh, Wave};
use glam::{Vec2, Vec3};
use std::f32::consts::{PI, TAU};

/// Triangulates `shape`. Pure and deterministic.
pub fn tessellate(shape: &Shape) -> TriangleMesh {
    let mut m = TriangleMesh::default();
    match shape {
        Shape::Mesh {
            positions,
            normals,
            uvs,
            indices,
        } => {
            m.positions = positions.to_vec();
            m.indices = indices.to_vec();
            m.uvs = if uvs.len() == positions.len() {
                uvs.to_vec()
            } else {
                vec![Vec2::ZERO; positions.len()]
            };
            m.normals = if normals.len() == positions.len() {
                normals.to_vec()
            } else {
                flat_vertex_normals(positions, indices)
            };
        }
        // not loaded: validation refuses it before anything tessellates it
        Shape::ObjFile { .. } => {}
        Shape::Sphere {
            center,
            radius,
            segments,
        } => sphere(&mut m, *center, *radius, (*segments).max(3)),
        Shape::Quad { center, u, v } => quad(&mut m, *center - *u - *v, 2.0 * *u, 2.0 * *v),
        Shape::Cuboid { min, max } => cuboid(&mut m, *min, *max),
        Shape::Ring {
            center,
            radius,
            thickness,
            height,
            segments,
        } => ring(
            &mut m,
            *center,
            *radius,
            *thickness,
            *height,
            (*segments).max(3),
        ),
        Shape::Prism {
            center,
            side,
            length,
        } => prism(&mut m, *center, *side, *length),
        Shape::HeightField {
            center,
            size,
            resolution,
            waves,
        } => height_field(&mut m, *center, *size, (*resolution).max(1), waves),
    }
    m
}

/// Per-vertex normal = normalised sum of the (area-weighted) face normals around it.
pub(crate) fn flat_vertex_normals(positions: &[Vec3], indices: &[[u32; 3]]) -> Vec<Vec3> {
    let mut n = vec![Vec3::ZERO; positions.len()];
    for t in indices {
        let [a, b, c] = t.map(|i| i as usize);
        if a >= positions.len() || b >= positions.len() || c >= positions.len() {
            continue;
        }
        let f = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        for i in [a, b, c] {
            n[i] += f;
        }
    }
    n.into_iter().map(|v| v.normalize_or(Vec3::Y)).collect()
}

/// Parallelogram from `origin` spanned by `du`, `dv`, normal `du x dv`, own vertices.
fn quad(m: &mut TriangleMesh, origin: Vec3, du: Vec3, dv: Vec3) {
    // Unit edges first, so that tiny quads (|du x dv|^2 below f32's range) keep their
    // normal.
    let n = du
        .normalize_or_zero()
        .cross(dv.normalize_or_zero())
        .normalize_or(Vec3::Y);
    let base = m.positions.len() as u32;
    for (s, t) in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
        m.positions.push(origin + s * du + t * dv);
        m.normals.push(n);
        m.uvs.push(Vec2::new(s, t));
    }
    m.indices.push([base, base + 1, base + 2]);
    m.indices.push([base, base + 2, base + 3]);
}

fn sphere(m: &mut TriangleMesh, c: Vec3, r: f32, segments: u32) {
    let rings = (segments / 2).max(2);
    let base = m.positions.len() as u32;
    for i in 0..=rings {
        let theta = PI * i as f32 / rings as f32;
        for j in 0..=segments {
            let phi = TAU * j as f32 / segments as f32;
            let n = Vec3::new(
                theta.sin() * phi.cos(),
                theta.cos(),
                theta.sin() * phi.sin(),
            );
            m.positions.push(c + r * n);
            m.normals.push(n);
            m.uvs.push(Vec2::new(
                j as f32 / segments as f32,
                i as f32 / rings as f32,
            ));
        }
    }
    let row = segments + 1;
    for i in 0..rings {
        for j in 0..segments {
            let a = base + i * row + j;
            let b = a + row;
            // Skip the zero-area triangles at the poles.
            if i != 0 {
                m.indices.push([a, a + 1, b]);
            }
            if i != rings - 1 {
                m.indices.push([a + 1, b + 1, b]);
            }
        }
    }
}

/// A box's six faces. Their uvs do not overlap (a caustic map addresses a receiver by
/// its uvs, `frame::receivers::atlas::layout`): face `k` fills cell `(k mod 3, k div 3)` of a 3 x 2
/// grid over `[0, 1]^2`.
fn cuboid(m: &mut TriangleMesh, lo: Vec3, hi: Vec3) {
    let d = hi - lo;
    let (x, y, z) = (Vec3::X * d.x, Vec3::Y * d.y, Vec3::Z * d.z);
    let faces = [
        (lo, y, x),     // -z
        (lo + z, x, y), // +z
        (lo, z, y),     // -x
        (lo + x, y, z), // +x
        (lo, x, z),     // -y
        (lo + y, z, x), // +y
    ];
    for (k, (origin, du, dv)) in faces.into_iter().enumerate() {
        let first = m.uvs.len();
        quad(m, origin, du, dv);
        let cell = Vec2::new((k % 3) as f32 / 3.0, (k / 3) as f32 / 2.0);
        for uv in &mut m.uvs[first..] {
            *uv = cell + *uv * Vec2::new(1.0 / 3.0, 0.5);
        }
    }
}

fn ring(m: &mut TriangleMesh, c: Vec3, r: f32, thick: f32, h: f32, segments: u32) {
    let ro = r + thick;
    for j in 0..segments {
        let (p0, p1) = (
            TAU * j as f32 / segments as f32,
            TAU * (j + 1) as f32 / segments as f32,
        );
        let d0 = Vec3::new(p0.cos(), 0.0, p0.sin());
        let d1 = Vec3::new(p1.cos(), 0.0, p1.sin());
        let u0 = j as f32 / segments as f32;
        let u1 = (j + 1) as f32 / segments as f32;
        let up = Vec3::Y * h;
        // outer wall (normals outward), inner wall (normals towards the axis),
        // top and bottom annuli.
        let mut face = |ps: [Vec3; 4], ns: [Vec3; 4]| {
            let base = m.positions.len() as u32;
            for (k, (p, n)) in ps.iter().zip(ns).enumerate() {
                m.positions.push(*p);
                m.normals.push(n);
                m.uvs.push(Vec2::new(
                    if k == 0 || k == 3 { u0 } else { u1 },
                    if k < 2 { 0.0 } else { 1.0 },
                ));
            }
            m.indices.push([base, base + 1, base + 2]);
            m.indices.push([base, base + 2, base + 3]);
        };
        face(
            [c + d0 * ro, c + d1 * ro, c + d1 * ro + up, c + d0 * ro + up],
            [d0, d1, d1, d0],
        );
        face(
            [c + d1 * r, c + d0 * r, c + d0 * r + up, c + d1 * r + up],
            [-d1, -d0, -d0, -d1],
        );
        face(
            [
                c + d0 * r + up,
                c + d0 * ro + up,
                c + d1 * ro + up,
                c + d1 * r + up,
            ],
            [Vec3::Y; 4],
        );
        face(
            [c + d1 * r, c + d1 * ro, c + d0 * ro, c + d0 * r],
            [-Vec3::Y; 4],
        );
    }
}

fn prism(m: &mut TriangleMesh, c: Vec3, side: f32, length: f32) {
    // Equilateral triangle in xy centred on its centroid, apex up.
    let h = side * 3f32.sqrt() / 2.0;
    let tri = [
        Vec3::new(-side / 2.0, -h / 3.0, 0.0),
        Vec3::new(side / 2.0, -h / 3.0, 0.0),
        Vec3::new(0.0, 2.0 * h / 3.0, 0.0),
    ];
    let dz = Vec3::Z * length;
    let back = c - dz * 0.5;
    for k in 0..3 {
        let (a, b) = (tri[k], tri[(k + 1) % 3]);
        // Side face from a to b extruded along +z: for a counter-clockwise triangle in xy,
        // (b - a) x z points away from the centroid.
        quad(m, back + a, b - a, dz);
    }
    // end caps
    let base = m.positions.len() as u32;
    for (z, n) in [(-0.5f32, -Vec3::Z), (0.5, Vec3::Z)] {
        for v in tri {
            m.positions.push(c + v + Vec3::Z * (z * length));
            m.normals.push(n);
            m.uvs.push(Vec2::new(v.x / side + 0.5, v.y / h + 1.0 / 3.0));
        }
    }
    m.indices.push([base, base + 2, base + 1]);
    m.indices.push([base + 3, base + 4, base + 5]);
}

fn height_field(m: &mut TriangleMesh, c: Vec3, size: Vec2, res: u32, waves: &[Wave]) {
    let height = |x: f32, z: f32| -> (f32, Vec2) {
        // value and gradient d/dx, d/dz
        let mut y = 0.0;
        let mut g = Vec2::ZERO;
        for w in waves {
            let k = w.direction.normalize_or(Vec2::X) * (TAU / w.wavelength.max(1e-12));
            let arg = k.x * x + k.y * z + w.phase;
            y += w.amplitude * arg.sin();
            g += w.amplitude * arg.cos() * k;
        }
        (y, g)
    };
    let base = m.positions.len() as u32;
    for i in 0..=res {
        for j in 0..=res {
            let s = j as f32 / res as f32;
            let t = i as f32 / res as f32;
            let x = (s - 0.5) * size.x;
            let z = (t - 0.5) * size.y;
            let (y, g) = height(x, z);
            m.positions.push(c + Vec3::new(x, y, z));
            m.normals.push(Vec3::new(-g.x, 1.0, -g.y).normalize());
            m.uvs.push(Vec2::new(s, t));
        }
    }
    let row = res + 1;
    for i in 0..res {
        for j in 0..res {
            let a = base + i * row + j;
            m.indices.push([a, a + row, a + 1]);
            m.indices.push([a + 1, a + row, a + row + 1]);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check_outward(m: &TriangleMesh, center: Vec3) {
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let ng = (b - a).cross(c - a);
            let centroid = (a + b + c) / 3.0;
            if ng.length() > 0.0 {
                assert!(
                    ng.dot(centroid - center) > 0.0,
                    "inward-wound triangle at {centroid}"
                );
            }
        }
        for (p, n) in m.positions.iter().zip(&m.normals) {
            assert!(n.dot(*p - center) >= -1e-5, "inward normal at {p}");
        }
    }

    #[test]
    fn closed_shapes_face_outward() {
        let c = Vec3::new(0.5, 1.0, -0.2);
        check_outward(
            &tessellate(&Shape::Sphere {
                center: c,
                radius: 0.5,
                segments: 16,
            }),
            c,
        );
        check_outward(
            &tessellate(&Shape::Cuboid {
                min: c - 0.3,
                max: c + 0.4,
            }),
            c + 0.05,
        );
        check_outward(
            &tessellate(&Shape::Prism {
                center: c,
                side: 1.0,
                length: 2.0,
            }),
            c,
        );
    }

    #[test]
    fn sphere_has_no_degenerate_triangles() {
        let m = tessellate(&Shape::Sphere {
            center: Vec3::ZERO,
            radius: 1.0,
            segments: 24,
        });
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            assert!((b - a).cross(c - a).length() > 1e-6);
        }
    }
}
