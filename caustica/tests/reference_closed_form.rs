//! References against a closed form: the ball-lens focus. `sphere-sun` with a paraxial
//! projection volume (half-width 0.1 = 0.2 R) focuses at f = n R / (2 (n - 1)) = 0.75
//! below the centre, y = 0.25 (paraxial optics). The floor is placed at y = 0.15, 0.25
//! and 0.35 and a reference is computed for each, seen by a camera that looks under the
//! sphere at 35 degrees. The radius enclosing half the caustic's flux on the floor must be
//! smallest at the focal plane: by similar triangles the blur radius grows as
//! 0.1 * |y - 0.25| / 0.75 = 0.013 away from focus (about 5 pixels here), while at focus
//! only spherical aberration at h <= 0.2 R remains (longitudinal ~ (h/R)^2 f / 2 = 0.015,
//! a blur of ~0.002, plus a pixel of 0.002). Threshold: the focal half-flux radius below
//! 0.6 x the defocused ones.

use caustica::reference::{compute, scene_hash, ReferenceSpec};
use caustica_core::scene::{builtin, Aabb, Light, Shape};
use caustica_cpu::CpuBackend;
use glam::Vec3;

fn half_flux_radius_at(floor_y: f32) -> f64 {
    let mut scene = builtin::sphere_sun();
    if let Light::Directional {
        projection_volume, ..
    } = &mut scene.lights[0]
    {
        *projection_volume = Some(Aabb {
            min: Vec3::new(-0.1, 0.45, -0.1),
            max: Vec3::new(0.1, 1.55, 0.1),
        });
    }
    for o in &mut scene.objects {
        if let Shape::Quad { center, .. } = &mut o.shape {
            center.y = floor_y;
        }
    }
    // 35 deg above the floor, 3 units away: under the sphere (any elevation below ~47 deg
    // clears it) and steep enough that a pixel covers 0.004 of floor.
    let (sin, cos) = 35f32.to_radians().sin_cos();
    scene.camera.position = Vec3::new(0.0, floor_y + 3.0 * sin, 3.0 * cos);
    scene.camera.target = Vec3::new(0.0, floor_y, 0.0);
    scene.camera.fov_y_deg = 6.0;
    let spec = ReferenceSpec {
        technique: "sspm".into(),
        width: 160,
        height: 160,
        photons_side: 256,
        target_noise: 0.05,
        max_frames: 4,
    };
    let mut b = CpuBackend::new().unwrap();
    let hash = scene_hash(&scene, &spec);
    let r = compute(&scene, &spec, &mut b, &mut |_, _, _| {}, hash).unwrap();
    assert!(r.image.all_finite());
    // Unproject every pixel onto the floor plane and weight it by its flux: radiance x
    // the surface area the pixel covers (pixel pencil cut by the plane y = floor_y).
    let mut cam = scene.camera.clone();
    cam.width = spec.width;
    cam.height = spec.height;
    let g = caustica_core::device::layout::GpuCamera::from_camera(&cam);
    let origin = Vec3::from(g.position);
    let mut samples: Vec<(f64, f64)> = Vec::new(); // (radius, flux weight)
    for py in 0..spec.height {
        for px in 0..spec.width {
            let d = caustica_core::device::layout::camera_ray(&g, px, py);
            if d.y >= 0.0 {
                continue;
            }
            let t = (floor_y - origin.y) / d.y;
            let p = origin + t * d;
            let depth = t * d.dot(Vec3::from(g.forward));
            let area = caustica_core::math::footprint::pixel_surface_area(
                caustica_core::math::footprint::pixel_footprint(
                    depth,
                    g.width,
                    g.height,
                    g.tan_half_fov_x,
                    g.tan_half_fov_y,
                ),
                d.dot(Vec3::from(g.forward)),
                d.y,
            );
            let l = r.image.at(px, py)[1] as f64;
            let w = l * area as f64;
            if w > 0.0 {
                samples.push(((p.x as f64).hypot(p.z as f64), w));
            }
        }
    }
    // radius that encloses half of the caustic flux (robust to the faint halo of photons
    // that left the sphere after internal reflections)
    let total: f64 = samples.iter().map(|s| s.1).sum();
    assert!(total > 0.0, "no caustic seen with the floor at {floor_y}");
    samples.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut acc = 0.0;
    for (r, w) in samples {
        acc += w;
        if acc >= 0.5 * total {
            return r;
        }
    }
    f64::INFINITY
}

#[test]
fn reference_focus_is_at_the_ball_lens_focal_plane() {
    let near = half_flux_radius_at(0.35);
    let focus = half_flux_radius_at(0.25);
    let far = half_flux_radius_at(0.15);
    eprintln!("half-flux caustic radius: y=0.35 {near:.4}, y=0.25 {focus:.4}, y=0.15 {far:.4}");
    assert!(
        focus < 0.6 * near && focus < 0.6 * far,
        "focus {focus}, near {near}, far {far}"
    );
}
