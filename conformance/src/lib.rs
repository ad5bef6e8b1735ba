//! Conformance: every backend checked against the CPU reference.
//! Backends: cpu, opencl, wgpu, vulkan; [`backends`] opens every one this machine has (one
//! named in `CAUSTICA_REQUIRE_BACKENDS` that cannot be opened is a failure, not a skip).
//!
//! - [`harness`]: the backends under test, verdicts and reports, every tolerance with its
//!   floating-point argument, the fixed inputs and the drivers that run one kernel on them,
//!   the case lists and the table of known device quirks.
//! - [`kernels`]: one check per kernel, on fixed inputs.
//! - [`techniques`]: whole frames of a technique compared with the reference's.
//! - [`stiff`]: the catalogue of stiff and extreme cases.
//! - [`strategies`]: proptest strategies for valid scenes and small settings.
//! - [`sphere_optics`]: the `sphere` scene's exact optics in f64 (closed-form anchor and
//!   traced reference).
//!
//! Used by `tests/cross_backend.rs`, `tests/stiff_cases.rs` and `tests/suite_sensitivity.rs`.

pub mod harness;
pub mod kernels;
pub mod sphere_optics;
pub mod stiff;
pub mod strategies;
pub mod techniques;

pub use harness::candidates::backends;

use caustica_core::TechniqueSettings;
use caustica_core::{Backend, Output, Scene, Sspm, SspmSettings};

/// Small test settings: a `n x n` photon grid.
pub fn small_settings(n: u32) -> SspmSettings {
    SspmSettings::default().with_photons(n, n)
}

/// Renders one frame at `w x h` and returns (stats, composite, raw, filtered, direct).
pub fn render(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: SspmSettings,
    w: u32,
    h: u32,
) -> (
    caustica_core::FrameStats,
    Vec<caustica_core::frame::image::Image>,
) {
    let mut scene = scene.clone();
    scene.camera.width = w;
    scene.camera.height = h;
    let mut s = Sspm::new(backend, &scene, settings).expect("valid scene");
    let stats = s.frame(backend, &mut |_| {}).expect("frame");
    let imgs = [
        Output::Composite,
        Output::RawCaustics,
        Output::FilteredCaustics,
        Output::Direct,
    ]
    .into_iter()
    .map(|o| s.read_output(backend, o).expect("read"))
    .collect();
    (stats, imgs)
}

/// AdaptiveCaustics with the default traversal over `map`'s blocks (its photon grid, trace,
/// view planes and atlas), depositing into the atlas: the two techniques compared on the
/// same settings.
pub fn adaptive_over(
    map: &caustica_core::techniques::caustic_map::CausticMapSettings,
) -> caustica_core::techniques::adaptive_caustics::AdaptiveCausticsSettings {
    caustica_core::techniques::adaptive_caustics::AdaptiveCausticsSettings {
        frame: map.frame.clone(),
        trace: map.trace,
        planes: map.planes,
        atlas: map.atlas,
        ..Default::default()
    }
}
