//! What replacing one object's shape costs a host (`Technique::set_object_shape`) against
//! creating the technique anew: `spot-glass` (its 50,176-triangle glass ball in the static
//! level) with a small glass box added as an instance, whose shape becomes a sphere (another
//! triangle count). Prints, per technique, the host time of `create`, of
//! `set_object_shape` and of the first frame after each (device work included).
//! Run: `cargo run --release -p caustica --example shape_update -- [BACKEND] [PHOTONS]`.

use caustica::glam::Vec3;
use caustica::scene::builtin::builtin;
use caustica::scene::{Object, Shape, Transform};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let backend_name = args.first().map_or("cpu", |s| s.as_str());
    let side: u32 = args.get(1).map_or(Ok(256), |s| s.parse())?;
    let mut backend = caustica::open_backend(backend_name)?;
    let mut scene = builtin("spot-glass").ok_or("spot-glass")?;
    scene.camera.width = 320;
    scene.camera.height = 180;
    scene.objects.push(Object {
        name: "box".into(),
        material: "glass".into(),
        shape: Shape::Cuboid {
            min: Vec3::splat(-0.2),
            max: Vec3::splat(0.2),
        },
        transform: Some(Transform::from_translation(Vec3::new(-1.0, 0.8, -0.5))),
    });
    let k = scene.objects.len() - 1;
    let sphere = Shape::Sphere {
        center: Vec3::ZERO,
        radius: 0.25,
        segments: 64,
    };
    println!(
        "{backend_name}, spot-glass + an instance, 320x180, {side}^2 photons (ms, host wall clock)"
    );
    println!("| technique | create | first frame | set_object_shape | frame after |");
    println!("| --- | ---: | ---: | ---: | ---: |");
    for name in ["sspm", "caustic-map", "adaptive-caustics", "photon-gi"] {
        let settings = serde_json::json!({ "frame": { "photons_w": side, "photons_h": side } });
        let ms = |t: Instant| t.elapsed().as_secs_f64() * 1e3;
        let t = Instant::now();
        let mut tech = caustica::techniques::create(name, backend.as_mut(), &scene, &settings)?;
        let create = ms(t);
        let t = Instant::now();
        tech.frame(backend.as_mut(), &mut |_| {})?;
        let first = ms(t);
        let t = Instant::now();
        tech.set_object_shape(backend.as_mut(), k, &sphere)?;
        let replace = ms(t);
        let t = Instant::now();
        tech.frame(backend.as_mut(), &mut |_| {})?;
        let after = ms(t);
        println!("| {name} | {create:.1} | {first:.1} | {replace:.1} | {after:.1} |");
        tech.free(backend.as_mut())?;
    }
    Ok(())
}
