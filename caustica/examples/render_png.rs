//! Pick a backend at run time and render a built-in scene to PNG (and EXR).
//!
//! `cargo run --release -p caustica --example render_png -- [BACKEND] [SCENE] [WxH] [PHOTONS]`
//! with BACKEND one of auto (default), cpu, opencl, wgpu, vulkan; SCENE a built-in name or
//! a scene file (JSON, glTF, GLB); PHOTONS the photon grid side per light. Writes
//! `out/examples/<scene>.png` (tone-mapped) and `<scene>.exr` (linear radiance).

use caustica::output::{write_exr, write_png};
use caustica::scene::builtin::builtin;
use caustica::TechniqueSettings;
use caustica::{open_backend, Output, Sspm, SspmSettings};
use std::path::Path;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let backend_name = args.first().map_or("auto", |s| s.as_str());
    let scene_arg = args.get(1).map_or("sphere", |s| s.as_str());
    let (w, h) = match args.get(2) {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("size is WxH, e.g. 480x270")?;
            (a.parse()?, b.parse()?)
        }
        None => (480, 270),
    };
    let side: u32 = args.get(3).map_or(Ok(512), |s| s.parse())?;

    // the backend is chosen by name at run time; "auto" prefers a hardware GPU
    let mut backend = open_backend(backend_name)?;
    let mut scene = match builtin(scene_arg) {
        Some(s) => s,
        None => {
            let loaded = caustica::scene_file::load_scene_file(Path::new(scene_arg))?;
            for w in &loaded.warnings {
                eprintln!("warning: {w}");
            }
            loaded.scene
        }
    };
    scene.camera.width = w;
    scene.camera.height = h;
    let settings = SspmSettings::default().with_photons(side, side);
    let mut sspm = Sspm::new(backend.as_mut(), &scene, settings)?;
    let stats = sspm.frame(backend.as_mut(), &mut |_| {})?;
    let image = sspm.read_output(backend.as_mut(), Output::Composite)?;
    sspm.free(backend.as_mut())?;

    let dir = Path::new("out/examples");
    std::fs::create_dir_all(dir)?;
    let stem = caustica::output::file_stem(&scene.name);
    write_png(&dir.join(format!("{stem}.png")), &image, 1.0)?;
    write_exr(&dir.join(format!("{stem}.exr")), &image)?;
    println!(
        "{} on {}: {} photons stored, {:.1} ms; wrote {}/{stem}.png",
        scene.name,
        backend.name(),
        stats.photons_stored,
        stats.frame_ms,
        dir.display()
    );
    Ok(())
}
