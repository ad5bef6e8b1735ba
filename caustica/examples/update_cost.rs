//! The host time of an update, without frames: `frame_loop`'s moves (the light circles,
//! the `sphere` scene's glass ball bobs and turns as an instance) on a backend, as the
//! medians of the ball's world vertices placed on the host (`world_vertices`, what a
//! build does), of their boxes alone (`placed_bounds`: the positions placed and bounded
//! from their coordinate columns, nothing written: what a move computes on the host, the
//! device placing the vertices), of the move of the instances alone
//! (`SceneInstances::move_instances`) and of each technique's `set_lights` and
//! `set_object_transforms`.
//! Run: `cargo run --release -p caustica --example update_cost -- [BACKEND] [UPDATES]
//! [TECHNIQUE,...]` (defaults: cpu, 60, the four techniques).

use caustica::glam;
use caustica::scene::builtin::builtin;
use caustica::scene::{Light, Shape, Transform};
use caustica_core::device::device_scene::{world_vertices, DeviceScene};
use caustica_core::device::placement::placed_bounds;
use std::hint::black_box;
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v.get(v.len() / 2).copied().unwrap_or(0.0)
}

/// Milliseconds since `t`.
fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let backend = a.first().map_or("cpu", |s| s.as_str());
    let n: usize = a.get(1).map_or(Ok(60), |s| s.parse())?;
    let techniques = a
        .get(2)
        .map_or("sspm,caustic-map,adaptive-caustics,photon-gi", |s| {
            s.as_str()
        });
    let mut b = caustica::open_backend(backend)?;
    let mut scene = builtin("sphere").ok_or("no sphere scene")?;
    scene.camera.width = 320;
    scene.camera.height = 180;
    let ball = 1;
    let Shape::Sphere { center, .. } = &mut scene.objects[ball].shape else {
        return Err("sphere's object 1 is its glass ball".into());
    };
    let home = std::mem::replace(center, glam::Vec3::ZERO);
    scene.objects[ball].transform = Some(Transform::from_translation(home));
    // update f of n: frame_loop's
    let phase = |f: usize| f as f32 / n as f32 * std::f32::consts::TAU;
    let placement = |f: usize| Transform {
        translation: home + glam::Vec3::new(0.0, 0.15 * phase(f).sin(), 0.0),
        rotation: glam::Quat::from_rotation_y(phase(f)),
        scale: glam::Vec3::ONE,
    };

    let mut instances = DeviceScene::build(&scene, Default::default())?.instances;
    let level = instances
        .levels
        .iter()
        .find(|l| l.object == Some(ball))
        .ok_or("the ball is an instance")?
        .clone();
    // the ball is the scene's one instance: its object-space vertices come first
    let count = level.vertex_count as usize;
    let local = instances.object_vertices[..count].to_vec();
    let (mut placed, mut boxed, mut moved) = (Vec::new(), Vec::new(), Vec::new());
    for f in 0..n {
        let t = Instant::now();
        let (_, placed_box) = black_box(world_vertices(&placement(f), black_box(&local)));
        placed.push(ms(t));
        let t = Instant::now();
        let (b, _) = black_box(placed_bounds(
            &placement(f),
            black_box(&instances.columns),
            0..count,
            &level.unused_vertices,
        ));
        boxed.push(ms(t));
        if b.min != placed_box.min || b.max != placed_box.max {
            return Err("the positions' box differs from the placement's".into());
        }
        let t = Instant::now();
        black_box(instances.move_instances(&[(ball, placement(f))])?);
        moved.push(ms(t));
    }
    println!(
        "{backend}: the ball's {} vertices placed {:.3} ms (their box alone {:.3} ms), the \
         instances moved {:.3} ms (medians of {n})",
        level.vertex_count,
        median(placed),
        median(boxed),
        median(moved)
    );

    for technique in techniques.split(',') {
        let mut settings = serde_json::json!({"frame": {"photons_w": 64, "photons_h": 64}});
        if technique.contains("caustic") {
            settings["atlas"] = serde_json::json!({ "atlas_size": 512 });
        }
        let mut t = caustica::techniques::create(technique, b.as_mut(), &scene, &settings)?;
        let (mut lights_ms, mut moves_ms) = (Vec::new(), Vec::new());
        for f in 0..n {
            let t0 = Instant::now();
            let mut lights = scene.lights.clone();
            if let Light::Point { position, .. } = &mut lights[0] {
                *position += glam::Vec3::new(0.4 * phase(f).cos(), 0.0, 0.4 * phase(f).sin());
            }
            t.set_lights(b.as_mut(), &lights)?;
            lights_ms.push(ms(t0));
            let t1 = Instant::now();
            t.set_object_transforms(b.as_mut(), &[(ball, placement(f))])?;
            moves_ms.push(ms(t1));
        }
        t.free(b.as_mut())?;
        println!(
            "  {technique}: set_lights {:.3} ms, set_object_transforms {:.3} ms",
            median(lights_ms),
            median(moves_ms)
        );
    }
    Ok(())
}
