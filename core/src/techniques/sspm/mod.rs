//! Screen-space photon mapping (`Sspm`, Kim 2019): Kim 2019's projection volumes
//! ([`crate::frame::emission::projection_volume`]) emit photons that the screen receiver
//! ([`crate::frame::receivers::screen`]) deposits, resolves, filters and composites over
//! the frame host's direct light. Per frame:
//!
//! 1. `primary_gbuffer`, `direct_light` (the frame host's);
//! 2. per light and per batch: `trace_photons` (emit, trace through specular chains, store
//!    photons on diffuse surfaces after >= 1 specular interaction) then `deposit_screen`
//!    (one photon -> one pixel, fixed-point integer sums; Kim 2019, section 30.3.1.3), or the
//!    fused trace that deposits where each path ends;
//! 3. `resolve_caustics` (flux -> radiance, Kim 2019, Eq. 5: the raw caustics), the filter, the
//!    opt-in temporal blend and A-Trous iterations, then `composite` (Kim 2019, section 30.3.3).
//!
//! Photons are processed in batches of at most `max_photons_per_batch`, so the photon
//! buffer never exceeds `32 * max_photons_per_batch` bytes; every batch is deposited before
//! the next is traced, so nothing is dropped when a buffer is "full".

mod constants;
mod settings;

pub use crate::frame::output::{Output, Outputs};
pub use crate::frame::receivers::screen::{plan_frame, FrameImages, GatherFilter, Needs};
pub use constants::{volume_light_plans, FrameConstants};
pub use settings::SspmSettings;

use crate::backend::Backend;
use crate::device::handle::{Buf, GBufferPlanes, ImageBuf};
use crate::device::layout::{Photon, TraceParams};
use crate::frame::allocation::{allocate, Allocation};
use crate::frame::error::Error;
use crate::frame::host::{FrameHost, HostOptions};
use crate::frame::image::Image;
use crate::frame::pipeline::{Change, FrameBuilder, Hosted, Pipeline, Reaction};
use crate::frame::plan::FramePlan;
use crate::frame::receivers::accumulation_seed;
use crate::frame::receivers::screen::ScreenReceiver;
use crate::kernels::{DepositScreen, FusedDeposit, ScreenDeposit, TracePhotons};
use crate::recording::Recording;

/// Screen-space photon mapping on one backend, for one scene: the frame host and
/// [`SspmPipeline`].
pub type Sspm = Hosted<SspmPipeline>;

/// The photon buffers of the projection volumes' batches (exist only when some light
/// emits photons).
#[derive(Clone, Copy, Debug)]
struct PhotonBuffers {
    /// Stored photons (one slot with the fused deposit, which stores none).
    photons: Buf<Photon>,
    /// Photons a batch traces.
    batch: u32,
    photon_count: Buf<u32>,
}

/// Sspm's own state over the frame host: its emission, its screen receiver, its plan.
pub struct SspmPipeline {
    settings: SspmSettings,
    constants: FrameConstants,
    plan: FramePlan,
    photons: Option<PhotonBuffers>,
    receiver: ScreenReceiver,
    /// Its own buffers.
    owned: Allocation,
}

/// The frame constants and plan of the host's scene with `settings`; refuses a light
/// whose flux is out of range.
fn frame_setup(
    host: &FrameHost,
    settings: &SspmSettings,
) -> Result<(FrameConstants, FramePlan), Error> {
    let g = host.geometry();
    let constants = FrameConstants::for_bounds(
        host.model(),
        g.bounds,
        (g.caster_bounds, g.caster_spheres),
        g.has_dispersion,
        settings,
    );
    constants.check_light_flux()?;
    let lights = volume_light_plans(&constants);
    let mut plan = plan_frame(
        host.model(),
        lights,
        settings.frame.outputs,
        settings.frame.prune,
        (
            settings.screen.filter,
            settings.frame.temporal,
            settings.frame.atrous_iterations > 0,
        ),
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
            p.reason = "trace_photons deposits each stored photon into the screen photon map \
                        (fused_deposit)"
                .into();
        }
    }
    Ok((constants, plan))
}

impl SspmPipeline {
    /// The camera images' and this frame's buffers in the plan.
    fn plan_buffers(&mut self, host: &FrameHost) {
        self.plan.buffers = host
            .buffer_plans()
            .into_iter()
            .chain(self.owned.buffers.iter().cloned())
            .collect();
    }

    /// Re-plans for the host's new scene (lights, instances): in place when the passes'
    /// needs stay, else the buffers are made anew.
    fn replan(&mut self, host: &FrameHost) -> Result<Reaction, Error> {
        let (constants, plan) = frame_setup(host, &self.settings)?;
        if Needs::of_plan(&plan) != self.receiver.needs() {
            return Ok(Reaction::Rebuild);
        }
        self.receiver.set_quanta(constants.quanta());
        self.constants = constants;
        self.plan = plan;
        self.plan_buffers(host);
        Ok(Reaction::Kept)
    }

    /// Records step 2: per emitting light, per batch, the trace and the deposit, each
    /// batch its own recording with the photons it covers.
    fn record_batches(&self, host: &FrameHost, frame: &mut FrameBuilder, p: PhotonBuffers) {
        let (Some(variant), Some(map), Some(gbuffer)) = (
            self.plan.trace_variant,
            self.receiver.photon_map(),
            host.screen().gbuffer,
        ) else {
            return;
        };
        let deposit_params = self.receiver.deposit_params(host.camera(), p.photons.len);
        let per_light = self.settings.frame.photons();
        // a new seed for every frame an accumulating photon map adds
        let mut settings = self.settings.clone();
        settings.frame.seed =
            accumulation_seed(self.settings.frame.seed, self.receiver.frame_index());
        for (light, d) in &self.constants.domains {
            frame.stats.photons_emitted += per_light;
            for c in 0..3 {
                frame.stats.emitted_flux[c] += d.flux[c] as f64;
            }
            let mut first = 0u64;
            while first < per_light {
                let count = (per_light - first).min(p.batch as u64) as u32;
                let mut rec = Recording::new();
                rec.clear(p.photon_count);
                // the frames of an accumulation stratify each grid cell together: the
                // first frame's jitter seed, this frame's stratum
                let first_frame =
                    self.constants
                        .trace_params(&self.settings, *light, d, first as u32, count);
                let params = TraceParams {
                    jitter_seed: first_frame.seed,
                    stratum: self.receiver.frame_index(),
                    ..self
                        .constants
                        .trace_params(&settings, *light, d, first as u32, count)
                };
                rec.kernel(TracePhotons {
                    scene: host.scene(),
                    variant,
                    params,
                    photons: p.photons,
                    photon_count: p.photon_count,
                    counters: map.counters,
                    clusters: None,
                    deposit: variant
                        .fused_deposit
                        .then_some(FusedDeposit::Screen(ScreenDeposit {
                            params: deposit_params,
                            gbuffer,
                            photon_map: map.planes,
                        })),
                });
                if !variant.fused_deposit {
                    rec.kernel(DepositScreen {
                        params: deposit_params,
                        gbuffer,
                        photons: p.photons,
                        photon_count: p.photon_count,
                        counters: map.counters,
                        photon_map: map.planes,
                    });
                }
                frame.stats.batches += 1;
                first += count as u64;
                frame.push(rec, count as u64);
            }
        }
    }
}

impl Pipeline for SspmPipeline {
    type Settings = SspmSettings;

    const NAME: &'static str = "sspm";

    fn validate(settings: &SspmSettings) -> Result<(), Error> {
        settings.validate()
    }

    fn host_options(settings: &SspmSettings) -> HostOptions {
        HostOptions {
            max_triangles: settings.frame.max_triangles,
            atlas_receivers: false,
        }
    }

    fn create(
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        settings: SspmSettings,
    ) -> Result<SspmPipeline, Error> {
        let (constants, plan) = frame_setup(host, &settings)?;
        let needs = Needs::of_plan(&plan);
        host.make_screen(
            backend,
            ScreenReceiver::screen_needs(needs, &settings.frame),
        )?;
        let camera = host.camera();
        let mut rec = Recording::new();
        let photons = needs.photons.then(|| {
            let per_light = settings.frame.photons();
            let batch = crate::frame::allocation::photons_per_batch(
                per_light,
                settings.trace.max_photons_per_batch,
                backend.capabilities().max_buffer_bytes,
            );
            // the fused deposit stores no photon
            let cap = if settings.fused_deposit { 1 } else { batch };
            PhotonBuffers {
                photons: rec.create(cap, "photons"),
                batch,
                photon_count: rec.create(1, "photon count"),
            }
        });
        let receiver = ScreenReceiver::create(
            &mut rec,
            camera,
            &plan,
            &settings.frame,
            settings.screen.clone(),
            constants.quanta(),
        );
        let alloc = allocate(backend, &rec, Some((camera.width, camera.height)))?;
        let mut p = SspmPipeline {
            settings,
            constants,
            plan,
            photons,
            receiver,
            owned: alloc,
        };
        p.plan_buffers(host);
        Ok(p)
    }

    fn settings(&self) -> &SspmSettings {
        &self.settings
    }

    fn set_seed(&mut self, seed: u32) {
        self.settings.frame.seed = seed;
    }

    fn record(
        &mut self,
        _backend: &mut dyn Backend,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        frame.stats.flux_quantum = self.constants.flux_quantum as f64;
        if let Some(variant) = self.plan.trace_variant.filter(|_| self.photons.is_some()) {
            frame.stats.variants.push(crate::kernels::variant_label(
                "trace_photons",
                &variant.constants(),
            ));
        }
        host.record_visibility(frame.rec());
        self.receiver.record_clear(frame.rec());
        let (Some(p), Some(_), Some(map)) = (
            self.photons,
            self.plan.trace_variant,
            self.receiver.photon_map(),
        ) else {
            return Ok(());
        };
        self.record_batches(host, frame, p);
        let camera = host.camera();
        let mut rec = Recording::new();
        self.receiver
            .record_resolve(&mut rec, camera, host.screen(), p.photons.len);
        frame.push(rec, 0);
        frame.counters_at_end(map.counters, self.constants.flux_quantum);
        // this frame's blend is the next frame's history
        frame.stats.accumulated_frames = self.receiver.end_frame(camera);
        Ok(())
    }

    fn react(
        &mut self,
        _backend: &mut dyn Backend,
        host: &mut FrameHost,
        change: Change,
    ) -> Result<Reaction, Error> {
        match change {
            Change::Camera => {
                // the photon map is the old camera's pixels
                self.receiver.restart_accumulation();
                Ok(Reaction::Kept)
            }
            Change::Resized => Ok(Reaction::Rebuild),
            Change::Lights | Change::Instances { .. } => self.replan(host),
            Change::Materials { same_plan: true } => {
                self.receiver.reset_history();
                Ok(Reaction::Kept)
            }
            Change::Materials { same_plan: false } => Ok(Reaction::Rebuild),
        }
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn own_outputs(&self) -> &'static [Output] {
        &ScreenReceiver::OUTPUTS
    }

    fn requested_outputs(&self) -> Outputs {
        self.settings.frame.outputs
    }

    fn output_image(&self, host: &FrameHost, output: Output) -> Option<ImageBuf> {
        self.receiver.image(host, output)
    }

    fn estimate_outputs(&self) -> (Output, Output) {
        (Output::FilteredCaustics, Output::RawCaustics)
    }

    fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        Ok(self.owned.free(backend)?)
    }

    fn owned(&self) -> (usize, u64) {
        self.owned.count()
    }
}

impl Hosted<SspmPipeline> {
    /// The frame's device images.
    pub fn images(&self) -> FrameImages {
        let host = self.host();
        self.pipeline()
            .receiver
            .images(host.camera(), host.screen())
    }

    /// The G-buffer's planes (for conformance and embedding; read them back assembled
    /// with [`crate::backend::read_gbuffer`]).
    pub fn gbuffer(&self) -> GBufferPlanes {
        self.host()
            .screen()
            .gbuffer
            .expect("Sspm always makes the G-buffer")
    }

    /// The stored-photon buffer and its count (absent when no light emits photons and
    /// with the fused deposit, which stores none: [`SspmSettings::fused_deposit`]). After
    /// a frame they hold the last batch.
    pub fn photon_buffers(&self) -> Option<(Buf<Photon>, Buf<u32>)> {
        let p = self.pipeline();
        p.photons
            .filter(|_| !p.plan.trace_variant.is_some_and(|v| v.fused_deposit))
            .map(|b| (b.photons, b.photon_count))
    }

    /// Reads a device image of the camera's size back to the host.
    pub fn read_image(&self, backend: &mut dyn Backend, image: ImageBuf) -> Result<Image, Error> {
        self.host().read_image(backend, image)
    }
}

/// The registry's constructor: `settings` is a JSON object of [`SspmSettings`] fields
/// (missing fields take their defaults, unknown ones are an error).
pub fn create(
    backend: &mut dyn Backend,
    scene: &crate::scene::Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn crate::frame::technique::Technique>, Error> {
    crate::frame::pipeline::create::<SspmPipeline>(backend, scene, settings)
}
