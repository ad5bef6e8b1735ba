//! Conformance helpers: open every backend named in `CAUSTICA_REQUIRE_BACKENDS` (a missing
//! one is a failure, not a skip) and render small frames for comparison. Backends: cpu,
//! opencl, wgpu, vulkan.
//!
//! [`strategies`]: proptest strategies for valid scenes and small settings. [`compare`]:
//! backend-generic comparisons with the CPU reference, per kernel and per technique, with
//! every tolerance argued (used by `tests/cross_backend.rs`).

pub mod compare;
pub mod stiff;
pub mod strategies;

use caustica_core::{Backend, Output, Scene, Sspm, SspmSettings};

/// Backends found on this machine (name, backend). Panics, loudly, when a backend listed
/// in `CAUSTICA_REQUIRE_BACKENDS` cannot be opened.
pub fn backends() -> Vec<(&'static str, Box<dyn Backend>)> {
    let required = std::env::var("CAUSTICA_REQUIRE_BACKENDS").unwrap_or_default();
    let mut out: Vec<(&'static str, Box<dyn Backend>)> = Vec::new();
    match caustica_cpu::CpuBackend::new() {
        Ok(b) => out.push(("cpu", Box::new(b))),
        Err(e) => eprintln!("SKIPPING cpu backend: {e}"),
    }
    match caustica_opencl::OpenClBackend::new() {
        Ok(b) => {
            eprintln!("opencl backend: {}", b.device().name);
            out.push(("opencl", Box::new(b)));
        }
        Err(e) => eprintln!("SKIPPING opencl backend (set CAUSTICA_REQUIRE_BACKENDS to fail): {e}"),
    }
    match caustica_wgpu::WgpuBackend::new() {
        Ok(b) => {
            eprintln!("wgpu backend: {}", b.capabilities().device);
            out.push(("wgpu", Box::new(b)));
        }
        Err(e) => eprintln!("SKIPPING wgpu backend (set CAUSTICA_REQUIRE_BACKENDS to fail): {e}"),
    }
    // The conformance suite runs Vulkan under the Khronos validation layer where it is
    // installed: any validation error fails the step that caused it.
    match caustica_vulkan::VulkanBackend::with_validation(true) {
        Ok(b) => {
            eprintln!(
                "vulkan backend: {} (validation layer {})",
                b.capabilities().device,
                if b.validation_active() {
                    "on"
                } else {
                    "NOT INSTALLED"
                }
            );
            out.push(("vulkan", Box::new(b)));
        }
        Err(e) => eprintln!("SKIPPING vulkan backend (set CAUSTICA_REQUIRE_BACKENDS to fail): {e}"),
    }
    for name in required.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        assert!(
            out.iter().any(|(n, _)| *n == name),
            "required backend '{name}' is not available on this machine"
        );
    }
    out
}

/// Small test settings: a `n x n` photon grid.
pub fn small_settings(n: u32) -> SspmSettings {
    SspmSettings {
        photons_w: n,
        photons_h: n,
        ..SspmSettings::default()
    }
}

/// Renders one frame at `w x h` and returns (stats, composite, raw, filtered, direct).
pub fn render(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: SspmSettings,
    w: u32,
    h: u32,
) -> (caustica_core::FrameStats, Vec<caustica_core::frame::image::Image>) {
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
