//! `primary_gbuffer`: texel by texel on the fixture's scene and camera. Materials must agree
//! on [`GBUFFER_MATERIAL_AGREEMENT`] of the pixels; positions, depths, normals and uvs within
//! the ulp-derived tolerances on [`GBUFFER_GEOMETRY_AGREEMENT`] of the rest; fields copied
//! from the material table exactly.

use crate::harness::fixture::Fixture;
use crate::harness::measure::{pct, v3};
use crate::harness::tolerance::{
    GBUFFER_GEOMETRY_AGREEMENT, GBUFFER_MATERIAL_AGREEMENT, GBUFFER_MIN_COS, GBUFFER_POSITION_REL,
    NORMAL_GRADIENT, UV_GRADIENT,
};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;
use caustica_core::device::device_scene::DeviceScene;
use caustica_core::device::layout::{primary_ray, GBufferTexel, GpuCamera, NO_MATERIAL};
use caustica_core::math::packing::unpack_unit_vector;
use glam::Vec3;

/// Two codes of a snorm16 octahedral normal, on the unit sphere (see the comparison).
const GEOMETRIC_NORMAL_CODES: f32 = 2.5e-4;

/// Whether `n` is, within [`GEOMETRIC_NORMAL_CODES`] (either sign: it faces the camera),
/// the geometric normal of a triangle of `scene` that point `p` lies on, within `tol` of
/// it (world space).
fn normal_of_a_triangle_at(scene: &DeviceScene, p: Vec3, n: Vec3, tol: f32) -> bool {
    scene.triangles.iter().any(|t| {
        let [a, b, c] = t
            .indices
            .map(|i| Vec3::from(scene.vertices[i as usize].position));
        let ng = (b - a).cross(c - a).normalize_or_zero();
        let close = |m: Vec3| (m - n).abs().max_element() <= GEOMETRIC_NORMAL_CODES;
        (close(ng) || close(-ng)) && point_triangle_distance(p, [a, b, c]) <= tol
    })
}

/// Distance from `p` to triangle `t` (world space).
fn point_triangle_distance(p: Vec3, t: [Vec3; 3]) -> f32 {
    let segment = |a: Vec3, b: Vec3| {
        let ab = b - a;
        let s = ((p - a).dot(ab) / ab.length_squared().max(f32::MIN_POSITIVE)).clamp(0.0, 1.0);
        (a + s * ab - p).length()
    };
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let inside = (0..3).all(|k| {
        let (a, b) = (t[k], t[(k + 1) % 3]);
        (b - a).cross(p - a).dot(n) >= 0.0
    });
    if inside && n.length_squared() > 0.0 {
        (p - t[0]).dot(n.normalize()).abs()
    } else {
        segment(t[0], t[1])
            .min(segment(t[1], t[2]))
            .min(segment(t[2], t[0]))
    }
}

/// Texel-by-texel comparison of two G-buffers of camera `cam` (reference first); also
/// returns which pixels agree (material equal and geometry within tolerance).
pub fn compare_gbuffers(
    scene: &DeviceScene,
    cam: &GpuCamera,
    reference: &[GBufferTexel],
    candidate: &[GBufferTexel],
) -> (Verdict, Vec<bool>) {
    let mut v = Verdict::new("primary_gbuffer");
    let mut agree = vec![false; reference.len()];
    if !v.check(reference.len() == candidate.len(), || {
        format!("{} texels, expected {}", candidate.len(), reference.len())
    }) {
        return (v, agree);
    }
    let n = reference.len() as u64;
    let (mut same_material, mut hits, mut geometry_ok) = (0u64, 0u64, 0u64);
    let mut worst = (0.0f32, String::new());
    let mut exact_mismatch = Vec::new();
    for (i, (a, b)) in reference.iter().zip(candidate).enumerate() {
        if a.material != b.material {
            continue;
        }
        same_material += 1;
        let (x, y) = (i as u32 % cam.width, i as u32 / cam.width);
        if a.material == NO_MATERIAL {
            // a miss writes depth 0, no flags; the rest is unspecified
            if b.depth == 0.0 && b.flags == 0 {
                agree[i] = true;
            } else if exact_mismatch.len() < 3 {
                exact_mismatch.push(format!(
                    "({x},{y}) miss with depth {} flags {}",
                    b.depth, b.flags
                ));
            }
            continue;
        }
        hits += 1;
        // Exactly copied fields: material table entries and flags derived from them.
        if a.flags != b.flags || a.albedo != b.albedo {
            if exact_mismatch.len() < 3 {
                exact_mismatch.push(format!(
                    "({x},{y}) flags/albedo {:?}/{:?} vs cpu {:?}/{:?}",
                    b.flags, b.albedo, a.flags, a.albedo
                ));
            }
            continue;
        }
        let ray = primary_ray(cam, x, y).1;
        let cos = ray.dot(v3(a.normal)).abs().max(GBUFFER_MIN_COS);
        let tol =
            GBUFFER_POSITION_REL * (a.view_distance / cos + v3(a.position).abs().max_element());
        let (ng_a, ng_b) = (
            unpack_unit_vector(a.geometric_normal),
            unpack_unit_vector(b.geometric_normal),
        );
        let errs = [
            (v3(a.position) - v3(b.position)).abs().max_element() / tol,
            (a.depth - b.depth).abs() / tol,
            (a.view_distance - b.view_distance).abs() / tol,
            (v3(a.normal) - v3(b.normal)).abs().max_element() / (1e-5 + NORMAL_GRADIENT * tol),
            // the geometric normal, packed in two snorm16 (octahedral): the cross product
            // of the triangle's edges rounds a few ulps apart, which can move a component
            // across a code boundary; one code is 2/32767 of the octahedral square, at
            // most ~1.2e-4 on the sphere, so two codes. A ray through a shared edge may
            // hit either triangle (both at the same t; the traversal order breaks the tie,
            // and it differs between backends): position, uv and shading normal are
            // continuous across the edge, the geometric normal is not. So a candidate
            // normal outside the codes is accepted when it is, within the codes, the
            // geometric normal of a triangle that the candidate's hit point lies on
            // (within the position tolerance): the other triangle of the edge.
            {
                let e = (ng_a - ng_b).abs().max_element()
                    / (GEOMETRIC_NORMAL_CODES + NORMAL_GRADIENT * tol);
                if e > 1.0 && normal_of_a_triangle_at(scene, v3(b.position), ng_b, tol) {
                    0.0
                } else {
                    e
                }
            },
            (glam::Vec2::from(a.uv) - glam::Vec2::from(b.uv))
                .abs()
                .max_element()
                / (1e-5 + UV_GRADIENT * tol),
        ];
        let e = errs.iter().fold(
            0.0f32,
            |m, &x| if x.is_nan() { f32::INFINITY } else { m.max(x) },
        );
        if e <= 1.0 {
            geometry_ok += 1;
            agree[i] = true;
        }
        if e > worst.0 {
            worst = (
                e,
                format!(
                    "({x},{y}): position {:?} vs cpu {:?}, normal {:?} vs {:?}, depth {} vs {}",
                    b.position, a.position, b.normal, a.normal, b.depth, a.depth
                ),
            );
        }
    }
    v.note(format!(
        "material agrees on {same_material}/{n} ({:.3}%); geometry within tolerance on \
         {geometry_ok}/{hits} hit pixels; worst error {:.3} of tolerance",
        pct(same_material, n),
        worst.0
    ));
    v.check(
        same_material as f64 >= GBUFFER_MATERIAL_AGREEMENT * n as f64,
        || {
            format!(
                "material id agrees on only {:.3}% of pixels (need {}%)",
                pct(same_material, n),
                100.0 * GBUFFER_MATERIAL_AGREEMENT
            )
        },
    );
    v.check(exact_mismatch.is_empty(), || {
        format!(
            "fields that must be exact differ: {}",
            exact_mismatch.join("; ")
        )
    });
    v.check(
        geometry_ok as f64 >= GBUFFER_GEOMETRY_AGREEMENT * hits as f64,
        || {
            format!(
                "geometry within tolerance on only {:.3}% of same-material pixels (need {}%); \
             worst {:.3e} x tolerance at {}",
                pct(geometry_ok, hits),
                100.0 * GBUFFER_GEOMETRY_AGREEMENT,
                worst.0,
                worst.1
            )
        },
    );
    (v, agree)
}

/// `primary_gbuffer` on the fixture's scene and camera.
pub fn check_gbuffer(
    fx: &Fixture,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let a = fx.run_gbuffer(r)?;
    let b = fx.run_gbuffer(c)?;
    Ok(compare_gbuffers(&fx.ds, &fx.camera, &a, &b).0)
}
