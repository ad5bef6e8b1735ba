//! Submissions on the CPU backend: its work is the host's, so `Backend::submit` and
//! `Backend::poll` are core's defaults (the recording runs at once through `execute` and
//! its readbacks are read: the submission is finished when it is made). Kernel times are
//! the host's clock (`Capabilities::timestamps` is false).

use crate::CpuBackend;
use caustica_core::backend::{BackendError, PassTime};
use caustica_core::recording::RecordedKernel;
use std::sync::Arc;
use std::time::Instant;

impl CpuBackend {
    /// Runs kernel step `k` on the backend's thread pool, timed by the host clock.
    pub(crate) fn run_timed(&mut self, k: &RecordedKernel) -> Result<PassTime, BackendError> {
        let t0 = Instant::now();
        // Run inside our pool so the thread count is the backend's.
        let pool = Arc::clone(&self.pool);
        pool.install(|| self.run_kernel(k.kernel()))?;
        Ok(PassTime {
            kernel: k.name(),
            seconds: t0.elapsed().as_secs_f64(),
        })
    }
}
