//! A dynamic scene, per backend: every frame the light and the caustic
//! casters move (`set_lights` and `set_object_transforms`: the casters are instances over
//! the two-level acceleration structure), beside a static object of about a million
//! triangles that is never rebuilt. Prints, medians over the frames: the host time of
//! the updates (both calls, including the writes they submit and, on Vulkan, the TLAS
//! build they wait for), the frame's host wall time and the sum of its device passes,
//! and the same frame with nothing moving (still and moving frames interleaved). Target (H200): updates < 0.5 ms on the host,
//! the moving frame within 10% of the static one. Every moving frame also deforms the
//! first caster (`set_object_vertices`: a wobble of its vertices, its BLAS rebuilt in
//! place, timed apart from the other updates).
//!
//! `cargo bench -p caustica --bench dynamic_frame`
//! Environment: `CAUSTICA_BENCH_BACKENDS=wgpu,vulkan` (default: every backend that opens
//! here), `CAUSTICA_BENCH_FRAMES=N` (default 10), `CAUSTICA_BENCH_SIZE=WxH` (default
//! 1920x1080), `CAUSTICA_BENCH_PHOTONS=N` (grid side, default 2048),
//! `CAUSTICA_BENCH_BIG=N` (segments of the static sphere, default 1024: N^2 triangles),
//! `CAUSTICA_BENCH_DEFORM=0` (moves only: no caster deformed per frame).

mod common;
use caustica::glam::{Quat, Vec3};
use caustica::scene::builtin::builtin;
use caustica::scene::{Light, Object, Scene, Shape, Transform};
use caustica::techniques::create;
use caustica::BACKEND_NAMES;
use common::{env_or, median, opened_backends};
use std::time::Instant;

/// `name` with its specular spheres as instances and a static diffuse sphere of
/// `big^2` triangles beside them.
fn dynamic_scene(name: &str, w: u32, h: u32, big: u32) -> Scene {
    let mut s = builtin(name).expect("built-in scene");
    s.camera.width = w;
    s.camera.height = h;
    for o in &mut s.objects {
        let specular = s.materials[&o.material].is_specular();
        if let (true, Shape::Sphere { center, .. }) = (specular, &mut o.shape) {
            o.transform = Some(Transform::from_translation(std::mem::replace(
                center,
                Vec3::ZERO,
            )));
        }
    }
    let diffuse = s
        .materials
        .iter()
        .find(|(_, m)| !m.is_specular())
        .map(|(n, _)| n.clone())
        .expect("a diffuse material");
    s.objects.push(Object {
        name: "static heavy sphere".into(),
        material: diffuse,
        shape: Shape::Sphere {
            center: Vec3::new(0.6, 0.25, -0.6),
            radius: 0.2,
            segments: big,
        },
        transform: None,
    });
    s
}

/// Frame `i`'s vertices of object `k` (object space): its tessellated mesh wobbling.
fn wobble(scene: &Scene, k: usize, i: usize) -> Vec<Vec3> {
    let phase = i as f32 * 0.7;
    caustica::scene::shapes::tessellate(&scene.objects[k].shape)
        .positions
        .iter()
        .map(|p| *p * (1.0 + 0.05 * (phase + 9.0 * p.y).sin()))
        .collect()
}

/// Frame `i`'s lights and instance placements: the light circles, the casters sway.
fn motion(scene: &Scene, i: usize) -> (Vec<Light>, Vec<(usize, Transform)>) {
    let a = i as f32 * 0.05;
    let mut lights = scene.lights.clone();
    for l in &mut lights {
        if let Light::Point { position, .. } | Light::Spot { position, .. } = l {
            *position += 0.1 * Vec3::new(a.cos(), 0.0, a.sin());
        }
    }
    let moves = scene
        .objects
        .iter()
        .enumerate()
        .filter_map(|(k, o)| {
            let t = o.transform?;
            Some((
                k,
                Transform {
                    translation: t.translation + 0.05 * Vec3::new(a.sin(), 0.0, a.cos()),
                    rotation: Quat::from_rotation_y(a),
                    ..t
                },
            ))
        })
        .collect();
    (lights, moves)
}

fn main() {
    let frames: usize = env_or("CAUSTICA_BENCH_FRAMES", "10")
        .parse()
        .unwrap_or(10)
        .max(1);
    let side: u32 = env_or("CAUSTICA_BENCH_PHOTONS", "2048")
        .parse()
        .unwrap_or(2048);
    let big: u32 = env_or("CAUSTICA_BENCH_BIG", "1024").parse().unwrap_or(1024);
    let deform_each_frame = env_or("CAUSTICA_BENCH_DEFORM", "1") != "0";
    let size = env_or("CAUSTICA_BENCH_SIZE", "1920x1080");
    let (w, h) = size
        .split_once('x')
        .and_then(|(a, b)| Some((a.parse().ok()?, b.parse().ok()?)))
        .unwrap_or((1920u32, 1080u32));
    let wanted = env_or("CAUSTICA_BENCH_BACKENDS", &BACKEND_NAMES.join(","));
    println!(
        "Dynamic Sspm frame, {w}x{h}, {side}x{side} photons, static sphere of {big}x{big} \
         segments, median of {frames} frames after one warm-up"
    );
    for (name, mut backend) in opened_backends(&wanted) {
        let device = backend.capabilities().device;
        for scene_name in ["sphere", "cornell"] {
            let scene = dynamic_scene(scene_name, w, h, big);
            let settings = serde_json::json!({ "photons_w": side, "photons_h": side });
            let t0 = Instant::now();
            let mut t = match create("sspm", backend.as_mut(), &scene, &settings) {
                Ok(t) => t,
                Err(e) => {
                    println!("{name}/{scene_name}: {e}");
                    continue;
                }
            };
            let build_ms = t0.elapsed().as_secs_f64() * 1e3;
            // still and moving frames interleaved (a still frame, then an update and a
            // frame), so that a GPU still ramping its clocks up slows both alike
            let (mut still, mut still_dev) = (Vec::new(), Vec::new());
            let (mut update, mut moving, mut moving_dev) = (Vec::new(), Vec::new(), Vec::new());
            let mut deform = Vec::new();
            let caster = scene
                .objects
                .iter()
                .position(|o| o.transform.is_some())
                .filter(|_| deform_each_frame);
            let caster_triangles = caster.map_or(0, |k| {
                caustica::scene::limits::tessellated_size(&scene.objects[k].shape).1
            });
            let mut failed = None;
            for i in 0..=frames {
                match t.frame(backend.as_mut(), &mut |_| {}) {
                    Ok(s) if i > 0 => {
                        still.push(s.frame_ms);
                        still_dev.push(s.pass_ms.values().sum::<f64>());
                    }
                    Ok(_) => {}
                    Err(e) => failed = Some(e.to_string()),
                }
                let (lights, moves) = motion(&scene, i + 1);
                let t0 = Instant::now();
                let r = t
                    .set_lights(backend.as_mut(), &lights)
                    .and_then(|_| t.set_object_transforms(backend.as_mut(), &moves));
                let ms = t0.elapsed().as_secs_f64() * 1e3;
                let t1 = Instant::now();
                let r = r.and_then(|_| match caster {
                    Some(k) => {
                        t.set_object_vertices(backend.as_mut(), k, &wobble(&scene, k, i), &[])
                    }
                    None => Ok(()),
                });
                let deform_ms = t1.elapsed().as_secs_f64() * 1e3;
                match r.and_then(|_| t.frame(backend.as_mut(), &mut |_| {})) {
                    Ok(s) if i > 0 => {
                        update.push(ms);
                        deform.push(deform_ms);
                        moving.push(s.frame_ms);
                        moving_dev.push(s.pass_ms.values().sum::<f64>());
                    }
                    Ok(_) => {}
                    Err(e) => failed = Some(e.to_string()),
                }
            }
            let _ = t.free(backend.as_mut());
            if let Some(e) = failed {
                println!("{name}/{scene_name}: {e}");
                continue;
            }
            let (s, m) = (median(&mut still), median(&mut moving));
            let deformed = match caster {
                Some(_) => format!(
                    "deform one caster ({caster_triangles} triangles) {:.3} ms host",
                    median(&mut deform)
                ),
                None => "no deformation".into(),
            };
            println!(
                "\n{name} on {device} / {scene_name} + static sphere: build {build_ms:.1} ms; \
                 update (lights + instances) {:.3} ms host; {deformed}; frame {m:.3} ms host / \
                 {:.3} ms passes moving{}, {s:.3} ms host / {:.3} ms passes still ({:+.1}%)",
                median(&mut update),
                median(&mut moving_dev),
                if caster.is_some() {
                    " and deformed"
                } else {
                    ""
                },
                median(&mut still_dev),
                100.0 * (m / s - 1.0)
            );
        }
    }
}
