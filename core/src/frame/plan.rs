//! The frame plan ("leave out what a scene does not need"), the part every
//! technique shares: derived from the scene and the settings before any work, it says
//! which lights emit photons (and why the others do not), which material features the
//! photon kernel needs (its compiled variant), which outputs the caller asked for, which
//! passes run and which device buffers exist, each with a reason. A technique builds it
//! in its own `plan` module and records exactly the planned passes; the plan travels in
//! [`crate::frame::stats::FrameStats`] (`stats.json`).
//!
//! With pruning off every pass that the scene's content would need runs, every buffer
//! exists, every light with a domain emits and the kernel variant has every feature: the
//! baseline conformance compares pruning against. A setting that fuses one pass into
//! another (Sspm's `fused_deposit`, AdaptiveCaustics' fused finest level) leaves the
//! fused pass out either way, with its reason.

use crate::kernels::TraceVariant;
use crate::scene::{Material, Scene};
use serde::Serialize;

/// Material features used by the scene's objects (materials no object uses do not count).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SceneFeatures {
    /// Some object is a mirror.
    pub mirrors: bool,
    /// Some object is a dielectric.
    pub dielectrics: bool,
    /// A dispersive dielectric (a non-zero Cauchy B, or the Abbe model).
    pub dispersion: bool,
    /// A dielectric with a non-zero absorption coefficient.
    pub absorption: bool,
}

impl SceneFeatures {
    /// The features of the materials the scene's objects use.
    pub fn of(scene: &Scene) -> SceneFeatures {
        let mut f = SceneFeatures::default();
        for o in &scene.objects {
            match scene.materials.get(&o.material) {
                Some(Material::Mirror { .. }) => f.mirrors = true,
                Some(m @ Material::Dielectric { absorption, .. }) => {
                    f.dielectrics = true;
                    f.dispersion |= m.is_dispersive();
                    f.absorption |= absorption.max_element() > 0.0;
                }
                _ => {}
            }
        }
        f
    }

    /// The `trace_photons` variant that covers these features and no more.
    pub fn trace_variant(&self) -> TraceVariant {
        TraceVariant {
            dielectric: self.dielectrics,
            dispersion: self.dispersion,
            absorption: self.absorption,
            surface_store: false,
            fresnel_split: false,
            adaptive: false,
            fused_deposit: false,
        }
    }
}

/// Whether a light emits photons this frame, and why (not).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightPlan {
    /// Index of the light in [`Scene::lights`].
    pub light: u32,
    /// Whether it emits photons this frame.
    pub emits: bool,
    /// Why it emits or not, in words.
    pub reason: String,
}

/// A pass of the frame: whether it runs, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassPlan {
    /// Kernel name of the pass.
    pub name: String,
    /// Whether it runs this frame.
    pub runs: bool,
    /// Why it runs or not, in words.
    pub reason: String,
}

/// A device buffer the technique created (name and bytes).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BufferPlan {
    /// The buffer's label.
    pub name: String,
    /// Its size (bytes).
    pub bytes: u64,
}

/// Everything decided about a frame before any work (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FramePlan {
    /// False: pruning off (every pass, buffer and feature; the comparison baseline).
    pub prune: bool,
    /// Material features of the scene's objects.
    pub features: SceneFeatures,
    /// The outputs the caller asked for, by name.
    pub outputs: Vec<String>,
    /// Every light of the scene, in order, with whether it emits and why.
    pub lights: Vec<LightPlan>,
    /// The `trace_photons` variant the photon passes run (`None`: no photon pass).
    pub trace_variant: Option<TraceVariant>,
    /// Every pass of the technique, in order, run or skipped.
    pub passes: Vec<PassPlan>,
    /// The device buffers created for the frame (filled in by the technique).
    pub buffers: Vec<BufferPlan>,
}

impl FramePlan {
    /// Whether pass `name` runs.
    pub fn runs(&self, name: &str) -> bool {
        self.passes.iter().any(|p| p.name == name && p.runs)
    }

    /// Whether the plan's device buffers include one whose name contains `what`.
    pub fn has_buffer(&self, what: &str) -> bool {
        self.buffers.iter().any(|b| b.name.contains(what))
    }
}
