//! Known device quirks, kept as data (backend, device substring, reason), not as cfgs.
//!
//! A [`Quirk`] holds one case back on the backend and devices it names; [`quirk`] is the
//! one function the suite asks, and no other code path of the suite is keyed on a backend's
//! or a device's name. (The reference's name, [`REFERENCE_BACKEND`], only says which
//! backend is the reference: it changes what a backend is compared with, not what is run
//! or how it is judged.) A held-back case is not passed: the tests that honour the table
//! say so on stderr, and an ignored test or a flag runs the held-back cases anyway.
//!
//! [`REFERENCE_BACKEND`]: super::candidates::REFERENCE_BACKEND

/// One known quirk: case `case` is not run by default on backend `backend` when the name of
/// its device contains `device`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Quirk {
    /// Backend name, as [`crate::backends`] names it.
    pub backend: &'static str,
    /// Substring of the device name (`Capabilities::device`); empty: every device.
    pub device: &'static str,
    /// Case id, as the test that runs it reports it (stiff cases: `group/name`).
    pub case: &'static str,
    /// Why the case is held back there, printed where it is.
    pub reason: &'static str,
}

/// The stiff catalogue's two heavy cases (an 8192x8192 image: a 4 GiB G-buffer in four
/// 1 GiB planes and ~10 GiB of frame buffers; 2^26 photons in 64 batches, run twice) take
/// minutes and ~10 GiB of host memory on the CI machine's software drivers (lavapipe under
/// Vulkan and wgpu, PoCL under OpenCL). They are held back on *every* device of those backends, not only on the
/// software ones, as the suite did before this table (`backend == "cpu"`): narrowing the
/// rows to llvmpipe and PoCL devices would run them by default on a GPU machine, a change
/// of what the default test runs. A GPU machine runs them with the ignored test
/// `heavy_cases_on_every_backend` or `stiff_table --heavy`; the CPU reference runs them in
/// the default test.
const HEAVY: &str =
    "heavy: minutes and ~10 GiB of host memory on lavapipe/PoCL; run on the GPU machine";

/// Every known quirk.
pub const QUIRKS: &[Quirk] = &[
    Quirk {
        backend: "opencl",
        device: "",
        case: "degenerate/image-8192x8192",
        reason: HEAVY,
    },
    Quirk {
        backend: "opencl",
        device: "",
        case: "degenerate/photons-2^26",
        reason: HEAVY,
    },
    Quirk {
        backend: "wgpu",
        device: "",
        case: "degenerate/image-8192x8192",
        reason: HEAVY,
    },
    Quirk {
        backend: "wgpu",
        device: "",
        case: "degenerate/photons-2^26",
        reason: HEAVY,
    },
    Quirk {
        backend: "vulkan",
        device: "",
        case: "degenerate/image-8192x8192",
        reason: HEAVY,
    },
    Quirk {
        backend: "vulkan",
        device: "",
        case: "degenerate/photons-2^26",
        reason: HEAVY,
    },
];

/// The quirk that holds case `case` back on backend `backend` with device `device`, if any.
pub fn quirk(backend: &str, device: &str, case: &str) -> Option<&'static Quirk> {
    QUIRKS
        .iter()
        .find(|q| q.backend == backend && q.case == case && device.contains(q.device))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::harness::REFERENCE_BACKEND;
    use crate::stiff::catalogue;

    /// Every quirk names a case of the catalogue (a misspelt id would silently run a heavy
    /// case everywhere), none holds back a case on the reference, and the table holds back
    /// exactly the heavy cases on every other backend, as the suite did before the table.
    #[test]
    fn quirks_name_catalogue_cases_and_hold_back_exactly_the_heavy_ones() {
        let cases = catalogue();
        for q in QUIRKS {
            assert!(
                cases.iter().any(|c| c.id() == q.case),
                "quirk for unknown case {q:?}"
            );
            assert_ne!(q.backend, REFERENCE_BACKEND, "{q:?}");
        }
        for backend in ["cpu", "opencl", "wgpu", "vulkan"] {
            for c in &cases {
                let held = quirk(backend, "any device", &c.id()).is_some();
                let want = c.heavy && backend != REFERENCE_BACKEND;
                assert_eq!(held, want, "{backend} / {}", c.id());
            }
        }
    }
}
