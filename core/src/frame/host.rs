//! The frame host: the world every technique renders, owned once (kajiya's world
//! renderer is the model). It holds the uploaded scene with its two-level acceleration
//! structure, the scene model it came from, the camera, the camera's own images
//! ([`crate::frame::screen`]: G-buffer, direct light, composite) and the scene writes of
//! the updates since the last frame; it applies every update (camera, lights, instance
//! moves and deformations, materials) the same way for every technique, and a technique
//! ([`crate::frame::pipeline`]) only re-plans its own passes over the result.
//!
//! The scene's upload, the camera images' creation and the scene writes of an update go
//! into [`FrameHost::take_pending`]'s recording, which the next frame runs first: nothing
//! runs before every buffer of the host and its technique has been checked against the
//! device, and an update costs the host its own arithmetic, never a submission or a wait
//! of its own (a light buffer of a new length is the exception: it is allocated at once).

use crate::backend::{read_buf, Backend};
use crate::device::bvh_cache::BvhCache;
use crate::device::caster_spheres::CasterSpheres;
use crate::device::device_scene::{
    gpu_light, BuildBudget, DeviceScene, InstanceUpdate, SceneInstances,
};
use crate::device::handle::{ImageBuf, ResourceId, SceneArgs};
use crate::device::layout::{material_kind, GpuCamera, GpuLight, GpuMaterial};
use crate::frame::allocation::planned_allocation;
use crate::frame::error::Error;
use crate::frame::image::Image;
use crate::frame::plan::{BufferPlan, FramePlan, SceneFeatures};
use crate::frame::receivers::atlas::layout::AtlasReceivers;
use crate::frame::screen::{ScreenNeeds, ScreenTargets};
use crate::frame::stats::FrameStats;
use crate::frame::submitted::FrameSequence;
use crate::math::geometry::Aabb;
use crate::recording::{Recording, Step};
use crate::scene::{Camera, Light, Scene};

/// What the host derives from the uploaded geometry, kept so that lights, cameras and
/// instance moves never need the flattened scene again. World space, scene units.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneGeometry {
    /// Bounds of every triangle.
    pub bounds: Aabb,
    /// Bounds of the caustic casters (mirrors and dielectrics).
    pub caster_bounds: Aabb,
    /// Balls around the casters that photons' first segments are tested against.
    pub caster_spheres: CasterSpheres,
    /// Some material disperses (a non-zero Cauchy B, or the Abbe model).
    pub has_dispersion: bool,
    /// Triangles the build dropped for zero area in f32.
    pub degenerate_triangles: u64,
    /// Triangles uploaded (what a `max_triangles` budget is checked against).
    pub triangles: u64,
    /// Bounding box of every caster object, with its scene object index, in object
    /// order (they follow moved instances).
    pub caster_boxes: Vec<(u32, Aabb)>,
}

/// What a technique asks the host to derive when it uploads the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct HostOptions {
    /// The triangle budget the scene is built under.
    pub max_triangles: u64,
    /// Keep the diffuse receivers' triangles for a caustic atlas
    /// ([`AtlasReceivers`]; only where the scene has casters and receivers).
    pub atlas_receivers: bool,
}

/// The state an update changed, kept to go back when the technique cannot follow it.
#[derive(Clone, Debug)]
pub struct HostState {
    model: Scene,
    geometry: SceneGeometry,
    instances: SceneInstances,
    receivers: Option<AtlasReceivers>,
    camera: GpuCamera,
    /// The camera's images, and where the pending writes stood (their length, and how
    /// many times they had been taken): an update whose writes have not run yet is undone
    /// by dropping them.
    screen: ScreenTargets,
    screen_queued: bool,
    pending_steps: usize,
    deferred_steps: usize,
    pending_taken: u64,
    /// The scene's buffers as they were (a new light count queues a new light buffer,
    /// which dropping the update's writes never makes).
    scene: SceneArgs,
    uploaded: Vec<ResourceId>,
    uploaded_bytes: u64,
    uploaded_buffers: Vec<BufferPlan>,
}

/// An uploaded scene: the model, its device buffers and what the host derived from it.
#[derive(Debug)]
pub struct SceneUpload {
    model: Scene,
    scene: SceneArgs,
    instances: SceneInstances,
    geometry: SceneGeometry,
    receivers: Option<AtlasReceivers>,
    uploaded: Vec<ResourceId>,
    uploaded_bytes: u64,
    uploaded_buffers: Vec<BufferPlan>,
}

impl SceneUpload {
    /// Builds `scene` (validated) under `options`, its BVHs through `cache`, and records
    /// its upload (every buffer checked against the device first).
    fn build(
        backend: &mut dyn Backend,
        scene: &Scene,
        options: HostOptions,
        cache: &mut BvhCache,
    ) -> Result<(SceneUpload, Recording), Error> {
        let ds = DeviceScene::build_cached(
            scene,
            BuildBudget {
                max_triangles: options.max_triangles,
            },
            cache,
        )?;
        let features = SceneFeatures::of(scene);
        let receiver = crate::frame::receivers::atlas::layout::atlas_receivers(scene);
        let receivers = (options.atlas_receivers
            && (features.mirrors || features.dielectrics)
            && receiver.iter().any(|r| *r))
        .then(|| AtlasReceivers::of(&ds, &receiver));
        let geometry = SceneGeometry {
            bounds: ds.bounds,
            caster_bounds: ds.caster_bounds,
            caster_spheres: ds.caster_spheres,
            has_dispersion: ds.has_dispersion,
            degenerate_triangles: ds.degenerate_triangles,
            triangles: ds.triangles.len() as u64,
            caster_boxes: caster_boxes(&ds),
        };
        let mut rec = Recording::new();
        let args = rec.upload_scene(&ds);
        let alloc = planned_allocation(backend, &rec, None)?;
        let up = SceneUpload {
            model: scene.clone(),
            scene: args,
            instances: ds.instances,
            geometry,
            receivers,
            uploaded: alloc.owned,
            uploaded_bytes: alloc.bytes,
            uploaded_buffers: alloc.buffers,
        };
        Ok((up, rec))
    }
}

/// The frame host of one technique on one backend.
#[derive(Debug)]
pub struct FrameHost {
    model: Scene,
    scene: SceneArgs,
    instances: SceneInstances,
    geometry: SceneGeometry,
    receivers: Option<AtlasReceivers>,
    camera: GpuCamera,
    options: HostOptions,
    /// The uploaded scene's buffers, their bytes and plan entries.
    uploaded: Vec<ResourceId>,
    uploaded_bytes: u64,
    uploaded_buffers: Vec<BufferPlan>,
    /// The uploaded scene's BVHs, kept for [`FrameHost::replace_scene`].
    bvh_cache: BvhCache,
    screen: ScreenTargets,
    pending: Recording,
    /// How many times the pending writes were taken (into a frame, or flushed).
    pending_taken: u64,
    /// The camera's images are made by the pending writes (a new size or new needs):
    /// they exist on the device once the next frame (which takes the writes) runs.
    screen_queued: bool,
    /// Some recording of this host has run (else freeing it runs nothing).
    on_device: bool,
    reference: Option<Image>,
    /// The technique's frames: recorded, run and submitted.
    sequence: FrameSequence,
    /// The technique's own work for the next frame ([`FrameHost::defer`]), run after
    /// `pending`: it targets the technique's buffers and goes when it is made anew.
    deferred: Recording,
}

/// The bounding box of every caster object (mirror or dielectric) of `ds`, from its
/// triangles, with its object index, in object order.
pub fn caster_boxes(ds: &DeviceScene) -> Vec<(u32, Aabb)> {
    let mut boxes: std::collections::BTreeMap<u32, Aabb> = Default::default();
    for (t, obj) in ds.triangles.iter().zip(&ds.triangle_objects) {
        if ds.materials[t.material as usize].kind == material_kind::DIFFUSE {
            continue;
        }
        let b = boxes.entry(*obj).or_insert(Aabb::EMPTY);
        for i in t.indices {
            b.grow(glam::Vec3::from(ds.vertices[i as usize].position));
        }
    }
    boxes.into_iter().collect()
}

/// The caster boxes after instances moved: an instance caster's box is its level's
/// `triangle_bounds` (the same vertices [`caster_boxes`] grows over, so the same box as a
/// fresh build's); the static level's casters keep theirs.
pub fn follow_moved_casters(
    boxes: &mut [(u32, Aabb)],
    levels: &[crate::device::acceleration::Level],
) {
    for (object, b) in boxes {
        if let Some(l) = levels.iter().find(|l| l.object == Some(*object as usize)) {
            *b = l.triangle_bounds;
        }
    }
}

/// `scene`'s validation, as an error that names the first offending path.
pub fn validated(scene: &Scene) -> Result<(), Error> {
    scene
        .validate()
        .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))
}

impl FrameHost {
    /// Validates `scene`, builds its device scene under the budget and records its upload
    /// (every buffer checked against the device first; it runs with the first frame, or
    /// at [`FrameHost::flush`]). No camera image exists yet: the technique asks for them
    /// ([`FrameHost::make_screen`]).
    pub fn upload(
        backend: &mut dyn Backend,
        scene: &Scene,
        options: HostOptions,
    ) -> Result<FrameHost, Error> {
        validated(scene)?;
        let mut bvh_cache = BvhCache::default();
        let (up, rec) = SceneUpload::build(backend, scene, options, &mut bvh_cache)?;
        Ok(FrameHost {
            model: up.model,
            scene: up.scene,
            instances: up.instances,
            geometry: up.geometry,
            receivers: up.receivers,
            camera: GpuCamera::from_camera(&scene.camera),
            options,
            uploaded: up.uploaded,
            uploaded_bytes: up.uploaded_bytes,
            uploaded_buffers: up.uploaded_buffers,
            bvh_cache,
            screen: ScreenTargets::none(),
            pending: rec,
            pending_taken: 0,
            screen_queued: false,
            on_device: false,
            reference: None,
            sequence: FrameSequence::default(),
            deferred: Recording::new(),
        })
    }

    /// Uploads `model` anew in place of the scene (the camera, its images and the
    /// reference stay): the scene is built with the BVHs of every level whose geometry is
    /// unchanged taken from the host's cache ([`DeviceScene::build_cached`]), so a scene
    /// with one object's shape replaced builds that object's BVH alone. The new buffers'
    /// upload goes with the next frame; the old ones are returned, still allocated, to be
    /// freed ([`FrameHost::release_scene`]) once the technique is made over the new scene,
    /// or put back ([`FrameHost::put_back_scene`]). On an error nothing changes.
    pub fn replace_scene(
        &mut self,
        backend: &mut dyn Backend,
        model: &Scene,
    ) -> Result<SceneUpload, Error> {
        validated(model)?;
        let (mut up, rec) = SceneUpload::build(backend, model, self.options, &mut self.bvh_cache)?;
        self.pending.steps.extend(rec.steps);
        self.swap_scene(&mut up);
        Ok(up)
    }

    /// Frees a scene [`FrameHost::replace_scene`] replaced, after the frames' work that
    /// still reads it (the pending writes run first).
    pub fn release_scene(&mut self, old: SceneUpload) {
        for id in old.uploaded {
            self.pending.steps.push(Step::Free { id });
        }
    }

    /// Puts back the scene [`FrameHost::replace_scene`] replaced, freeing the new one.
    pub fn put_back_scene(&mut self, mut old: SceneUpload) {
        self.swap_scene(&mut old);
        self.release_scene(old);
    }

    /// Exchanges the host's scene with `other`.
    fn swap_scene(&mut self, other: &mut SceneUpload) {
        std::mem::swap(&mut self.model, &mut other.model);
        std::mem::swap(&mut self.scene, &mut other.scene);
        std::mem::swap(&mut self.instances, &mut other.instances);
        std::mem::swap(&mut self.geometry, &mut other.geometry);
        std::mem::swap(&mut self.receivers, &mut other.receivers);
        std::mem::swap(&mut self.uploaded, &mut other.uploaded);
        std::mem::swap(&mut self.uploaded_bytes, &mut other.uploaded_bytes);
        std::mem::swap(&mut self.uploaded_buffers, &mut other.uploaded_buffers);
    }

    /// BVHs built and taken from the host's cache since the host was made (uploads,
    /// [`FrameHost::replace_scene`]).
    pub fn bvh_builds(&self) -> (u64, u64) {
        (self.bvh_cache.built, self.bvh_cache.reused)
    }

    /// The scene model as it is now (after every update).
    pub fn model(&self) -> &Scene {
        &self.model
    }

    /// The uploaded scene's buffers, as kernels bind them.
    pub fn scene(&self) -> SceneArgs {
        self.scene
    }

    /// What the host derived from the geometry (bounds, casters).
    pub fn geometry(&self) -> &SceneGeometry {
        &self.geometry
    }

    /// The diffuse receivers' triangles, when the technique asked for them and the scene
    /// has casters and receivers.
    pub fn receivers(&self) -> Option<&AtlasReceivers> {
        self.receivers.as_ref()
    }

    /// The acceleration structure's levels.
    pub fn instances(&self) -> &SceneInstances {
        &self.instances
    }

    /// The camera as the kernels read it.
    pub fn camera(&self) -> GpuCamera {
        self.camera
    }

    /// The number of lights.
    pub fn light_count(&self) -> u32 {
        self.model.lights.len() as u32
    }

    /// The options the scene was uploaded with.
    pub fn options(&self) -> HostOptions {
        self.options
    }

    /// The camera's images.
    pub fn screen(&self) -> &ScreenTargets {
        &self.screen
    }

    /// Bytes of the uploaded scene and the camera's images.
    pub fn bytes(&self) -> u64 {
        self.uploaded_bytes + self.screen.bytes
    }

    /// Device buffers the host owns.
    pub fn buffer_count(&self) -> usize {
        self.uploaded.len() + self.screen.owned.len()
    }

    /// The plan entries of the uploaded scene and the camera's images.
    pub fn buffer_plans(&self) -> Vec<BufferPlan> {
        self.uploaded_buffers
            .iter()
            .chain(&self.screen.buffers)
            .cloned()
            .collect()
    }

    /// Appends a technique's own writes of an update (an atlas laid out anew) to the
    /// scene writes the next frame runs first.
    pub fn defer(&mut self, rec: Recording) {
        self.deferred.steps.extend(rec.steps);
    }

    /// Drops the technique's deferred work ([`FrameHost::defer`]): the technique that
    /// recorded it is gone, and with it the buffers the work would write.
    pub(crate) fn drop_deferred(&mut self) {
        self.deferred.steps.clear();
    }

    /// The technique's frames: how many it recorded or ran, which were submitted.
    pub(crate) fn sequence(&mut self) -> &mut FrameSequence {
        &mut self.sequence
    }

    /// Whether every frame before the one being recorded was submitted
    /// ([`FrameSequence::earlier_frames_submitted`]).
    pub(crate) fn earlier_frames_submitted(&self) -> bool {
        self.sequence.earlier_frames_submitted()
    }

    /// An error when a recorded frame waits to be submitted, for an update (`what`) that
    /// would run on the device at once ([`FrameSequence::check_all_submitted`]).
    pub(crate) fn check_all_submitted(&self, what: &str) -> Result<(), Error> {
        self.sequence.check_all_submitted(what)
    }

    /// The scene writes of the updates since the last frame, then the technique's
    /// deferred work (the frame runs them first).
    pub fn take_pending(&mut self) -> Recording {
        self.on_device = true;
        self.pending_taken += 1;
        self.screen_queued = false;
        let mut pending = std::mem::take(&mut self.pending);
        pending.steps.append(&mut self.deferred.steps);
        pending
    }

    /// Runs the pending scene writes now (a technique whose update reads the device,
    /// such as PhotonGi's RSM probe, needs the scene as it is after the update). Refused
    /// while a recorded frame waits to be submitted: its own updates must run first.
    pub fn flush(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        self.sequence
            .check_all_submitted("this update reads the device, so the updates before it")?;
        let pending = self.take_pending();
        if !pending.steps.is_empty() {
            backend.execute(&pending)?;
        }
        Ok(())
    }

    /// Makes the camera's images `needs` asks for at the camera's size (checked against
    /// the device now, created with the pending writes; the old ones are freed after
    /// them; nothing changes on an error). Images already made for `needs` at this size
    /// stay.
    pub fn make_screen(
        &mut self,
        backend: &mut dyn Backend,
        needs: ScreenNeeds,
    ) -> Result<(), Error> {
        let size = (self.camera.width, self.camera.height);
        if self.screen.needs == needs && self.screen.size == size && needs != ScreenNeeds::NONE {
            return Ok(());
        }
        let mut rec = Recording::new();
        let targets = ScreenTargets::create(backend, &mut rec, self.camera, needs)?;
        for id in &self.screen.owned {
            rec.steps.push(Step::Free { id: *id });
        }
        self.pending.steps.extend(rec.steps);
        self.screen = targets;
        self.screen_queued = true;
        Ok(())
    }

    /// Whether the camera's images are still to be made by the next frame (after a new
    /// image size or new settings): reading them before it is an error that says so.
    pub fn screen_queued(&self) -> bool {
        self.screen_queued
    }

    /// Records the G-buffer and the direct light, as the camera's images were made.
    pub fn record_visibility(&self, rec: &mut Recording) {
        self.screen
            .record_visibility(rec, self.scene, self.camera, self.light_count());
    }

    /// Records the composite of the direct light and `light`.
    pub fn record_composite(&self, rec: &mut Recording, light: ImageBuf) {
        self.screen.record_composite(rec, light);
    }

    /// Reads a camera-space image back (the camera's size).
    pub fn read_image(&self, backend: &mut dyn Backend, image: ImageBuf) -> Result<Image, Error> {
        let px = read_buf(backend, image)?;
        Ok(Image::new(self.camera.width, self.camera.height, px))
    }

    /// A black image of the camera's size (an output the plan knows to be zero).
    pub fn black_image(&self) -> Image {
        let (w, h) = (self.camera.width, self.camera.height);
        Image::new(w, h, vec![[0.0; 4]; w as usize * h as usize])
    }

    /// Reads a camera-space output back: its device image, or black where it has none
    /// (the plan knows it is zero).
    pub fn read_output_image(
        &self,
        backend: &mut dyn Backend,
        image: Option<ImageBuf>,
    ) -> Result<Image, Error> {
        match image {
            Some(i) => self.read_image(backend, i),
            None => Ok(self.black_image()),
        }
    }

    /// A frame's statistics before anything runs: the technique, backend and device,
    /// the frame size and timing source, the plan with every skipped pass, the bytes of
    /// every buffer (`own_bytes`: the technique's) and the scene's degenerate triangles.
    pub fn frame_stats(
        &self,
        backend: &dyn Backend,
        technique: &str,
        plan: &FramePlan,
        own_bytes: u64,
    ) -> FrameStats {
        let caps = backend.capabilities();
        let mut stats = FrameStats {
            technique: technique.into(),
            backend: backend.name().into(),
            device: caps.device.clone(),
            width: self.camera.width,
            height: self.camera.height,
            timing: if caps.timestamps {
                "device timestamps".into()
            } else {
                "host wall clock".into()
            },
            bytes_allocated: self.bytes() + own_bytes,
            degenerate_triangles: self.geometry.degenerate_triangles,
            plan: Some(plan.clone()),
            ..Default::default()
        };
        for p in plan.passes.iter().filter(|p| !p.runs) {
            stats.skip(&p.name, p.reason.clone());
        }
        stats
    }

    /// The reference image of the technique's filtered estimate, if set.
    pub fn reference(&self) -> Option<&Image> {
        self.reference.as_ref()
    }

    /// Drops the reference image (the camera's image size changed).
    pub(crate) fn drop_reference(&mut self) {
        self.reference = None;
    }

    /// Sets (or clears) the reference image (linear radiance, the camera's size, every
    /// channel finite and >= 0).
    pub fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error> {
        if let Some(r) = &reference {
            let bad = |why: String| Err(Error::InvalidParameter(format!("reference: {why}")));
            if (r.width, r.height) != (self.camera.width, self.camera.height) {
                return bad(format!(
                    "{}x{}, the frame {}x{}",
                    r.width, r.height, self.camera.width, self.camera.height
                ));
            }
            if r.pixels.len() as u64 != r.width as u64 * r.height as u64 {
                return bad(format!(
                    "{} pixels for {}x{}",
                    r.pixels.len(),
                    r.width,
                    r.height
                ));
            }
            if let Some(k) = r
                .pixels
                .iter()
                .position(|p| !p[..3].iter().all(|c| *c >= 0.0 && c.is_finite()))
            {
                return bad(format!(
                    "pixel {k} is {:?}: a reference is linear radiance, finite and >= 0",
                    r.pixels[k]
                ));
            }
        }
        self.reference = reference;
        Ok(())
    }

    /// What an update may change, to go back to.
    pub fn state(&self) -> HostState {
        HostState {
            model: self.model.clone(),
            geometry: self.geometry.clone(),
            instances: self.instances.clone(),
            receivers: self.receivers.clone(),
            camera: self.camera,
            screen: self.screen.clone(),
            screen_queued: self.screen_queued,
            pending_steps: self.pending.steps.len(),
            deferred_steps: self.deferred.steps.len(),
            pending_taken: self.pending_taken,
            scene: self.scene,
            uploaded: self.uploaded.clone(),
            uploaded_bytes: self.uploaded_bytes,
            uploaded_buffers: self.uploaded_buffers.clone(),
        }
    }

    /// Moves the camera (validated). Returns whether the image size changed; then the
    /// camera's images are made anew (on an error nothing changes); the caller drops the
    /// reference image once the technique follows ([`FrameHost::drop_reference`]).
    pub fn set_camera(
        &mut self,
        backend: &mut dyn Backend,
        camera: &Camera,
    ) -> Result<bool, Error> {
        let model = crate::frame::technique::with_camera(&self.model, camera)?;
        let new = GpuCamera::from_camera(camera);
        let resized = (new.width, new.height) != (self.camera.width, self.camera.height);
        let old = self.camera;
        self.camera = new;
        if resized {
            if let Err(e) = self.make_screen(backend, self.screen.needs) {
                self.camera = old;
                return Err(e);
            }
        }
        self.model = model;
        Ok(resized)
    }

    /// The camera of `state` back, with images of its size.
    fn restore_camera(
        &mut self,
        backend: &mut dyn Backend,
        state: &HostState,
    ) -> Result<(), Error> {
        if (state.camera.width, state.camera.height) != (self.camera.width, self.camera.height) {
            self.camera = state.camera;
            self.make_screen(backend, self.screen.needs)?;
        }
        self.camera = state.camera;
        Ok(())
    }

    /// Replaces the lights (validated): written in place with the next frame when their
    /// number stays, else a light buffer of the new length replaces the old one with the
    /// next frame (checked against the device now).
    pub fn set_lights(&mut self, backend: &mut dyn Backend, lights: &[Light]) -> Result<(), Error> {
        let model = crate::frame::technique::with_lights(&self.model, lights)?;
        self.write_lights(backend, lights)?;
        self.model = model;
        Ok(())
    }

    /// Writes `lights` into the light buffer (a new one when the length changes).
    fn write_lights(&mut self, backend: &mut dyn Backend, lights: &[Light]) -> Result<(), Error> {
        let gpu: Vec<GpuLight> = lights.iter().map(gpu_light).collect();
        if gpu.len() as u32 == self.scene.lights.len {
            self.pending.write(self.scene.lights, 0, &gpu, "lights")?;
            return Ok(());
        }
        // made with the next frame's writes, after earlier updates' writes into the old
        // buffer (which a recorded frame not yet submitted may still use), then freed
        let old = self.scene.lights;
        let mut rec = Recording::new();
        let new = rec.upload(&gpu, "lights");
        let alloc = planned_allocation(backend, &rec, None)?;
        rec.steps.push(Step::Free { id: old.id });
        self.pending.steps.extend(rec.steps);
        self.scene.lights = new;
        for id in &mut self.uploaded {
            if *id == old.id {
                *id = new.id;
            }
        }
        let old_bytes = old.len as u64 * std::mem::size_of::<GpuLight>() as u64;
        self.uploaded_bytes = self.uploaded_bytes - old_bytes + alloc.bytes;
        for b in &mut self.uploaded_buffers {
            if b.name == "lights" {
                b.bytes = alloc.bytes;
            }
        }
        Ok(())
    }

    /// Applies an instance update already made to `instances` (a copy of the host's) for
    /// `model`, the scene after it: its writes go with the next frame, and the geometry
    /// (bounds, caster balls and boxes, receivers' triangles) follows; the device places
    /// the moved instances' vertices. Returns whether a receiver of the
    /// atlas moved. On an error (checked first) nothing changes.
    pub fn apply_instances(
        &mut self,
        model: Scene,
        instances: SceneInstances,
        u: InstanceUpdate,
    ) -> Result<bool, Error> {
        Recording::check_instance_update(&u, &self.scene)?;
        let m = u.moved();
        let mut receivers_moved = false;
        if let Some(r) = self.receivers.as_mut() {
            if let InstanceUpdate::Deformed(d) = &u {
                // the deformed level's triangles in their new order
                r.reorder_triangles(d.triangles.0, &d.triangles.1);
            }
            // the device places every moved instance; the host places the receivers'
            // again, for their corners and areas
            let receiver = |l: &&crate::device::acceleration::Level| {
                l.object.is_some_and(|o| r.objects.contains(&(o as u32)))
            };
            let runs: Vec<(u32, Vec<crate::device::layout::GpuVertex>)> = instances
                .levels
                .iter()
                .filter(receiver)
                .filter_map(|l| m.placements.iter().find(|p| p.world_first == l.vertex_base))
                .map(|p| (p.world_first, instances.placed(p)))
                .collect();
            receivers_moved = r.move_vertices(&runs);
        }
        follow_moved_casters(&mut self.geometry.caster_boxes, &instances.levels);
        self.geometry.bounds = m.bounds;
        self.geometry.caster_bounds = m.caster_bounds;
        self.geometry.caster_spheres = m.caster_spheres;
        // the device places the moved instances (place_vertices) with the next frame
        self.pending.update_instances(u, &self.scene)?;
        self.instances = instances;
        self.model = model;
        Ok(receivers_moved)
    }

    /// Writes new material parameters (checked: [`crate::frame::material_update`]) with
    /// the next frame. Returns whether the scene's features and dispersion stayed.
    pub fn set_materials(
        &mut self,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<bool, Error> {
        let u = crate::frame::material_update::material_update(&self.model, materials)?;
        self.pending
            .update(self.scene.materials, &u.gpu, "materials")?;
        self.geometry.has_dispersion = u.has_dispersion;
        self.model = u.model;
        Ok(u.same_plan)
    }

    /// Goes back to `state` after an update the technique could not follow: the model,
    /// the geometry and the instances, with the device's lights, materials and instances
    /// written back (`undo`: the instance update back to `state`'s, where instances moved).
    pub fn restore(
        &mut self,
        backend: &mut dyn Backend,
        state: HostState,
        undo: Option<InstanceUpdate>,
    ) -> Result<(), Error> {
        if self.pending_taken == state.pending_taken
            && self.pending.steps.len() >= state.pending_steps
        {
            // none of the update's writes has run: dropped, the camera's images of
            // `state` (whose freeing was among them) are still the device's; the writes
            // below then put back values the device still holds
            self.pending.steps.truncate(state.pending_steps);
            self.deferred.steps.truncate(state.deferred_steps);
            self.screen = state.screen.clone();
            self.screen_queued = state.screen_queued;
            self.scene = state.scene;
            self.uploaded = state.uploaded.clone();
            self.uploaded_bytes = state.uploaded_bytes;
            self.uploaded_buffers = state.uploaded_buffers.clone();
        }
        if let Some(u) = undo {
            self.pending.update_instances(u, &self.scene)?;
        }
        if state.model.lights != self.model.lights {
            self.write_lights(backend, &state.model.lights)?;
        }
        if state.model.materials != self.model.materials {
            let gpu: Vec<GpuMaterial> = state
                .model
                .materials
                .values()
                .map(crate::device::device_scene::gpu_material)
                .collect();
            self.pending
                .update(self.scene.materials, &gpu, "materials")?;
        }
        self.restore_camera(backend, &state)?;
        self.model = state.model;
        self.geometry = state.geometry;
        self.instances = state.instances;
        self.receivers = state.receivers;
        Ok(())
    }

    /// Checks a new triangle budget against the uploaded scene.
    pub fn check_budget(&self, max_triangles: u64) -> Result<(), Error> {
        if self.geometry.triangles > max_triangles {
            return Err(Error::InvalidParameter(format!(
                "max_triangles {max_triangles} is below the scene's {} triangles: create the \
                 technique again",
                self.geometry.triangles
            )));
        }
        Ok(())
    }

    /// Releases every device buffer of the host (after the pending writes, which may
    /// create some; nothing runs when nothing of the host ever ran).
    pub fn free(&mut self, backend: &mut dyn Backend) -> Result<(), Error> {
        let mut rec = std::mem::take(&mut self.pending);
        for id in std::mem::take(&mut self.uploaded)
            .into_iter()
            .chain(std::mem::take(&mut self.screen.owned))
        {
            rec.steps.push(Step::Free { id });
        }
        self.uploaded_bytes = 0;
        self.screen = ScreenTargets::none();
        if self.on_device {
            backend.execute(&rec)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use crate::device::device_scene::DeviceScene;
    use crate::scene::builtin::builtin;
    use crate::scene::{Shape, Transform};
    use glam::{Quat, Vec3};

    /// A moved instance caster's box is its level's triangle bounds, the box a fresh
    /// build of the moved scene gives it ([`super::follow_moved_casters`]).
    #[test]
    fn caster_boxes_follow_moved_instances() {
        let mut s = builtin("cornell").unwrap();
        for o in s.objects.iter_mut().filter(|o| o.name.ends_with("ball")) {
            if let Shape::Sphere { center, .. } = &mut o.shape {
                let c = std::mem::replace(center, Vec3::ZERO);
                o.transform = Some(Transform::from_translation(c));
            }
        }
        let ds = DeviceScene::build(&s, Default::default()).unwrap();
        let mut boxes = super::caster_boxes(&ds);
        let mut instances = ds.instances.clone();
        let to = Transform {
            translation: Vec3::new(0.1, 0.5, 0.2),
            rotation: Quat::from_rotation_x(0.3),
            scale: Vec3::splat(0.7),
        };
        instances.move_instances(&[(5, to)]).unwrap();
        super::follow_moved_casters(&mut boxes, &instances.levels);
        s.objects[5].transform = Some(to);
        let fresh = DeviceScene::build(&s, Default::default()).unwrap();
        assert_eq!(boxes, super::caster_boxes(&fresh));
    }
}
