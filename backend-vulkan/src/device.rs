//! The Vulkan instance, device and queue: created here (with the ray-tracing extensions
//! and features, and the Khronos validation layer when asked for and installed) or taken
//! from a caller's renderer; the backend's command pool, fence and counter banks on it;
//! what the device can do. Every failure is a typed error; what is created here is
//! destroyed on drop, what a caller lent is left alone.

use crate::memory::{self, Buffer, COUNTER_BANK_BYTES};
use crate::VulkanBackend;
use ash::vk;
use caustica_core::backend::{driver_lifecycle, BackendError, Capabilities, DeviceType};
use std::collections::HashMap;
use std::ffi::{c_void, CStr};
use std::sync::{Arc, Mutex};

/// Device extensions the backend needs.
pub const DEVICE_EXTENSIONS: [&CStr; 3] = [
    ash::khr::acceleration_structure::NAME,
    ash::khr::ray_tracing_pipeline::NAME,
    ash::khr::deferred_host_operations::NAME,
];

const VALIDATION_LAYER: &CStr = c"VK_LAYER_KHRONOS_validation";

/// Vulkan result to a typed error.
pub fn vk_error(what: &'static str) -> impl Fn(vk::Result) -> BackendError {
    move |r| match r {
        vk::Result::ERROR_OUT_OF_DEVICE_MEMORY | vk::Result::ERROR_OUT_OF_HOST_MEMORY => {
            BackendError::OutOfMemory {
                bytes: 0,
                what: format!("{what} ({r:?})"),
            }
        }
        vk::Result::ERROR_DEVICE_LOST => BackendError::DeviceLost(format!("{what}: {r:?}")),
        vk::Result::ERROR_EXTENSION_NOT_PRESENT | vk::Result::ERROR_FEATURE_NOT_PRESENT => {
            BackendError::Unsupported(format!("{what}: {r:?}"))
        }
        _ => BackendError::Driver(format!("{what}: {r:?}")),
    }
}

pub fn unavailable(reason: impl Into<String>) -> BackendError {
    BackendError::Unavailable {
        backend: "vulkan".into(),
        reason: reason.into(),
    }
}

/// Messages of severity ERROR reported by the validation layer.
pub type ValidationLog = Arc<Mutex<Vec<String>>>;

unsafe extern "system" fn on_validation_message(
    severity: vk::DebugUtilsMessageSeverityFlagsEXT,
    _types: vk::DebugUtilsMessageTypeFlagsEXT,
    data: *const vk::DebugUtilsMessengerCallbackDataEXT<'_>,
    user: *mut c_void,
) -> vk::Bool32 {
    if severity.contains(vk::DebugUtilsMessageSeverityFlagsEXT::ERROR) && !user.is_null() {
        // SAFETY: `user` is the `Mutex<Vec<String>>` inside the `ValidationLog` the
        // messenger was created with; the context keeps that Arc alive until the
        // messenger is destroyed.
        let log = unsafe { &*(user as *const Mutex<Vec<String>>) };
        let msg = unsafe { data.as_ref() }
            .and_then(|d| unsafe { d.message_as_c_str() })
            .map(|m| m.to_string_lossy().into_owned())
            .unwrap_or_else(|| "(no message)".into());
        if let Ok(mut v) = log.lock() {
            v.push(msg);
        }
    }
    vk::FALSE
}

/// Instance, device and the extension loaders.
pub struct Context {
    /// Keeps the Vulkan loader library loaded while the instance lives.
    _entry: ash::Entry,
    pub instance: ash::Instance,
    pub device: ash::Device,
    pub queue: vk::Queue,
    pub queue_family: u32,
    pub accel: ash::khr::acceleration_structure::Device,
    pub rt: ash::khr::ray_tracing_pipeline::Device,
    pub rt_props: RtProperties,
    pub memory: vk::PhysicalDeviceMemoryProperties,
    pub limits: vk::PhysicalDeviceLimits,
    /// Largest single allocation: `maxMemoryAllocationSize`, at most the largest heap.
    pub max_allocation: u64,
    pub timestamps: bool,
    /// `rayTracingPipelineTraceRaysIndirect` enabled (on a device this backend created
    /// where supported; never assumed of a lent one): traced kernels with their size on
    /// the device launch it with `vkCmdTraceRaysIndirectKHR`, else their bound.
    pub trace_rays_indirect: bool,
    pub name: String,
    /// The physical device's type.
    pub device_type: vk::PhysicalDeviceType,
    pub validation: ValidationLog,
    debug: Option<(ash::ext::debug_utils::Instance, vk::DebugUtilsMessengerEXT)>,
    /// Whether instance and device are ours to destroy.
    owned: bool,
}

/// Whether `physical` can launch ray-tracing pipelines with their size in a buffer.
fn trace_rays_indirect_supported(instance: &ash::Instance, physical: vk::PhysicalDevice) -> bool {
    let mut rt = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default();
    let mut f = vk::PhysicalDeviceFeatures2::default().push_next(&mut rt);
    unsafe { instance.get_physical_device_features2(physical, &mut f) };
    rt.ray_tracing_pipeline_trace_rays_indirect == vk::TRUE
}

/// The ray-tracing properties the shader binding table needs.
#[derive(Clone, Copy, Debug)]
pub struct RtProperties {
    pub handle_size: u32,
    pub handle_alignment: u32,
    pub base_alignment: u32,
    pub scratch_alignment: u32,
}

fn rt_properties(
    instance: &ash::Instance,
    physical: vk::PhysicalDevice,
) -> (RtProperties, vk::PhysicalDeviceLimits, u64) {
    let mut rt = vk::PhysicalDeviceRayTracingPipelinePropertiesKHR::default();
    let mut accel = vk::PhysicalDeviceAccelerationStructurePropertiesKHR::default();
    let mut m3 = vk::PhysicalDeviceMaintenance3Properties::default();
    let mut props = vk::PhysicalDeviceProperties2::default()
        .push_next(&mut rt)
        .push_next(&mut accel)
        .push_next(&mut m3);
    unsafe { instance.get_physical_device_properties2(physical, &mut props) };
    let limits = props.properties.limits;
    let max_allocation = m3.max_memory_allocation_size;
    (
        RtProperties {
            handle_size: rt.shader_group_handle_size,
            handle_alignment: rt.shader_group_handle_alignment,
            base_alignment: rt.shader_group_base_alignment,
            scratch_alignment: accel.min_acceleration_structure_scratch_offset_alignment,
        },
        limits,
        max_allocation,
    )
}

fn device_name(instance: &ash::Instance, physical: vk::PhysicalDevice) -> String {
    let p = unsafe { instance.get_physical_device_properties(physical) };
    let name = p
        .device_name_as_c_str()
        .map(|c| c.to_string_lossy().into_owned())
        .unwrap_or_default();
    format!(
        "{name} (Vulkan {}.{}.{})",
        vk::api_version_major(p.api_version),
        vk::api_version_minor(p.api_version),
        vk::api_version_patch(p.api_version)
    )
}

fn has_extensions(instance: &ash::Instance, physical: vk::PhysicalDevice) -> Result<(), String> {
    let exts = unsafe { instance.enumerate_device_extension_properties(physical) }
        .map_err(|e| format!("{e:?}"))?;
    for want in DEVICE_EXTENSIONS {
        if !exts.iter().any(|e| e.extension_name_as_c_str() == Ok(want)) {
            return Err(format!("missing {}", want.to_string_lossy()));
        }
    }
    Ok(())
}

impl Context {
    /// Creates an instance and a device on the first physical device with ray-tracing
    /// pipelines (a discrete or integrated GPU before a CPU implementation such as
    /// lavapipe; `CAUSTICA_VULKAN_DEVICE=N` picks one). `validation` enables the Khronos
    /// validation layer when it is installed.
    pub fn new(validation: bool) -> Result<Context, BackendError> {
        let entry = unsafe { ash::Entry::load() }
            .map_err(|e| unavailable(format!("no Vulkan loader (libvulkan.so.1): {e}")))?;
        let layers = unsafe { entry.enumerate_instance_layer_properties() }.unwrap_or_default();
        let use_validation = validation
            && layers
                .iter()
                .any(|l| l.layer_name_as_c_str() == Ok(VALIDATION_LAYER));
        let app = vk::ApplicationInfo::default()
            .application_name(c"caustica")
            .api_version(vk::API_VERSION_1_2);
        let layer_names = if use_validation {
            vec![VALIDATION_LAYER.as_ptr()]
        } else {
            vec![]
        };
        let ext_names = if use_validation {
            vec![ash::ext::debug_utils::NAME.as_ptr()]
        } else {
            vec![]
        };
        let instance = unsafe {
            entry.create_instance(
                &vk::InstanceCreateInfo::default()
                    .application_info(&app)
                    .enabled_layer_names(&layer_names)
                    .enabled_extension_names(&ext_names),
                None,
            )
        }
        .map_err(|e| {
            unavailable(format!(
                "vkCreateInstance: {e:?} (the Vulkan loader found no usable driver: install a \
                 GPU driver or Mesa's lavapipe, scripts/install-drivers.sh, and check \
                 VK_ICD_FILENAMES / VK_DRIVER_FILES if set)"
            ))
        })?;
        let validation_log: ValidationLog = Arc::new(Mutex::new(Vec::new()));
        let debug = if use_validation {
            let loader = ash::ext::debug_utils::Instance::new(&entry, &instance);
            let info = vk::DebugUtilsMessengerCreateInfoEXT::default()
                .message_severity(
                    vk::DebugUtilsMessageSeverityFlagsEXT::ERROR
                        | vk::DebugUtilsMessageSeverityFlagsEXT::WARNING,
                )
                .message_type(
                    vk::DebugUtilsMessageTypeFlagsEXT::GENERAL
                        | vk::DebugUtilsMessageTypeFlagsEXT::VALIDATION
                        | vk::DebugUtilsMessageTypeFlagsEXT::PERFORMANCE,
                )
                .pfn_user_callback(Some(on_validation_message))
                .user_data(Arc::as_ptr(&validation_log) as *mut c_void);
            match unsafe { loader.create_debug_utils_messenger(&info, None) } {
                Ok(m) => Some((loader, m)),
                Err(_) => None,
            }
        } else {
            None
        };
        let result = Self::open_device(&instance);
        let (physical, device, queue_family) = match result {
            Ok(v) => v,
            Err(e) => {
                unsafe {
                    if let Some((l, m)) = &debug {
                        l.destroy_debug_utils_messenger(*m, None);
                    }
                    instance.destroy_instance(None);
                }
                return Err(e);
            }
        };
        let indirect = trace_rays_indirect_supported(&instance, physical);
        let mut ctx = Self::assemble(
            entry,
            instance,
            physical,
            device,
            (queue_family, None),
            true,
        );
        ctx.trace_rays_indirect = indirect;
        ctx.debug = debug;
        ctx.validation = validation_log;
        Ok(ctx)
    }

    fn open_device(
        instance: &ash::Instance,
    ) -> Result<(vk::PhysicalDevice, ash::Device, u32), BackendError> {
        let physicals = unsafe { instance.enumerate_physical_devices() }
            .map_err(vk_error("enumerating devices"))?;
        let mut candidates: Vec<(u32, vk::PhysicalDevice)> = Vec::new();
        let mut why_not = Vec::new();
        for p in physicals {
            match has_extensions(instance, p) {
                Ok(()) => {
                    let t = unsafe { instance.get_physical_device_properties(p) }.device_type;
                    let rank = match t {
                        vk::PhysicalDeviceType::DISCRETE_GPU => 0,
                        vk::PhysicalDeviceType::INTEGRATED_GPU => 1,
                        vk::PhysicalDeviceType::VIRTUAL_GPU => 2,
                        vk::PhysicalDeviceType::CPU => 3,
                        _ => 4,
                    };
                    candidates.push((rank, p));
                }
                Err(e) => why_not.push(format!("{}: {e}", device_name(instance, p))),
            }
        }
        if let Ok(v) = std::env::var("CAUSTICA_VULKAN_DEVICE") {
            let n: usize = v.trim().parse().map_err(|_| {
                unavailable(format!("CAUSTICA_VULKAN_DEVICE='{v}' is not a number"))
            })?;
            if n >= candidates.len() {
                return Err(unavailable(format!(
                    "CAUSTICA_VULKAN_DEVICE={n}, but the devices with ray tracing are {}",
                    match candidates.len() {
                        0 => "none".to_string(),
                        k => format!("numbered 0 to {}", k - 1),
                    }
                )));
            }
            candidates = vec![candidates[n]];
        }
        candidates.sort_by_key(|c| c.0);
        let Some(&(_, physical)) = candidates.first() else {
            return Err(unavailable(format!(
                "no device with ray-tracing pipelines ({}); install a GPU driver or Mesa's lavapipe from bookworm-backports (scripts/install-drivers.sh)",
                if why_not.is_empty() { "no Vulkan device".to_string() } else { why_not.join("; ") }
            )));
        };
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let queue_family = families
            .iter()
            .position(|f| f.queue_flags.contains(vk::QueueFlags::COMPUTE))
            .ok_or_else(|| unavailable("no compute queue"))? as u32;
        let priorities = [1.0f32];
        let queue_info = [vk::DeviceQueueCreateInfo::default()
            .queue_family_index(queue_family)
            .queue_priorities(&priorities)];
        let mut f12 = vk::PhysicalDeviceVulkan12Features::default()
            .buffer_device_address(true)
            // a Vulkan 1.2 core feature every 1.2 device has: the submissions' timeline
            .timeline_semaphore(true)
            .scalar_block_layout(true);
        let mut fas = vk::PhysicalDeviceAccelerationStructureFeaturesKHR::default()
            .acceleration_structure(true);
        let mut frt = vk::PhysicalDeviceRayTracingPipelineFeaturesKHR::default()
            .ray_tracing_pipeline(true)
            .ray_tracing_pipeline_trace_rays_indirect(trace_rays_indirect_supported(
                instance, physical,
            ));
        let ext: Vec<_> = DEVICE_EXTENSIONS.iter().map(|e| e.as_ptr()).collect();
        let info = vk::DeviceCreateInfo::default()
            .queue_create_infos(&queue_info)
            .enabled_extension_names(&ext)
            .push_next(&mut f12)
            .push_next(&mut fas)
            .push_next(&mut frt);
        let device = unsafe { instance.create_device(physical, &info, None) }
            .map_err(vk_error("vkCreateDevice"))?;
        Ok((physical, device, queue_family))
    }

    fn assemble(
        entry: ash::Entry,
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        (queue_family, queue): (u32, Option<vk::Queue>),
        owned: bool,
    ) -> Context {
        let queue = queue.unwrap_or_else(|| unsafe { device.get_device_queue(queue_family, 0) });
        let accel = ash::khr::acceleration_structure::Device::new(&instance, &device);
        let rt = ash::khr::ray_tracing_pipeline::Device::new(&instance, &device);
        let (rt_props, limits, max_allocation) = rt_properties(&instance, physical);
        let memory = unsafe { instance.get_physical_device_memory_properties(physical) };
        let largest_heap = memory.memory_heaps[..memory.memory_heap_count as usize]
            .iter()
            .map(|h| h.size)
            .max()
            .unwrap_or(0);
        let max_allocation = max_allocation.min(largest_heap);
        let families = unsafe { instance.get_physical_device_queue_family_properties(physical) };
        let timestamps = families
            .get(queue_family as usize)
            .is_some_and(|f| f.timestamp_valid_bits > 0)
            && limits.timestamp_period > 0.0;
        let name = device_name(&instance, physical);
        let device_type = unsafe { instance.get_physical_device_properties(physical) }.device_type;
        Context {
            _entry: entry,
            instance,
            device,
            queue,
            queue_family,
            accel,
            rt,
            rt_props,
            memory,
            limits,
            max_allocation,
            timestamps,
            trace_rays_indirect: false,
            name,
            device_type,
            validation: Arc::new(Mutex::new(Vec::new())),
            debug: None,
            owned,
        }
    }

    /// Adopts a caller's objects. The device must have been created with
    /// [`DEVICE_EXTENSIONS`] and the features `bufferDeviceAddress`, `scalarBlockLayout`,
    /// `accelerationStructure` and `rayTracingPipeline`; `queue` must belong to
    /// `queue_family`, which must support compute. Nothing lent is destroyed on drop.
    pub fn adopt(
        entry: ash::Entry,
        instance: ash::Instance,
        physical: vk::PhysicalDevice,
        device: ash::Device,
        queue_family: u32,
        queue: vk::Queue,
    ) -> Result<Context, BackendError> {
        has_extensions(&instance, physical)
            .map_err(|e| BackendError::Unsupported(format!("the caller's device: {e}")))?;
        Ok(Self::assemble(
            entry,
            instance,
            physical,
            device,
            (queue_family, Some(queue)),
            false,
        ))
    }

    /// Index of a memory type with `flags` allowed by `bits`.
    pub fn memory_type(&self, bits: u32, flags: vk::MemoryPropertyFlags) -> Option<u32> {
        (0..self.memory.memory_type_count).find(|&i| {
            bits & (1 << i) != 0
                && self.memory.memory_types[i as usize]
                    .property_flags
                    .contains(flags)
        })
    }

    pub fn validation_active(&self) -> bool {
        self.debug.is_some()
    }

    /// Takes the validation errors reported since the last call.
    pub fn take_validation_errors(&self) -> Vec<String> {
        self.validation
            .lock()
            .map(|mut v| std::mem::take(&mut *v))
            .unwrap_or_default()
    }
}

impl Drop for Context {
    fn drop(&mut self) {
        if !self.owned {
            return;
        }
        driver_lifecycle(|| unsafe {
            let _ = self.device.device_wait_idle();
            self.device.destroy_device(None);
            if let Some((l, m)) = &self.debug {
                l.destroy_debug_utils_messenger(*m, None);
            }
            self.instance.destroy_instance(None);
        })
    }
}

impl VulkanBackend {
    /// The backend on `ctx`: its command pool, fence, counter banks and pipelines.
    pub(crate) fn with_context(ctx: Context) -> Result<VulkanBackend, BackendError> {
        let ctx = Arc::new(ctx);
        let d = &ctx.device;
        let pool = unsafe {
            d.create_command_pool(
                &vk::CommandPoolCreateInfo::default()
                    .queue_family_index(ctx.queue_family)
                    .flags(vk::CommandPoolCreateFlags::RESET_COMMAND_BUFFER),
                None,
            )
        }
        .map_err(vk_error("creating a command pool"))?;
        let fence = match unsafe { d.create_fence(&vk::FenceCreateInfo::default(), None) } {
            Ok(f) => f,
            Err(e) => {
                unsafe { d.destroy_command_pool(pool, None) };
                return Err(vk_error("creating a fence")(e));
            }
        };
        let counter_banks = Buffer::new(
            &ctx,
            COUNTER_BANK_BYTES,
            memory::storage_usage(),
            false,
            "counter banks",
        );
        let counter_banks = match counter_banks {
            Ok(b) => b,
            Err(e) => {
                unsafe {
                    d.destroy_fence(fence, None);
                    d.destroy_command_pool(pool, None);
                }
                return Err(e);
            }
        };
        let mut backend = VulkanBackend {
            buffers: Default::default(),
            scenes: HashMap::new(),
            bottom_level_builds: 0,
            written_top_levels: HashMap::new(),
            submissions: Default::default(),
            free_slots: Vec::new(),
            timeline: None,
            pipelines: HashMap::new(),
            counter_banks,
            pool,
            fence,
            ctx,
        };
        backend.pipelines = crate::pipelines::create_pipelines(&backend.ctx)?;
        // the banks start at zero; the reduce pass leaves them zeroed after every use
        let banks = backend.counter_banks.buffer;
        backend.one_shot(&|cmd| unsafe {
            backend
                .ctx
                .device
                .cmd_fill_buffer(cmd, banks, 0, vk::WHOLE_SIZE, 0)
        })?;
        Ok(backend)
    }

    /// The validation errors reported since the last check, as an error.
    pub(crate) fn check_validation(&self) -> Result<(), BackendError> {
        let errors = self.ctx.take_validation_errors();
        if errors.is_empty() {
            Ok(())
        } else {
            Err(BackendError::Driver(format!(
                "Vulkan validation: {}",
                errors.join(" | ")
            )))
        }
    }

    /// What the device can do ([`caustica_core::backend::Backend::capabilities`]).
    pub(crate) fn describe(&self) -> Capabilities {
        Capabilities {
            device: self.ctx.name.clone(),
            device_type: match self.ctx.device_type {
                vk::PhysicalDeviceType::DISCRETE_GPU => DeviceType::DiscreteGpu,
                vk::PhysicalDeviceType::INTEGRATED_GPU => DeviceType::IntegratedGpu,
                vk::PhysicalDeviceType::VIRTUAL_GPU => DeviceType::VirtualGpu,
                vk::PhysicalDeviceType::CPU => DeviceType::SoftwareGpu,
                _ => DeviceType::Other,
            },
            hardware_ray_tracing: true,
            float_atomics: false,
            int64_atomics: false,
            timestamps: self.ctx.timestamps,
            max_buffer_bytes: self
                .ctx
                .max_allocation
                .min(self.ctx.limits.max_storage_buffer_range as u64),
            max_buffer_limit: if self.ctx.max_allocation
                < self.ctx.limits.max_storage_buffer_range as u64
            {
                "device allocation size (maxMemoryAllocationSize)"
            } else {
                "storage-binding size (maxStorageBufferRange)"
            },
        }
    }
}
