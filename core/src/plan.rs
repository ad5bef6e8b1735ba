//! The frame plan (DESIGN 3, "leave out what a scene does not need"): derived from the
//! scene and the settings before any work, it says which lights emit photons (and why
//! the others do not), which material features the photon kernel needs (its compiled
//! variant), which outputs the caller asked for, and from those which passes run and
//! which device buffers exist. [`crate::Sspm`] records exactly the planned passes and
//! creates exactly the planned buffers; the plan travels in `FrameStats` (`stats.json`)
//! with a reason for every pass, run or skipped.
//!
//! With `SspmSettings::prune` off every pass runs, every buffer exists, every light with
//! a domain emits (lights that miss the casters emit their whole domain) and the kernel
//! variant has every feature: the baseline that conformance compares pruning against.

use crate::kernels::TraceVariant;
use crate::scene::{Material, Scene};
use crate::sspm::FrameConstants;
use serde::{Deserialize, Serialize};

/// The images a caller asks a frame for (all by default). Composite needs direct light
/// and filtered caustics internally even when they are not asked for themselves.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct Outputs {
    /// Direct light + filtered caustics.
    pub composite: bool,
    /// Direct light alone.
    pub direct: bool,
    /// Caustic radiance straight from the screen-space photon map.
    pub raw_caustics: bool,
    /// Caustic radiance after the bilateral gather.
    pub filtered_caustics: bool,
}

impl Default for Outputs {
    fn default() -> Self {
        Outputs {
            composite: true,
            direct: true,
            raw_caustics: true,
            filtered_caustics: true,
        }
    }
}

impl Outputs {
    /// Only the filtered caustics (a renderer that does its own direct light).
    pub const CAUSTICS_ONLY: Outputs = Outputs {
        composite: false,
        direct: false,
        raw_caustics: false,
        filtered_caustics: true,
    };

    pub fn any(&self) -> bool {
        self.composite || self.direct || self.raw_caustics || self.filtered_caustics
    }
}

/// One of a frame's output images.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Output {
    Composite,
    Direct,
    RawCaustics,
    FilteredCaustics,
}

impl Output {
    pub const ALL: [Output; 4] = [
        Output::Composite,
        Output::Direct,
        Output::RawCaustics,
        Output::FilteredCaustics,
    ];

    /// File-name stem (`composite`, `direct`, `caustics_raw`, `caustics_filtered`).
    pub fn stem(&self) -> &'static str {
        match self {
            Output::Composite => "composite",
            Output::Direct => "direct",
            Output::RawCaustics => "caustics_raw",
            Output::FilteredCaustics => "caustics_filtered",
        }
    }

    pub fn requested(&self, o: &Outputs) -> bool {
        match self {
            Output::Composite => o.composite,
            Output::Direct => o.direct,
            Output::RawCaustics => o.raw_caustics,
            Output::FilteredCaustics => o.filtered_caustics,
        }
    }
}

/// Material features used by the scene's objects (materials no object uses do not count).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct SceneFeatures {
    pub mirrors: bool,
    pub dielectrics: bool,
    /// A dielectric with a non-zero Cauchy B.
    pub dispersion: bool,
    /// A dielectric with a non-zero absorption coefficient.
    pub absorption: bool,
}

impl SceneFeatures {
    pub fn of(scene: &Scene) -> SceneFeatures {
        let mut f = SceneFeatures::default();
        for o in &scene.objects {
            match scene.materials.get(&o.material) {
                Some(Material::Mirror { .. }) => f.mirrors = true,
                Some(Material::Dielectric {
                    cauchy_b,
                    absorption,
                    ..
                }) => {
                    f.dielectrics = true;
                    f.dispersion |= *cauchy_b != 0.0;
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
        }
    }
}

/// Whether a light emits photons this frame, and why (not).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightPlan {
    pub light: u32,
    pub emits: bool,
    pub reason: String,
}

/// A pass of the frame: whether it runs, and why.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PassPlan {
    pub name: String,
    pub runs: bool,
    pub reason: String,
}

/// A device buffer the technique created (name and bytes).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct BufferPlan {
    pub name: String,
    pub bytes: u64,
}

/// Everything decided about a frame before any work (see the module docs).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FramePlan {
    /// False: pruning off (every pass, buffer and feature; the comparison baseline).
    pub prune: bool,
    pub features: SceneFeatures,
    pub outputs: Outputs,
    pub lights: Vec<LightPlan>,
    /// The `trace_photons` variant the photon passes run (`None`: no photon pass).
    pub trace_variant: Option<TraceVariant>,
    /// Every pass of the technique, in order, run or skipped.
    pub passes: Vec<PassPlan>,
    /// The device buffers created for the frame (filled in by the technique).
    pub buffers: Vec<BufferPlan>,
}

/// What the passes of a plan need, as flags (the technique creates buffers from them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Needs {
    pub direct_light: bool,
    pub photons: bool,
    pub gather: bool,
    pub composite: bool,
}

impl FramePlan {
    /// Plans a frame of `Sspm` for `scene` with emission already decided in `constants`.
    pub fn new(
        scene: &Scene,
        constants: &FrameConstants,
        outputs: Outputs,
        prune: bool,
    ) -> FramePlan {
        let features = SceneFeatures::of(scene);
        let mut lights: Vec<LightPlan> = constants
            .domains
            .iter()
            .map(|(i, _)| LightPlan {
                light: *i,
                emits: true,
                reason: if constants.unpruned.contains(i) {
                    "pruning off: emits its whole domain".into()
                } else {
                    "its emission domain reaches a caustic caster".into()
                },
            })
            .collect();
        lights.extend(constants.skipped_lights.iter().map(|(i, why)| LightPlan {
            light: *i,
            emits: false,
            reason: why.reason().into(),
        }));
        lights.sort_by_key(|l| l.light);

        let emits = !constants.domains.is_empty();
        let n = Needs::of(outputs, emits, prune);
        let mut passes = Vec::new();
        let mut pass = |name: &str, runs: bool, reason: &str| {
            passes.push(PassPlan {
                name: name.into(),
                runs,
                reason: reason.into(),
            })
        };
        let off = "pruning off: every pass runs";
        let why_photons = if !prune {
            off
        } else if !emits {
            "no light emits photons"
        } else if !(outputs.composite || outputs.raw_caustics || outputs.filtered_caustics) {
            "no caustic output requested"
        } else {
            "a light reaches a caustic caster and a caustic output is requested"
        };
        pass(
            "primary_gbuffer",
            true,
            "every output is shaded from the G-buffer",
        );
        pass(
            "direct_light",
            n.direct_light,
            if !prune {
                off
            } else if n.direct_light {
                "direct or composite output requested"
            } else {
                "neither direct nor composite output requested"
            },
        );
        pass("trace_photons", n.photons, why_photons);
        pass("deposit_screen", n.photons, why_photons);
        pass("resolve_caustics", n.photons, why_photons);
        let why_gather = if !prune {
            off
        } else if !n.photons {
            why_photons
        } else if n.gather {
            "filtered caustics or composite requested"
        } else {
            "neither filtered caustics nor composite requested"
        };
        pass("tile_hit_distance", n.gather, why_gather);
        pass("bilateral_gather", n.gather, why_gather);
        pass(
            "composite",
            n.composite,
            if !prune {
                off
            } else if !outputs.composite {
                "composite not requested"
            } else if n.composite {
                "composite requested"
            } else {
                "no caustics: the composite is the direct image"
            },
        );
        FramePlan {
            prune,
            features,
            outputs,
            lights,
            trace_variant: n.photons.then(|| {
                if prune {
                    features.trace_variant()
                } else {
                    TraceVariant::ALL
                }
            }),
            passes,
            buffers: Vec::new(),
        }
    }

    /// The plan's needs (which pass groups run).
    pub fn needs(&self) -> Needs {
        let runs = |name: &str| self.passes.iter().any(|p| p.name == name && p.runs);
        Needs {
            direct_light: runs("direct_light"),
            photons: runs("trace_photons"),
            gather: runs("bilateral_gather"),
            composite: runs("composite"),
        }
    }

    /// Whether the plan's device buffers include one whose name contains `what`.
    pub fn has_buffer(&self, what: &str) -> bool {
        self.buffers.iter().any(|b| b.name.contains(what))
    }
}

impl Needs {
    /// Which pass groups run for `outputs`, given whether any light emits.
    pub fn of(outputs: Outputs, emits: bool, prune: bool) -> Needs {
        if !prune {
            return Needs {
                direct_light: true,
                photons: true,
                gather: true,
                composite: true,
            };
        }
        let photons =
            emits && (outputs.composite || outputs.raw_caustics || outputs.filtered_caustics);
        Needs {
            direct_light: outputs.direct || outputs.composite,
            photons,
            gather: photons && (outputs.filtered_caustics || outputs.composite),
            composite: photons && outputs.composite,
        }
    }
}
