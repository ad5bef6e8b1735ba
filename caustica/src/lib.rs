//! caustica: real-time photon-mapping techniques for caustics and indirect light,
//! written once against a small backend trait and run on the backend chosen at run time
//! (CPU, OpenCL, wgpu or Vulkan).
//!
//! ```no_run
//! use caustica::{open_backend, scene::builtin, Sspm, SspmSettings, Output};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! let mut backend = open_backend("auto")?; // a hardware GPU, else the CPU backend
//! let scene = builtin::builtin("sphere").expect("built-in scene");
//! let mut sspm = Sspm::new(backend.as_mut(), &scene, SspmSettings::default())?;
//! let stats = sspm.frame(backend.as_mut(), &mut |_| {})?;
//! let image = sspm.read_output(backend.as_mut(), Output::Composite)?; // linear radiance
//! println!("{} photons stored, {:.1} ms", stats.photons_stored, stats.frame_ms);
//! sspm.free(backend.as_mut())?;
//! # let _ = image;
//! # Ok(())
//! # }
//! ```
//!
//! Every technique is a type of its own with its settings, created over a scene and
//! driven the same way (frame, updates, outputs, free); see [`CausticMap`],
//! [`AdaptiveCaustics`] and [`PhotonGi`] for one example each. Any technique by name,
//! without naming its type: [`techniques::create`] returns a `Box<dyn` [`Technique`]`>`;
//! [`techniques::TECHNIQUES`] lists them.
//!
//! Every technique speaks one output vocabulary ([`Output`]) and lists the outputs it has
//! ([`Technique::outputs`]), so a host writes one function for all four. This one renders
//! a frame of any technique and reads its caustics (an output the technique lacks, such as
//! PhotonGi's, is [`Error::NoSuchOutput`]):
//!
//! ```
//! use caustica::{open_backend, scene::builtin, techniques, Error, Output, Technique};
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! fn caustics(t: &mut dyn Technique, backend: &mut dyn caustica::Backend)
//!     -> Result<Option<caustica::Image>, Error> {
//!     t.frame(backend, &mut |_| {})?;
//!     let has = t.outputs().iter().any(|o| o.output == Output::FilteredCaustics);
//!     if !has {
//!         return Ok(None);
//!     }
//!     t.read_output(backend, Output::FilteredCaustics).map(Some)
//! }
//!
//! let mut backend = open_backend("cpu")?;
//! let mut scene = builtin::builtin("sphere").expect("built-in scene");
//! (scene.camera.width, scene.camera.height) = (64, 36);
//! for name in techniques::technique_names() {
//!     let small = serde_json::json!({ "frame": { "photons_w": 64, "photons_h": 64 } });
//!     let mut t = techniques::create(name, backend.as_mut(), &scene, &small)?;
//!     match caustics(t.as_mut(), backend.as_mut())? {
//!         Some(img) => println!("{name}: {} caustic pixels", img.pixels.len()),
//!         None => println!("{name} has no caustics"),
//!     }
//!     let e = t.read_output(backend.as_mut(), Output::CausticAtlas);
//!     assert!(e.is_ok() || matches!(e, Err(Error::NoSuchOutput { .. })));
//!     t.free(backend.as_mut())?;
//! }
//! # Ok(())
//! # }
//! ```
//!
//! What is here: scenes ([`scene`]: the model, built-ins, the JSON format), opening a
//! backend ([`open_backend`], [`backend_statuses`]), the techniques with their settings
//! and outputs, frame statistics, errors, host images and their files ([`output`]), error
//! metrics ([`metrics`]) and references ([`reference`](mod@reference)); each backend's own API behind its
//! cargo feature in [`backends`] (embedding into a host's wgpu or Vulkan device);
//! `glam`, `wgpu` and `ash` as caustica uses them. Backend authors find the kernel list,
//! recordings, device layouts and the frame host under [`internals`], the one module of
//! what lies below the techniques. With the `report` feature,
//! [`report`] measures error against run time.

#![warn(missing_docs)]

/// The README's examples, compiled by `cargo test --doc` (the embedding fragments are
/// marked `ignore`: the wgpu and Vulkan ones are taken from the runnable examples
/// `frame_loop` and `embed_ash`; the OpenCL one has no example program).
#[cfg(doctest)]
#[doc = include_str!("../../README.md")]
pub struct ReadmeExamples;

#[cfg(feature = "gltf")]
pub mod gltf_scene;
pub mod output;
pub mod reference;
#[cfg(feature = "report")]
pub mod report;
pub mod scene_file;
pub mod technique_spec;

pub use caustica_core::backend::{
    Backend, BackendError, Capabilities, DeviceType, Finished, Submission,
};
pub use caustica_core::frame::error::Error;
pub use caustica_core::frame::image::Image;
pub use caustica_core::frame::metrics;
pub use caustica_core::frame::output::{Output, OutputInfo, Outputs};
pub use caustica_core::frame::plan::FramePlan;
pub use caustica_core::frame::settings::{
    Dispersion, FrameSettings, TechniqueSettings, TraceSettings,
};
pub use caustica_core::frame::stats::FrameStats;
pub use caustica_core::frame::submitted::{FrameTicket, RecordedFrame};
pub use caustica_core::frame::technique::{Progress, Technique};
pub use caustica_core::scene;
pub use caustica_core::scene::Scene;
pub use caustica_core::techniques::sspm::{FrameImages, GatherFilter, Sspm, SspmSettings};
pub use caustica_core::{AtlasSettings, PlaneSettings, ScreenSettings, TraversalSettings};

/// CausticMap (Vanderstichelen 2021): photons from each light's view planes into a caustic atlas in
/// the receivers' texture space, looked up by the camera through mirrors and glass. The
/// atlas is remade only when lights, settings or the seed change: a frame after a camera
/// move reuses it.
///
/// ```no_run
/// use caustica::{open_backend, scene::builtin, CausticMap, CausticMapSettings, Output};
/// use caustica::TechniqueSettings; // with_photons
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut backend = open_backend("auto")?;
/// let scene = builtin::builtin("sphere").expect("built-in scene");
/// // the knobs every technique shares sit in `frame`, the atlas's in `atlas`
/// let mut settings = CausticMapSettings::default().with_photons(1024, 1024);
/// settings.atlas.atlas_size = 1024;
/// let mut map = CausticMap::new(backend.as_mut(), &scene, settings)?;
/// map.frame(backend.as_mut(), &mut |_| {})?;
/// let caustics = map.read_output(backend.as_mut(), Output::FilteredCaustics)?; // radiance
/// let atlas = map.read_output(backend.as_mut(), Output::CausticAtlas)?; // irradiance, W/m^2
/// map.free(backend.as_mut())?;
/// # let _ = (caustics, atlas);
/// # Ok(())
/// # }
/// ```
pub use caustica_core::techniques::caustic_map::CausticMap;
pub use caustica_core::techniques::caustic_map::{
    CausticMapSettings, EmissionPlane, FresnelModel, FresnelSplit, MapGather,
};

/// AdaptiveCaustics (Wyman 2009): the light view planes sampled coarse to fine, so that
/// photons are traced only where the casters are; its photons land in the caustic atlas
/// (the default) or the screen photon map (`deposit: screen`).
///
/// ```no_run
/// use caustica::{open_backend, scene::builtin, AdaptiveCaustics, AdaptiveCausticsSettings};
/// use caustica::{AdaptiveDeposit, AdaptiveMetric, AdaptiveStats, Output};
/// use caustica::{TechniqueSettings, TraversalSettings};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut backend = open_backend("auto")?;
/// let scene = builtin::builtin("spot-glass").expect("built-in scene");
/// let settings = AdaptiveCausticsSettings {
///     traversal: TraversalSettings { metric: AdaptiveMetric::Error, ..Default::default() },
///     deposit: AdaptiveDeposit::Atlas,
///     ..Default::default()
/// }
/// .with_photons(2048, 2048); // the dense-equivalent grid: the pyramid's finest level
/// let mut t = AdaptiveCaustics::new(backend.as_mut(), &scene, settings)?;
/// let stats = t.frame(backend.as_mut(), &mut |_| {})?;
/// if let Some(a) = AdaptiveStats::of(&stats) {
///     println!("{} of {} photons traced", a.photons_processed, a.dense_equivalent_photons);
/// }
/// let composite = t.read_output(backend.as_mut(), Output::Composite)?;
/// t.free(backend.as_mut())?;
/// # let _ = composite;
/// # Ok(())
/// # }
/// ```
pub use caustica_core::techniques::adaptive_caustics::AdaptiveCaustics;
pub use caustica_core::techniques::adaptive_caustics::{
    AdaptiveCausticsSettings, AdaptiveDeposit, AdaptiveMetric, AdaptiveStats, ClusterRelevance,
};

/// PhotonGi (Smal 2019): multi-bounce indirect light by photon splatting from each light's
/// reflective shadow map, with the chapter's temporal and A-Trous filters.
///
/// ```no_run
/// use caustica::{open_backend, scene::builtin, Output, PhotonGi, PhotonGiSettings};
/// # fn main() -> Result<(), Box<dyn std::error::Error>> {
/// let mut backend = open_backend("auto")?;
/// let scene = builtin::builtin("cornell").expect("built-in scene");
/// let mut gi = PhotonGi::new(backend.as_mut(), &scene, PhotonGiSettings::default())?;
/// for seed in 0..4 {
///     gi.set_seed(seed); // the temporal filter accumulates over frames
///     gi.frame(backend.as_mut(), &mut |_| {})?;
/// }
/// let composite = gi.read_output(backend.as_mut(), Output::Composite)?;
/// gi.free(backend.as_mut())?;
/// # let _ = composite;
/// # Ok(())
/// # }
/// ```
pub use caustica_core::techniques::photon_gi::PhotonGi;
pub use caustica_core::techniques::photon_gi::{
    IndirectEstimator, PhotonGiSettings, PhotonGiStats, RsmSampling,
};

/// The techniques: the registry ([`techniques::TECHNIQUES`], [`techniques::create`]) and
/// one module per technique, with everything each exports.
pub mod techniques {
    pub use caustica_core::techniques::{
        adaptive_caustics, caustic_map, create, photon_gi, sspm, technique_names, TechniqueEntry,
        TECHNIQUES,
    };
}

/// For backend authors and tools that work below the techniques; not needed to use a
/// technique. The backend trait's vocabulary: [`backend`](internals::backend),
/// [`recording`](internals::recording) (recordings and their steps),
/// [`kernels`](internals::kernels) (the kernel list and declarations),
/// [`device`](internals::device) (device layouts and handles) and
/// [`math`](internals::math) (the scalar math every shader mirrors). The frame machinery:
/// the frame [`host`](internals::host) and the seam a technique implements over it
/// ([`pipeline::Pipeline`](internals::pipeline::Pipeline)), the non-blocking frame
/// ([`submitted`](internals::submitted)), and the modules behind the top level's
/// [`Image`], [`FramePlan`] and [`FrameStats`] with their helpers
/// ([`image`](internals::image), [`plan`](internals::plan), [`stats`](internals::stats)).
pub mod internals {
    pub use caustica_core::frame::{host, image, pipeline, plan, stats, submitted};
    pub use caustica_core::{backend, device, kernels, math, recording};
}

/// Each backend's own API (embedding into a host's device, device choice), behind its
/// cargo feature.
pub mod backends {
    #[cfg(feature = "cpu")]
    pub use caustica_cpu as cpu;
    #[cfg(feature = "opencl")]
    pub use caustica_opencl as opencl;
    #[cfg(feature = "vulkan")]
    pub use caustica_vulkan as vulkan;
    #[cfg(feature = "wgpu")]
    pub use caustica_wgpu as wgpu;
}

#[cfg(feature = "vulkan")]
pub use ash;
pub use glam;
#[cfg(feature = "wgpu")]
pub use wgpu;

/// A backend this build knows about, and whether it works on this machine.
#[derive(Clone, Debug, serde::Serialize)]
pub struct BackendStatus {
    /// Backend name (`cpu`, `opencl`, `wgpu`, `vulkan`).
    pub name: &'static str,
    /// Compiled into this build (cargo feature).
    pub compiled: bool,
    /// `Ok((device description, device type))` when it opened, else why not.
    pub available: Result<(String, DeviceType), String>,
}

/// Every backend of the project.
pub const BACKEND_NAMES: [&str; 4] = ["vulkan", "wgpu", "opencl", "cpu"];

/// Opens a backend by name: `cpu`, `opencl`, `wgpu`, `vulkan`, or `auto`, which opens
/// every backend that works here and keeps the best by [`DeviceType::auto_rank`]: a
/// hardware GPU (discrete before integrated; on one device, the backends in
/// [`BACKEND_NAMES`] order), then the native CPU backend, then GPU APIs emulated on the
/// CPU (lavapipe, PoCL).
pub fn open_backend(name: &str) -> Result<Box<dyn Backend>, BackendError> {
    if name != "auto" {
        return open_named(name);
    }
    let mut best: Option<(u32, Box<dyn Backend>)> = None;
    let mut why = Vec::new();
    for n in BACKEND_NAMES {
        match open_named(n) {
            Ok(b) => {
                let rank = b.capabilities().device_type.auto_rank();
                if best.as_ref().is_none_or(|(r, _)| rank < *r) {
                    best = Some((rank, b));
                }
            }
            Err(e) => why.push(e.to_string()),
        }
    }
    best.map(|(_, b)| b)
        .ok_or_else(|| BackendError::Unavailable {
            backend: "auto".into(),
            reason: format!("no backend opened: {}", why.join("; ")),
        })
}

/// The order in which `auto` prefers the backends that open here (best first), with
/// their device types.
pub fn auto_order() -> Vec<(&'static str, DeviceType)> {
    let mut v: Vec<(&'static str, DeviceType)> = BACKEND_NAMES
        .iter()
        .filter_map(|&n| {
            open_named(n)
                .ok()
                .map(|b| (n, b.capabilities().device_type))
        })
        .collect();
    v.sort_by_key(|(_, t)| t.auto_rank()); // stable: BACKEND_NAMES order within a type
    v
}

fn not_compiled(name: &str) -> BackendError {
    BackendError::Unavailable {
        backend: name.into(),
        reason: format!("not compiled in (cargo feature `{name}`)"),
    }
}

fn open_named(name: &str) -> Result<Box<dyn Backend>, BackendError> {
    match name {
        #[cfg(feature = "cpu")]
        "cpu" => Ok(Box::new(caustica_cpu::CpuBackend::new()?)),
        #[cfg(feature = "opencl")]
        "opencl" => Ok(Box::new(caustica_opencl::OpenClBackend::new()?)),
        #[cfg(feature = "wgpu")]
        "wgpu" => Ok(Box::new(caustica_wgpu::WgpuBackend::new()?)),
        #[cfg(feature = "vulkan")]
        "vulkan" => Ok(Box::new(caustica_vulkan::VulkanBackend::new()?)),
        n if BACKEND_NAMES.contains(&n) => Err(not_compiled(n)),
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
            let opened = open_named(name);
            BackendStatus {
                name,
                compiled: !matches!(&opened, Err(BackendError::Unavailable { reason, .. }) if reason.starts_with("not compiled")),
                available: opened
                    .map(|b| {
                        let c = b.capabilities();
                        (c.device, c.device_type)
                    })
                    .map_err(|e| e.to_string()),
            }
        })
        .collect()
}
