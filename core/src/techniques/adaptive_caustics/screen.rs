//! AdaptiveCaustics' screen target (`deposit: screen`): the traversal's output photons,
//! listed in world space by `refine_clusters`, deposited by `deposit_screen` into the
//! screen receiver ([`crate::frame::receivers::screen`]), which resolves, filters and
//! composites them as for Sspm; a photon's "texel" for the error metric is its pixel.

use super::settings::AdaptiveCausticsSettings;
use crate::backend::Backend;
use crate::device::handle::ResourceId;
use crate::frame::allocation::planned_allocation;
use crate::frame::emission::adaptive::{
    fit_planes, DepositTarget, PhotonOptics, ScreenTarget, Traversal,
};
use crate::frame::emission::view_planes::ViewPlanes;
use crate::frame::error::Error;
use crate::frame::host::{FrameHost, HostOptions};
use crate::frame::image::Image;
use crate::frame::pipeline::{Change, FrameBuilder, Hosted, Pipeline, Reaction};
use crate::frame::plan::{BufferPlan, FramePlan};
use crate::frame::receivers::screen::{plan_frame, Needs, Output, ScreenQuanta, ScreenReceiver};
use crate::frame::stats::AdaptiveStats;
use crate::frame::technique::OutputInfo;
use crate::recording::{Recording, Step};

/// AdaptiveCaustics with the screen target, on one backend, for one scene.
pub type AdaptiveScreen = Hosted<AdaptiveScreenPipeline>;

/// The screen target's own state over the frame host.
pub struct AdaptiveScreenPipeline {
    settings: AdaptiveCausticsSettings,
    planes: ViewPlanes,
    plan: FramePlan,
    traversal: Option<Traversal>,
    receiver: ScreenReceiver,
    owned: Vec<ResourceId>,
    bytes: u64,
    buffers: Vec<BufferPlan>,
}

/// The photon capacity `deposit_screen` and `resolve_caustics` are parameterised with
/// outside the traversal's steps (the traversal's own list sets it in each step).
const NO_PHOTON_LIST: u32 = 1;

/// The light view planes fitted to the pyramid, the quanta and the plan of the host's
/// scene; refuses a light whose flux is out of range.
fn frame_setup(
    host: &FrameHost,
    s: &AdaptiveCausticsSettings,
) -> Result<(ViewPlanes, ScreenQuanta, FramePlan), Error> {
    let g = host.geometry();
    let mut planes = ViewPlanes::new(
        host.model(),
        g.bounds,
        g.caster_bounds,
        g.caster_spheres,
        g.has_dispersion,
        &s.map,
    );
    fit_planes(&mut planes, &s.traversal(), g.has_dispersion);
    planes.check_light_flux()?;
    let quanta = ScreenQuanta {
        flux_quantum: planes.flux_quantum,
        hit_distance_quantum: planes.hit_distance_quantum,
        ..ScreenQuanta::new(g.bounds, planes.flux_quantum, &s.screen)
    };
    let sc = &s.screen;
    let mut plan = plan_frame(
        host.model(),
        planes.light_plans(),
        sc.outputs,
        sc.prune,
        (sc.filter, sc.temporal, sc.atrous_iterations > 0),
    );
    if let Some(v) = &mut plan.trace_variant {
        // seed 004's slots, in world space for the screen deposit
        v.adaptive = true;
        v.surface_store = false;
        v.fresnel_split = false;
    }
    if let Some(i) = plan.passes.iter().position(|p| p.name == "trace_photons") {
        let mut refine = plan.passes[i].clone();
        refine.name = "refine_clusters".into();
        if refine.runs {
            refine.reason = "seed 004's traversal: judges the clusters and lists the output \
                             photons for deposit_screen"
                .into();
        }
        plan.passes.insert(i + 1, refine);
    }
    Ok((planes, quanta, plan))
}

impl Pipeline for AdaptiveScreenPipeline {
    type Settings = AdaptiveCausticsSettings;

    fn name(&self) -> &'static str {
        "adaptive-caustics"
    }

    fn parse_settings(json: &serde_json::Value) -> Result<AdaptiveCausticsSettings, Error> {
        let mut s = AdaptiveCausticsSettings::from_json(json)?;
        s.deposit = super::AdaptiveDeposit::Screen;
        Ok(s)
    }

    fn validate(settings: &AdaptiveCausticsSettings) -> Result<(), Error> {
        settings.validate()
    }

    fn host_options(settings: &AdaptiveCausticsSettings) -> HostOptions {
        HostOptions {
            max_triangles: settings.map.max_triangles,
            atlas_receivers: false,
        }
    }

    fn create(
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        mut settings: AdaptiveCausticsSettings,
    ) -> Result<AdaptiveScreenPipeline, Error> {
        settings.deposit = super::AdaptiveDeposit::Screen;
        let (planes, quanta, plan) = frame_setup(host, &settings)?;
        let needs = Needs::of_plan(&plan);
        host.make_screen(
            backend,
            ScreenReceiver::screen_needs(needs, &settings.screen),
        )?;
        let camera = host.camera();
        let mut rec = Recording::new();
        let receiver =
            ScreenReceiver::create(&mut rec, camera, &plan, settings.screen.clone(), quanta);
        let traversal = needs.photons.then(|| {
            let finest = planes
                .planes
                .iter()
                .map(|(_, _, p)| p.resolution.0)
                .max()
                .unwrap_or(1);
            let levels = (finest / settings.start_grid).max(1).ilog2();
            let boxes: Vec<_> = host.geometry().caster_boxes.iter().map(|(_, b)| *b).collect();
            Traversal::record(&mut rec, &settings.traversal(), levels, &boxes, true)
        });
        let alloc = planned_allocation(backend, &rec, Some((camera.width, camera.height)))?;
        if let Err(e) = backend.execute(&rec) {
            let mut free = Recording::new();
            for id in &alloc.owned {
                free.steps.push(Step::Free { id: *id });
            }
            let _ = backend.execute(&free);
            return Err(e.into());
        }
        let mut plan = plan;
        plan.buffers = host
            .buffer_plans()
            .into_iter()
            .chain(alloc.buffers.iter().cloned())
            .collect();
        Ok(AdaptiveScreenPipeline {
            settings,
            planes,
            plan,
            traversal,
            receiver,
            owned: alloc.owned,
            bytes: alloc.bytes,
            buffers: alloc.buffers,
        })
    }

    fn settings(&self) -> &AdaptiveCausticsSettings {
        &self.settings
    }

    fn set_seed(&mut self, seed: u32) {
        self.settings.map.seed = seed;
    }

    fn record(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        let q = self.receiver.quanta().flux_quantum;
        frame.stats.flux_quantum = q as f64;
        let variant = self.plan.trace_variant;
        if let Some(v) = variant.filter(|_| self.traversal.is_some()) {
            frame
                .stats
                .variants
                .push(crate::kernels::variant_label("trace_photons", &v.constants()));
        }
        host.record_visibility(frame.rec());
        self.receiver.record_clear(frame.rec());
        let (Some(t), Some(variant), Some(map), Some(gbuffer)) = (
            &self.traversal,
            variant,
            self.receiver.photon_map(),
            host.screen().gbuffer,
        ) else {
            return Ok(());
        };
        // TODO(issue 46): the traversal reads its queues back between levels; it is to be
        // recorded once per frame with its queues on the device.
        let mut rec = Recording::new();
        rec.clear(t.output_counters);
        frame.run_now(backend, rec)?;
        let camera = host.camera();
        let target = DepositTarget::Screen(ScreenTarget {
            deposit: self.receiver.deposit_params(camera, NO_PHOTON_LIST),
            gbuffer,
            photon_map: map.planes,
            trace_counters: map.counters,
        });
        let s = &self.settings.map;
        let optics = PhotonOptics {
            max_bounces: s.max_bounces,
            min_relative_power: s.min_relative_power,
            fresnel_model: s.fresnel.kernel_value(),
            caster_spheres: self.planes.caster_spheres,
        };
        let total: u64 = self.planes.planes.iter().map(|(_, _, p)| p.texels()).sum();
        let mut adaptive = AdaptiveStats::default();
        for (light, k, plane) in &self.planes.planes {
            let flux = plane.power.as_dvec3() * plane.plane_measure();
            for c in 0..3 {
                frame.stats.emitted_flux[c] += flux[c];
            }
            let before = adaptive.photons_processed;
            let mut done = 0;
            t.run_plane(
                backend,
                host.scene(),
                variant,
                &target,
                (*light, plane, ViewPlanes::plane_seed(s.seed, *light, *k)),
                optics,
                &mut frame.stats,
                &mut adaptive,
                &mut |traced| done = (traced - before).min(total),
            )?;
            frame.progress(done, total);
        }
        // the resolve reads the photon map only: the counters are final here
        let c = frame.read_now(backend, map.counters)?;
        frame.stats.read_counters(&c, q);
        t.output_stats(backend, q, &mut frame.stats, adaptive)?;
        let mut rec = Recording::new();
        self.receiver
            .record_resolve(&mut rec, camera, host.screen(), NO_PHOTON_LIST);
        frame.push(rec, 0);
        // this frame's blend is the next frame's history
        self.receiver.end_frame(camera);
        Ok(())
    }

    fn react(
        &mut self,
        _backend: &mut dyn Backend,
        _host: &mut FrameHost,
        change: Change,
    ) -> Result<Reaction, Error> {
        Ok(match change {
            Change::Camera => Reaction::Kept,
            Change::Materials { same_plan: true } => {
                self.receiver.reset_history();
                Reaction::Kept
            }
            // the traversal's planes follow the lights and casters
            _ => Reaction::Rebuild,
        })
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn outputs(&self) -> Vec<OutputInfo> {
        Output::ALL
            .iter()
            .map(|o| OutputInfo {
                name: o.stem(),
                description: o.description(),
                requested: o.requested(&self.settings.screen.outputs),
                camera_space: true,
            })
            .collect()
    }

    fn read_output(
        &self,
        backend: &mut dyn Backend,
        host: &FrameHost,
        name: &str,
    ) -> Result<Image, Error> {
        let o = Output::from_stem(name).ok_or_else(|| {
            Error::InvalidParameter(format!(
                "adaptive-caustics has no output '{name}'; outputs: {}",
                Output::ALL.map(|o| o.stem()).join(", ")
            ))
        })?;
        if !o.requested(&self.settings.screen.outputs) {
            return Err(Error::InvalidParameter(format!(
                "output '{}' was not requested (screen.outputs)",
                o.stem()
            )));
        }
        match self.receiver.images(host.camera(), host.screen()).get(o) {
            Some(h) => host.read_image(backend, h),
            None => Ok(host.black_image()),
        }
    }

    fn estimate_outputs(&self) -> (&'static str, &'static str) {
        (Output::FilteredCaustics.stem(), Output::RawCaustics.stem())
    }

    fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = Recording::new();
        for id in std::mem::take(&mut self.owned) {
            rec.steps.push(Step::Free { id });
        }
        self.bytes = 0;
        self.buffers.clear();
        backend.execute(&rec)?;
        Ok(())
    }

    fn owned(&self) -> (usize, u64) {
        (self.owned.len(), self.bytes)
    }
}
