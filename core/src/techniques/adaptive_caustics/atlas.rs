//! AdaptiveCaustics' atlas target (`deposit: atlas`, the default): `refine_clusters`
//! deposits the traversal's output photons into the caustic atlas
//! ([`crate::frame::receivers::atlas`]), whose gather, lookup, filters and outputs are
//! CausticMap's, so the two techniques differ only in which photons reach the map. Every
//! receiver keeps its tile: the error metric refines clusters by the atlas texels their
//! photons land in, so the photons (and the receivers they reach) depend on the layout.

use super::traversal::{AtlasTarget, DepositTarget, Traversal};
use super::{AdaptiveCausticsPipeline, AdaptiveCausticsSettings, Target};
use crate::backend::Backend;
use crate::frame::emission::view_planes::ViewPlanes;
use crate::frame::error::Error;
use crate::frame::host::FrameHost;
use crate::frame::pipeline::{Change, FrameBuilder, Reaction};
use crate::frame::plan::{FramePlan, SceneFeatures};
use crate::frame::receivers::atlas::{with_atlas, AtlasQuanta, AtlasReceiver};
use crate::kernels::TraceVariant;
use crate::recording::Recording;

/// The plan from the planes, the traversal, the atlas and the camera images.
fn plan(
    host: &FrameHost,
    receiver: &AtlasReceiver,
    planes: &ViewPlanes,
    s: &AdaptiveCausticsSettings,
    traversal: Option<&Traversal>,
    variant: TraceVariant,
) -> FramePlan {
    let why = format!(
        "Wyman 2009's traversal ({:?} metric, {}^2 start grid, batches of {} clusters), {}",
        s.traversal.metric,
        s.traversal.start_grid,
        traversal.map_or(0, |t| t.sizes.pass_clusters),
        receiver.stale_words()
    );
    let mut plan = receiver.plan(
        host,
        planes.light_plans(),
        &[("trace_photons", why.clone()), ("refine_clusters", why)],
        variant,
    );
    if let Some(t) = traversal {
        t.leave_out_unused_passes(&mut plan);
    }
    plan
}

/// The atlas target's pipeline over `host` with `planes` (fitted to the pyramid).
pub(super) fn create(
    backend: &mut dyn Backend,
    host: &mut FrameHost,
    settings: AdaptiveCausticsSettings,
    planes: ViewPlanes,
) -> Result<AdaptiveCausticsPipeline, Error> {
    let map = &settings.atlas_config();
    let atlas = with_atlas(host, map, !planes.planes.is_empty());
    host.make_screen(backend, AtlasReceiver::screen_needs(map, atlas))?;
    let mut variant = SceneFeatures::of(host.model()).trace_variant();
    variant.surface_store = true;
    // one stored photon per emitted photon (validated: fresnel_split is stochastic)
    variant.fresnel_split = false;
    // the traversal keeps its slots for refine_clusters to judge
    variant.adaptive = true;
    variant.fused_deposit = false;
    let mut traversal = None;
    let levels = super::finest_level(&planes, settings.traversal.start_grid);
    let boxes: Vec<_> = host
        .geometry()
        .caster_boxes
        .iter()
        .map(|(_, b)| *b)
        .collect();
    let ts = settings.traversal();
    let max_buffer_bytes = backend.capabilities().max_buffer_bytes;
    let receiver = AtlasReceiver::create(
        backend,
        host,
        map.clone(),
        AtlasQuanta::of(&planes),
        atlas,
        &mut |rec| {
            traversal = Some(Traversal::record(
                rec,
                &ts,
                (planes.planes.len(), levels),
                &boxes,
                (false, max_buffer_bytes),
            ))
        },
    )?;
    let plan = plan(
        host,
        &receiver,
        &planes,
        &settings,
        traversal.as_ref(),
        variant,
    );
    Ok(AdaptiveCausticsPipeline {
        settings,
        planes,
        variant,
        plan,
        traversal,
        target: Target::Atlas {
            receiver: Box::new(receiver),
            valid: false,
        },
    })
}

impl AdaptiveCausticsPipeline {
    fn replan_atlas(&mut self, host: &FrameHost) {
        if let Target::Atlas { receiver, .. } = &self.target {
            self.plan = plan(
                host,
                receiver,
                &self.planes,
                &self.settings,
                self.traversal.as_ref(),
                self.variant,
            );
        }
    }

    /// The atlas target's frame: the traversal into the atlas and its gather when the
    /// atlas is stale, then the camera's passes, all recorded.
    pub(super) fn record_atlas(
        &mut self,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        let Target::Atlas { receiver, valid } = &self.target else {
            return Ok(());
        };
        let photons = self.plan.trace_variant.is_some();
        if let (true, Some(a), Some(target)) = (photons, receiver.atlas(), atlas_target(receiver)) {
            if *valid {
                AtlasReceiver::skip_photon_passes(&self.plan, &mut frame.stats);
            } else {
                receiver.record_clear(frame.rec());
                frame.stats.variants.push(crate::kernels::variant_label(
                    "trace_photons",
                    &self.variant.constants(),
                ));
                let mut gather = Recording::new();
                receiver.record_gather(&mut gather);
                let (counters, pass) = (a.counters, receiver.pass_index());
                self.traverse(host, frame, &DepositTarget::Atlas(target), counters, pass)?;
                frame.rec().steps.extend(gather.steps);
                if let Target::Atlas { receiver, valid } = &mut self.target {
                    frame.stats.accumulated_frames = receiver.end_photon_pass();
                    // an accumulating atlas takes new photons every frame
                    *valid = !self.settings.frame.accumulate;
                }
            }
        }
        let Target::Atlas { receiver, .. } = &mut self.target else {
            return Ok(());
        };
        host.record_visibility(frame.rec());
        receiver.record_camera(host, frame.rec());
        receiver.end_frame(host.camera());
        Ok(())
    }

    /// The atlas target follows moved lights or instances: the planes re-aimed (a rebuild
    /// where photon passes start or stop, or a plane's pyramid grows deeper than the
    /// traversal's buffers), the caster boxes followed, a moved receiver's tile laid out
    /// anew.
    pub(super) fn react_atlas(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        change: Change,
    ) -> Result<Reaction, Error> {
        if let (Change::Resized, Target::Atlas { receiver, .. }) = (change, &mut self.target) {
            // only the camera-sized images: the atlas stays valid; made (and the old ones
            // freed) at once, so never ahead of a recorded frame that uses them
            host.check_all_submitted("a new image size makes the caustic images anew")?;
            receiver.make_images(backend, host.camera())?;
            self.replan_atlas(host);
            return Ok(Reaction::Kept);
        }
        let planes = super::view_planes(host, &self.settings)?;
        let start = self.settings.traversal.start_grid;
        // more planes than the traversal has counts for (a light added) also rebuilds
        let deeper = super::finest_level(&planes, start) > super::finest_level(&self.planes, start)
            || planes.planes.len() > self.planes.planes.len();
        let had_photons = self.plan.trace_variant.is_some();
        if (planes.planes.is_empty() == had_photons && self.settings.frame.prune) || deeper {
            return Ok(Reaction::Rebuild);
        }
        if let Some(t) = &mut self.traversal {
            let boxes: Vec<_> = host
                .geometry()
                .caster_boxes
                .iter()
                .map(|(_, b)| *b)
                .collect();
            t.set_caster_boxes(&boxes);
        }
        let Target::Atlas { receiver, valid } = &mut self.target else {
            return Ok(Reaction::Rebuild);
        };
        receiver.set_quanta(AtlasQuanta::of(&planes));
        *valid = false;
        if let Change::Instances {
            receivers_moved: true,
            ..
        } = change
        {
            let all = vec![true; receiver.tiled().len()];
            let mut rec = Recording::new();
            receiver.relayout(host, &mut rec, &all)?;
            host.defer(rec);
        }
        self.planes = planes;
        self.replan_atlas(host);
        Ok(Reaction::Kept)
    }
}

/// The traversal's target in the atlas of `receiver` (`None` without an atlas).
fn atlas_target(receiver: &AtlasReceiver) -> Option<AtlasTarget> {
    let quanta = receiver.quanta();
    receiver.atlas().map(|a| AtlasTarget {
        triangle_tiles: a.triangle_tiles,
        tiles: a.tiles,
        sums: a.sums,
        centroids: a.centroids,
        triangle_reach: a.triangle_reach,
        atlas_width: receiver.settings().atlas.atlas_size,
        flux_quantum: quanta.flux_quantum,
        hit_distance_quantum: quanta.hit_distance_quantum,
        trace_counters: a.counters,
    })
}
