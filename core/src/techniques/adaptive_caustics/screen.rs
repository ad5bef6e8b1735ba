//! AdaptiveCaustics' screen target (`deposit: screen`): the traversal's output photons,
//! listed in world space by `refine_clusters`, deposited by `deposit_screen` into the
//! screen receiver ([`crate::frame::receivers::screen`]), which resolves, filters and
//! composites them as for Sspm; a photon's "texel" for the error metric is its pixel.

use super::traversal::{DepositTarget, ScreenTarget, Traversal};
use super::{AdaptiveCausticsPipeline, AdaptiveCausticsSettings, Target};
use crate::backend::Backend;
use crate::frame::allocation::allocate;
use crate::frame::emission::view_planes::ViewPlanes;
use crate::frame::error::Error;
use crate::frame::host::FrameHost;
use crate::frame::pipeline::FrameBuilder;
use crate::frame::plan::SceneFeatures;
use crate::frame::receivers::screen::{plan_frame, Needs, ScreenQuanta, ScreenReceiver};
use crate::recording::Recording;

/// The photon capacity `deposit_screen` and `resolve_caustics` are parameterised with
/// outside the traversal's steps (the traversal's own list sets it in each step).
const NO_PHOTON_LIST: u32 = 1;

/// The screen target's pipeline over `host` with `planes` (fitted to the pyramid).
pub(super) fn create(
    backend: &mut dyn Backend,
    host: &mut FrameHost,
    settings: AdaptiveCausticsSettings,
    planes: ViewPlanes,
) -> Result<AdaptiveCausticsPipeline, Error> {
    let g = host.geometry();
    let (frame, sc) = (&settings.frame, settings.screen.clone());
    let quanta = ScreenQuanta {
        flux_quantum: planes.flux_quantum,
        hit_distance_quantum: planes.hit_distance_quantum,
        ..ScreenQuanta::new(g.bounds, planes.flux_quantum, &sc)
    };
    let mut plan = plan_frame(
        host.model(),
        planes.light_plans(),
        frame.outputs,
        frame.prune,
        (sc.filter, frame.temporal, frame.atrous_iterations > 0),
    );
    let mut variant = plan
        .trace_variant
        .unwrap_or_else(|| SceneFeatures::of(host.model()).trace_variant());
    // Wyman 2009's slots, in world space for the screen deposit
    variant.adaptive = true;
    variant.surface_store = false;
    variant.fresnel_split = false;
    if let Some(v) = &mut plan.trace_variant {
        *v = variant;
    }
    if let Some(i) = plan.passes.iter().position(|p| p.name == "trace_photons") {
        let mut refine = plan.passes[i].clone();
        refine.name = "refine_clusters".into();
        if refine.runs {
            refine.reason = "Wyman 2009's traversal: judges the clusters and lists the output \
                             photons for deposit_screen"
                .into();
        }
        plan.passes.insert(i + 1, refine);
    }
    let needs = Needs::of_plan(&plan);
    host.make_screen(backend, ScreenReceiver::screen_needs(needs, frame))?;
    let camera = host.camera();
    let mut rec = Recording::new();
    let receiver = ScreenReceiver::create(&mut rec, camera, &plan, frame, sc, quanta);
    let max_buffer_bytes = backend.capabilities().max_buffer_bytes;
    let traversal = needs.photons.then(|| {
        let levels = super::finest_level(&planes, settings.traversal.start_grid);
        let boxes: Vec<_> = host
            .geometry()
            .caster_boxes
            .iter()
            .map(|(_, b)| *b)
            .collect();
        Traversal::record(
            &mut rec,
            &settings.traversal(),
            (planes.planes.len(), levels),
            &boxes,
            (true, max_buffer_bytes),
        )
    });
    if let Some(t) = &traversal {
        t.leave_out_unused_passes(&mut plan);
    }
    let owned = allocate(backend, &rec, Some((camera.width, camera.height)))?;
    plan.buffers = host
        .buffer_plans()
        .into_iter()
        .chain(owned.buffers.iter().cloned())
        .collect();
    Ok(AdaptiveCausticsPipeline {
        settings,
        planes,
        variant,
        plan,
        traversal,
        target: Target::Screen {
            receiver: Box::new(receiver),
            owned,
        },
    })
}

impl AdaptiveCausticsPipeline {
    /// The screen target's frame: visibility, the traversal into the screen photon map,
    /// the resolve, filters and composite, all recorded.
    pub(super) fn record_screen(
        &mut self,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        let Target::Screen { receiver, .. } = &self.target else {
            return Ok(());
        };
        if let Some(v) = self.plan.trace_variant.filter(|_| self.traversal.is_some()) {
            frame.stats.variants.push(crate::kernels::variant_label(
                "trace_photons",
                &v.constants(),
            ));
        }
        host.record_visibility(frame.rec());
        receiver.record_clear(frame.rec());
        let (Some(map), Some(gbuffer), true) = (
            receiver.photon_map(),
            host.screen().gbuffer,
            self.traversal.is_some() && self.plan.trace_variant.is_some(),
        ) else {
            return Ok(());
        };
        let camera = host.camera();
        let target = DepositTarget::Screen(ScreenTarget {
            deposit: receiver.deposit_params(camera, NO_PHOTON_LIST),
            gbuffer,
            photon_map: map.planes,
            trace_counters: map.counters,
        });
        let pass = receiver.frame_index();
        self.traverse(host, frame, &target, map.counters, pass)?;
        let Target::Screen { receiver, .. } = &mut self.target else {
            return Ok(());
        };
        let mut rec = Recording::new();
        receiver.record_resolve(&mut rec, camera, host.screen(), NO_PHOTON_LIST);
        frame.push(rec, 0);
        // this frame's blend is the next frame's history
        frame.stats.accumulated_frames = receiver.end_frame(camera);
        Ok(())
    }
}
