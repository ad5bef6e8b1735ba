//! AdaptiveCaustics (Wyman 2009, "Adaptive Caustic Maps Using Deferred
//! Shading"): light view planes ([`crate::frame::emission::view_planes`]) sampled coarse
//! to fine by Wyman 2009's traversal ([`traversal`]), so that photons
//! are traced only where the casters are and, with the error metric, only where the map
//! still needs them; its output photons land in a receiver: the caustic atlas
//! ([`crate::frame::receivers::atlas`], the default, [`atlas`]) or the screen photon map
//! ([`crate::frame::receivers::screen`], [`screen`]).
//!
//! The source emits photons by point-sampling rasterised G-buffers of the refractor from
//! the light and refracts them in image space; here the traversal drives the exact
//! tracer of the other techniques (`trace_photons`, its `ADAPTIVE` variant), which makes
//! the source's G-buffer resolution question moot.
//!
//! Per frame with photon work, per light view plane: the 64^2 start grid's 2x2 clusters
//! are traced and judged (`refine_clusters`): discarded when every photon missed the
//! casters, output at the finest level or when the error metric holds, else refined into
//! four clusters of the next level; batches of clusters under `max_traversal_bytes`.
//! Photons output early carry their coarse texels' flux (the cluster's solid angle or
//! area), so the map's expectation is the dense grid's. With Wyman 2009's one-texel metric
//! (`error_texels: 1`) they all landed in one atlas texel, so that texel *is* the
//! cluster's footprint; with a wider tolerance (Wyman 2009's alternative) each output photon is
//! splatted over its cluster's footprint, the flux split exactly
//! (`math::photon_clusters::footprint_window`).

mod atlas;
mod screen;
mod settings;
mod stats;
pub mod traversal;

pub use settings::{
    AdaptiveCausticsSettings, AdaptiveDeposit, AdaptiveMetric, ClusterRelevance, TraversalSizes,
    LIST_BYTES_PER_ENTRY, MAX_PASSES_PER_LEVEL, SLOT_BYTES_PER_CLUSTER,
};
pub use stats::AdaptiveStats;
pub use traversal::{
    caster_rects, fit_planes, seed_window, AtlasTarget, DepositTarget, PhotonOptics, PlaneSeeds,
    ProbeLevels, ScreenTarget, Traversal, TraversalSettings, EMPTY_RECT,
};

use crate::backend::Backend;
use crate::device::handle::ImageBuf;
use crate::frame::allocation::Allocation;
use crate::frame::emission::view_planes::ViewPlanes;
use crate::frame::error::Error;
use crate::frame::host::{FrameHost, HostOptions};
use crate::frame::image::Image;
use crate::frame::output::{Output, Outputs};
use crate::frame::pipeline::{Change, FrameBuilder, Hosted, Pipeline, Reaction};
use crate::frame::plan::FramePlan;
use crate::frame::receivers::accumulation_seed;
use crate::frame::receivers::atlas::AtlasReceiver;
use crate::frame::receivers::screen::ScreenReceiver;
use crate::kernels::TraceVariant;

/// AdaptiveCaustics on one backend, for one scene: the frame host and
/// [`AdaptiveCausticsPipeline`].
pub type AdaptiveCaustics = Hosted<AdaptiveCausticsPipeline>;

/// Where the traversal's output photons land.
enum Target {
    /// The caustic atlas (texture-space photons, deposited by `refine_clusters`).
    Atlas {
        receiver: Box<AtlasReceiver>,
        /// The atlas holds the photons of the current lights, settings and seed.
        valid: bool,
    },
    /// The screen photon map (world-space photons, deposited by `deposit_screen`).
    Screen {
        receiver: Box<ScreenReceiver>,
        /// The receiver's and the traversal's buffers.
        owned: Allocation,
    },
}

/// AdaptiveCaustics' own state over the frame host.
pub struct AdaptiveCausticsPipeline {
    settings: AdaptiveCausticsSettings,
    planes: ViewPlanes,
    variant: TraceVariant,
    plan: FramePlan,
    traversal: Option<Traversal>,
    target: Target,
}

/// The light view planes of the host's scene fitted to the pyramid; refuses a light
/// whose flux is out of range.
fn view_planes(host: &FrameHost, s: &AdaptiveCausticsSettings) -> Result<ViewPlanes, Error> {
    let g = host.geometry();
    let mut planes = ViewPlanes::new(
        host.model(),
        g.bounds,
        g.caster_bounds,
        g.caster_spheres,
        g.has_dispersion,
        &s.frame,
        &s.planes,
    );
    fit_planes(
        &mut planes,
        &s.traversal(),
        s.frame.dispersion.flux_gain(g.has_dispersion),
    );
    planes.check_light_flux()?;
    Ok(planes)
}

/// The deepest level of any of `planes`' pyramids.
fn finest_level(planes: &ViewPlanes, start_grid: u32) -> u32 {
    let finest = planes
        .planes
        .iter()
        .map(|(_, _, p)| p.resolution.0)
        .max()
        .unwrap_or(1);
    (finest / start_grid).max(1).ilog2()
}

impl AdaptiveCausticsPipeline {
    /// Records the traversal of every plane into `target` (no wait: each level's passes
    /// read their counts on the device), the trace counters (`counters`) and the
    /// traversal's own read into the statistics at the frame's end.
    fn traverse(
        &mut self,
        host: &FrameHost,
        frame: &mut FrameBuilder,
        target: &DepositTarget,
        counters: crate::device::handle::Buf<u32>,
        stratum: u32,
    ) -> Result<(), Error> {
        // a new seed for every pass an accumulation adds; the passes stratify each cell
        // together (the first pass's jitter seed, this pass's stratum), as CausticMap's
        let seed = accumulation_seed(self.settings.frame.seed, stratum);
        let (Some(t), Some(variant)) = (&self.traversal, self.plan.trace_variant) else {
            return Ok(());
        };
        let s = &self.settings;
        let optics = PhotonOptics {
            max_bounces: s.trace.max_bounces,
            min_relative_power: s.trace.min_relative_power,
            fresnel_model: s.planes.fresnel.kernel_value(),
            dispersion_mode: s.frame.dispersion.kernel_value(),
            caster_spheres: self.planes.caster_spheres,
        };
        let total: u64 = self.planes.planes.iter().map(|(_, _, p)| p.texels()).sum();
        frame.expect_photons(total);
        let mut planes = Vec::with_capacity(self.planes.planes.len());
        for (light, k, plane) in &self.planes.planes {
            let flux = plane.power.as_dvec3() * plane.plane_measure();
            for c in 0..3 {
                frame.stats.emitted_flux[c] += flux[c];
            }
            planes.push(PlaneSeeds {
                light: *light,
                plane: *plane,
                seed: ViewPlanes::plane_seed(seed, *light, *k),
                jitter_seed: ViewPlanes::plane_seed(s.frame.seed, *light, *k),
                stratum,
            });
        }
        // the trace counters go into the statistics first (read at the frame's end like
        // the traversal's counts): the traversal's accounting takes their stored photons
        frame.counters_at_end(counters, self.planes.flux_quantum);
        t.record_frame(frame, host.scene(), variant, target, &planes, optics)
    }
}

impl Pipeline for AdaptiveCausticsPipeline {
    type Settings = AdaptiveCausticsSettings;

    const NAME: &'static str = "adaptive-caustics";

    fn parse_settings(json: &serde_json::Value) -> Result<AdaptiveCausticsSettings, Error> {
        let json = settings::earlier_form(json);
        crate::frame::settings::from_json(Self::NAME, &AdaptiveCausticsSettings::default(), &json)
    }

    fn validate(settings: &AdaptiveCausticsSettings) -> Result<(), Error> {
        settings.validate()
    }

    fn host_options(settings: &AdaptiveCausticsSettings) -> HostOptions {
        HostOptions {
            max_triangles: settings.frame.max_triangles,
            atlas_receivers: settings.deposit == AdaptiveDeposit::Atlas,
        }
    }

    fn create(
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        settings: AdaptiveCausticsSettings,
    ) -> Result<AdaptiveCausticsPipeline, Error> {
        let planes = view_planes(host, &settings)?;
        match settings.deposit {
            AdaptiveDeposit::Atlas => atlas::create(backend, host, settings, planes),
            AdaptiveDeposit::Screen => screen::create(backend, host, settings, planes),
        }
    }

    fn settings(&self) -> &AdaptiveCausticsSettings {
        &self.settings
    }

    fn set_seed(&mut self, seed: u32) {
        if seed != self.settings.frame.seed {
            self.settings.frame.seed = seed;
            if let Target::Atlas { receiver, valid } = &mut self.target {
                receiver.set_seed(seed);
                *valid = false;
            }
        }
    }

    fn record(
        &mut self,
        _backend: &mut dyn Backend,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        frame.stats.flux_quantum = self.planes.flux_quantum as f64;
        match self.target {
            Target::Atlas { .. } => self.record_atlas(host, frame),
            Target::Screen { .. } => self.record_screen(host, frame),
        }
    }

    fn react(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        change: Change,
    ) -> Result<Reaction, Error> {
        match change {
            Change::Camera => Ok(Reaction::Kept),
            Change::Materials { same_plan: true } => {
                match &mut self.target {
                    Target::Atlas { receiver, valid } => {
                        *valid = false;
                        receiver.reset_history();
                    }
                    Target::Screen { receiver, .. } => receiver.reset_history(),
                }
                Ok(Reaction::Kept)
            }
            Change::Materials { same_plan: false } => Ok(Reaction::Rebuild),
            _ => match self.target {
                Target::Atlas { .. } => self.react_atlas(backend, host, change),
                // the traversal's planes follow the lights and casters
                Target::Screen { .. } => Ok(Reaction::Rebuild),
            },
        }
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn own_outputs(&self) -> &'static [Output] {
        match &self.target {
            Target::Atlas { .. } => &crate::frame::receivers::atlas::OUTPUTS,
            Target::Screen { .. } => &ScreenReceiver::OUTPUTS,
        }
    }

    fn requested_outputs(&self) -> Outputs {
        self.settings.frame.outputs
    }

    fn output_image(&self, host: &FrameHost, output: Output) -> Option<ImageBuf> {
        match &self.target {
            Target::Atlas { receiver, .. } => receiver.output_image(host, output),
            Target::Screen { receiver, .. } => receiver.image(host, output),
        }
    }

    fn read_data_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error> {
        match &self.target {
            Target::Atlas { receiver, .. } if output == Output::CausticAtlas => {
                receiver.read_atlas(backend)
            }
            _ => Err(Error::Unsupported(format!(
                "adaptive-caustics has no data output '{output}'"
            ))),
        }
    }

    fn estimate_outputs(&self) -> (Output, Output) {
        (Output::FilteredCaustics, Output::RawCaustics)
    }

    fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        self.traversal = None;
        match &mut self.target {
            Target::Atlas { receiver, .. } => receiver.free(backend),
            Target::Screen { owned, .. } => Ok(owned.free(backend)?),
        }
    }

    fn owned(&self) -> (usize, u64) {
        match &self.target {
            Target::Atlas { receiver, .. } => receiver.owned(),
            Target::Screen { owned, .. } => owned.count(),
        }
    }
}

/// The registry's constructor: `settings` is a JSON object of
/// [`AdaptiveCausticsSettings`] fields (CausticMap's at the top level; missing fields
/// take their defaults, unknown ones are an error).
pub fn create(
    backend: &mut dyn Backend,
    scene: &crate::scene::Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn crate::frame::technique::Technique>, Error> {
    crate::frame::pipeline::create::<AdaptiveCausticsPipeline>(backend, scene, settings)
}
