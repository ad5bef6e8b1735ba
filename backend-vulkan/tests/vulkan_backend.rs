//! The Vulkan backend on this machine (lavapipe in CI, a GPU elsewhere): it opens with
//! the Khronos validation layer, renders a frame with zero validation errors, and turns
//! an impossible allocation into a typed error. Fails loudly when Vulkan with ray-tracing
//! pipelines is missing (CI installs Mesa from bookworm-backports).

use caustica_core::backend::{Backend, BackendError};
use caustica_core::recording::Recording;
use caustica_core::scene::builtin::builtin;
use caustica_core::TechniqueSettings;
use caustica_core::{Sspm, SspmSettings, Technique};
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
    let settings = SspmSettings::default().with_photons(32, 32);
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

/// The non-blocking frame: a host's own work waits on the backend's timeline semaphore for a
/// submitted frame's number instead of the CPU waiting; here the host waits on it with
/// `vkWaitSemaphores` (under the validation layer), then collects the frame's statistics
/// without blocking.
#[test]
fn a_submitted_frame_signals_the_timeline_semaphore_with_its_number() {
    use ash::vk;
    let mut b = backend();
    let timeline = b.completion_semaphore().expect("timeline semaphore");
    let mut scene = builtin("sphere").unwrap();
    scene.camera.width = 64;
    scene.camera.height = 36;
    let settings = SspmSettings::default().with_photons(32, 32);
    let mut s = Sspm::new(&mut b, &scene, settings).expect("scene uploads");
    let mut tickets = Vec::new();
    for _ in 0..3 {
        tickets.push(s.submit_frame(&mut b).expect("submit_frame"));
    }
    let last = tickets.last().unwrap().submission_id();
    {
        let (device, _) = b.device();
        let semaphores = [timeline];
        let values = [last];
        unsafe {
            device.wait_semaphores(
                &vk::SemaphoreWaitInfo::default()
                    .semaphores(&semaphores)
                    .values(&values),
                60_000_000_000,
            )
        }
        .expect("the timeline reaches the last frame's number");
        let value = unsafe { device.get_semaphore_counter_value(timeline) }.unwrap();
        assert!(value >= last, "timeline at {value}, last frame {last}");
    }
    // done on the device: every frame's statistics are there without a wait
    for t in &mut tickets {
        let stats = t
            .stats(&mut b, false)
            .expect("stats")
            .expect("finished once the timeline passed it");
        assert!(stats.photons_stored > 0);
    }
    s.free(&mut b).unwrap();
}

/// Deformed instances on Vulkan: deforming one instance builds that instance's BLAS only
/// (the driver's build), moving one builds none.
#[test]
fn a_deformed_instance_rebuilds_its_own_bottom_level_only() {
    use caustica_core::scene::{Shape, Transform};
    let mut b = backend();
    let mut scene = builtin("cornell").unwrap();
    scene.camera.width = 32;
    scene.camera.height = 18;
    // both balls instances: three levels with the static one
    for o in scene
        .objects
        .iter_mut()
        .filter(|o| o.name.ends_with("ball"))
    {
        if let Shape::Sphere { center, .. } = &mut o.shape {
            o.transform = Some(Transform::from_translation(std::mem::replace(
                center,
                glam::Vec3::ZERO,
            )));
        }
    }
    let ball = scene
        .objects
        .iter()
        .position(|o| o.transform.is_some())
        .unwrap();
    let settings = SspmSettings::default().with_photons(16, 16);
    let mut s = Sspm::new(&mut b, &scene, settings).expect("scene uploads");
    s.frame(&mut b, &mut |_| {}).expect("frame");
    let built = b.bottom_level_builds();
    assert_eq!(built, 3, "one BLAS per level");
    let m = caustica_core::scene::shapes::tessellate(&scene.objects[ball].shape);
    let squashed: Vec<glam::Vec3> = m
        .positions
        .iter()
        .map(|p| glam::Vec3::new(p.x, 0.7 * p.y, p.z))
        .collect();
    s.set_object_vertices(&mut b, ball, &squashed, &[])
        .expect("deform");
    s.frame(&mut b, &mut |_| {}).expect("frame");
    assert_eq!(
        b.bottom_level_builds(),
        built + 1,
        "the deformed ball's BLAS only"
    );
    let t = scene.objects[ball].transform.unwrap();
    s.set_object_transforms(
        &mut b,
        &[(
            ball,
            Transform::from_translation(t.translation + glam::Vec3::X * 0.1),
        )],
    )
    .expect("move");
    s.frame(&mut b, &mut |_| {}).expect("frame");
    assert_eq!(b.bottom_level_builds(), built + 1, "a move builds no BLAS");
    s.free(&mut b).unwrap();
}
