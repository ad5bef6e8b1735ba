//! The CPU kernels, one module per registry kernel, named as the kernel's declaration in
//! `caustica_core::kernels` (`prepare_scene` only checks the node buffer with
//! [`crate::traversal::check_nodes`]: the traversal reads it in place). The modules and
//! the dispatch (`run`) are generated from core's list ([`caustica_core::with_kernels`]):
//! each module has a `run(cpu, k)` that takes the kernel's buffers from the backend, calls
//! the kernel's function and writes its results back. What several kernels share lives in
//! the module of the kernel that defines it (`deposit_screen`'s photon-map deposit) or, for
//! the atlas deposit of `trace_photons` and `refine_clusters`, in
//! [`crate::atlas_deposit`].

/// Called with core's list ([`caustica_core::with_kernels`]): one module per kernel and
/// [`run`], the dispatch to each module's `run`.
macro_rules! cpu_kernels {
    ($($variant:ident => $module:ident),* $(,)?) => {
        $(pub mod $module;)*

        /// Runs kernel `k` on the host: its module's `run` takes the kernel's buffers from
        /// `cpu`, calls the kernel's function and writes its results back.
        pub(crate) fn run(cpu: &mut CpuBackend, k: &Kernel) -> Result<(), BackendError> {
            match k {
                $(Kernel::$variant(a) => $module::run(cpu, a),)*
            }
        }
    };
}

caustica_core::with_kernels!(cpu_kernels);

use crate::CpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::counter;
use caustica_core::kernels::Kernel;
use caustica_core::math::fixed_point::join_u64;

/// Photon counters accumulated per worker and merged (sums are order-independent).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Counters {
    /// Counts indexed like the device counter buffer ([`counter`]); a 64-bit counter sums
    /// in its first word and leaves the second unused.
    pub words: [u64; counter::WORDS],
}

impl Counters {
    /// Adds one to counter `word`.
    pub fn bump(&mut self, word: usize) {
        self.words[word] += 1;
    }

    /// The sum of two sets of counters.
    pub fn merge(mut self, o: Counters) -> Counters {
        for (a, b) in self.words.iter_mut().zip(o.words) {
            *a += b;
        }
        self
    }

    /// Adds to the device counter buffer: 32-bit counters wrap like the GPU atomics would
    /// (batches keep them far below 2^32), 64-bit (lo, hi) pairs carry.
    pub fn add_to(&self, buf: &mut [u32]) {
        let pairs = [
            counter::RAYS,
            counter::STORED_FLUX,
            counter::STORED_FLUX + 2,
            counter::STORED_FLUX + 4,
        ];
        for (i, &v) in self.words.iter().enumerate() {
            if pairs.contains(&i) {
                let sum = join_u64([buf[i], buf[i + 1]]).wrapping_add(v);
                buf[i] = sum as u32;
                buf[i + 1] = (sum >> 32) as u32;
            } else if !pairs.iter().any(|&p| i == p + 1) && i < buf.len() {
                buf[i] = buf[i].wrapping_add(v as u32);
            }
        }
    }
}
