//! The CPU backend's pipelines: its kernels are Rust functions compiled with the crate
//! (`src/kernels/`), a kernel's compiled switches monomorphised variants of them, so
//! nothing is built at run time; what is kept, as the GPU backends keep their pipelines
//! by variant, is the label of every variant run ([`caustica_core::backend::Backend::variants`]).

use caustica_core::backend::BackendError;
use caustica_core::recording::RecordedKernel;
use std::collections::BTreeSet;

/// Labels of the kernel variants run so far.
#[derive(Default)]
pub(crate) struct Variants(BTreeSet<String>);

impl Variants {
    /// Notes the variant kernel step `k` runs, if its kernel has compiled switches.
    pub fn note(&mut self, k: &RecordedKernel) -> Result<(), BackendError> {
        if let Some(l) = k.launch()?.filter(|l| !l.constants.is_empty()) {
            self.0.insert(l.variant_label());
        }
        Ok(())
    }

    /// The labels, sorted.
    pub fn labels(&self) -> Vec<String> {
        self.0.iter().cloned().collect()
    }
}
