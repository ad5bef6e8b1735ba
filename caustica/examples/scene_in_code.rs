//! Build a scene in code: a glass ball and a mirror cube on a floor under a spot light,
//! validated, then rendered on the CPU backend and written as PNG.
//!
//! `cargo run --release -p caustica --example scene_in_code -- [WxH] [PHOTONS]`

use caustica::output::write_png;
use caustica::scene::{Camera, Light, Material, Object, Scene, Shape};
use caustica::TechniqueSettings;
use caustica::{open_backend, Output, Sspm, SspmSettings};
use glam::Vec3;
use std::collections::BTreeMap;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (w, h) = match args.first() {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("size is WxH")?;
            (a.parse()?, b.parse()?)
        }
        None => (480, 270),
    };
    let side: u32 = args.get(1).map_or(Ok(512), |s| s.parse())?;

    // scene units are metres here; intensities in W/sr, albedos in [0, 1]
    let materials = BTreeMap::from([
        (
            "floor".to_string(),
            Material::Diffuse {
                albedo: Vec3::splat(0.8),
            },
        ),
        (
            "glass".to_string(),
            Material::Dielectric {
                ior: 1.5,
                cauchy_b: 0.0,
                absorption: Vec3::ZERO,
                ior_model: Default::default(),
            },
        ),
        (
            "mirror".to_string(),
            Material::Mirror {
                reflectance: Vec3::splat(0.95),
            },
        ),
    ]);
    let object = |name: &str, material: &str, shape: Shape| Object {
        name: name.into(),
        material: material.into(),
        shape,
        transform: None,
    };
    let scene = Scene {
        name: "ball-and-cube".into(),
        description: "a glass ball (focusing a caustic below it) and a mirror cube on a floor under a spot light".into(),
        camera: Camera {
            position: Vec3::new(0.3, 3.4, 3.0),
            target: Vec3::new(-0.1, 0.2, 0.0),
            up: Vec3::Y,
            fov_y_deg: 40.0,
            width: w,
            height: h,
        },
        materials,
        objects: vec![
            object("floor", "floor", Shape::Quad { center: Vec3::ZERO, u: Vec3::X * 3.0, v: Vec3::NEG_Z * 3.0 }),
            object("ball", "glass", Shape::Sphere { center: Vec3::new(-0.6, 1.0, 0.0), radius: 0.5, segments: 128 }),
            object("cube", "mirror", Shape::Cuboid { min: Vec3::new(0.4, 0.0, -0.3), max: Vec3::new(1.0, 0.6, 0.3) }),
        ],
        lights: vec![Light::Spot {
            position: Vec3::new(-0.3, 3.5, 0.0),
            direction: Vec3::new(0.0, -1.0, 0.0),
            intensity: Vec3::splat(8.0),
            inner_angle_deg: 20.0,
            outer_angle_deg: 35.0,
        }],
    };
    // a bad scene is a list of problems with field paths, never a panic
    if let Err(problems) = scene.validate() {
        for p in problems {
            eprintln!("{}: {}", p.path, p.reason);
        }
        return Err("invalid scene".into());
    }

    let mut backend = open_backend("cpu")?;
    let settings = SspmSettings::default().with_photons(side, side);
    let mut sspm = Sspm::new(backend.as_mut(), &scene, settings)?;
    let stats = sspm.frame(backend.as_mut(), &mut |_| {})?;
    let image = sspm.read_output(backend.as_mut(), Output::Composite)?;
    sspm.free(backend.as_mut())?;
    std::fs::create_dir_all("out/examples")?;
    write_png(
        std::path::Path::new("out/examples/ball-and-cube.png"),
        &image,
        1.0,
    )?;
    println!(
        "{} photons stored; wrote out/examples/ball-and-cube.png",
        stats.photons_stored
    );
    Ok(())
}
