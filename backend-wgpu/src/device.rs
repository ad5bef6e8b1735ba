//! The adapter, device and queue: opened here (a GPU before a CPU adapter such as
//! lavapipe, the adapter's own limits, timestamp queries where offered) or taken from a
//! caller's renderer; what the device can do; the errors wgpu reports outside an error
//! scope.

use crate::WgpuBackend;
use caustica_core::backend::{BackendError, Capabilities, DeviceType};
use caustica_shaders as shaders;
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

fn unavailable(reason: impl Into<String>) -> BackendError {
    BackendError::Unavailable {
        backend: "wgpu".into(),
        reason: reason.into(),
    }
}

/// Every adapter wgpu finds on the native compute backends (Vulkan, Metal, DX12), with
/// its description.
pub fn list_adapters() -> Vec<wgpu::AdapterInfo> {
    let instance = instance();
    pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY))
        .iter()
        .map(|a| a.get_info())
        .collect()
}

fn instance() -> wgpu::Instance {
    wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::PRIMARY,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    })
}

/// Preference among adapters: discrete, integrated, virtual GPU, then CPU (lavapipe).
fn adapter_rank(info: &wgpu::AdapterInfo) -> u32 {
    match info.device_type {
        wgpu::DeviceType::DiscreteGpu => 0,
        wgpu::DeviceType::IntegratedGpu => 1,
        wgpu::DeviceType::VirtualGpu => 2,
        wgpu::DeviceType::Cpu => 3,
        wgpu::DeviceType::Other => 4,
    }
}

impl WgpuBackend {
    /// [`WgpuBackend::new`]'s body.
    pub(crate) fn open() -> Result<WgpuBackend, BackendError> {
        let instance = instance();
        let mut adapters = pollster::block_on(instance.enumerate_adapters(wgpu::Backends::PRIMARY));
        if adapters.is_empty() {
            return Err(unavailable(
                "no Vulkan/Metal/DX12 adapter; install a GPU driver or Mesa's lavapipe \
                 (scripts/install-drivers.sh)",
            ));
        }
        let adapter = match std::env::var("CAUSTICA_WGPU_ADAPTER") {
            Ok(v) => {
                let n: usize = v.trim().parse().map_err(|_| {
                    unavailable(format!("CAUSTICA_WGPU_ADAPTER='{v}' is not a number"))
                })?;
                if n >= adapters.len() {
                    return Err(unavailable(format!(
                        "CAUSTICA_WGPU_ADAPTER={n}, but the adapters are numbered 0 to {}",
                        adapters.len().saturating_sub(1)
                    )));
                }
                adapters.swap_remove(n)
            }
            Err(_) => {
                adapters.sort_by_key(|a| adapter_rank(&a.get_info()));
                adapters.swap_remove(0)
            }
        };
        let info = adapter.get_info();
        let features = adapter.features() & wgpu::Features::TIMESTAMP_QUERY;
        let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
            label: Some("caustica"),
            required_features: features,
            // lavapipe's acceleration-structure minimums exceed wgpu's defaults
            required_limits: adapter.limits(),
            ..Default::default()
        }))
        .map_err(|e| unavailable(format!("{} refused a device: {e}", info.name)))?;
        let description = format!("{} ({:?}, {})", info.name, info.backend, info.driver_info);
        let mut b = WgpuBackend::adopt(device, queue, &description, true)?;
        b.device_type = match info.device_type {
            wgpu::DeviceType::DiscreteGpu => DeviceType::DiscreteGpu,
            wgpu::DeviceType::IntegratedGpu => DeviceType::IntegratedGpu,
            wgpu::DeviceType::VirtualGpu => DeviceType::VirtualGpu,
            wgpu::DeviceType::Cpu => DeviceType::SoftwareGpu,
            wgpu::DeviceType::Other => DeviceType::Other,
        };
        Ok(b)
    }

    /// [`WgpuBackend::from_device`]'s body; `own_device`: a device caustica opened
    /// itself, whose uncaptured errors it collects (a caller's device keeps the caller's
    /// handler).
    pub(crate) fn adopt(
        device: wgpu::Device,
        queue: wgpu::Queue,
        description: &str,
        own_device: bool,
    ) -> Result<WgpuBackend, BackendError> {
        let uncaptured = Arc::new(Mutex::new(Vec::new()));
        if own_device {
            let sink = Arc::clone(&uncaptured);
            device.on_uncaptured_error(Arc::new(move |e: wgpu::Error| {
                if let Ok(mut v) = sink.lock() {
                    v.push(e.to_string());
                }
            }));
        }
        let mut pipelines = HashMap::new();
        for (name, _) in shaders::KERNELS {
            if !shaders::VARIANT_KERNELS.contains(name) {
                pipelines.insert(
                    name.to_string(),
                    crate::pipelines::create_pipeline(&device, name, &[])?,
                );
            }
        }
        Ok(WgpuBackend {
            limits: device.limits(),
            timestamps: device.features().contains(wgpu::Features::TIMESTAMP_QUERY),
            device: std::mem::ManuallyDrop::new(device),
            queue: std::mem::ManuallyDrop::new(queue),
            description: description.to_string(),
            device_type: DeviceType::Other,
            pipelines,
            texture_pipelines: HashMap::new(),
            buffers: Default::default(),
            uncaptured,
            submissions: Default::default(),
            pool: Default::default(),
        })
    }

    /// Takes the errors wgpu reported since the last call.
    pub(crate) fn check_uncaptured(&self) -> Result<(), BackendError> {
        let mut v = self.uncaptured.lock().unwrap_or_else(|e| e.into_inner());
        if v.is_empty() {
            return Ok(());
        }
        let all = v.join("; ");
        v.clear();
        Err(if all.contains("lost") {
            BackendError::DeviceLost(all)
        } else {
            BackendError::Driver(all)
        })
    }

    /// Waits for every submitted work, then takes wgpu's reported errors.
    pub(crate) fn wait(&self) -> Result<(), BackendError> {
        self.device
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|e| BackendError::DeviceLost(e.to_string()))?;
        self.check_uncaptured()
    }

    /// What the device can do ([`caustica_core::backend::Backend::capabilities`]).
    pub(crate) fn describe(&self) -> Capabilities {
        Capabilities {
            device: self.description.clone(),
            device_type: self.device_type,
            hardware_ray_tracing: false,
            float_atomics: false,
            int64_atomics: false,
            timestamps: self.timestamps,
            max_buffer_bytes: self
                .limits
                .max_buffer_size
                .min(self.limits.max_storage_buffer_binding_size),
            max_buffer_limit: if self.limits.max_buffer_size
                < self.limits.max_storage_buffer_binding_size
            {
                "device allocation size (max_buffer_size)"
            } else {
                "storage-binding size (max_storage_buffer_binding_size)"
            },
        }
    }
}
