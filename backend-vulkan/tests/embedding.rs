//! Embedding: a "renderer" creates its own Vulkan instance and device (with the
//! extensions and features the backend documents), hands them to
//! `VulkanBackend::from_raw`, renders a frame, drops the backend and then destroys its
//! own objects, which must still be valid (the backend destroys only what it created).

use ash::vk;
use caustica_core::scene::builtin::builtin;
use caustica_core::{Sspm, SspmSettings};
use caustica_vulkan::{VulkanBackend, DEVICE_EXTENSIONS};

#[test]
fn renders_on_a_callers_device() {
    let entry = unsafe { ash::Entry::load() }.expect("Vulkan loader");
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
    let instance = unsafe {
        entry.create_instance(
            &vk::InstanceCreateInfo::default().application_info(&app),
            None,
        )
    }
    .unwrap();
    // the renderer's choice: the first device with every extension the backend needs
    let physical = unsafe { instance.enumerate_physical_devices() }
        .unwrap()
        .into_iter()
        .find(|&p| {
            let exts = unsafe { instance.enumerate_device_extension_properties(p) }.unwrap();
            DEVICE_EXTENSIONS
                .iter()
                .all(|w| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(*w)))
        })
        .expect("a device with ray-tracing pipelines");
    let family = unsafe { instance.get_physical_device_queue_family_properties(physical) }
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
        .unwrap() as u32;
    let prio = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&prio)];
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
        .buffer_device_address(true)
        .scalar_block_layout(true);
    let mut fas =
        vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default().acceleration_structure(true);
    let mut frt =
        vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default().ray_tracing_pipeline(true);
    let ext: Vec<_> = DEVICE_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
    let device = unsafe {
        instance.create_device(
            physical,
            &vk::DeviceCreateInfo::default()
                .queue_create_infos(&queues)
                .enabled_extension_names(&ext)
                .push_next(&mut f12)
                .push_next(&mut fas)
                .push_next(&mut frt),
            None,
        )
    }
    .unwrap();
    let queue = unsafe { device.get_device_queue(family, 0) };
    {
        let mut b = VulkanBackend::from_raw(
            entry.clone(),
            instance.clone(),
            physical,
            device.clone(),
            family,
            queue,
        )
        .unwrap();
        let mut scene = builtin("sphere").unwrap();
        scene.camera.width = 48;
        scene.camera.height = 27;
        let settings = SspmSettings {
            photons_w: 32,
            photons_h: 32,
            ..SspmSettings::default()
        };
        let mut s = Sspm::new(&mut b, &scene, settings).unwrap();
        let stats = s.frame(&mut b, &mut |_| {}).unwrap();
        assert!(stats.photons_stored > 0);
        s.free(&mut b).unwrap();
    }
    // still ours, still valid
    unsafe {
        device.device_wait_idle().unwrap();
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
}
