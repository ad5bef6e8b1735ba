//! Screen-space photon mapping (`Sspm`, seed 000) as a sequence of passes:
//!
//! 1. `primary_gbuffer`, `direct_light` (once per frame);
//! 2. per light and per batch: `trace_photons` (emit, trace through specular chains, store
//!    photons on diffuse surfaces after >= 1 specular interaction) then `deposit_screen`
//!    (one photon -> one pixel, fixed-point integer sums; section 30.3.1.3);
//! 3. `resolve_caustics` (flux -> radiance, Eq. 5: the raw caustics), the filter, then
//!    `composite` (section 30.3.3). The filter ([`GatherFilter`]) is by default the
//!    density-adaptive, flux-keeping gather (`photon_count_table` twice,
//!    `gather_footprint`, `density_gather` twice; [`crate::math::density_gather`]), or the
//!    seed's `tile_hit_distance` and two `bilateral_gather` passes (section 30.3.2).
//!
//! Photons are processed in batches of at most `max_photons_per_batch`, so the photon
//! buffer never exceeds `32 * max_photons_per_batch` bytes; every batch is deposited before
//! the next is traced, so nothing is dropped when a buffer is "full".
//!
//! AdaptiveCaustics' screen target is this frame with step 2 replaced: seed 004's
//! traversal of CausticMap's light view planes (`adaptive_caustics::traversal`) lists the
//! photons it outputs and `deposit_screen` deposits them, step by step
//! ([`Sspm::with_adaptive_emission`]).

mod constants;
mod outputs;
mod plan;
mod settings;

pub use constants::FrameConstants;
pub use outputs::{FrameImages, Output, Outputs};
pub use plan::{plan_frame, volume_light_plans, Needs};
pub use settings::{GatherFilter, SspmSettings};

use crate::backend::{read_buf, Backend};
use crate::device::device_scene::{
    BuildBudget, BuildError, DeviceScene, InstanceUpdate, SceneInstances,
};
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf, PhotonMapPlanes, ResourceId, SceneArgs};
use crate::device::layout::*;
use crate::frame::allocation::planned_allocation;
use crate::frame::error::Error;
use crate::frame::image::Image;
use crate::frame::irradiance_passes::FilterChain;
use crate::frame::plan::FramePlan;
use crate::frame::stats::FrameStats;
use crate::frame::submitted::RecordedFrame;
use crate::frame::technique::{OutputInfo, Progress, Technique};
use crate::kernels::{
    BilateralGather, Composite, DensityGather, DepositScreen, DirectLight, FusedDeposit,
    GatherFootprint, PhotonCountTable, PrimaryGbuffer, ResolveCaustics, ScreenDeposit,
    TileHitDistance, TracePhotons,
};
use crate::recording::{Recording, Step};
use crate::scene::Scene;
use crate::techniques::adaptive_caustics::{
    self, AdaptiveCausticsSettings, DepositTarget, PhotonOptics, ScreenTarget, Traversal,
};
use crate::techniques::caustic_map::Emission;
use std::time::Instant;

/// Seed 004's adaptive emission in place of seed 000's projection volumes (AdaptiveCaustics
/// with the screen target): its settings and the casters' bounding boxes.
#[derive(Clone, Debug)]
struct AdaptiveEmission {
    settings: AdaptiveCausticsSettings,
    caster_boxes: Vec<crate::math::geometry::Aabb>,
    /// The scene object of each box (they follow moved instances).
    caster_objects: Vec<u32>,
}

/// The adaptive emission of one frame setup: the light view planes (fitted to the
/// pyramid) and the traversal's buffers.
#[derive(Clone, Debug)]
struct AdaptiveFrame {
    emission: Emission,
    traversal: Traversal,
}

/// Device buffers of the photon passes (exist only when some light emits photons).
#[derive(Clone, Copy, Debug)]
struct PhotonBuffers {
    /// Stored photons (one slot with the fused deposit, which stores none).
    photons: Buf<Photon>,
    /// Photons a batch traces.
    batch: u32,
    photon_count: Buf<u32>,
    photon_map: PhotonMapPlanes,
    counters: Buf<u32>,
}

/// Device buffers of the filter (exist only when filtered caustics are needed).
#[derive(Clone, Copy, Debug)]
enum GatherBuffers {
    /// The density gather: the photon counts' summed-area table, the edge texels and the
    /// image between its two passes (the footprint pass writes into the filtered image,
    /// which the last pass overwrites).
    Density {
        table: Buf<u32>,
        edge: ImageBuf,
        scratch: ImageBuf,
        /// The passes' source index (`math::density_gather::source_index_len`).
        source_index: Buf<u32>,
    },
    /// The bilateral gather: hit-distance tiles and the image between its two passes.
    Bilateral { tiles: Buf<f32>, scratch: ImageBuf },
}

/// Screen-space photon mapping on one backend, for one scene.
pub struct Sspm {
    settings: SspmSettings,
    scene: SceneArgs,
    camera: GpuCamera,
    light_count: u32,
    constants: FrameConstants,
    plan: FramePlan,
    gbuffer: GBufferPlanes,
    photon: Option<PhotonBuffers>,
    gather: Option<GatherBuffers>,
    /// The opt-in temporal blend and A-Trous iterations on the filtered caustics.
    filters: Option<FilterChain>,
    images: FrameImages,
    /// Every image buffer the plan created, by [`Output`], requested or not.
    image_buffers: [Option<ImageBuf>; 4],
    /// The frame's buffers (freed by [`Sspm::free`], remade when the settings or the
    /// image size change) and the bytes of all buffers, the scene's included.
    owned: Vec<ResourceId>,
    bytes: u64,
    /// The uploaded scene's buffers, their plan entries and bytes.
    scene_owned: Vec<ResourceId>,
    scene_buffers: Vec<crate::frame::plan::BufferPlan>,
    scene_bytes: u64,
    reference: Option<Image>,
    /// The scene model (re-planned when lights change).
    model: Scene,
    /// Scene and caster bounds and whether a material disperses (from the device scene).
    bounds: SceneBounds,
    /// AdaptiveCaustics' screen target: the traversal's settings, and its frame.
    adaptive: Option<AdaptiveEmission>,
    adaptive_frame: Option<AdaptiveFrame>,
    /// The acceleration structure's levels, to move instances without a rebuild.
    instances: SceneInstances,
    /// Scene writes of the updates since the last frame (moved lights and instances): run
    /// with the next frame's first submission, so that an update costs the host its own
    /// arithmetic and no submission or wait of its own.
    pending: Recording,
}

/// What the frame constants need of the device scene, kept so that lights can change
/// without rebuilding it.
#[derive(Clone, Copy, Debug)]
struct SceneBounds {
    bounds: crate::math::geometry::Aabb,
    caster_bounds: crate::math::geometry::Aabb,
    caster_spheres: crate::device::caster_spheres::CasterSpheres,
    has_dispersion: bool,
    /// Triangles the build dropped for zero area in f32.
    degenerate_triangles: u64,
    /// Triangles uploaded (what `max_triangles` is checked against).
    triangles: u64,
}

/// The per-frame resources a scene's settings and image size decide (everything but the
/// uploaded scene): rebuilt by [`Sspm::set_settings`] and by a camera of a new size.
struct FrameParts {
    camera: GpuCamera,
    constants: FrameConstants,
    plan: FramePlan,
    gbuffer: GBufferPlanes,
    photon: Option<PhotonBuffers>,
    gather: Option<GatherBuffers>,
    /// The opt-in temporal blend and A-Trous iterations on the filtered caustics.
    filters: Option<FilterChain>,
    images: FrameImages,
    image_buffers: [Option<ImageBuf>; 4],
    owned: Vec<ResourceId>,
    bytes: u64,
    adaptive: Option<AdaptiveFrame>,
}

impl Sspm {
    /// Validates the scene and settings, plans the frame ([`crate::frame::plan`]), uploads the
    /// scene and creates the buffers the plan needs.
    pub fn new(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: SspmSettings,
    ) -> Result<Sspm, Error> {
        Self::build(backend, scene, settings, None)
    }

    /// AdaptiveCaustics with the screen target: Sspm's frame (G-buffer, screen deposit,
    /// resolve, filter, composite) with `adaptive`'s traversal of CausticMap's light view
    /// planes in place of seed 000's photons (`adaptive.screen_settings()` are the Sspm
    /// settings).
    pub fn with_adaptive_emission(
        backend: &mut dyn Backend,
        scene: &Scene,
        adaptive: AdaptiveCausticsSettings,
    ) -> Result<Sspm, Error> {
        adaptive.validate()?;
        let settings = adaptive.screen_settings();
        Self::build(backend, scene, settings, Some(adaptive))
    }

    fn build(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: SspmSettings,
        adaptive: Option<AdaptiveCausticsSettings>,
    ) -> Result<Sspm, Error> {
        settings.validate()?;
        scene
            .validate()
            .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
        let ds = DeviceScene::build(
            scene,
            BuildBudget {
                max_triangles: settings.max_triangles,
            },
        )?;
        let bounds = SceneBounds {
            bounds: ds.bounds,
            caster_bounds: ds.caster_bounds,
            caster_spheres: ds.caster_spheres,
            has_dispersion: ds.has_dispersion,
            degenerate_triangles: ds.degenerate_triangles,
            triangles: ds.triangles.len() as u64,
        };
        let adaptive = adaptive.map(|settings| AdaptiveEmission {
            settings,
            caster_boxes: adaptive_caustics::caster_boxes(&ds),
            caster_objects: adaptive_caustics::caster_boxes_by_object(&ds)
                .into_iter()
                .map(|(o, _)| o)
                .collect(),
        });
        // the frame's constants first: a light whose flux is out of range is refused
        // before anything is uploaded
        Sspm::frame_setup(scene, bounds, &settings, adaptive.as_ref())?;
        let mut rec = Recording::new();
        let scene_args = rec.upload_scene(&ds);
        let scene_allocation = planned_allocation(backend, &rec, None)?;
        // every buffer checked against the device before any work runs
        let (parts, frame_rec) = Sspm::build_frame(
            backend,
            bounds,
            &scene_allocation.buffers,
            scene,
            &settings,
            adaptive.as_ref(),
        )?;
        backend.execute(&rec)?;
        if let Err(e) = backend.execute(&frame_rec) {
            // nothing of this technique may outlive a failed `new`
            let mut free = Recording::new();
            for id in scene_allocation.owned.iter().chain(&parts.owned) {
                free.steps.push(Step::Free { id: *id });
            }
            let _ = backend.execute(&free);
            return Err(e.into());
        }
        Ok(Sspm {
            settings,
            scene: scene_args,
            camera: parts.camera,
            light_count: scene.lights.len() as u32,
            constants: parts.constants,
            plan: parts.plan,
            gbuffer: parts.gbuffer,
            photon: parts.photon,
            gather: parts.gather,
            filters: parts.filters,
            images: parts.images,
            image_buffers: parts.image_buffers,
            owned: parts.owned,
            bytes: scene_allocation.bytes + parts.bytes,
            scene_owned: scene_allocation.owned,
            scene_buffers: scene_allocation.buffers,
            scene_bytes: scene_allocation.bytes,
            reference: None,
            model: scene.clone(),
            bounds,
            adaptive,
            adaptive_frame: parts.adaptive,
            instances: ds.instances,
            pending: Recording::new(),
        })
    }

    /// The frame constants and plan of `scene` with `settings`: seed 000's emission
    /// domains, or (`adaptive`) the traversal's light view planes, whose flux quantum the
    /// fixed-point sums then use. Refuses a light whose flux is out of range.
    fn frame_setup(
        scene: &Scene,
        b: SceneBounds,
        settings: &SspmSettings,
        adaptive: Option<&AdaptiveEmission>,
    ) -> Result<(FrameConstants, FramePlan, Option<Emission>), Error> {
        let mut constants = FrameConstants::for_bounds(
            scene,
            b.bounds,
            (b.caster_bounds, b.caster_spheres),
            b.has_dispersion,
            settings,
        );
        let (out, prune, filter) = (settings.outputs, settings.prune, settings.filter);
        let Some(a) = adaptive else {
            constants.check_light_flux()?;
            let lights = volume_light_plans(&constants);
            let mut plan = plan_frame(
                scene,
                lights,
                out,
                prune,
                (filter, settings.temporal, settings.atrous_iterations > 0),
            );
            if settings.fused_deposit {
                if let Some(v) = &mut plan.trace_variant {
                    v.fused_deposit = true;
                }
                if let Some(p) = plan
                    .passes
                    .iter_mut()
                    .find(|p| p.name == "deposit_screen" && p.runs)
                {
                    p.runs = false;
                    p.reason = "trace_photons deposits each stored photon into the screen \
                                photon map (fused_deposit)"
                        .into();
                }
            }
            return Ok((constants, plan, None));
        };
        let mut emission = Emission::new(
            scene,
            b.bounds,
            b.caster_bounds,
            b.caster_spheres,
            b.has_dispersion,
            &a.settings.map,
        );
        adaptive_caustics::fit_planes(&mut emission, &a.settings, b.has_dispersion);
        emission.check_light_flux()?;
        constants.flux_quantum = emission.flux_quantum;
        constants.hit_distance_quantum = emission.hit_distance_quantum;
        let mut plan = plan_frame(
            scene,
            emission.light_plans(),
            out,
            prune,
            (filter, settings.temporal, settings.atrous_iterations > 0),
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
                refine.reason = "seed 004's traversal: judges the clusters and lists the \
                                 output photons for deposit_screen"
                    .into();
            }
            plan.passes.insert(i + 1, refine);
        }
        Ok((constants, plan, Some(emission)))
    }

    /// Plans the frame of `scene` with `settings` and records the creation of its buffers,
    /// each checked against the device (the scene is uploaded, or about to be: `bounds`
    /// and `scene_buffers` describe it); the caller executes the recording.
    fn build_frame(
        backend: &mut dyn Backend,
        bounds: SceneBounds,
        scene_buffers: &[crate::frame::plan::BufferPlan],
        scene: &Scene,
        settings: &SspmSettings,
        adaptive: Option<&AdaptiveEmission>,
    ) -> Result<(FrameParts, Recording), Error> {
        let (constants, mut plan, emission) = Sspm::frame_setup(scene, bounds, settings, adaptive)?;
        let needs = Needs::of_plan(&plan);
        let out = settings.outputs;
        let keep = |requested: bool| requested || !settings.prune;

        let mut rec = Recording::new();
        let camera = GpuCamera::from_camera(&scene.camera);
        let (w, h) = (camera.width, camera.height);
        let pixels = w * h;
        let gbuffer = rec.create_gbuffer(pixels);
        let direct = needs
            .direct_light
            .then(|| rec.create(pixels, "direct image"));
        let photon = needs.photons.then(|| {
            let per_light = settings.photons_w as u64 * settings.photons_h as u64;
            let batch = crate::frame::allocation::photons_per_batch(
                per_light,
                settings.max_photons_per_batch,
                backend.capabilities().max_buffer_bytes,
            );
            // with adaptive emission the traversal holds the photons (its output list),
            // with the fused deposit the screen photon map
            let cap = if adaptive.is_some() || settings.fused_deposit {
                1
            } else {
                batch
            };
            PhotonBuffers {
                photons: rec.create(cap, "photons"),
                batch,
                photon_count: rec.create(1, "photon count"),
                photon_map: rec.create_photon_map(pixels),
                counters: rec.create(counter::WORDS as u32, "photon counters"),
            }
        });
        let raw_caustics = needs
            .photons
            .then(|| rec.create(pixels, "raw caustics image"));
        let gather = needs.gather.then(|| match settings.filter {
            GatherFilter::Density => GatherBuffers::Density {
                table: rec.create(pixels, "photon count table"),
                edge: rec.create(pixels, "gather edge texels"),
                scratch: rec.create(pixels, "gather scratch image"),
                source_index: rec.create(
                    crate::math::density_gather::source_index_len(w, h),
                    "gather source index",
                ),
            },
            GatherFilter::Bilateral => GatherBuffers::Bilateral {
                tiles: rec.create(
                    w.div_ceil(settings.tile_size) * h.div_ceil(settings.tile_size),
                    "hit distance tiles",
                ),
                scratch: rec.create(pixels, "gather scratch image"),
            },
        });
        let filtered_caustics = needs
            .gather
            .then(|| rec.create(pixels, "filtered caustics image"));
        let (temporal, atrous) = (plan.runs("temporal_blend"), plan.runs("atrous_filter"));
        let filters = (temporal || atrous)
            .then(|| FilterChain::create(&mut rec, pixels, camera, temporal, atrous));
        let own_composite = needs
            .composite
            .then(|| rec.create(pixels, "composite image"));
        let composite = if own_composite.is_some() {
            own_composite
        } else if out.composite {
            direct // no caustics: the composite is the direct image
        } else {
            None
        };
        let images = FrameImages {
            width: w,
            height: h,
            composite,
            direct: direct.filter(|_| keep(out.direct)),
            raw_caustics: raw_caustics.filter(|_| keep(out.raw_caustics)),
            filtered_caustics: filtered_caustics.filter(|_| keep(out.filtered_caustics)),
        };
        let adaptive = match (adaptive, emission) {
            (Some(a), Some(emission)) if needs.photons => {
                let finest = emission
                    .planes
                    .iter()
                    .map(|(_, _, p)| p.resolution.0)
                    .max()
                    .unwrap_or(1);
                let levels = (finest / a.settings.start_grid).max(1).ilog2();
                let traversal =
                    Traversal::record(&mut rec, &a.settings, levels, &a.caster_boxes, true);
                Some(AdaptiveFrame {
                    emission,
                    traversal,
                })
            }
            _ => None,
        };
        let allocation = planned_allocation(backend, &rec, Some((w, h)))?;
        plan.buffers = scene_buffers
            .iter()
            .cloned()
            .chain(allocation.buffers)
            .collect();
        let parts = FrameParts {
            camera,
            constants,
            plan,
            gbuffer,
            photon,
            gather,
            filters,
            images,
            image_buffers: [own_composite, direct, raw_caustics, filtered_caustics],
            owned: allocation.owned,
            bytes: allocation.bytes,
            adaptive,
        };
        Ok((parts, rec))
    }

    fn install(&mut self, p: FrameParts) {
        self.camera = p.camera;
        self.constants = p.constants;
        self.plan = p.plan;
        self.gbuffer = p.gbuffer;
        self.photon = p.photon;
        self.gather = p.gather;
        self.filters = p.filters;
        self.images = p.images;
        self.image_buffers = p.image_buffers;
        self.owned = p.owned;
        self.bytes = self.scene_bytes + p.bytes;
        self.adaptive_frame = p.adaptive;
    }

    /// Frees the frame's buffers (not the scene's).
    fn free_frame(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = Recording::new();
        for id in std::mem::take(&mut self.owned) {
            rec.steps.push(Step::Free { id });
        }
        self.bytes = self.scene_bytes;
        self.photon = None;
        self.gather = None;
        self.filters = None;
        self.adaptive_frame = None;
        self.image_buffers = [None; 4];
        backend.execute(&rec)?;
        Ok(())
    }

    /// Replaces the frame's resources with those of `model` and `settings`: frees the old
    /// ones first (the two never hold memory at once) and, if the new ones cannot be
    /// made, rebuilds the old ones and returns why.
    fn rebuild_frame(
        &mut self,
        backend: &mut dyn Backend,
        model: Scene,
        settings: SspmSettings,
    ) -> Result<(), Error> {
        self.free_frame(backend)?;
        let (b, buffers) = (self.bounds, self.scene_buffers.clone());
        let adaptive = self.adaptive.clone();
        match Sspm::build_frame(backend, b, &buffers, &model, &settings, adaptive.as_ref())
            .and_then(|(parts, rec)| Ok(backend.execute(&rec).map(|_| parts)?))
        {
            Ok(parts) => {
                self.install(parts);
                self.model = model;
                self.settings = settings;
                Ok(())
            }
            Err(e) => {
                let old = self.model.clone();
                let (parts, rec) = Sspm::build_frame(
                    backend,
                    b,
                    &buffers,
                    &old,
                    &self.settings,
                    adaptive.as_ref(),
                )?;
                backend.execute(&rec)?;
                self.install(parts);
                Err(e)
            }
        }
    }

    /// Changes the settings for the next frames without uploading the scene again: the
    /// frame is re-planned and its buffers (photons, G-buffer, images, filter) are made
    /// anew for the new settings. `max_triangles` may change only to a budget the built
    /// scene fits. On an error the technique keeps its old settings.
    pub fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: SspmSettings,
    ) -> Result<(), Error> {
        settings.validate()?;
        if let Some(a) = &mut self.adaptive {
            // the photon fields are the traversal's
            let mut next = a.settings.clone();
            next.screen = SspmSettings {
                photons_w: next.screen.photons_w,
                photons_h: next.screen.photons_h,
                max_bounces: next.screen.max_bounces,
                min_relative_power: next.screen.min_relative_power,
                seed: next.screen.seed,
                point_emission: next.screen.point_emission,
                max_photons_per_batch: next.screen.max_photons_per_batch,
                max_triangles: next.screen.max_triangles,
                ..settings.clone()
            };
            if next.screen_settings() != settings {
                return Err(Error::InvalidParameter(
                    "adaptive-caustics: the photon settings (photons_w, photons_h, \
                     max_bounces, min_relative_power, seed, max_triangles) are the \
                     traversal's and cannot change through set_settings"
                        .into(),
                ));
            }
            a.settings = next;
        }
        if self.bounds.triangles > settings.max_triangles {
            return Err(Error::InvalidParameter(format!(
                "max_triangles {} is below the scene's {} triangles: create the technique again",
                settings.max_triangles, self.bounds.triangles
            )));
        }
        let model = self.model.clone();
        self.rebuild_frame(backend, model, settings)
    }

    /// The frame plan: passes run and skipped with reasons, the photon kernel's variant,
    /// the lights that emit, the buffers created.
    pub fn plan(&self) -> &FramePlan {
        &self.plan
    }

    /// Sets the frame seed of the next frames (progressive rendering, repeated
    /// measurements); nothing else of the settings can change after `new`.
    pub fn set_seed(&mut self, seed: u32) {
        self.settings.seed = seed;
        if let Some(a) = &mut self.adaptive {
            a.settings.map.seed = seed;
        }
    }

    /// The settings in effect.
    pub fn settings(&self) -> &SspmSettings {
        &self.settings
    }

    /// The frame's device images.
    pub fn images(&self) -> FrameImages {
        self.images
    }

    /// The G-buffer's planes (for conformance and embedding; read them back assembled
    /// with [`crate::backend::read_gbuffer`]).
    pub fn gbuffer(&self) -> GBufferPlanes {
        self.gbuffer
    }

    /// The stored-photon buffer and its count (absent when no light emits photons and with
    /// the fused deposit, which stores none: [`SspmSettings::fused_deposit`]). After a
    /// frame they hold the last batch.
    pub fn photon_buffers(&self) -> Option<(Buf<Photon>, Buf<u32>)> {
        self.photon
            .filter(|_| !self.plan.trace_variant.is_some_and(|v| v.fused_deposit))
            .map(|p| (p.photons, p.photon_count))
    }

    /// Renders one frame: the planned passes, nothing else. `progress` is called after
    /// every photon batch has run. The recordings of [`Sspm::record_frame`] are submitted
    /// without a wait between them and waited for at the end (one wait a frame);
    /// AdaptiveCaustics' screen target waits between its traversal's levels.
    pub fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        let start = Instant::now();
        let mut stats = self.frame_stats(&*backend);
        match &self.adaptive_frame {
            None => self.pipelined_passes(backend, &mut stats, progress)?,
            Some(_) => self.adaptive_passes(backend, &mut stats, progress)?,
        }
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(r) = &self.reference {
            let filtered = self.read_output(backend, Output::FilteredCaustics)?;
            stats.error = Some(crate::frame::metrics::compare(&filtered, r));
        }
        Ok(stats)
    }

    /// The frame with projection volumes: visibility, the batches, the resolve, submitted
    /// as one pipeline ([`crate::frame::submitted::run_pipelined`]), the counters read back
    /// at its end.
    fn pipelined_passes(
        &mut self,
        backend: &mut dyn Backend,
        stats: &mut FrameStats,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), Error> {
        let mut recordings = vec![(self.visibility_recording(), 0)];
        let mut readbacks = Vec::new();
        if let Some(p) = self.photon.filter(|_| self.plan.trace_variant.is_some()) {
            recordings.extend(self.batch_recordings(stats));
            recordings.push((self.resolve_recording(), 0));
            readbacks.push(p.counters.id);
        }
        let back = crate::frame::submitted::run_pipelined(
            backend, recordings, &readbacks, stats, progress,
        )?;
        if let Some(c) = back.first() {
            let words: Vec<u32> = bytemuck::pod_collect_to_vec(c);
            stats.read_counters(&words, self.constants.flux_quantum);
            // this frame's blend is the next frame's history
            if let Some(f) = &mut self.filters {
                f.end_frame(self.camera);
            }
        }
        Ok(())
    }

    /// The frame with adaptive emission (AdaptiveCaustics' screen target): its photon
    /// passes ([`Sspm::adaptive_photon_passes`]), then the resolve.
    fn adaptive_passes(
        &mut self,
        backend: &mut dyn Backend,
        stats: &mut FrameStats,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), Error> {
        if self.adaptive_photon_passes(backend, stats, progress)? {
            let rec = self.resolve_recording();
            self.run(backend, &rec, stats)?;
            // this frame's blend is the next frame's history
            if let Some(f) = &mut self.filters {
                f.end_frame(self.camera);
            }
        }
        Ok(())
    }

    /// AdaptiveCaustics' screen target up to the resolve, waited for: visibility, seed
    /// 004's traversal of the light view planes (it reads its queues back between
    /// levels), and the photon accounting (trace counters, then the traversal's). Returns
    /// whether there are photon passes (then the resolve follows).
    fn adaptive_photon_passes(
        &mut self,
        backend: &mut dyn Backend,
        stats: &mut FrameStats,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<bool, Error> {
        let cam = self.camera;
        let rec = self.visibility_recording();
        self.run(backend, &rec, stats)?;
        let (Some(p), Some(variant), Some(a)) =
            (self.photon, self.plan.trace_variant, &self.adaptive_frame)
        else {
            return Ok(false);
        };
        let mut adaptive = crate::frame::stats::AdaptiveStats::default();
        let target = DepositTarget::Screen(ScreenTarget {
            deposit: self
                .constants
                .deposit_params(cam, &self.settings, p.photons.len),
            gbuffer: self.gbuffer,
            photon_map: p.photon_map,
            trace_counters: p.counters,
        });
        self.traverse(backend, a, variant, &target, stats, &mut adaptive, progress)?;
        // the resolve reads the photon map only: the counters are final here
        let c = read_buf(backend, p.counters)?;
        stats.read_counters(&c, self.constants.flux_quantum);
        let q = self.constants.flux_quantum;
        a.traversal.output_stats(backend, q, stats, adaptive)?;
        Ok(true)
    }

    /// Records one whole frame without running it (issue 19 point 2): the same passes as
    /// [`Sspm::frame`], in one [`Recording`] that [`RecordedFrame::submit`] submits
    /// without waiting (one submission a frame), or that an embedding host encodes into
    /// its own command stream. The photon counters are copied to the host at the frame's
    /// end and come back with [`crate::frame::submitted::FrameTicket::stats`], a frame or
    /// more later. No progress callback (nothing runs here) and no error against the
    /// reference (that reads the image back: use [`Sspm::frame`]). AdaptiveCaustics'
    /// screen target runs its visibility pass and traversal here, waited for (the
    /// traversal reads its queues back between levels; its statistics are complete when
    /// this returns), and records the resolve and filters.
    pub fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        let start = Instant::now();
        let mut stats = self.frame_stats(&*backend);
        if self.adaptive_frame.is_some() {
            // the traversal waits; the resolve is recorded
            let mut recording = Recording::new();
            if self.adaptive_photon_passes(backend, &mut stats, &mut |_| {})? {
                recording = self.resolve_recording();
                if let Some(f) = &mut self.filters {
                    f.end_frame(self.camera);
                }
            }
            stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
            return Ok(RecordedFrame {
                recording,
                readbacks: Vec::new(),
                stats,
                counters: None,
            });
        }
        let mut recording = self.visibility_recording();
        let mut counters = None;
        let mut readbacks = Vec::new();
        if let Some(p) = self.photon.filter(|_| self.plan.trace_variant.is_some()) {
            for (rec, _) in self.batch_recordings(&mut stats) {
                recording.steps.extend(rec.steps);
            }
            recording.steps.extend(self.resolve_recording().steps);
            readbacks.push(p.counters.id);
            counters = Some((0, self.constants.flux_quantum));
            if let Some(f) = &mut self.filters {
                f.end_frame(self.camera);
            }
        }
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        Ok(RecordedFrame {
            recording,
            readbacks,
            stats,
            counters,
        })
    }

    /// A frame's statistics before anything runs: names, sizes, plan, skipped passes.
    fn frame_stats(&self, backend: &dyn Backend) -> FrameStats {
        let caps = backend.capabilities();
        let mut stats = FrameStats {
            technique: self.technique_name().into(),
            backend: backend.name().into(),
            device: caps.device.clone(),
            width: self.camera.width,
            height: self.camera.height,
            timing: if caps.timestamps {
                "device timestamps".into()
            } else {
                "host wall clock".into()
            },
            flux_quantum: self.constants.flux_quantum as f64,
            bytes_allocated: self.bytes,
            degenerate_triangles: self.bounds.degenerate_triangles,
            plan: Some(self.plan.clone()),
            ..Default::default()
        };
        for p in self.plan.passes.iter().filter(|p| !p.runs) {
            stats.skip(&p.name, p.reason.clone());
        }
        if let Some(variant) = self.plan.trace_variant.filter(|_| self.photon.is_some()) {
            stats.variants.push(crate::kernels::variant_label(
                "trace_photons",
                &variant.constants(),
            ));
        }
        stats
    }

    /// Step 1: the updates' pending scene writes, the G-buffer and direct light, and the
    /// photon map and counters cleared.
    fn visibility_recording(&mut self) -> Recording {
        let cam = self.camera;
        let mut rec = std::mem::take(&mut self.pending);
        rec.kernel(PrimaryGbuffer {
            scene: self.scene,
            camera: cam,
            gbuffer: self.gbuffer,
        });
        if let Some(direct) = self.direct_image() {
            rec.kernel(DirectLight {
                scene: self.scene,
                params: FrameConstants::direct_params(cam, self.light_count, &self.settings),
                gbuffer: self.gbuffer,
                out: direct,
            });
        }
        if let Some(p) = self.photon {
            rec.clear_photon_map(&p.photon_map);
            rec.clear(p.counters);
        }
        rec
    }

    /// Step 2 with projection volumes: per emitting light, per batch, the trace and the
    /// deposit, each with the photons it covers; counts the emitted photons and flux and
    /// the batches into `stats`. Empty with adaptive emission or without photon passes.
    fn batch_recordings(&self, stats: &mut FrameStats) -> Vec<(Recording, u64)> {
        let (Some(p), Some(variant)) = (self.photon, self.plan.trace_variant) else {
            return Vec::new();
        };
        if self.adaptive_frame.is_some() {
            return Vec::new();
        }
        let cam = self.camera;
        let deposit_params = self
            .constants
            .deposit_params(cam, &self.settings, p.photons.len);
        let per_light = self.settings.photons_w as u64 * self.settings.photons_h as u64;
        let mut out = Vec::new();
        for (light, d) in &self.constants.domains {
            stats.photons_emitted += per_light;
            for c in 0..3 {
                stats.emitted_flux[c] += d.flux[c] as f64;
            }
            let mut first = 0u64;
            while first < per_light {
                let count = (per_light - first).min(p.batch as u64) as u32;
                let mut rec = Recording::new();
                rec.clear(p.photon_count);
                rec.kernel(TracePhotons {
                    scene: self.scene,
                    variant,
                    params: self.constants.trace_params(
                        &self.settings,
                        *light,
                        d,
                        first as u32,
                        count,
                    ),
                    photons: p.photons,
                    photon_count: p.photon_count,
                    counters: p.counters,
                    clusters: None,
                    deposit: variant
                        .fused_deposit
                        .then_some(FusedDeposit::Screen(ScreenDeposit {
                            params: deposit_params,
                            gbuffer: self.gbuffer,
                            photon_map: p.photon_map,
                        })),
                });
                if !variant.fused_deposit {
                    rec.kernel(DepositScreen {
                        params: deposit_params,
                        gbuffer: self.gbuffer,
                        photons: p.photons,
                        photon_count: p.photon_count,
                        counters: p.counters,
                        photon_map: p.photon_map,
                    });
                }
                stats.batches += 1;
                first += count as u64;
                out.push((rec, count as u64));
            }
        }
        out
    }

    /// Step 3: resolve, the filter chain, the composite.
    fn resolve_recording(&self) -> Recording {
        let mut rec = Recording::new();
        let Some(p) = self.photon else {
            return rec;
        };
        let cam = self.camera;
        let deposit_params = self
            .constants
            .deposit_params(cam, &self.settings, p.photons.len);
        let raw = self.raw_image().expect("planned with the photon passes");
        rec.kernel(ResolveCaustics {
            params: deposit_params,
            gbuffer: self.gbuffer,
            photon_map: p.photon_map,
            out: raw,
        });
        if let (Some(g), Some(filtered)) = (self.gather, self.filtered_image()) {
            // the filter, then the temporal blend, then the A-Trous iterations, each
            // opt-in; the last that runs writes `filtered`
            let last = self.filters.map_or(filtered, |f| f.input(filtered));
            let gather = self.constants.gather_params(cam, &self.settings, 0);
            let columns = GatherParams { axis: 1, ..gather };
            match g {
                GatherBuffers::Density {
                    table,
                    edge,
                    scratch,
                    source_index,
                } => {
                    for params in [gather, columns] {
                        rec.kernel(PhotonCountTable {
                            params,
                            photon_map: p.photon_map,
                            table,
                            gbuffer: self.gbuffer,
                            edge,
                        });
                    }
                    rec.clear(source_index);
                    rec.kernel(GatherFootprint {
                        params: gather,
                        photon_map: p.photon_map,
                        table,
                        out: filtered,
                        edge,
                        source_index,
                    });
                    rec.kernel(DensityGather {
                        params: gather,
                        gbuffer: self.gbuffer,
                        edge,
                        input: filtered,
                        out: scratch,
                        source_index,
                    });
                    rec.kernel(DensityGather {
                        params: columns,
                        gbuffer: self.gbuffer,
                        edge,
                        input: scratch,
                        out: last,
                        source_index,
                    });
                }
                GatherBuffers::Bilateral { tiles, scratch } => {
                    rec.kernel(TileHitDistance {
                        params: gather,
                        photon_map: p.photon_map,
                        tiles,
                    });
                    rec.kernel(BilateralGather {
                        params: gather,
                        gbuffer: self.gbuffer,
                        tiles,
                        input: raw,
                        out: scratch,
                    });
                    rec.kernel(BilateralGather {
                        params: columns,
                        gbuffer: self.gbuffer,
                        tiles,
                        input: scratch,
                        out: last,
                    });
                }
            }
            if let Some(f) = &self.filters {
                let s = &self.settings;
                let iterations = (s.atrous_iterations, s.atrous_clip_sigmas);
                f.record(&mut rec, cam, self.gbuffer, iterations, filtered);
            }
            if let (true, Some(direct), Some(out)) = (
                Needs::of_plan(&self.plan).composite,
                self.direct_image(),
                self.images.composite,
            ) {
                rec.kernel(Composite {
                    direct,
                    caustics: filtered,
                    out,
                });
            }
        }
        rec
    }

    /// The registry and stats name: `sspm`, or `adaptive-caustics` with adaptive emission.
    fn technique_name(&self) -> &'static str {
        if self.adaptive.is_some() {
            "adaptive-caustics"
        } else {
            "sspm"
        }
    }

    /// Step 2 with adaptive emission: every light view plane's pyramid traversed, its
    /// output photons deposited into the screen photon map.
    #[allow(clippy::too_many_arguments)]
    fn traverse(
        &self,
        backend: &mut dyn Backend,
        a: &AdaptiveFrame,
        variant: crate::kernels::TraceVariant,
        target: &DepositTarget,
        stats: &mut FrameStats,
        adaptive: &mut crate::frame::stats::AdaptiveStats,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<(), Error> {
        let s = &self.adaptive.as_ref().expect("adaptive frame").settings.map;
        let mut rec = Recording::new();
        rec.clear(a.traversal.output_counters);
        self.run(backend, &rec, stats)?;
        let total: u64 = a.emission.planes.iter().map(|(_, _, p)| p.texels()).sum();
        let optics = PhotonOptics {
            max_bounces: s.max_bounces,
            min_relative_power: s.min_relative_power,
            fresnel_model: s.fresnel.kernel_value(),
            caster_spheres: a.emission.caster_spheres,
        };
        for (light, k, plane) in &a.emission.planes {
            let flux = plane.power.as_dvec3() * plane.plane_measure();
            for c in 0..3 {
                stats.emitted_flux[c] += flux[c];
            }
            let before = adaptive.photons_processed;
            a.traversal.run_plane(
                backend,
                self.scene,
                variant,
                target,
                (*light, plane, Emission::plane_seed(s.seed, *light, *k)),
                optics,
                stats,
                adaptive,
                &mut |traced| {
                    progress(Progress {
                        photons_done: (traced - before).min(total),
                        photons_total: total,
                    })
                },
            )?;
        }
        Ok(())
    }

    /// The direct-light image buffer (also when only the composite needs it).
    fn direct_image(&self) -> Option<ImageBuf> {
        self.internal(Output::Direct)
    }

    fn raw_image(&self) -> Option<ImageBuf> {
        self.internal(Output::RawCaustics)
    }

    fn filtered_image(&self) -> Option<ImageBuf> {
        self.internal(Output::FilteredCaustics)
    }

    /// An image's buffer whether or not the caller asked for it (the composite needs the
    /// direct and filtered images): recovered from the buffers the plan created.
    fn internal(&self, output: Output) -> Option<ImageBuf> {
        self.image_buffers[output as usize]
    }

    fn run(
        &self,
        backend: &mut dyn Backend,
        rec: &Recording,
        stats: &mut FrameStats,
    ) -> Result<(), Error> {
        for t in backend.execute(rec)? {
            stats.add_pass_time(t.kernel, t.seconds);
        }
        Ok(())
    }

    /// Sets (or clears) the reference image of the caustics (linear radiance, the frame's
    /// size): every later [`Sspm::frame`] reads its filtered caustics back and puts their
    /// error against it in [`FrameStats::error`].
    pub fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        if let Some(r) = &reference {
            if (r.width, r.height) != (self.images.width, self.images.height) {
                return Err(Error::InvalidParameter(format!(
                    "reference is {}x{}, the frame {}x{}",
                    r.width, r.height, self.images.width, self.images.height
                )));
            }
        }
        self.reference = reference;
        Ok(())
    }

    /// Reads a device image back to the host.
    pub fn read_image(&self, backend: &mut dyn Backend, image: ImageBuf) -> Result<Image, Error> {
        let px = read_buf(backend, image)?;
        Ok(Image::new(self.images.width, self.images.height, px))
    }

    /// Reads one of the frame's outputs back. An output the plan knows to be zero (no
    /// light emits photons) has no device buffer and reads as zeros; one that was not
    /// requested in [`SspmSettings::outputs`] is an error.
    pub fn read_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error> {
        if !output.requested(&self.settings.outputs) {
            return Err(Error::InvalidParameter(format!(
                "output '{}' was not requested (SspmSettings::outputs)",
                output.stem()
            )));
        }
        match self.images.get(output) {
            Some(h) => self.read_image(backend, h),
            None => Ok(Image::new(
                self.images.width,
                self.images.height,
                vec![[0.0; 4]; self.images.width as usize * self.images.height as usize],
            )),
        }
    }

    /// Releases every device buffer of this technique.
    pub fn free(mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = Recording::new();
        let scene = std::mem::take(&mut self.scene_owned);
        for id in std::mem::take(&mut self.owned).into_iter().chain(scene) {
            rec.steps.push(Step::Free { id });
        }
        backend.execute(&rec)?;
        Ok(())
    }

    /// Moves the camera for the next frames. At the same image size no buffer is rebuilt;
    /// a new size remakes the frame's buffers (G-buffer, photon map, images, filter) and
    /// nothing of the scene, and clears the reference image (it has the old size).
    pub fn set_camera(
        &mut self,
        backend: &mut dyn Backend,
        camera: &crate::scene::Camera,
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_camera(&self.model, camera)?;
        if (camera.width, camera.height) != (self.camera.width, self.camera.height) {
            let settings = self.settings.clone();
            self.rebuild_frame(backend, model, settings)?;
            self.reference = None;
            return Ok(());
        }
        self.camera = GpuCamera::from_camera(camera);
        self.model = model;
        Ok(())
    }

    /// Replaces the lights for the next frames without rebuilding geometry. With as many
    /// lights as before and the same passes, the lights are written into the existing
    /// buffer with the next frame's first submission and emission is re-planned (no buffer
    /// is made, nothing is submitted here); lights added or removed, or
    /// lights that start or stop photon passes (the first to reach a caster, the last to
    /// stop), replace the light buffer and remake the frame's resources (see
    /// [`Sspm::set_settings`]). The geometry and its acceleration structure stay.
    pub fn set_lights(
        &mut self,
        backend: &mut dyn Backend,
        lights: &[crate::scene::Light],
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_lights(&self.model, lights)?;
        let (constants, mut plan, _) =
            Sspm::frame_setup(&model, self.bounds, &self.settings, self.adaptive.as_ref())?;
        let gpu: Vec<GpuLight> = lights
            .iter()
            .map(crate::device::device_scene::gpu_light)
            .collect();
        // the adaptive traversal's planes follow the lights: its frame is remade
        if lights.len() != self.model.lights.len()
            || Needs::of_plan(&plan) != Needs::of_plan(&self.plan)
            || self.adaptive.is_some()
        {
            return self.replace_lights(backend, model, &gpu);
        }
        plan.buffers = std::mem::take(&mut self.plan.buffers);
        // written with the next frame (`pending`)
        self.pending.write(self.scene.lights, 0, &gpu, "lights")?;
        if let Some(f) = &mut self.filters {
            f.reset();
        }
        self.model = model;
        self.constants = constants;
        self.plan = plan;
        Ok(())
    }

    /// Moves instances for the next frames (`(object index, transform)` pairs; each object
    /// must have had a transform in the scene this technique was built from: see
    /// [`crate::scene::Object::transform`]). No BVH is rebuilt: the moved objects' world
    /// vertices and the top level are rewritten in place (Vulkan rebuilds only its TLAS),
    /// the emission is re-planned for the new caster bounds, and the frame's buffers are
    /// remade only if the plan's needs change. The writes run with the next frame's first
    /// submission (no submission or wait here). The next frame equals, bitwise, a frame of
    /// a technique built fresh from the moved scene. On an error nothing changes.
    pub fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, crate::scene::Transform)],
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_transforms(&self.model, moves)?;
        // the old placement, to go back to if the frame cannot be remade
        let back: Vec<(usize, crate::scene::Transform)> = moves
            .iter()
            .map(|(k, _)| (*k, self.model.objects[*k].transform.unwrap_or_default()))
            .collect();
        let mut instances = self.instances.clone();
        let m = instances.move_instances(moves)?;
        self.update_instances(backend, model, instances, InstanceUpdate::Moved(m), &|i| {
            i.move_instances(&back).map(InstanceUpdate::Moved)
        })
    }

    /// Deforms an instance for the next frames
    /// ([`crate::frame::technique::Technique::set_object_vertices`]): its BLAS is rebuilt
    /// in place (no other BVH; Vulkan rebuilds that BLAS only), its triangles, world
    /// vertices and the top level rewritten, and the frame re-planned as for a move. The
    /// writes run with the next frame's first submission. On an error nothing changes.
    pub fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        let d = crate::frame::technique::deformation(
            &self.model,
            &self.instances,
            object,
            positions,
            normals,
        )?;
        let before = d.before;
        self.update_instances(backend, d.model, d.instances, d.update, &|i| {
            i.deform_instance(object, before.clone())
                .map(InstanceUpdate::Deformed)
        })
    }

    /// Applies an instance update already made to `instances` (a copy of the technique's)
    /// and re-plans the frame for `model`, the scene after it; `undo` goes back if the
    /// frame cannot be remade.
    fn update_instances(
        &mut self,
        backend: &mut dyn Backend,
        model: Scene,
        instances: SceneInstances,
        u: InstanceUpdate,
        undo: &dyn Fn(&mut SceneInstances) -> Result<InstanceUpdate, BuildError>,
    ) -> Result<(), Error> {
        let m = u.moved();
        let bounds = SceneBounds {
            bounds: m.bounds,
            caster_bounds: m.caster_bounds,
            caster_spheres: m.caster_spheres,
            ..self.bounds
        };
        let mut adaptive = self.adaptive.clone();
        if let Some(a) = &mut adaptive {
            adaptive_caustics::follow_moved_casters(
                &mut a.caster_boxes,
                &a.caster_objects,
                &instances.levels,
            );
        }
        let (constants, mut plan, _) =
            Sspm::frame_setup(&model, bounds, &self.settings, adaptive.as_ref())?;
        // written with the next frame (`pending`)
        self.pending.update_instances(&u, &self.scene)?;
        self.instances = instances;
        let old_bounds = self.bounds;
        self.bounds = bounds;
        if let Some(f) = &mut self.filters {
            f.reset();
        }
        let old_adaptive = std::mem::replace(&mut self.adaptive, adaptive);
        // the adaptive traversal's planes follow the casters: its frame is remade (as for
        // moved lights)
        if Needs::of_plan(&plan) != Needs::of_plan(&self.plan) || self.adaptive.is_some() {
            let settings = self.settings.clone();
            if let Err(e) = self.rebuild_frame(backend, model, settings) {
                // the old geometry back, then the error
                let u = undo(&mut self.instances)?;
                self.pending.update_instances(&u, &self.scene)?;
                self.bounds = old_bounds;
                self.adaptive = old_adaptive;
                return Err(e);
            }
            return Ok(());
        }
        plan.buffers = std::mem::take(&mut self.plan.buffers);
        self.model = model;
        self.constants = constants;
        self.plan = plan;
        Ok(())
    }

    /// Replaces the materials' parameters for the next frames
    /// ([`crate::frame::material_update`]): the table is uploaded in place; when the
    /// scene's features or dispersion change, the frame is also re-planned and its
    /// buffers remade (the uploaded geometry stays). On an error nothing changes.
    pub fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        let u = crate::frame::material_update::material_update(&self.model, materials)?;
        let old = self
            .model
            .materials
            .values()
            .map(crate::device::device_scene::gpu_material)
            .collect::<Vec<_>>();
        let mut rec = Recording::new();
        rec.update(self.scene.materials, &u.gpu, "materials")?;
        backend.execute(&rec)?;
        if u.same_plan {
            self.model = u.model;
            if let Some(f) = &mut self.filters {
                f.reset();
            }
            return Ok(());
        }
        let had = self.bounds.has_dispersion;
        self.bounds.has_dispersion = u.has_dispersion;
        let settings = self.settings.clone();
        if let Err(e) = self.rebuild_frame(backend, u.model, settings) {
            // the old table and the old frame back
            self.bounds.has_dispersion = had;
            let mut rec = Recording::new();
            rec.update(self.scene.materials, &old, "materials")?;
            backend.execute(&rec)?;
            let (model, settings) = (self.model.clone(), self.settings.clone());
            self.rebuild_frame(backend, model, settings)?;
            return Err(e);
        }
        Ok(())
    }

    /// A light buffer of the new size, then the frame remade for `model`; if the frame
    /// cannot be remade, the old lights come back (the frame is rebuilt for them by
    /// `rebuild_frame`) and the error is returned.
    fn replace_lights(
        &mut self,
        backend: &mut dyn Backend,
        model: Scene,
        gpu: &[GpuLight],
    ) -> Result<(), Error> {
        self.swap_light_buffer(backend, gpu)?;
        let settings = self.settings.clone();
        if let Err(e) = self.rebuild_frame(backend, model, settings) {
            let old: Vec<GpuLight> = self
                .model
                .lights
                .iter()
                .map(crate::device::device_scene::gpu_light)
                .collect();
            self.swap_light_buffer(backend, &old)?;
            return Err(e);
        }
        Ok(())
    }

    /// Replaces the scene's light buffer with one holding `gpu`.
    fn swap_light_buffer(
        &mut self,
        backend: &mut dyn Backend,
        gpu: &[GpuLight],
    ) -> Result<(), Error> {
        // earlier updates' writes into the old buffer first
        let pending = std::mem::take(&mut self.pending);
        if !pending.steps.is_empty() {
            backend.execute(&pending)?;
        }
        let old = self.scene.lights;
        let mut rec = Recording::new();
        let new = rec.upload(gpu, "lights");
        let alloc = planned_allocation(backend, &rec, None)?;
        rec.steps.push(Step::Free { id: old.id });
        backend.execute(&rec)?;
        self.scene.lights = new;
        for id in &mut self.scene_owned {
            if *id == old.id {
                *id = new.id;
            }
        }
        let old_bytes = old.len as u64 * std::mem::size_of::<GpuLight>() as u64;
        self.scene_bytes = self.scene_bytes - old_bytes + alloc.bytes;
        self.bytes = self.bytes - old_bytes + alloc.bytes;
        for b in &mut self.scene_buffers {
            if b.name == "lights" {
                b.bytes = alloc.bytes;
            }
        }
        for b in &mut self.plan.buffers {
            if b.name == "lights" {
                b.bytes = alloc.bytes;
            }
        }
        self.light_count = gpu.len() as u32;
        Ok(())
    }
}

impl Drop for Sspm {
    fn drop(&mut self) {
        crate::frame::technique::report_leak(
            self.technique_name(),
            self.owned.len() + self.scene_owned.len(),
            self.bytes,
        );
    }
}

impl Technique for Sspm {
    fn name(&self) -> &'static str {
        self.technique_name()
    }

    fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        Sspm::frame(self, backend, progress)
    }

    fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        Sspm::record_frame(self, backend)
    }

    fn outputs(&self) -> Vec<OutputInfo> {
        Output::ALL
            .iter()
            .map(|o| OutputInfo {
                name: o.stem(),
                description: o.description(),
                requested: o.requested(&self.settings.outputs),
                camera_space: true,
            })
            .collect()
    }

    fn read_output(&self, backend: &mut dyn Backend, name: &str) -> Result<Image, Error> {
        let o = Output::from_stem(name).ok_or_else(|| {
            Error::InvalidParameter(format!(
                "sspm has no output '{name}'; outputs: {}",
                Output::ALL.map(|o| o.stem()).join(", ")
            ))
        })?;
        Sspm::read_output(self, backend, o)
    }

    fn estimate_outputs(&self) -> (&'static str, &'static str) {
        (Output::FilteredCaustics.stem(), Output::RawCaustics.stem())
    }

    fn settings_json(&self) -> serde_json::Value {
        match &self.adaptive {
            Some(a) => serde_json::to_value(&a.settings),
            None => serde_json::to_value(&self.settings),
        }
        .unwrap_or(serde_json::Value::Null)
    }

    fn set_seed(&mut self, seed: u32) {
        Sspm::set_seed(self, seed)
    }

    fn set_camera(
        &mut self,
        backend: &mut dyn Backend,
        camera: &crate::scene::Camera,
    ) -> Result<(), Error> {
        Sspm::set_camera(self, backend, camera)
    }

    fn set_lights(
        &mut self,
        backend: &mut dyn Backend,
        lights: &[crate::scene::Light],
    ) -> Result<(), Error> {
        Sspm::set_lights(self, backend, lights)
    }

    fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, crate::scene::Transform)],
    ) -> Result<(), Error> {
        Sspm::set_object_transforms(self, backend, moves)
    }

    fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        Sspm::set_object_vertices(self, backend, object, positions, normals)
    }

    fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        Sspm::set_materials(self, backend, materials)
    }

    fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        Sspm::set_reference(self, reference)
    }

    fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: &serde_json::Value,
    ) -> Result<(), Error> {
        let next = match &self.adaptive {
            None => serde_json::from_value::<SspmSettings>(settings.clone())
                .map_err(|e| Error::InvalidParameter(format!("sspm settings: {e}")))?,
            Some(a) => {
                let parsed = AdaptiveCausticsSettings::from_json(settings)?;
                let same_traversal = AdaptiveCausticsSettings {
                    screen: a.settings.screen.clone(),
                    ..parsed.clone()
                } == a.settings;
                if !same_traversal {
                    return Err(Error::InvalidParameter(
                        "adaptive-caustics (screen): only the `screen` settings can change \
                         through set_settings; the traversal's need a new technique"
                            .into(),
                    ));
                }
                parsed.screen_settings()
            }
        };
        Sspm::set_settings(self, backend, next)
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn free(self: Box<Self>, backend: &mut dyn Backend) -> Result<(), Error> {
        Sspm::free(*self, backend)
    }
}

/// The registry's constructor: `settings` is a JSON object of [`SspmSettings`] fields
/// (missing fields take their defaults, unknown ones are an error).
pub fn create(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn Technique>, Error> {
    let settings: SspmSettings = serde_json::from_value(settings.clone())
        .map_err(|e| Error::InvalidParameter(format!("sspm settings: {e}")))?;
    Ok(Box::new(Sspm::new(backend, scene, settings)?))
}
