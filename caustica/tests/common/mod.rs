//! Helpers shared by the facade's integration tests.

use caustica::TechniqueSettings;
use caustica::{Output, Scene, Sspm, SspmSettings};
use caustica_cpu::CpuBackend;

/// The composite of one Sspm frame of `scene` at 96x64 with 128² photons per light on
/// the CPU backend (linear radiance, row-major).
pub fn render_small(scene: &Scene) -> Vec<[f32; 4]> {
    let mut scene = scene.clone();
    scene.camera.width = 96;
    scene.camera.height = 64;
    let mut b = CpuBackend::new().unwrap();
    let settings = SspmSettings::default().with_photons(128, 128);
    let mut t = Sspm::new(&mut b, &scene, settings).unwrap();
    t.frame(&mut b, &mut |_| {}).unwrap();
    let img = t.read_output(&mut b, Output::Composite).unwrap();
    t.free(&mut b).unwrap();
    img.pixels
}
