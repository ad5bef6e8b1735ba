//! Embedding caustica in an ash (Vulkan) renderer: the "renderer" creates its own Vulkan
//! instance and device (with the extensions and features the backend documents), hands
//! them to `VulkanBackend::from_raw`, renders a frame with the blocking `frame()`, then
//! submits one without waiting (`submit_frame`) and waits for it on the backend's timeline
//! semaphore (`completion_semaphore`, here with `vkWaitSemaphores` on the host), drops the
//! backend and then destroys its own objects, which must still be valid (the backend
//! destroys only what it created). Exits non-zero if any step fails or no photon is stored.
//! Run: `cargo run --release -p caustica --example embed_ash -- [WxH] [PHOTONS]`.

use caustica::ash::{self, vk};
use caustica::backends::vulkan::{VulkanBackend, DEVICE_EXTENSIONS};
use caustica::scene::builtin::builtin;
use caustica::{Sspm, SspmSettings};
use caustica::{Technique, TechniqueSettings}; // submit_frame; with_photons

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (w, h): (u32, u32) = match args.first() {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("size is WxH")?;
            (a.parse()?, b.parse()?)
        }
        None => (320, 180),
    };
    let side: u32 = args.get(1).map_or(Ok(256), |s| s.parse())?;
    let entry = unsafe { ash::Entry::load() }?;
    let app = vk::ApplicationInfo::default().api_version(vk::API_VERSION_1_2);
    let instance = unsafe {
        entry.create_instance(
            &vk::InstanceCreateInfo::default().application_info(&app),
            None,
        )
    }?;
    // the renderer's choice: the first device with every extension the backend needs
    let physical = unsafe { instance.enumerate_physical_devices() }?
        .into_iter()
        .find(|&p| {
            let exts =
                unsafe { instance.enumerate_device_extension_properties(p) }.unwrap_or_default();
            DEVICE_EXTENSIONS
                .iter()
                .all(|w| exts.iter().any(|e| e.extension_name_as_c_str() == Ok(*w)))
        })
        .ok_or("no Vulkan device with ray-tracing pipelines")?;
    let family = unsafe { instance.get_physical_device_queue_family_properties(physical) }
        .iter()
        .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
        .ok_or("no compute queue")? as u32;
    let prio = [1.0f32];
    let queues = [vk::DeviceQueueCreateInfo::default()
        .queue_family_index(family)
        .queue_priorities(&prio)];
    let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
        .buffer_device_address(true)
        .scalar_block_layout(true)
        // for `completion_semaphore` (a Vulkan 1.2 core feature)
        .timeline_semaphore(true);
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
    }?;
    let queue = unsafe { device.get_device_queue(family, 0) };
    {
        let mut b = VulkanBackend::from_raw(
            entry.clone(),
            instance.clone(),
            physical,
            device.clone(),
            family,
            queue,
        )?;
        let mut scene = builtin("sphere").ok_or("no sphere scene")?;
        scene.camera.width = w;
        scene.camera.height = h;
        let settings = SspmSettings::default().with_photons(side, side);
        let mut s = Sspm::new(&mut b, &scene, settings)?;
        let stats = s.frame(&mut b, &mut |_| {})?;
        println!(
            "{} photons stored, frame {:.1} ms on the renderer's device",
            stats.photons_stored, stats.frame_ms
        );
        // a frame loop's path: the timeline semaphore (signalled by every submission made
        // after this first call) and a frame submitted without waiting
        let timeline = b.completion_semaphore()?;
        let mut ticket = s.submit_frame(&mut b)?;
        let (semaphores, values) = ([timeline], [ticket.submission_id()]);
        let wait = vk::SemaphoreWaitInfo::default()
            .semaphores(&semaphores)
            .values(&values);
        // at most 10 s (a timeout is an error here, not a hang)
        unsafe { device.wait_semaphores(&wait, 10_000_000_000) }?;
        // the frame is done (`true`: the frame slot's fence may signal just after the
        // semaphore)
        let submitted = ticket.stats(&mut b, true)?.ok_or("no statistics")?;
        println!(
            "{} photons stored, frame recorded and submitted in {:.1} ms of host time",
            submitted.photons_stored, submitted.frame_ms
        );
        s.free(&mut b)?;
        if stats.photons_stored == 0 || submitted.photons_stored == 0 {
            return Err("no photon stored".into());
        }
    }
    // still ours, still valid
    unsafe {
        device.device_wait_idle()?;
        device.destroy_device(None);
        instance.destroy_instance(None);
    }
    println!("the renderer's device and instance outlived the backend");
    Ok(())
}
