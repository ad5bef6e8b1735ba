//! The seam every technique implements, so that the library, the CLI, `report`,
//! references, benches and conformance create and drive any technique the same way
//! (by name through [`crate::techniques::create`]), without naming its type.

use crate::backend::Backend;
use crate::frame::error::Error;
use crate::frame::image::Image;
pub use crate::frame::output::{Output, OutputInfo, Outputs};
use crate::frame::plan::FramePlan;
use crate::frame::stats::FrameStats;
pub use crate::frame::stats::Progress;
use crate::frame::submitted::{FrameTicket, RecordedFrame};
use crate::scene::{Camera, Light};
use std::sync::atomic::{AtomicU64, Ordering};

/// A technique on one backend, for one scene: created by [`crate::techniques::create`]
/// (or its own typed `new`), it owns its device buffers until [`Technique::free`].
pub trait Technique {
    /// Registry name (`sspm`, ...).
    fn name(&self) -> &'static str;

    /// Renders one frame: the planned passes, nothing else. `progress` is called after
    /// every photon batch.
    fn frame(
        &mut self,
        backend: &mut dyn Backend,
        progress: &mut dyn FnMut(Progress),
    ) -> Result<FrameStats, Error>;

    /// Records a frame for a host's frame loop: submit it with
    /// [`RecordedFrame::submit`] (one submission, no wait) or encode it into the host's
    /// own command stream, and collect its statistics a frame or more later with
    /// [`crate::frame::submitted::FrameTicket::stats`]. The images are those
    /// [`Technique::frame`] would make, bitwise. Nothing here waits on the device: what
    /// depends on data the device computes stays on the device (AdaptiveCaustics'
    /// traversal) or is read back a frame later (CausticMap's reach mask);
    /// [`FrameStats::host_waits`] counts any wait, and is 0 for every technique.
    fn record_frame(&mut self, backend: &mut dyn Backend) -> Result<RecordedFrame, Error>;

    /// Records one frame and submits it without waiting ([`Technique::record_frame`],
    /// then [`RecordedFrame::submit`]).
    fn submit_frame(&mut self, backend: &mut dyn Backend) -> Result<FrameTicket, Error> {
        self.record_frame(backend)?.submit(backend)
    }

    /// Every output of the technique, requested or not, in [`Output::ALL`]'s order.
    fn outputs(&self) -> Vec<OutputInfo>;

    /// Reads `output` back: linear radiance of the camera's size for camera-space
    /// outputs ([`Output::camera_space`]), the caustic atlas's irradiance per texel
    /// otherwise; zeros where the plan knows the output is zero. An output the technique
    /// does not have is [`Error::NoSuchOutput`], one that was not requested
    /// [`Error::OutputNotRequested`].
    fn read_output(&self, backend: &mut dyn Backend, output: Output) -> Result<Image, Error>;

    /// The device image of camera-space `output`, for a host that uses it on the device
    /// (a composite, a copy into its own texture): `width x height` texels of linear
    /// radiance (`[r, g, b, 1]`, W/(sr m^2)), row-major from the camera's top-left pixel.
    /// It holds the last recorded frame once that frame has run, and stays valid until
    /// the next update that resizes the frame (`set_camera` with a new size,
    /// `set_settings`). `None`: the plan knows the output is zero (it has no image). An
    /// output the technique lacks, one not requested, or one that is not camera-space is
    /// an error.
    fn output_image(
        &self,
        output: Output,
    ) -> Result<Option<crate::device::handle::ImageBuf>, Error>;

    /// The technique's estimate after its filter and its unfiltered estimate: what
    /// error-against-time measurements compare with a reference.
    fn estimate_outputs(&self) -> (Output, Output);

    /// The settings in effect (serialised form, as `create` accepts them).
    fn settings_json(&self) -> serde_json::Value;

    /// Sets the frame seed of the next frames (progressive rendering, repeated runs).
    fn set_seed(&mut self, seed: u32);

    /// Moves the camera for the next frames; a new image size remakes only what depends on
    /// it (the frame's images and per-pixel buffers), never the uploaded scene.
    fn set_camera(&mut self, backend: &mut dyn Backend, camera: &Camera) -> Result<(), Error>;

    /// Replaces the scene's lights for the next frames (moved, re-powered, added or
    /// removed), without rebuilding geometry.
    fn set_lights(&mut self, backend: &mut dyn Backend, lights: &[Light]) -> Result<(), Error>;

    /// Moves instances for the next frames (`(object index, transform)` pairs; each object
    /// must have had a transform in the scene the technique was built from, see
    /// [`crate::scene::Object::transform`]): their world vertices and the top level of the
    /// acceleration structure are rewritten, no BVH is rebuilt, and the next frame equals
    /// that of a technique created for the moved scene, bitwise. An error leaves the
    /// technique as it was.
    fn set_object_transforms(
        &mut self,
        backend: &mut dyn Backend,
        moves: &[(usize, crate::scene::Transform)],
    ) -> Result<(), Error>;
    /// Deforms an instance for the next frames: `positions` (object space) and `normals`
    /// (empty: generated as the area-weighted face average) are the new vertices of object
    /// `object`'s tessellated mesh, the same count, the same triangles (its shape becomes
    /// that mesh). Only that object's bottom-level BVH is rebuilt, in place; the next
    /// frame equals that of a technique created for the deformed scene, bitwise. The
    /// object must have had a transform in the scene the technique was built from (an
    /// instance; identity will do). An error leaves the technique as it was.
    fn set_object_vertices(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        positions: &[glam::Vec3],
        normals: &[glam::Vec3],
    ) -> Result<(), Error>;
    /// Replaces object `object`'s shape for the next frames: any shape, any triangle count
    /// (a mesh whose topology changed). Only that object's bottom-level BVH is built; the
    /// other levels' are taken from the host's cache of the uploaded scene's BVHs. The
    /// scene's buffers are uploaded anew with the next frame (the old ones freed after
    /// it) and the technique's own buffers made anew for the new scene, as
    /// `set_settings` makes them; the next frame equals that of a technique created for
    /// the changed scene, bitwise. Costs one BVH build, the scene's flattening and upload
    /// and the technique's creation (Vulkan also builds its driver's acceleration
    /// structures for the new buffers). A deformation that keeps the mesh's triangles is
    /// cheaper: `set_object_vertices`. An error leaves the technique as it was.
    fn set_object_shape(
        &mut self,
        backend: &mut dyn Backend,
        object: usize,
        shape: &crate::scene::Shape,
    ) -> Result<(), Error>;
    /// Replaces the materials' parameters for the next frames without rebuilding geometry
    /// (the same names, none switching between diffuse and specular:
    /// [`crate::frame::material_update`]); an error leaves the technique as it was.
    fn set_materials(
        &mut self,
        backend: &mut dyn Backend,
        materials: &std::collections::BTreeMap<String, crate::scene::Material>,
    ) -> Result<(), Error>;

    /// Replaces the technique's settings for the next frames (`settings`: a JSON object
    /// as [`crate::techniques::create`] takes it, laid over the technique's defaults, not
    /// its current settings: missing fields take their defaults); the next frame equals,
    /// bitwise, that of a technique created with them. The uploaded scene always stays:
    /// Sspm and PhotonGi remake their frame buffers, CausticMap and AdaptiveCaustics'
    /// atlas target their atlas and images; AdaptiveCaustics' screen target may change
    /// its screen settings only. A `max_triangles` below the scene's triangle count and
    /// settings that need the atlas receivers the scene was uploaded without are errors
    /// (create the technique again), as is a call while a recorded frame
    /// ([`Technique::record_frame`]) is not yet submitted. An error leaves the technique
    /// as it was.
    fn set_settings(
        &mut self,
        backend: &mut dyn Backend,
        settings: &serde_json::Value,
    ) -> Result<(), Error>;

    /// Sets (or clears) the reference image of the filtered estimate: every later frame
    /// puts its error against it in [`FrameStats::error`].
    fn set_reference(&mut self, reference: Option<Image>) -> Result<(), Error>;

    /// The frame plan: passes run and skipped with reasons, lights, variants, buffers.
    fn plan(&self) -> &FramePlan;

    /// Releases every device buffer of the technique.
    fn free(self: Box<Self>, backend: &mut dyn Backend) -> Result<(), Error>;
}

static LEAKED_BUFFERS: AtomicU64 = AtomicU64::new(0);

/// Device buffers of techniques dropped without `free`, in this process. A technique
/// does not hold its backend, so it cannot free on `Drop`; it reports instead.
pub fn leaked_buffers() -> u64 {
    LEAKED_BUFFERS.load(Ordering::Relaxed)
}

/// `model` checked after a change that leaves every shape as it was (validated when the
/// technique was made): [`crate::scene::Scene::validate_except_shapes`], whose time does
/// not grow with the meshes.
fn validated_update(model: crate::scene::Scene) -> Result<crate::scene::Scene, Error> {
    model
        .validate_except_shapes()
        .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
    Ok(model)
}

/// `model` with object `object`'s shape replaced by `shape`, validated (the whole scene:
/// the new shape's tessellation too): what `set_object_shape` checks first.
pub fn with_shape(
    model: &crate::scene::Scene,
    object: usize,
    shape: &crate::scene::Shape,
) -> Result<crate::scene::Scene, Error> {
    let count = model.objects.len();
    let mut model = model.clone();
    let o = model.objects.get_mut(object).ok_or_else(|| {
        Error::InvalidParameter(format!(
            "set_object_shape: object {object} does not exist (the scene has {count})"
        ))
    })?;
    o.shape = shape.clone();
    model
        .validate()
        .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
    Ok(model)
}

/// `model` with its camera replaced by `camera`, validated: what every technique's
/// `set_camera` checks before it changes anything.
pub fn with_camera(
    model: &crate::scene::Scene,
    camera: &Camera,
) -> Result<crate::scene::Scene, Error> {
    let mut model = model.clone();
    model.camera = camera.clone();
    validated_update(model)
}

/// `model` with its lights replaced by `lights`, validated: what every technique's
/// `set_lights` checks before it changes anything.
pub fn with_lights(
    model: &crate::scene::Scene,
    lights: &[Light],
) -> Result<crate::scene::Scene, Error> {
    let mut model = model.clone();
    model.lights = lights.to_vec();
    validated_update(model)
}

/// `model` with the objects in `moves` given their new transforms, validated: what every
/// technique's `set_object_transforms` checks before it changes anything.
pub fn with_transforms(
    model: &crate::scene::Scene,
    moves: &[(usize, crate::scene::Transform)],
) -> Result<crate::scene::Scene, Error> {
    let mut model = model.clone();
    for (k, t) in moves {
        let count = model.objects.len();
        let o = model.objects.get_mut(*k).ok_or_else(|| {
            Error::InvalidParameter(format!(
                "set_object_transforms: object {k} does not exist (the scene has {count})"
            ))
        })?;
        o.transform = Some(*t);
    }
    validated_update(model)
}

/// `model` with object `object` deformed to `positions` and `normals` (see
/// [`Technique::set_object_vertices`]), validated, and the object's new and old
/// object-space vertices as the device holds them: what every technique checks before
/// it changes anything. Refused: an unknown object, one without a transform, another vertex count,
/// and a deformation that makes a triangle degenerate in f32 or a degenerate one proper
/// (a fresh build would keep another set of triangles).
pub fn with_deformed_object(
    model: &crate::scene::Scene,
    object: usize,
    positions: &[glam::Vec3],
    normals: &[glam::Vec3],
) -> Result<
    (
        crate::scene::Scene,
        Vec<crate::device::layout::GpuVertex>,
        Vec<crate::device::layout::GpuVertex>,
    ),
    Error,
> {
    use crate::scene::limits::is_degenerate;
    use crate::scene::shapes::tessellate;
    let bad = |why: String| Error::InvalidParameter(format!("set_object_vertices: {why}"));
    let count = model.objects.len();
    let o = model.objects.get(object).ok_or_else(|| {
        bad(format!(
            "object {object} does not exist (the scene has {count})"
        ))
    })?;
    if o.transform.is_none() {
        return Err(bad(format!(
            "objects[{object}] ('{}') has no transform: it is part of the static level, \
             whose BVH a deformation would rebuild; give it one (identity will do) when \
             creating the technique",
            o.name
        )));
    }
    let old = tessellate(&o.shape);
    if positions.len() != old.positions.len() {
        return Err(bad(format!(
            "{} positions for objects[{object}], whose mesh has {} vertices",
            positions.len(),
            old.positions.len()
        )));
    }
    if !normals.is_empty() && normals.len() != positions.len() {
        return Err(bad(format!(
            "{} normals for {} positions (give none to generate them)",
            normals.len(),
            positions.len()
        )));
    }
    let mut model = model.clone();
    model.objects[object].shape = crate::scene::Shape::Mesh {
        positions: positions.to_vec().into(),
        normals: normals.to_vec().into(),
        uvs: old.uvs.clone().into(),
        indices: old.indices.clone().into(),
    };
    model
        .validate()
        .map_err(|p| Error::InvalidScene(format!("{}: {}", p[0].path, p[0].reason)))?;
    let new = tessellate(&model.objects[object].shape);
    if let Some(t) = old
        .indices
        .iter()
        .position(|t| is_degenerate(&old, *t) != is_degenerate(&new, *t))
    {
        return Err(bad(format!(
            "triangle {t} of objects[{object}] would {} zero area in f32: the scene keeps \
             another set of triangles then; build it anew",
            if is_degenerate(&new, old.indices[t]) {
                "get"
            } else {
                "lose its"
            }
        )));
    }
    let local = crate::device::device_scene::mesh_vertices(&new);
    let before = crate::device::device_scene::mesh_vertices(&old);
    Ok((model, local, before))
}

/// A deformation as every technique's `set_object_vertices` applies it: the deformed
/// scene, the technique's instances with the deformation made
/// ([`crate::device::device_scene::SceneInstances::deform_instance`]), the update to
/// write, and the object's vertices before it (to go back on a later error).
pub struct Deformation {
    /// The scene with the object's shape the deformed mesh.
    pub model: crate::scene::Scene,
    /// The instances with the deformation made.
    pub instances: crate::device::device_scene::SceneInstances,
    /// What to write into the uploaded scene.
    pub update: crate::device::device_scene::InstanceUpdate,
    /// The object's object-space vertices before the deformation.
    pub before: Vec<crate::device::layout::GpuVertex>,
}

/// Checks and makes a deformation of object `object` of `model` on a copy of `instances`
/// ([`with_deformed_object`]); nothing is changed on an error.
pub fn deformation(
    model: &crate::scene::Scene,
    instances: &crate::device::device_scene::SceneInstances,
    object: usize,
    positions: &[glam::Vec3],
    normals: &[glam::Vec3],
) -> Result<Deformation, Error> {
    let (deformed, local, before) = with_deformed_object(model, object, positions, normals)?;
    let mut instances = instances.clone();
    let d = instances.deform_instance(object, local)?;
    Ok(Deformation {
        model: deformed,
        instances,
        update: crate::device::device_scene::InstanceUpdate::Deformed(d),
        before,
    })
}

/// What a technique's `Drop` calls when it still owns device buffers: counts them in
/// [`leaked_buffers`] and says so on stderr, never silently.
pub fn report_leak(technique: &str, buffers: usize, bytes: u64) {
    if buffers == 0 {
        return;
    }
    LEAKED_BUFFERS.fetch_add(buffers as u64, Ordering::Relaxed);
    // counted above; the message is best effort (a closed stderr must not panic)
    use std::io::Write;
    let _ = writeln!(
        std::io::stderr(),
        "caustica: {technique} dropped without free(): {buffers} device buffers ({bytes} bytes) \
         stay allocated until the backend is dropped"
    );
}
