//! caustica: real-time photon-mapping techniques for caustics, written once against a
//! backend trait and run on the backend chosen at run time.
//!
//! ```no_run
//! use caustica::{open_backend, scene::builtin, Output, Sspm, SspmSettings};
//! let mut backend = open_backend("cpu").unwrap();
//! let scene = builtin::builtin("sphere").unwrap();
//! let mut sspm = Sspm::new(backend.as_mut(), &scene, SspmSettings::default()).unwrap();
//! let stats = sspm.frame(backend.as_mut(), &mut |_| {}).unwrap();
//! let image = sspm.read_output(backend.as_mut(), Output::Composite).unwrap();
//! println!("{} photons stored, {:.1} ms", stats.photons_stored, stats.frame_ms);
//! # let _ = image;
//! ```

pub mod output;
pub mod reference;
pub mod report;

pub use caustica_core::*;

/// A backend this build knows about, and whether it works on this machine.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BackendStatus {
    pub name: &'static str,
    /// Compiled into this build (cargo feature).
    pub compiled: bool,
    /// `Ok(device description)` when it opened, else why not.
    pub available: Result<String, String>,
}

/// Every backend of the project, in preference order for `auto`.
pub const BACKEND_NAMES: [&str; 4] = ["vulkan", "wgpu", "opencl", "cpu"];

/// Opens a backend by name (`cpu`, ...; `auto` = the first in [`BACKEND_NAMES`] that works).
pub fn open_backend(name: &str) -> Result<Box<dyn Backend>, BackendError> {
    match name {
        "auto" => {
            let mut last = None;
            for n in BACKEND_NAMES {
                match open_backend(n) {
                    Ok(b) => return Ok(b),
                    Err(e) => last = Some(e),
                }
            }
            Err(last.unwrap_or_else(|| BackendError::Unavailable {
                backend: "auto".into(),
                reason: "no backend".into(),
            }))
        }
        #[cfg(feature = "cpu")]
        "cpu" => Ok(Box::new(caustica_cpu::CpuBackend::new()?)),
        #[cfg(feature = "opencl")]
        "opencl" => Ok(Box::new(caustica_opencl::OpenClBackend::new()?)),
        #[cfg(feature = "wgpu")]
        "wgpu" => Ok(Box::new(caustica_wgpu::WgpuBackend::new()?)),
        #[cfg(not(feature = "wgpu"))]
        "wgpu" => Err(BackendError::Unavailable {
            backend: name.into(),
            reason: "not compiled in (cargo feature `wgpu`)".into(),
        }),
        #[cfg(feature = "vulkan")]
        "vulkan" => Ok(Box::new(caustica_vulkan::VulkanBackend::new()?)),
        #[cfg(not(feature = "vulkan"))]
        "vulkan" => Err(BackendError::Unavailable {
            backend: name.into(),
            reason: "not compiled in (cargo feature `vulkan`)".into(),
        }),
        #[cfg(not(feature = "cpu"))]
        "cpu" => Err(BackendError::Unavailable {
            backend: name.into(),
            reason: "not compiled in (cargo feature `cpu`)".into(),
        }),
        #[cfg(not(feature = "opencl"))]
        "opencl" => Err(BackendError::Unavailable {
            backend: name.into(),
            reason: "not compiled in (cargo feature `opencl`)".into(),
        }),
        _ => Err(BackendError::Unavailable {
            backend: name.into(),
            reason: format!(
                "unknown backend; choose one of auto, {}",
                BACKEND_NAMES.join(", ")
            ),
        }),
    }
}

/// Status of every backend on this machine.
pub fn backend_statuses() -> Vec<BackendStatus> {
    BACKEND_NAMES
        .iter()
        .map(|&name| {
            let compiled = (name == "cpu" && cfg!(feature = "cpu"))
                || (name == "opencl" && cfg!(feature = "opencl"))
                || (name == "wgpu" && cfg!(feature = "wgpu"))
                || (name == "vulkan" && cfg!(feature = "vulkan"));
            BackendStatus {
                name,
                compiled,
                available: open_backend(name)
                    .map(|b| b.capabilities().device)
                    .map_err(|e| e.to_string()),
            }
        })
        .collect()
}
