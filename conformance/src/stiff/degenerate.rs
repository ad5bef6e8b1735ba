//! The degenerate group: degenerate and invalid geometry, zero-size lights, and the image
//! and photon-count extremes (1x1 and 8192x8192 pixels, 1 and 2^26 photons).

use super::runner::{outcome, run_checked, universal};
use super::scenes::{obj, settings, sized, sphere_scene};
use super::{Outcome, GRID};
use crate::harness::measure::relative_l2;
use crate::harness::verdict::Verdict;
use crate::techniques::sspm;
use caustica_core::backend::{Backend, BackendError};
use caustica_core::device::layout::GBufferPlaneTexel;
use caustica_core::scene::builtin;
use caustica_core::scene::{Aabb, Light, Material, Scene, Shape};
use caustica_core::TraceSettings;
use caustica_core::{Sspm, SspmSettings};
use glam::Vec3;

/// The plane as an explicit mesh, optionally with degenerate triangles and a repeated
/// vertex added.
fn plane_mesh(degenerate: bool) -> Shape {
    let mut positions = vec![
        Vec3::new(-2.0, 0.0, 2.0),
        Vec3::new(2.0, 0.0, 2.0),
        Vec3::new(2.0, 0.0, -2.0),
        Vec3::new(-2.0, 0.0, -2.0),
    ];
    let mut indices = vec![[0, 1, 2], [0, 2, 3]];
    if degenerate {
        positions.push(Vec3::new(2.0, 0.0, 2.0)); // repeat of vertex 1
        positions.push(Vec3::new(0.0, 0.0, 0.0)); // on the diagonal 0-2
        indices.extend([[0, 0, 1], [1, 4, 2], [0, 5, 2], [3, 3, 3], [4, 1, 4]]);
    }
    Shape::Mesh {
        positions: positions.into(),
        normals: Vec::new().into(),
        uvs: Vec::new().into(),
        indices: indices.into(),
    }
}

pub(super) fn degenerate_triangles(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut clean = sphere_scene();
    clean.objects[0].shape = plane_mesh(false);
    let mut scene = clean.clone();
    scene.objects[0].shape = plane_mesh(true);
    let st = settings(GRID);
    let mut v = Verdict::new("degenerate triangles");
    let f = run_checked(b, &scene, &st, &mut v)?;
    let c = sspm::render_frame(b, &clean, &st)?;
    let mut cv = sspm::compare_frames(&clean, &c, &f);
    cv.what = "vs clean mesh".into();
    cv.notes.retain(|n| n.contains("relative L2"));
    let e = relative_l2(&c.raw.pixels, &f.raw.pixels, None);
    v.absorb(cv);
    outcome(format!("rel L2 vs clean mesh {e:.1e}"), v)
}

pub(super) fn nan_normals(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut v = Verdict::new("nan normals");
    let mut rejected = Vec::new();
    let variants: [(&str, Vec3, bool); 3] = [
        ("NaN normal", Vec3::new(f32::NAN, 1.0, 0.0), true),
        ("zero normal", Vec3::ZERO, true),
        ("NaN position", Vec3::new(0.0, f32::NAN, 0.0), false),
    ];
    for (what, bad, is_normal) in variants {
        let mut scene = sphere_scene();
        let Shape::Mesh {
            positions, indices, ..
        } = plane_mesh(false)
        else {
            unreachable!()
        };
        let mut normals = vec![Vec3::Y; positions.len()];
        let mut positions = positions.to_vec();
        if is_normal {
            normals[2] = bad;
        } else {
            positions[2] = bad;
        }
        scene.objects[0].shape = Shape::Mesh {
            positions: positions.into(),
            normals: normals.into(),
            uvs: Vec::new().into(),
            indices,
        };
        let field = if is_normal {
            "objects[0].shape.normals[2]"
        } else {
            "objects[0].shape.positions[2]"
        };
        match caustica_core::Sspm::new(b, &scene, settings(4)) {
            Ok(s) => {
                v.fail(format!("{what}: scene accepted"));
                let _ = s.free(b);
            }
            Err(e) => {
                let msg = e.to_string();
                v.check(msg.contains(field), || {
                    format!("{what}: error does not name {field}: {msg}")
                });
                rejected.push(msg);
            }
        }
    }
    v.note(rejected.join(" | "));
    outcome(format!("{} of 3 rejected", rejected.len()), v)
}

pub(super) fn zero_size_lights(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut scene = sphere_scene();
    let p = Vec3::new(0.0, 1.0, 0.0);
    scene.lights = vec![
        Light::Directional {
            direction: -Vec3::Y,
            irradiance: Vec3::ONE,
            projection_volume: Some(Aabb { min: p, max: p }),
        },
        Light::Spot {
            position: Vec3::new(0.0, 3.0, 0.0),
            direction: -Vec3::Y,
            intensity: Vec3::splat(10.0),
            inner_angle_deg: 0.0,
            outer_angle_deg: 1e-4,
        },
        Light::Point {
            position: Vec3::new(0.0, 3.0, 0.0),
            intensity: Vec3::ZERO,
        },
    ];
    let mut v = Verdict::new("zero-size lights");
    let grid = 16;
    let f = run_checked(b, &scene, &settings(grid), &mut v)?;
    let s = &f.stats;
    // Only the spot emits: the directional light's point-sized volume gives its photons
    // a rectangle of no area, the zero-power light has nothing to emit; the plan says so.
    v.check(s.photons_emitted <= (grid * grid) as u64, || {
        format!(
            "{} photons emitted: a light without emission emitted",
            s.photons_emitted
        )
    });
    let says = |light: u32, why: &str| {
        s.plan.as_ref().is_some_and(|p| {
            p.lights
                .iter()
                .any(|l| l.light == light && !l.emits && l.reason.contains(why))
        })
    };
    v.check(says(0, "flat") && says(2, "zero power"), || {
        format!(
            "the plan does not say why lights 0 and 2 emit nothing: {:?}",
            s.plan.as_ref().map(|p| &p.lights)
        )
    });
    outcome(
        format!(
            "emitted {} photons, {:.2e} W, stored {:.2e} W",
            s.photons_emitted, s.emitted_flux[1], s.stored_flux[1]
        ),
        v,
    )
}

pub(super) fn image_1x1(b: &mut dyn Backend) -> Result<Outcome, String> {
    let scene = sized(builtin::sphere(), (1, 1));
    let mut v = Verdict::new("1x1");
    let f = run_checked(b, &scene, &settings(GRID), &mut v)?;
    outcome(format!("pixel {:.4}", f.composite.pixels[0][1]), v)
}

pub(super) fn photons_1(b: &mut dyn Backend) -> Result<Outcome, String> {
    let scene = sphere_scene();
    let mut v = Verdict::new("1 photon");
    let f = run_checked(b, &scene, &settings(1), &mut v)?;
    v.check(f.stats.photons_emitted == 1, || {
        format!("{} photons emitted", f.stats.photons_emitted)
    });
    outcome(
        format!(
            "stored {} deposited {}",
            f.stats.photons_stored, f.stats.photons_deposited
        ),
        v,
    )
}

/// A cheap scene for the huge cases: a vertical mirror quad standing on the plane's far
/// side, point light above.
/// The built-in sphere scene at `w x h` with the sphere replaced by a mirror quad: a
/// handful of triangles, so that a frame's cost is its pixels (large-frame cases).
pub fn cheap_scene((w, h): (u32, u32)) -> Scene {
    let mut s = sized(builtin::sphere(), (w, h));
    s.materials.insert(
        "mirror".into(),
        Material::Mirror {
            reflectance: Vec3::splat(0.9),
        },
    );
    s.objects[1] = obj(
        "mirror",
        "mirror",
        Shape::Quad {
            // Vertical, facing +z: light from (0, 3, 0) reflects down onto the plane.
            center: Vec3::new(0.0, 1.0, -1.0),
            u: Vec3::new(1.0, 0.0, 0.0),
            v: Vec3::new(0.0, 0.5, 0.0),
        },
    );
    s
}

pub(super) fn image_8192(b: &mut dyn Backend) -> Result<Outcome, String> {
    let scene = cheap_scene((8192, 8192));
    let mut v = Verdict::new("8192^2");
    // The G-buffer is stored in planes of 16 bytes a pixel (GBUFFER_PLANES), as large as
    // the frame's images and the photon map's largest planes: at 8192^2 pixels
    // 16 B x 2^26 = 1 GiB, the largest per-pixel buffer, and the first one created. It
    // fits NVIDIA's Vulkan (maxStorageBufferRange = 2^32 - 1) and wgpu there, so the frame
    // renders; a device whose largest buffer or storage binding is smaller (lavapipe:
    // 128 MiB) must refuse the frame in `Sspm::new` with OutOfMemory naming the buffer
    // and the limit: a typed error, never a panic or an out-of-range binding.
    let plane_bytes = 8192u64 * 8192 * std::mem::size_of::<GBufferPlaneTexel>() as u64;
    let largest = b.capabilities().max_buffer_bytes;
    if plane_bytes > largest {
        return match Sspm::new(b, &scene, settings(64)) {
            Err(caustica_core::Error::Backend(BackendError::OutOfMemory { bytes, what })) => {
                v.check(bytes == plane_bytes && what.contains("gbuffer"), || {
                    format!("OutOfMemory for {bytes} bytes of '{what}', not a G-buffer plane")
                });
                outcome(format!("OutOfMemory: G-buffer plane {bytes} B > {largest} B"), v)
            }
            Err(e) => Err(format!("expected OutOfMemory for a G-buffer plane, got: {e}")),
            Ok(_) => Err(format!(
                "a {plane_bytes}-byte G-buffer plane was accepted by a device binding {largest} bytes"
            )),
        };
    }
    // No cpu comparison frame here (it would double the ~10 GiB of frame buffers).
    let (stats, imgs) = crate::render(b, &scene, settings(64), 8192, 8192);
    for (i, im) in imgs.iter().enumerate() {
        v.check(im.all_finite(), || format!("image {i} has NaN/Inf"));
    }
    for c in 0..3 {
        v.check(
            stats.stored_flux[c]
                <= stats.emitted_flux[c] + 0.5 * stats.flux_quantum * stats.photons_stored as f64,
            || format!("stored flux[{c}] exceeds emitted"),
        );
    }
    v.check(stats.photons_deposited > 0, || "nothing deposited".into());
    outcome(
        format!(
            "deposited {}, {:.0} ms",
            stats.photons_deposited, stats.frame_ms
        ),
        v,
    )
}

/// Photon buffer bytes per photon (`core::gpu::Photon`).
const PHOTON_BYTES: u64 = 32;

pub(super) fn photons_2_26(b: &mut dyn Backend) -> Result<Outcome, String> {
    let scene = cheap_scene((16, 9));
    let batch = 1u32 << 20;
    let run = |b: &mut dyn Backend, per_batch: u32| {
        let st = SspmSettings {
            trace: TraceSettings {
                max_photons_per_batch: per_batch,
                ..settings(8192).trace
            },
            ..settings(8192)
        };
        sspm::render_frame(b, &scene, &st)
    };
    let mut v = Verdict::new("2^26 photons");
    let f = run(b, batch)?;
    v.absorb(universal(&scene, &f));
    let s = &f.stats;
    v.check(s.photons_emitted == 1 << 26, || {
        format!("{} photons emitted", s.photons_emitted)
    });
    v.check(s.batches == 64, || format!("{} batches", s.batches));
    // Stated limit: photon buffer 32 B x 2^20 = 32 MiB; everything else is the 16x9
    // frame's buffers and the scene (< 1 MiB).
    let limit = PHOTON_BYTES * batch as u64 + (1 << 20);
    v.check(s.bytes_allocated <= limit, || {
        format!("{} bytes allocated, limit {limit}", s.bytes_allocated)
    });
    // The same photons in 4 batches of 2^24: integer sums are order-independent.
    let g = run(b, 1 << 24)?;
    v.check(
        g.stats.stored_flux == s.stored_flux && g.stats.photons_stored == s.photons_stored,
        || {
            format!(
                "stored flux {:?} / {} photons, 4-batch run {:?} / {}",
                s.stored_flux, s.photons_stored, g.stats.stored_flux, g.stats.photons_stored
            )
        },
    );
    outcome(
        format!(
            "{} batches, {} MiB, stored {}",
            s.batches,
            s.bytes_allocated >> 20,
            s.photons_stored
        ),
        v,
    )
}
