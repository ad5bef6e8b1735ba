//! The CPU backend's device: a rayon thread pool of its own on the host's cores, and what
//! it can do.

use crate::CpuBackend;
use caustica_core::backend::{BackendError, Capabilities, DeviceType};
use std::sync::Arc;

impl CpuBackend {
    /// [`CpuBackend::with_threads`]'s body.
    pub(crate) fn open(threads: usize) -> Result<CpuBackend, BackendError> {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .thread_name(|i| format!("caustica-cpu-{i}"))
            .build()
            .map_err(|e| BackendError::Unavailable {
                backend: "cpu".into(),
                reason: e.to_string(),
            })?;
        let threads = pool.current_num_threads();
        Ok(CpuBackend {
            buffers: Default::default(),
            pool: Arc::new(pool),
            threads,
            variants: Default::default(),
            host: crate::memory::HostBudget::now(),
        })
    }

    /// What the device can do ([`caustica_core::backend::Backend::capabilities`]).
    pub(crate) fn describe(&self) -> Capabilities {
        Capabilities {
            device: format!("host CPU, {} threads (rayon + obvhs)", self.threads),
            device_type: DeviceType::Cpu,
            hardware_ray_tracing: false,
            float_atomics: false,
            int64_atomics: true,
            timestamps: false,
            max_buffer_bytes: isize::MAX as u64,
            max_buffer_limit: "host address space",
        }
    }
}
