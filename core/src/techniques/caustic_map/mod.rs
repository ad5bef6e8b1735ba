//! CausticMap (Vanderstichelen 2021, "Real-time caustics via texture-space photon mapping"): photons
//! shot from each light's view planes ([`crate::frame::emission::view_planes`]) deposit
//! into the caustic atlas in the receivers' texture space
//! ([`crate::frame::receivers::atlas`]), which the camera's lookup samples wherever a
//! camera path ends on a receiver (directly, in a mirror or through glass). Passes:
//!
//! 1. photon work, only when the atlas is stale (new lights, settings or seed; never for
//!    a camera move): per light view plane and per batch `trace_photons` (the
//!    `SURFACE_STORE` and `FUSED_DEPOSIT` variant: each stored photon's uv and triangle
//!    go straight into the atlas's fixed-point sums; no photon buffer, no second pass),
//!    then the atlas's gather (Vanderstichelen 2021's N x N gather fixed to keep flux, or the density
//!    gather on the atlas);
//! 2. every frame: the frame host's `primary_gbuffer` and `direct_light`, then
//!    `caustic_map_lookup` (the camera's specular ray tree reading the map), the opt-in
//!    filters and `composite`.
//!
//! **Tiles only for reached receivers.** A photon pass runs on a layout that gives every
//! receiver the photons can reach a tile: at creation and after a change of the lights or
//! instances every receiver has one, so no photon's flux is lost. Its reach mask comes
//! back without a wait (a readback submitted at the next frame's recording, collected
//! at a later one: two frames later in a blocking loop, whenever the device is done in
//! a host's loop): when the set of receivers the photons reached differs from the set
//! that has tiles, the atlas is laid out anew for the reached ones (they share the whole
//! atlas, so their texel density rises) and the same photons are traced (counter-based
//! random numbers: the same paths) and deposited again. Which receivers the photons
//! reach does not depend on the layout, so that pass reaches the same set, and a
//! technique updated into a state lays its atlas out exactly as a fresh one built in
//! that state, frame for frame (the seam tests compare them bitwise). With pruning off
//! every receiver keeps its tile.
//!
//! Not built yet: a footprint carried through curved glass (the lookup unfolds the
//! pixel's square along the path, blind to focusing).

mod settings;

pub use crate::frame::emission::view_planes::ViewPlanes;
pub use crate::frame::receivers::atlas::settings::{
    AtlasSettings, EmissionPlane, FresnelModel, FresnelSplit, MapGather, PlaneSettings,
    ATLAS_BYTES_PER_TEXEL, DENSITY_GATHER_BYTES_PER_TEXEL, MAX_ATLAS_SIZE,
};
pub use crate::frame::receivers::atlas::{atlas_gather_params, OUTPUTS};
pub use settings::CausticMapSettings;

use crate::backend::Backend;
use crate::device::handle::ImageBuf;
use crate::device::layout::{AtlasTexel, TraceParams};
use crate::frame::error::Error;
use crate::frame::host::{FrameHost, HostOptions};
use crate::frame::image::Image;
use crate::frame::output::{Output, Outputs};
use crate::frame::pipeline::{Change, FrameBuilder, Hosted, Pipeline, Reaction};
use crate::frame::plan::{FramePlan, SceneFeatures};
use crate::frame::receivers::accumulation_seed;
use crate::frame::receivers::atlas::{with_atlas, AtlasQuanta, AtlasReceiver};
use crate::kernels::{FusedDeposit, TracePhotons, TraceVariant};
use crate::recording::Recording;

/// CausticMap on one backend, for one scene: the frame host and [`CausticMapPipeline`].
pub type CausticMap = Hosted<CausticMapPipeline>;

/// CausticMap's own state over the frame host: its light view planes, the atlas
/// receiver, whether the atlas holds the current photons, its plan.
pub struct CausticMapPipeline {
    settings: CausticMapSettings,
    planes: ViewPlanes,
    variant: TraceVariant,
    receiver: AtlasReceiver,
    plan: FramePlan,
    /// The atlas holds the photons of the current lights, settings and seed.
    atlas_valid: bool,
    /// The device's largest buffer (bytes): batches hold at most that many photons.
    max_buffer_bytes: u64,
    /// Photon passes recorded (the reach mask's generation).
    photon_passes: u64,
    /// The last photon pass's reach mask on its way back.
    reach: Reach,
}

/// A photon pass's reach mask on its way to the host, never waited for inside a frame.
#[derive(Debug)]
enum Reach {
    /// Nothing to read.
    Idle,
    /// Pass `n`'s mask is to be read (submitted at the next recording, after pass `n`'s
    /// frame on the device's queue).
    Wanted(u64),
    /// Pass `n`'s mask is being copied back.
    Pending(crate::backend::Submission, u64),
}

/// The light view planes of the host's scene; refuses a light whose flux is out of
/// range.
fn view_planes(host: &FrameHost, settings: &CausticMapSettings) -> Result<ViewPlanes, Error> {
    let g = host.geometry();
    let planes = ViewPlanes::new(
        host.model(),
        g.bounds,
        g.caster_bounds,
        g.caster_spheres,
        g.has_dispersion,
        &settings.frame,
        &settings.planes,
    );
    planes.check_light_flux()?;
    Ok(planes)
}

/// The plan from the planes, the atlas and the camera images.
fn plan(
    host: &FrameHost,
    receiver: &AtlasReceiver,
    planes: &ViewPlanes,
    variant: TraceVariant,
) -> FramePlan {
    let why = format!(
        "each stored photon straight into the atlas, {}",
        receiver.stale_words()
    );
    receiver.plan(
        host,
        planes.light_plans(),
        &[("trace_photons", why)],
        variant,
    )
}

impl CausticMapPipeline {
    fn replan(&mut self, host: &FrameHost) {
        self.plan = plan(host, &self.receiver, &self.planes, self.variant);
    }

    /// Moves the last photon pass's reach mask along without waiting: submits its
    /// readback once the pass's frame is ahead of it on the device's queue (every frame
    /// before this one submitted; else it waits for a later frame), or collects it
    /// if the device is done; a mask of the current pass whose reached receivers differ
    /// from the tiled ones lays the atlas out for them (recorded into `frame`) and makes
    /// the atlas stale, so this frame traces the same photons into the new tiles.
    fn follow_reach(
        &mut self,
        backend: &mut dyn Backend,
        host: &FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        let Some(a) = self.receiver.atlas() else {
            return Ok(());
        };
        match std::mem::replace(&mut self.reach, Reach::Idle) {
            Reach::Idle => {}
            Reach::Wanted(n) if !host.earlier_frames_submitted() => {
                self.reach = Reach::Wanted(n);
            }
            Reach::Wanted(n) => {
                let s = backend.submit(&Recording::new(), &[a.triangle_reach.id])?;
                self.reach = Reach::Pending(s, n);
            }
            Reach::Pending(mut s, n) => match backend.poll(&mut s, false)? {
                None => self.reach = Reach::Pending(s, n),
                Some(f) if n == self.photon_passes => {
                    let mask: Vec<u32> = f
                        .readbacks
                        .first()
                        .map(|b| bytemuck::pod_collect_to_vec(b))
                        .unwrap_or_default();
                    if let Some(reached) = self.receiver.reached(host, &mask) {
                        if reached != self.receiver.tiled() {
                            self.receiver.relayout(host, frame.rec(), &reached)?;
                            self.replan(host);
                            frame.stats.plan = Some(self.plan.clone());
                            self.atlas_valid = false;
                        }
                    }
                }
                // an older pass's mask
                Some(_) => {}
            },
        }
        Ok(())
    }

    /// Gives every receiver a tile again, as at creation, when some has none (moved
    /// lights, casters or new optics may reach it, and the next pass would lose its
    /// flux); a later frame keeps the reached ones. A mask on its way back is of the old
    /// state.
    fn unprune(&mut self, host: &mut FrameHost) -> Result<(), Error> {
        if self.receiver.tiled().iter().any(|t| !t) {
            self.relayout_all(host)?;
        }
        self.photon_passes += 1;
        Ok(())
    }

    /// Records every receiver laid out anew (deferred to the next frame's recording).
    fn relayout_all(&mut self, host: &mut FrameHost) -> Result<(), Error> {
        let all = vec![true; self.receiver.tiled().len()];
        let mut rec = Recording::new();
        self.receiver.relayout(host, &mut rec, &all)?;
        host.defer(rec);
        Ok(())
    }

    /// Collects a reach mask still on its way back (before the technique is freed).
    fn drain_reach(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        if let Reach::Pending(mut s, _) = std::mem::replace(&mut self.reach, Reach::Idle) {
            backend.poll(&mut s, true)?;
        }
        Ok(())
    }

    /// Records the photon pass's start and every plane's batches (the fused trace
    /// deposits into the atlas); counts the emitted photons and flux.
    fn trace(&self, host: &FrameHost, frame: &mut FrameBuilder) {
        let Some(deposit) = self.receiver.fused_deposit() else {
            return;
        };
        let a = self.receiver.atlas().expect("an atlas with its deposit");
        let s = &self.settings;
        // a new seed for every pass an accumulating atlas adds
        let seed = accumulation_seed(s.frame.seed, self.receiver.pass_index());
        self.receiver.record_clear(frame.rec());
        frame.stats.variants.push(crate::kernels::variant_label(
            "trace_photons",
            &self.variant.constants(),
        ));
        for (light, k, plane) in &self.planes.planes {
            let n = plane.texels();
            let flux = plane.power.as_dvec3() * plane.plane_measure();
            for c in 0..3 {
                frame.stats.emitted_flux[c] += flux[c];
            }
            frame.stats.photons_emitted += n;
            // the fused deposit stores nothing: a batch is bounded by the settings and the
            // largest launch only
            let per_batch = crate::frame::allocation::photons_per_batch(
                n,
                s.trace.max_photons_per_batch,
                self.max_buffer_bytes,
            ) as u64;
            let mut first = 0u64;
            while first < n {
                let count = (n - first).min(per_batch) as u32;
                let mut rec = Recording::new();
                rec.kernel(TracePhotons {
                    scene: host.scene(),
                    variant: self.variant,
                    params: TraceParams {
                        split_budget: s.planes.split_budget,
                        fresnel_model: s.planes.fresnel.kernel_value(),
                        dispersion_mode: s.frame.dispersion.kernel_value(),
                        // the passes of an accumulation stratify each grid cell together
                        jitter_seed: ViewPlanes::plane_seed(s.frame.seed, *light, *k),
                        stratum: self.receiver.pass_index(),
                        ..self.planes.trace_params(
                            plane,
                            *light,
                            (first as u32, count),
                            ViewPlanes::plane_seed(seed, *light, *k),
                            s.trace.max_bounces,
                            s.trace.min_relative_power,
                        )
                    },
                    photons: a.photons,
                    photon_count: a.photon_count,
                    counters: a.counters,
                    clusters: None,
                    deposit: Some(FusedDeposit::Atlas(deposit)),
                });
                frame.stats.batches += 1;
                first += count as u64;
                frame.push(rec, count as u64);
            }
        }
    }

    /// The photon pass: trace and deposit every plane (twice when the reached receivers
    /// change: see the module doc), then the gather; the counters come back at the
    /// frame's end.
    fn photon_pass(&mut self, host: &mut FrameHost, frame: &mut FrameBuilder) -> Result<(), Error> {
        let Some(a) = self.receiver.atlas() else {
            return Ok(());
        };
        frame.expect_photons(self.planes.planes.iter().map(|(_, _, p)| p.texels()).sum());
        self.trace(host, frame);
        self.photon_passes += 1;
        if self.settings.frame.prune && host.receivers().is_some() {
            self.reach = Reach::Wanted(self.photon_passes);
        }
        self.receiver.record_gather(frame.rec());
        frame.counters_at_end(a.counters, self.planes.flux_quantum);
        frame.stats.accumulated_frames = self.receiver.end_photon_pass();
        // an accumulating atlas takes new photons every frame
        self.atlas_valid = !self.settings.frame.accumulate;
        Ok(())
    }
}

impl Pipeline for CausticMapPipeline {
    type Settings = CausticMapSettings;

    const NAME: &'static str = "caustic-map";

    fn validate(settings: &CausticMapSettings) -> Result<(), Error> {
        settings.validate()
    }

    fn host_options(settings: &CausticMapSettings) -> HostOptions {
        HostOptions {
            max_triangles: settings.frame.max_triangles,
            atlas_receivers: true,
        }
    }

    fn create(
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        settings: CausticMapSettings,
    ) -> Result<CausticMapPipeline, Error> {
        let planes = view_planes(host, &settings)?;
        let config = settings.atlas_config();
        let atlas = with_atlas(host, &config, !planes.planes.is_empty());
        host.make_screen(backend, AtlasReceiver::screen_needs(&config, atlas))?;
        let features = SceneFeatures::of(host.model());
        let mut variant = features.trace_variant();
        variant.surface_store = true;
        // the split only changes dielectrics: a scene without one runs the plain variant
        variant.fresnel_split =
            settings.planes.fresnel_split == FresnelSplit::Deterministic && features.dielectrics;
        variant.adaptive = false;
        // CausticMap's photons go straight into the atlas
        variant.fused_deposit = true;
        let receiver = AtlasReceiver::create(
            backend,
            host,
            config,
            AtlasQuanta::of(&planes),
            atlas,
            &mut |_| {},
        )?;
        let plan = plan(host, &receiver, &planes, variant);
        Ok(CausticMapPipeline {
            settings,
            planes,
            variant,
            receiver,
            plan,
            atlas_valid: false,
            max_buffer_bytes: backend.capabilities().max_buffer_bytes,
            photon_passes: 0,
            reach: Reach::Idle,
        })
    }

    fn settings(&self) -> &CausticMapSettings {
        &self.settings
    }

    fn set_seed(&mut self, seed: u32) {
        if seed != self.settings.frame.seed {
            self.settings.frame.seed = seed;
            self.receiver.set_seed(seed);
            self.atlas_valid = false;
        }
    }

    fn record(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error> {
        frame.stats.flux_quantum = self.planes.flux_quantum as f64;
        self.follow_reach(backend, host, frame)?;
        let photons = self.plan.trace_variant.is_some();
        if photons && self.receiver.atlas().is_some() {
            if self.atlas_valid {
                AtlasReceiver::skip_photon_passes(&self.plan, &mut frame.stats);
            } else {
                self.photon_pass(host, frame)?;
            }
        }
        host.record_visibility(frame.rec());
        self.receiver.record_camera(host, frame.rec());
        self.receiver.end_frame(host.camera());
        Ok(())
    }

    fn react(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        change: Change,
    ) -> Result<Reaction, Error> {
        let receivers_moved = match change {
            Change::Camera => return Ok(Reaction::Kept),
            Change::Resized => {
                // only the camera-sized images: the atlas stays valid; made (and the old
                // ones freed) at once, so never ahead of a recorded frame that uses them
                host.check_all_submitted("a new image size makes the caustic images anew")?;
                self.receiver.make_images(backend, host.camera())?;
                self.replan(host);
                return Ok(Reaction::Kept);
            }
            Change::Materials { same_plan: true } => {
                // new optics may reach receivers without a tile
                self.unprune(host)?;
                self.atlas_valid = false;
                self.receiver.reset_history();
                return Ok(Reaction::Kept);
            }
            Change::Materials { same_plan: false } => return Ok(Reaction::Rebuild),
            Change::Lights => false,
            Change::Instances {
                receivers_moved, ..
            } => receivers_moved,
        };
        let planes = view_planes(host, &self.settings)?;
        let had_photons = self.plan.trace_variant.is_some();
        if planes.planes.is_empty() == had_photons && self.settings.frame.prune {
            // photon passes start or stop: other buffers
            return Ok(Reaction::Rebuild);
        }
        self.receiver.set_quanta(AtlasQuanta::of(&planes));
        self.planes = planes;
        self.atlas_valid = false;
        if receivers_moved {
            // a moved receiver's tile follows its new area
            self.relayout_all(host)?;
        }
        self.unprune(host)?;
        self.replan(host);
        Ok(Reaction::Kept)
    }

    fn plan(&self) -> &FramePlan {
        &self.plan
    }

    fn own_outputs(&self) -> &'static [Output] {
        &OUTPUTS
    }

    fn requested_outputs(&self) -> Outputs {
        self.settings.frame.outputs
    }

    fn output_image(&self, host: &FrameHost, output: Output) -> Option<ImageBuf> {
        self.receiver.output_image(host, output)
    }

    fn read_data_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error> {
        debug_assert_eq!(output, Output::CausticAtlas);
        self.receiver.read_atlas(backend)
    }

    fn estimate_outputs(&self) -> (Output, Output) {
        (Output::FilteredCaustics, Output::RawCaustics)
    }

    fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        self.drain_reach(backend)?;
        self.receiver.free(backend)
    }

    fn owned(&self) -> (usize, u64) {
        self.receiver.owned()
    }
}

impl Hosted<CausticMapPipeline> {
    /// The atlas layout as the kernels read it now, per atlas texel (row-major):
    /// `[world area bits, tile]` ([`AtlasTexel`]; `NO_TILE` and area 0 outside the tiles),
    /// read back from the device; `None` without an atlas. With the `caustic_atlas`
    /// output (irradiance, W/m^2) it gives each texel's flux, `E x area`. The layout
    /// follows the receivers the last photon pass reached (see the module doc).
    pub fn atlas_texels(
        &self,
        backend: &mut dyn Backend,
    ) -> Result<Option<Vec<AtlasTexel>>, Error> {
        self.pipeline().receiver.atlas_texels(backend)
    }
}

/// The registry's constructor: `settings` is a JSON object of [`CausticMapSettings`]
/// fields (missing fields take their defaults, unknown ones are an error).
pub fn create(
    backend: &mut dyn Backend,
    scene: &crate::scene::Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn crate::frame::technique::Technique>, Error> {
    crate::frame::pipeline::create::<CausticMapPipeline>(backend, scene, settings)
}
