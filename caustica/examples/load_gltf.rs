//! Load a glTF 2.0 file (or, without an argument, a built-in scene written as glTF and
//! read back), print what caustica could not represent, render it on the CPU backend.
//!
//! `cargo run --release -p caustica --example load_gltf -- [FILE.gltf|FILE.glb] [WxH] [PHOTONS]`

use caustica::gltf_scene::{load_gltf, scene_to_gltf};
use caustica::output::write_png;
use caustica::scene::builtin::builtin;
use caustica::TechniqueSettings;
use caustica::{open_backend, Output, Sspm, SspmSettings};
use std::path::PathBuf;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = match args.first() {
        Some(p) => PathBuf::from(p),
        None => {
            // a built-in scene as glTF, for other tools too: `caustica scenes --export`
            let p = std::env::temp_dir().join("caustica-prism.gltf");
            std::fs::write(&p, scene_to_gltf(&builtin("prism").expect("built-in")))?;
            p
        }
    };
    let (w, h) = match args.get(1) {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("size is WxH")?;
            (a.parse()?, b.parse()?)
        }
        None => (480, 270),
    };
    let side: u32 = args.get(2).map_or(Ok(512), |s| s.parse())?;

    let imported = load_gltf(&path)?;
    for w in &imported.warnings {
        println!("warning: {w}");
    }
    let mut scene = imported.scene;
    println!(
        "{}: {} objects, {} materials, {} lights",
        path.display(),
        scene.objects.len(),
        scene.materials.len(),
        scene.lights.len()
    );
    scene.camera.width = w;
    scene.camera.height = h;
    let mut backend = open_backend("cpu")?;
    let settings = SspmSettings::default().with_photons(side, side);
    let mut sspm = Sspm::new(backend.as_mut(), &scene, settings)?;
    sspm.frame(backend.as_mut(), &mut |_| {})?;
    let image = sspm.read_output(backend.as_mut(), Output::Composite)?;
    sspm.free(backend.as_mut())?;
    std::fs::create_dir_all("out/examples")?;
    let out = PathBuf::from(format!(
        "out/examples/{}.png",
        caustica::output::file_stem(&scene.name)
    ));
    write_png(&out, &image, 1.0)?;
    println!("wrote {}", out.display());
    Ok(())
}
