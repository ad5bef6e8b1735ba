//! The screen receiver's frame plan: which of its passes run for the scene, the lights'
//! emission and the requested outputs, and why ([`crate::frame::plan`] holds the shared
//! vocabulary).

use super::settings::GatherFilter;
use crate::frame::output::{Output, Outputs};
use crate::frame::plan::{FramePlan, LightPlan, PassPlan, SceneFeatures};
use crate::kernels::TraceVariant;
use crate::scene::Scene;

/// What the passes of a plan need, as flags (the technique creates buffers from them).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Needs {
    /// `direct_light` runs.
    pub direct_light: bool,
    /// The photon passes run: `trace_photons`, `deposit_screen` (unless the trace
    /// deposits itself), `resolve_caustics`.
    pub photons: bool,
    /// The filter runs: `photon_count_table`, `gather_footprint` and `density_gather`
    /// (twice each but the footprint), or `tile_hit_distance` and both
    /// `bilateral_gather` passes, as [`GatherFilter`] says.
    pub gather: bool,
    /// `composite` runs.
    pub composite: bool,
}

/// Plans a screen-receiver frame for `scene` whose lights' emission is already decided
/// (`lights`: Sspm's projection volumes or AdaptiveCaustics' light view planes).
pub fn plan_frame(
    scene: &Scene,
    lights: Vec<LightPlan>,
    outputs: Outputs,
    prune: bool,
    (filter, temporal, atrous): (GatherFilter, bool, bool),
) -> FramePlan {
    let features = SceneFeatures::of(scene);
    let emits = lights.iter().any(|l| l.emits);
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
    } else if !(outputs.any_of(&[
        Output::Composite,
        Output::RawCaustics,
        Output::FilteredCaustics,
    ])) {
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
    let density = filter == GatherFilter::Density;
    let other = |chosen: bool| {
        if chosen {
            why_gather
        } else if density {
            "filter is density: the bilateral gather's passes never run"
        } else {
            "filter is bilateral: the density gather's passes never run"
        }
    };
    for name in ["photon_count_table", "gather_footprint", "density_gather"] {
        pass(name, n.gather && density, other(density));
    }
    for name in ["tile_hit_distance", "bilateral_gather"] {
        pass(name, n.gather && !density, other(!density));
    }
    pass(
        "temporal_blend",
        n.gather && temporal,
        if !n.gather {
            why_gather
        } else if temporal {
            "temporal on: the filtered caustics blended with their reprojected history"
        } else {
            "temporal off (frame.temporal)"
        },
    );
    pass(
        "atrous_filter",
        n.gather && atrous,
        if !n.gather {
            why_gather
        } else if atrous {
            "atrous_iterations > 0: the caustics filtered again by A-Trous iterations"
        } else {
            "atrous_iterations is 0 (frame.atrous_iterations)"
        },
    );
    pass(
        "composite",
        n.composite,
        if !prune {
            off
        } else if !outputs.has(Output::Composite) {
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
        outputs: outputs.names(&super::outputs::OUTPUTS),
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

impl Needs {
    /// The needs of a plan made by [`plan_frame`] (which pass groups run).
    pub fn of_plan(plan: &FramePlan) -> Needs {
        Needs {
            direct_light: plan.runs("direct_light"),
            photons: plan.runs("trace_photons"),
            gather: plan.runs("density_gather") || plan.runs("bilateral_gather"),
            composite: plan.runs("composite"),
        }
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
        let photons = emits
            && (outputs.any_of(&[
                Output::Composite,
                Output::RawCaustics,
                Output::FilteredCaustics,
            ]));
        Needs {
            direct_light: outputs.any_of(&[Output::Direct, Output::Composite]),
            photons,
            gather: photons && (outputs.any_of(&[Output::FilteredCaustics, Output::Composite])),
            composite: photons && outputs.has(Output::Composite),
        }
    }
}
