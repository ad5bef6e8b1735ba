//! The CPU backend, watched (for tests of what a technique asks of a device): it counts
//! the recordings it executes and the uploads in them by label, and can claim a smaller
//! largest buffer than it has.

use caustica_core::backend::{Backend, BackendError, PassTime};
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::{Recording, Step};
use std::collections::BTreeMap;

/// The CPU backend, watched (see the module doc).
pub struct WatchedCpu {
    inner: caustica_cpu::CpuBackend,
    /// The largest buffer it claims (`None`: the CPU's own).
    pub max_buffer_bytes: Option<u64>,
    /// Recordings executed.
    pub executed: usize,
    /// Uploads executed, by buffer label (`"bvh nodes"`: the scene's node buffer).
    pub uploads: BTreeMap<&'static str, usize>,
}

impl WatchedCpu {
    /// A watched CPU backend, claiming `max_buffer_bytes` if given.
    pub fn new(max_buffer_bytes: Option<u64>) -> WatchedCpu {
        WatchedCpu {
            inner: caustica_cpu::CpuBackend::new().expect("the CPU backend opens"),
            max_buffer_bytes,
            executed: 0,
            uploads: BTreeMap::new(),
        }
    }

    /// Uploads of the buffer labelled `label` executed so far.
    pub fn uploads_of(&self, label: &str) -> usize {
        self.uploads.get(label).copied().unwrap_or(0)
    }
}

impl Backend for WatchedCpu {
    fn name(&self) -> &'static str {
        "watched-cpu"
    }
    fn capabilities(&self) -> caustica_core::Capabilities {
        let own = self.inner.capabilities();
        caustica_core::Capabilities {
            max_buffer_bytes: self.max_buffer_bytes.unwrap_or(own.max_buffer_bytes),
            ..own
        }
    }
    fn execute(&mut self, r: &Recording) -> Result<Vec<PassTime>, BackendError> {
        self.executed += 1;
        for s in &r.steps {
            if let Step::Upload { label, .. } = s {
                *self.uploads.entry(label).or_default() += 1;
            }
        }
        self.inner.execute(r)
    }
    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        self.inner.read(id)
    }
    fn variants(&self) -> Vec<String> {
        self.inner.variants()
    }
}
