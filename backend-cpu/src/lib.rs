#![warn(missing_docs)]
#![allow(clippy::neg_cmp_op_on_partial_ord)]
// `!(x > 0.0)` is deliberate: true for NaN.
//! caustica CPU backend: every kernel of the registry on the host, with rayon for data
//! parallelism and obvhs for BVH traversal. It is the readable reference the other
//! backends are tested against; each kernel lives in its own module under [`kernels`] and
//! calls core's shared scalar functions by the same names the shader ports use.
//!
//! Determinism: random numbers are counter-based, stored photons are written in photon
//! order, and the screen photon map is summed with integer atomics, so every result is
//! bitwise identical across runs and thread counts.
//!
//! The crate's files, as in every caustica backend: `lib.rs` (this: the public face and
//! the backend trait's implementation, which delegates), `device.rs` (the thread pool,
//! capabilities), `memory.rs` (host buffers), `pipelines.rs` (the kernel variants run),
//! `recording.rs` (the interpreter that runs a recording's steps and hands each kernel its
//! buffers), `submission.rs` (host-clock kernel times; submit and poll are core's
//! defaults); and the kernels themselves ([`kernels`], [`atlas_deposit`], [`traversal`]).

pub mod atlas_deposit;
mod device;
pub mod kernels;
mod memory;
mod pipelines;
mod recording;
mod submission;
pub mod traversal;
pub mod traversal_stats;

use caustica_core::backend::{Backend, BackendError, Capabilities, PassTime, ResourceTable};
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::Recording;
use memory::Storage;
use std::sync::Arc;

/// The CPU backend.
pub struct CpuBackend {
    buffers: ResourceTable<Storage>,
    pool: Arc<rayon::ThreadPool>,
    threads: usize,
    /// Labels of the kernel variants run so far (see [`Backend::variants`]).
    variants: pipelines::Variants,
    /// The host memory the buffers may still take.
    host: memory::HostBudget,
}

impl CpuBackend {
    /// A backend using every available core.
    pub fn new() -> Result<CpuBackend, BackendError> {
        CpuBackend::with_threads(0)
    }

    /// A backend with `threads` worker threads (0: one per available core).
    pub fn with_threads(threads: usize) -> Result<CpuBackend, BackendError> {
        CpuBackend::open(threads)
    }

    /// How many buffers the backend holds now (made and not yet freed): what a leak check
    /// counts once every technique on it is freed.
    pub fn buffer_count(&self) -> usize {
        self.buffers.len()
    }
}

/// `submit` and `poll` are the trait's defaults (`submission.rs`).
impl Backend for CpuBackend {
    fn name(&self) -> &'static str {
        "cpu"
    }

    fn capabilities(&self) -> Capabilities {
        self.describe()
    }

    fn execute(&mut self, recording: &Recording) -> Result<Vec<PassTime>, BackendError> {
        self.execute_recording(recording)
    }

    fn read(&mut self, id: ResourceId) -> Result<Vec<u8>, BackendError> {
        self.read_resource(id)
    }

    fn variants(&self) -> Vec<String> {
        self.variants.labels()
    }
}
