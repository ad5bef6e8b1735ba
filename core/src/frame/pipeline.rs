//! What a technique is over the frame host: its photon pipeline, its filter and its own
//! temporal state ([`Pipeline`]), and the one implementation of the public
//! [`Technique`] seam for all of them ([`Hosted`]): creation, the frame (blocking or
//! recorded for a host's loop), every update (camera, lights, instances, materials,
//! settings, seed), reference images and freeing are written here once, and a technique
//! only re-plans its own passes when the host tells it what changed ([`Change`]).

use crate::backend::Backend;
use crate::device::device_scene::InstanceUpdate;
use crate::device::handle::ImageBuf;
use crate::device::handle::{Buf, ResourceId};
use crate::frame::error::Error;
use crate::frame::host::{FrameHost, HostOptions, HostState};
use crate::frame::image::Image;
use crate::frame::output::{Output, OutputInfo, Outputs};
use crate::frame::plan::FramePlan;
use crate::frame::stats::FrameStats;
use crate::frame::submitted::{EndRead, RecordedFrame};
use crate::frame::technique::{Progress, Technique};
use crate::recording::Recording;
use crate::scene::{Camera, Light, Scene, Transform};
use std::time::Instant;

/// What the host changed before it asks the technique to follow.
#[derive(Clone, Copy, Debug)]
pub enum Change {
    /// The camera moved at the same image size.
    Camera,
    /// The camera moved to a new image size: the host's camera images are made anew; a
    /// technique remakes its own camera-sized buffers or asks for a rebuild.
    Resized,
    /// The lights changed (moved, re-powered, added or removed).
    Lights,
    /// Instances moved or one deformed; `receivers_moved` says whether a receiver of the
    /// atlas moved with them.
    Instances {
        /// A receiver's triangles moved ([`FrameHost::receivers`]).
        receivers_moved: bool,
    },
    /// Material parameters changed; `same_plan`: the scene's features and dispersion
    /// stayed.
    Materials {
        /// The plan, trace variant and quanta can stay.
        same_plan: bool,
    },
}

/// How a technique followed a [`Change`].
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Reaction {
    /// Re-planned in place: its buffers fit the new state.
    Kept,
    /// Its buffers must be made anew for the new state ([`Pipeline::create`] over the
    /// updated host, the old ones freed first).
    Rebuild,
}

/// One frame as a technique records it: recordings in submission order, each with the
/// photons it completes (for progress), the buffers to read back at its end, and its
/// statistics. Work whose next step depends on data read back runs at once
/// ([`FrameBuilder::run_now`], [`FrameBuilder::read_now`]); each such wait is counted in
/// [`FrameStats::host_waits`].
pub struct FrameBuilder<'p> {
    recordings: Vec<(Recording, u64)>,
    readbacks: Vec<ResourceId>,
    ends: Vec<EndRead>,
    /// The frame's statistics so far.
    pub stats: FrameStats,
    progress: &'p mut dyn FnMut(Progress),
    /// Photons completed by work run at once, and the frame's expected total.
    done: u64,
    expected: u64,
}

impl<'p> FrameBuilder<'p> {
    /// A frame that starts with `first` (the host's pending scene writes).
    pub fn new(first: Recording, stats: FrameStats, progress: &'p mut dyn FnMut(Progress)) -> Self {
        FrameBuilder {
            recordings: vec![(first, 0)],
            readbacks: Vec::new(),
            ends: Vec::new(),
            stats,
            progress,
            done: 0,
            expected: 0,
        }
    }

    /// The photons the whole frame will complete (for progress when part of it runs at
    /// once).
    pub fn expect_photons(&mut self, total: u64) {
        self.expected = total;
    }

    /// The recording being filled (the last one).
    pub fn rec(&mut self) -> &mut Recording {
        &mut self
            .recordings
            .last_mut()
            .expect("a frame has a recording")
            .0
    }

    /// Starts a new recording after the current one; `photons` is what it completes (a
    /// blocking frame reports progress as each completes).
    pub fn push(&mut self, rec: Recording, photons: u64) {
        self.recordings.push((rec, photons));
    }

    /// Copies the photon counters `counters` (fixed point with `quantum`) to the host at
    /// the frame's end; their values go into the statistics when the frame completes.
    pub fn counters_at_end(&mut self, counters: Buf<u32>, quantum: f32) {
        let at = self.read_at_end(counters);
        self.ends.push(EndRead::Counters { at, quantum });
    }

    /// Copies `buf` to the host at the frame's end; returns its index among the frame's
    /// readbacks (for an [`EndRead`]).
    pub fn read_at_end<T>(&mut self, buf: Buf<T>) -> usize {
        self.readbacks.push(buf.id);
        self.readbacks.len() - 1
    }

    /// Puts `end` into the statistics when the frame completes (after those pushed
    /// before it).
    pub fn end_read(&mut self, end: EndRead) {
        self.ends.push(end);
    }

    /// The index, among the kernel steps whose times the frame's completion sees, of the
    /// next kernel recorded.
    pub fn kernel_index(&self) -> usize {
        self.recordings
            .iter()
            .map(|(r, _)| r.kernel_count() as usize)
            .sum()
    }

    /// Runs everything recorded so far and then `rec`, and waits (a host wait: counted).
    pub fn run_now(&mut self, backend: &mut dyn Backend, rec: Recording) -> Result<(), Error> {
        let mut all = Recording::new();
        let mut photons = 0;
        for (r, n) in std::mem::take(&mut self.recordings) {
            all.steps.extend(r.steps);
            photons += n;
        }
        all.steps.extend(rec.steps);
        for t in backend.execute(&all)? {
            self.stats.add_pass_time(t.kernel, t.seconds);
        }
        self.stats.host_waits += 1;
        self.recordings.push((Recording::new(), 0));
        if photons > 0 {
            self.done += photons;
            self.progress(self.done, self.expected.max(self.done));
        }
        Ok(())
    }

    /// Runs everything recorded so far, waits and reads `buf` back (a host wait: counted).
    pub fn read_now<T: bytemuck::Pod>(
        &mut self,
        backend: &mut dyn Backend,
        buf: Buf<T>,
    ) -> Result<Vec<T>, Error> {
        if self.recordings.iter().any(|(r, _)| !r.steps.is_empty()) {
            self.run_now(backend, Recording::new())?;
        } else {
            self.stats.host_waits += 1;
        }
        Ok(crate::backend::read_buf(backend, buf)?)
    }

    /// Reports progress of work done outside the recordings (after a [`FrameBuilder::run_now`]).
    pub fn progress(&mut self, done: u64, total: u64) {
        (self.progress)(Progress {
            photons_done: done,
            photons_total: total,
        });
    }

    /// Runs the frame as one pipeline and waits at its end: every recording submitted,
    /// progress reported as each completes, the counters read into the statistics.
    fn run(self, backend: &mut dyn Backend) -> Result<FrameStats, Error> {
        let FrameBuilder {
            recordings,
            readbacks,
            ends,
            mut stats,
            progress,
            done,
            expected,
        } = self;
        let recordings: Vec<(Recording, u64)> = recordings
            .into_iter()
            .filter(|(r, _)| !r.steps.is_empty())
            .collect();
        // progress continues from the work run at once
        let mut report = |p: Progress| {
            let d = done + p.photons_done;
            progress(Progress {
                photons_done: d,
                photons_total: expected.max(done + p.photons_total),
            })
        };
        let (back, times) = crate::frame::submitted::run_pipelined(
            backend,
            recordings,
            &readbacks,
            &mut stats,
            &mut report,
        )?;
        for end in &ends {
            end.apply(&back, &times, &mut stats);
        }
        Ok(stats)
    }

    /// The frame as one recording, not run.
    fn recorded(self) -> RecordedFrame {
        let mut recording = Recording::new();
        for (r, _) in self.recordings {
            recording.steps.extend(r.steps);
        }
        RecordedFrame {
            recording,
            readbacks: self.readbacks,
            stats: self.stats,
            ends: self.ends,
            order: None,
        }
    }
}

/// A technique over a [`FrameHost`]: its photon pipeline, filter and temporal state.
/// [`Hosted`] gives every implementation the public [`Technique`] seam.
pub trait Pipeline: Sized {
    /// Its settings (their JSON form is what [`crate::techniques::create`] takes).
    type Settings: Clone
        + Default
        + PartialEq
        + std::fmt::Debug
        + serde::Serialize
        + serde::de::DeserializeOwned
        + crate::frame::settings::TechniqueSettings;

    /// The registry and statistics name.
    const NAME: &'static str;

    /// The registry and statistics name ([`Pipeline::NAME`]).
    fn name(&self) -> &'static str {
        Self::NAME
    }

    /// Parses a JSON object of settings laid over the technique's defaults (missing
    /// fields keep them, unknown ones are an error naming where a moved field is now:
    /// [`crate::frame::settings::from_json`]).
    fn parse_settings(json: &serde_json::Value) -> Result<Self::Settings, Error> {
        crate::frame::settings::from_json(Self::NAME, &Self::Settings::default(), json)
    }

    /// Checks every field's range.
    fn validate(settings: &Self::Settings) -> Result<(), Error>;

    /// What the host must derive when it uploads the scene for these settings.
    fn host_options(settings: &Self::Settings) -> HostOptions;

    /// Makes the technique's own buffers over the host's scene (and asks the host for
    /// the camera images it needs). On an error nothing of it remains on the device.
    fn create(
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        settings: Self::Settings,
    ) -> Result<Self, Error>;

    /// The settings in effect.
    fn settings(&self) -> &Self::Settings;

    /// Sets the frame seed of the next frames.
    fn set_seed(&mut self, seed: u32);

    /// Records one frame into `frame` (after the host's pending writes). The temporal
    /// history advances as if the frame ran.
    fn record(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        frame: &mut FrameBuilder,
    ) -> Result<(), Error>;

    /// Follows a change the host made. On an error the technique is as it was (the host
    /// then goes back too).
    fn react(
        &mut self,
        backend: &mut dyn Backend,
        host: &mut FrameHost,
        change: Change,
    ) -> Result<Reaction, Error>;

    /// The frame plan: passes run and skipped with reasons, lights, variants, buffers
    /// (the host's included).
    fn plan(&self) -> &FramePlan;

    /// The outputs the technique has, in [`Output::ALL`]'s order.
    fn own_outputs(&self) -> &'static [Output];

    /// The outputs the settings ask for.
    fn requested_outputs(&self) -> Outputs;

    /// The device image of camera-space output `output`, one of
    /// [`Pipeline::own_outputs`] that was requested ([`Hosted`] checks both): `None` where
    /// the plan knows it is zero.
    fn output_image(&self, host: &FrameHost, output: Output) -> Option<ImageBuf>;

    /// Reads back an output that is not camera-space ([`Output::camera_space`]), one of
    /// [`Pipeline::own_outputs`] that was requested. Only techniques with such an output
    /// (the caustic atlas) override it.
    fn read_data_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error> {
        let _ = backend;
        Err(Error::Unsupported(format!(
            "{} has no data output '{output}'",
            self.name()
        )))
    }

    /// The filtered estimate and the raw one: what error-against-time measurements
    /// compare with a reference.
    fn estimate_outputs(&self) -> (Output, Output);

    /// The settings' JSON form (as [`Pipeline::parse_settings`] reads it).
    fn settings_json(&self) -> serde_json::Value {
        serde_json::to_value(self.settings()).unwrap_or(serde_json::Value::Null)
    }

    /// Releases the technique's own buffers.
    fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error>;

    /// Its own device buffers and their bytes (for leak reports and statistics).
    fn owned(&self) -> (usize, u64);
}

/// A technique with its frame host: the type users hold (`Sspm`, `CausticMap`, ...).
pub struct Hosted<P: Pipeline> {
    host: FrameHost,
    pipeline: Option<P>,
}

impl<P: Pipeline> Hosted<P> {
    /// Validates the scene and settings, uploads the scene and makes the technique's
    /// buffers (each checked against the device first). On an error nothing remains on
    /// the device.
    pub fn new(
        backend: &mut dyn Backend,
        scene: &Scene,
        settings: P::Settings,
    ) -> Result<Hosted<P>, Error> {
        P::validate(&settings)?;
        let mut host = FrameHost::upload(backend, scene, P::host_options(&settings))?;
        match P::create(backend, &mut host, settings) {
            Ok(p) => {
                let mut t = Hosted {
                    host,
                    pipeline: Some(p),
                };
                // every buffer is checked: the scene goes up now
                match t.host.flush(backend) {
                    Ok(()) => Ok(t),
                    Err(e) => {
                        let _ = t.free(backend);
                        Err(e)
                    }
                }
            }
            Err(e) => {
                let _ = host.free(backend);
                Err(e)
            }
        }
    }

    /// The frame host (scene, camera, the camera's images).
    pub fn host(&self) -> &FrameHost {
        &self.host
    }

    /// The technique's own state.
    pub fn pipeline(&self) -> &P {
        self.pipeline.as_ref().expect("a live technique")
    }

    fn parts(&mut self) -> (&mut FrameHost, &mut P) {
        (
            &mut self.host,
            self.pipeline.as_mut().expect("a live technique"),
        )
    }

    /// The settings in effect.
    pub fn settings(&self) -> &P::Settings {
        self.pipeline().settings()
    }

    /// The frame plan.
    pub fn plan(&self) -> &FramePlan {
        self.pipeline().plan()
    }

    fn builder<'p>(
        &mut self,
        backend: &dyn Backend,
        progress: &'p mut dyn FnMut(Progress),
    ) -> FrameBuilder<'p> {
        let p = self.pipeline();
        let stats = self
            .host
            .frame_stats(backend, p.name(), p.plan(), p.owned().1);
        let pending = self.host.take_pending();
        FrameBuilder::new(pending, stats, progress)
    }

    /// Renders one frame and waits for it: the planned passes, nothing else, submitted
    /// as one pipeline (one wait), `progress` called as photon work completes. With a
    /// reference image the filtered estimate's error against it is in the statistics.
    pub fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        let start = Instant::now();
        let seq = self.host.sequence();
        let n = seq.count;
        seq.order.run_now(n)?;
        seq.count += 1;
        let mut frame = self.builder(&*backend, progress);
        self.record_numbered(backend, &mut frame, n)?;
        let mut stats = frame.run(backend)?;
        stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        if let Some(r) = self.host.reference() {
            let (filtered, _) = self.pipeline().estimate_outputs();
            let img = Hosted::read_output(self, backend, filtered)?;
            stats.error = Some(crate::frame::metrics::compare(&img, r));
        }
        Ok(stats)
    }

    /// Records one frame for a host's frame loop without running it: submit it with
    /// [`RecordedFrame::submit`] (one submission, no wait) or encode it into the host's
    /// own command stream, and collect its statistics a frame or more later with
    /// [`crate::frame::submitted::FrameTicket::stats`]. The images are those
    /// [`Hosted::frame`] makes, bitwise. Work that must read the device back before it
    /// can record the rest runs here and is counted in [`FrameStats::host_waits`].
    pub fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        let start = Instant::now();
        self.host.sequence().order.check()?;
        let mut none = |_: Progress| {};
        let mut frame = self.builder(&*backend, &mut none);
        let n = self.host.sequence().count;
        self.host.sequence().count += 1;
        self.record_numbered(backend, &mut frame, n)?;
        let mut recorded = frame.recorded();
        recorded.stats.frame_ms = start.elapsed().as_secs_f64() * 1e3;
        recorded.order = Some((self.host.sequence().order.clone(), n));
        Ok(recorded)
    }

    /// Records frame `n`'s passes into `frame`. A failure loses the pending writes the
    /// frame took, so it breaks the frame order (the next frame says why).
    fn record_numbered(
        &mut self,
        backend: &mut dyn Backend,
        frame: &mut FrameBuilder<'_>,
        n: u64,
    ) -> Result<(), Error> {
        let (host, p) = self.parts();
        let recorded = p.record(backend, host, frame);
        if let Err(e) = &recorded {
            self.host
                .sequence()
                .order
                .break_with(format!("frame {n} failed while recording ({e})"));
        }
        recorded
    }

    /// Follows a host change: re-planned in place, or the technique's buffers made anew;
    /// when that fails, the host goes back to `state` (`undo` makes the instance update
    /// back: only then, so that an update that succeeds never computes it), the technique
    /// is made anew over it, and the error is returned.
    fn follow(
        &mut self,
        backend: &mut dyn Backend,
        change: Change,
        state: HostState,
        undo: impl FnOnce() -> Result<Option<InstanceUpdate>, Error>,
    ) -> Result<(), Error> {
        let (host, p) = self.parts();
        let reaction = match p.react(backend, host, change) {
            Ok(r) => r,
            Err(e) => {
                self.host.restore(backend, state, undo()?)?;
                return Err(e);
            }
        };
        if reaction == Reaction::Kept {
            return Ok(());
        }
        let settings = self.pipeline().settings().clone();
        self.rebuild(backend, settings.clone(), |host, backend| {
            host.restore(backend, state, undo()?)
        })
    }

    /// Frees the technique's buffers and makes them anew with `settings` over the host;
    /// when that fails, `undo` puts the host back and the technique is made with `old`
    /// settings over it again.
    fn rebuild(
        &mut self,
        backend: &mut dyn Backend,
        settings: P::Settings,
        undo: impl FnOnce(&mut FrameHost, &mut dyn Backend) -> Result<(), Error>,
    ) -> Result<(), Error> {
        if let Err(e) = self
            .host
            .check_all_submitted("making the technique's buffers anew (it frees those it has)")
        {
            undo(&mut self.host, backend)?;
            return Err(e);
        }
        let old = self.pipeline().settings().clone();
        if let Some(mut p) = self.pipeline.take() {
            p.free(backend)?;
        }
        // the work the technique deferred into its own buffers goes with them
        self.host.drop_deferred();
        match P::create(backend, &mut self.host, settings) {
            Ok(p) => {
                self.pipeline = Some(p);
                Ok(())
            }
            Err(e) => {
                // and so does the failed technique's
                self.host.drop_deferred();
                undo(&mut self.host, backend)?;
                self.pipeline = Some(P::create(backend, &mut self.host, old)?);
                Err(e)
            }
        }
    }

    /// Moves the camera for the next frames. At the same image size nothing is made; a
    /// new size makes the camera's images and the technique's camera-sized buffers anew
    /// (never the uploaded scene) and drops the reference image.
    pub fn set_camera(&mut self, backend: &mut dyn Backend, camera: &Camera) -> Result<(), Error> {
        let state = self.host.state();
        let resized = self.host.set_camera(backend, camera)?;
        let change = if resized {
            Change::Resized
        } else {
            Change::Camera
        };
        self.follow(backend, change, state, || Ok(None))?;
        if resized {
            self.host.drop_reference();
        }
        Ok(())
    }

    /// Replaces the lights for the next frames (moved, re-powered, added or removed)
    /// without rebuilding geometry.
    pub fn set_lights(&mut self, backend: &mut dyn Backend, lights: &[Light]) -> Result<(), Error> {
        let state = self.host.state();
        self.host.set_lights(backend, lights)?;
        self.follow(backend, Change::Lights, state, || Ok(None))
    }

    /// Moves instances for the next frames ([`Technique::set_object_transforms`]): no
    /// BVH is rebuilt; the next frame equals that of a technique created for the moved
    /// scene, bitwise. On an error nothing changes.
    pub fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, Transform)],
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_transforms(self.host.model(), moves)?;
        let back: Vec<(usize, Transform)> = moves
            .iter()
            .map(|(k, _)| {
                (
                    *k,
                    self.host.model().objects[*k].transform.unwrap_or_default(),
                )
            })
            .collect();
        let mut instances = self.host.instances().clone();
        let m = instances.move_instances(moves)?;
        let state = self.host.state();
        let u = InstanceUpdate::Moved(m);
        // the moved levels (cheap to copy: their vertices and triangles are shared), from
        // which the move back is made if the technique cannot follow
        let mut after = instances.clone();
        let receivers_moved = self.host.apply_instances(model, instances, u)?;
        let change = Change::Instances { receivers_moved };
        self.follow(backend, change, state, move || {
            Ok(Some(InstanceUpdate::Moved(after.move_instances(&back)?)))
        })
    }

    /// Deforms an instance for the next frames ([`Technique::set_object_vertices`]):
    /// only its bottom-level BVH is rebuilt. On an error nothing changes.
    pub fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        let d = crate::frame::technique::deformation(
            self.host.model(),
            self.host.instances(),
            object,
            positions,
            normals,
        )?;
        let state = self.host.state();
        let receivers_moved = self
            .host
            .apply_instances(d.model, d.instances.clone(), d.update)?;
        let mut after = d.instances;
        let before = d.before;
        let change = Change::Instances { receivers_moved };
        self.follow(backend, change, state, move || {
            Ok(Some(InstanceUpdate::Deformed(
                after.deform_instance(object, before)?,
            )))
        })
    }

    /// Replaces object `object`'s shape for the next frames ([`Technique::set_object_shape`]):
    /// the scene is uploaded anew with only that object's BVH built (the others from the
    /// host's cache), and the technique made anew over it with its settings. On an error
    /// nothing changes.
    pub fn set_object_shape(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        shape: &crate::scene::Shape,
    ) -> Result<(), Error> {
        let model = crate::frame::technique::with_shape(self.host.model(), object, shape)?;
        self.host.check_all_submitted(
            "a new shape uploads the scene anew and frees the old one, so it",
        )?;
        let old = self.host.replace_scene(backend, &model)?;
        let mut old = Some(old);
        let settings = self.pipeline().settings().clone();
        let made = self.rebuild(backend, settings, |host, _| {
            if let Some(old) = old.take() {
                host.put_back_scene(old);
            }
            Ok(())
        });
        if let Some(old) = old {
            self.host.release_scene(old);
        }
        made
    }

    /// Replaces the materials' parameters for the next frames without rebuilding
    /// geometry ([`crate::frame::material_update`]). On an error nothing changes.
    pub fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        let state = self.host.state();
        let same_plan = self.host.set_materials(materials)?;
        self.follow(backend, Change::Materials { same_plan }, state, || Ok(None))
    }

    /// Replaces the settings for the next frames; the next frame equals, bitwise, that of
    /// a technique created with them. The uploaded scene stays (a triangle budget below
    /// the scene's is an error). On an error the technique keeps its old settings.
    pub fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: P::Settings,
    ) -> Result<(), Error> {
        P::validate(&settings)?;
        self.host
            .check_budget(P::host_options(&settings).max_triangles)?;
        if P::host_options(&settings).atlas_receivers && !self.host.options().atlas_receivers {
            return Err(Error::InvalidParameter(
                "these settings need the atlas receivers, which the scene was not uploaded \
                 with: create the technique again"
                    .into(),
            ));
        }
        // a refusal keeps the camera's images (the new settings' needs queued none that
        // runs) as well as the old settings
        let state = self.host.state();
        self.rebuild(backend, settings, |host, backend| {
            host.restore(backend, state, None)
        })
    }

    /// Sets the frame seed of the next frames.
    pub fn set_seed(&mut self, seed: u32) {
        self.parts().1.set_seed(seed);
    }

    /// Sets (or clears) the reference image of the filtered estimate: every later
    /// [`Hosted::frame`] puts its error against it in [`FrameStats::error`].
    pub fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        self.host.set_reference(reference)
    }

    /// Checks that `output` is one of the technique's and was requested.
    fn check_output(&self, output: Output) -> Result<(), Error> {
        let p = self.pipeline();
        if !p.own_outputs().contains(&output) {
            return Err(Error::NoSuchOutput {
                technique: p.name(),
                output,
                has: p.own_outputs().to_vec(),
            });
        }
        if !p.requested_outputs().has(output) {
            return Err(Error::OutputNotRequested { output });
        }
        Ok(())
    }

    /// Every output of the technique, requested or not, in [`Output::ALL`]'s order.
    pub fn outputs(&self) -> Vec<OutputInfo> {
        let p = self.pipeline();
        OutputInfo::list(p.own_outputs(), p.requested_outputs())
    }

    /// Reads `output` back ([`Technique::read_output`]).
    pub fn read_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error> {
        self.check_output(output)?;
        if output.camera_space() && self.host.screen_queued() {
            return Err(Error::InvalidParameter(format!(
                "output '{output}': the camera's images are made anew by the next frame \
                 (after a new image size or new settings); run a frame before reading them"
            )));
        }
        if output.camera_space() {
            let image = self.pipeline().output_image(&self.host, output);
            self.host.read_output_image(backend, image)
        } else {
            self.pipeline().read_data_output(backend, output)
        }
    }

    /// The device image of camera-space `output` ([`Technique::output_image`]).
    pub fn output_image(&self, output: Output) -> Result<Option<ImageBuf>, Error> {
        self.check_output(output)?;
        if !output.camera_space() {
            return Err(Error::InvalidParameter(format!(
                "output '{output}' is not camera-space: read it back with read_output"
            )));
        }
        Ok(self.pipeline().output_image(&self.host, output))
    }

    /// Releases every device buffer (the technique's and the host's).
    pub fn free(mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        if let Some(mut p) = self.pipeline.take() {
            p.free(backend)?;
        }
        self.host.free(backend)
    }
}

impl<P: Pipeline> Drop for Hosted<P> {
    fn drop(&mut self) {
        let (name, (buffers, bytes)) = match &self.pipeline {
            Some(p) => (p.name(), p.owned()),
            None => ("technique", (0, 0)),
        };
        crate::frame::technique::report_leak(
            name,
            buffers + self.host.buffer_count(),
            bytes + self.host.bytes(),
        );
    }
}

impl<P: Pipeline> Technique for Hosted<P> {
    fn name(&self) -> &'static str {
        self.pipeline().name()
    }

    fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error> {
        Hosted::frame(self, backend, progress)
    }

    fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error> {
        Hosted::record_frame(self, backend)
    }

    fn outputs(&self) -> Vec<OutputInfo> {
        Hosted::outputs(self)
    }

    fn read_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error> {
        Hosted::read_output(self, backend, output)
    }

    fn output_image(&self, output: Output) -> Result<Option<ImageBuf>, Error> {
        Hosted::output_image(self, output)
    }

    fn estimate_outputs(&self) -> (Output, Output) {
        self.pipeline().estimate_outputs()
    }

    fn settings_json(&self) -> serde_json::Value {
        self.pipeline().settings_json()
    }

    fn set_seed(&mut self, seed: u32) {
        Hosted::set_seed(self, seed)
    }

    fn set_camera(&mut self, backend: &mut dyn Backend, camera: &Camera) -> Result<(), Error> {
        Hosted::set_camera(self, backend, camera)
    }

    fn set_lights(&mut self, backend: &mut dyn Backend, lights: &[Light]) -> Result<(), Error> {
        Hosted::set_lights(self, backend, lights)
    }

    fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, Transform)],
    ) -> Result<(), Error> {
        Hosted::set_object_transforms(self, backend, moves)
    }

    fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error> {
        Hosted::set_object_vertices(self, backend, object, positions, normals)
    }

    fn set_object_shape(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        shape: &crate::scene::Shape,
    ) -> Result<(), Error> {
        Hosted::set_object_shape(self, backend, object, shape)
    }

    fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error> {
        Hosted::set_materials(self, backend, materials)
    }

    fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: &serde_json::Value,
    ) -> Result<(), Error> {
        let s = P::parse_settings(settings)?;
        Hosted::set_settings(self, backend, s)
    }

    fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        Hosted::set_reference(self, reference)
    }

    fn plan(&self) -> &FramePlan {
        self.pipeline().plan()
    }

    fn free(self: Box<Self>, backend: &mut dyn Backend) -> Result<(), Error> {
        Hosted::free(*self, backend)
    }
}

/// The registry's constructor for a pipeline: `settings` is a JSON object of its fields.
pub fn create<P: Pipeline + 'static>(
    backend: &mut dyn Backend,
    scene: &Scene,
    settings: &serde_json::Value,
) -> Result<Box<dyn Technique>, Error> {
    let s = P::parse_settings(settings)?;
    Ok(Box::new(Hosted::<P>::new(backend, scene, s)?))
}
