//! What every comparison with the CPU reference shares.
//!
//! The suite compares at two levels, because floating point differs between devices and
//! refraction chains are chaotic (a tiny difference can send one photon elsewhere):
//!
//! - **per kernel, on fixed inputs** ([`crate::kernels`]): each kernel is driven through a
//!   `Recording` on both backends with *the same* input buffers (the scene, and for the
//!   later kernels the CPU's G-buffer, photon list, photon map and images, uploaded to
//!   both: [`fixture`]), so that only the kernel itself can make the outputs differ.
//!   Tolerances are tight and argued from floating-point facts ([`tolerance`]).
//! - **per technique** ([`crate::techniques`]): a whole frame on each backend, compared by
//!   photon statistics (emitted equal, stored and deposited within a path-divergence
//!   allowance, total flux) and image relative L2 error.
//!
//! Modules: [`candidates`](mod@candidates) (the backends found, the reference and the
//! candidates), [`verdict`] (verdicts and reports), [`tolerance`] (every tolerance with its
//! argument), [`fixture`] (fixed inputs and the drivers that run one kernel on them),
//! [`cases`] (the scenes the suite runs), [`measure`] (numbers the checks measure) and
//! [`quirks`] (known device quirks, as data).

pub mod candidates;
pub mod cases;
pub mod fixture;
pub mod measure;
pub mod quirks;
pub mod tolerance;
pub mod verdict;
pub mod watched;

pub use candidates::{candidates, check_generated, loud, reference, Candidate, REFERENCE_BACKEND};
pub use cases::{builtin_small, kernel_cases, BUILTIN_SIZE};
pub use fixture::{Fixture, ReferenceInputs};
pub use quirks::{quirk, Quirk, QUIRKS};
pub use verdict::{Report, Verdict};
pub use watched::WatchedCpu;
