//! The Vulkan backend on this machine (lavapipe in CI, a GPU elsewhere): it opens with
//! the Khronos validation layer, renders a frame with zero validation errors, and turns
//! an impossible allocation into a typed error. Fails loudly when Vulkan with ray-tracing
//! pipelines is missing (CI installs Mesa from bookworm-backports).

use caustica_core::backend::{Backend, BackendError};
use caustica_core::recording::Recording;
use caustica_core::scene::builtin::builtin;
use caustica_core::{Sspm, SspmSettings};
use caustica_vulkan::VulkanBackend;

fn backend() -> VulkanBackend {
    VulkanBackend::with_validation(true)
        .unwrap_or_else(|e| panic!("Vulkan backend unavailable: {e}"))
}

#[test]
fn renders_a_frame_under_the_validation_layer() {
    let mut b = backend();
    let layer_installed =
        std::path::Path::new("/usr/share/vulkan/explicit_layer.d/VkLayer_khronos_validation.json")
            .exists();
    assert_eq!(
        b.validation_active(),
        layer_installed,
        "validation layer state"
    );
    eprintln!(
        "{} (validation {})",
        b.capabilities().device,
        b.validation_active()
    );
    let mut scene = builtin("sphere").unwrap();
    scene.camera.width = 64;
    scene.camera.height = 36;
    let settings = SspmSettings {
        photons_w: 32,
        photons_h: 32,
        ..SspmSettings::default()
    };
    // every execute fails on a validation error, so Ok here means zero errors
    let mut s = Sspm::new(&mut b, &scene, settings).expect("scene uploads");
    let stats = s
        .frame(&mut b, &mut |_| {})
        .expect("frame renders without validation errors");
    assert!(stats.photons_stored > 0);
    assert_eq!(stats.timing, "device timestamps");
    s.free(&mut b).unwrap();
}

#[test]
fn impossible_allocation_is_a_typed_error() {
    let mut b = backend();
    let mut rec = Recording::new();
    let _ = rec.create::<[f32; 4]>(u32::MAX, "64 GiB buffer");
    match b.execute(&rec) {
        Err(BackendError::OutOfMemory { .. }) | Err(BackendError::Unsupported(_)) => {}
        other => panic!("expected OutOfMemory, got {other:?}"),
    }
}
