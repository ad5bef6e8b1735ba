//! The render world's side: caustica's wgpu backend on Bevy's `RenderDevice` and
//! `RenderQueue`, one technique per camera with [`Caustics`], updated from the main
//! world's snapshot through caustica's update API, recorded into Bevy's command encoder by
//! a system in `Core3d` (after the main passes, before post-processing and tonemapping),
//! and added to the view's HDR target by an additive full-screen pass. Nothing here waits
//! on the device: a frame's statistics are collected once the device is done, after
//! Bevy's submission, and handed to the main world's [`CausticaStats`].

use crate::convert::MeshGeometry;
use crate::world::WorldSnapshot;
use crate::{CameraCaustics, CausticaStats, Caustics, CausticsStatus, CausticsTechnique};
use bevy::core_pipeline::schedule::{Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::camera::ExtractedCamera;
use bevy::render::renderer::{
    RenderContext, RenderDevice, RenderGraph, RenderGraphSystems, RenderQueue, ViewQuery,
};
use bevy::render::sync_world::MainEntity;
use bevy::render::view::{ExtractedView, ViewTarget};
use bevy::render::{Extract, ExtractSchedule, Render, RenderApp, RenderSystems};
use caustica::backends::wgpu::WgpuBackend;
use caustica::scene::{Camera as CCamera, Material, Object, Scene, Shape};
use caustica::technique_spec::put_setting;
use caustica::wgpu;
use caustica::{FrameTicket, Output, Submission, Technique};
use std::collections::{BTreeMap, HashMap, HashSet};
use std::future::Future;
use std::sync::Arc;

/// The camera-space output of `technique` that the plugin adds to Bevy's image: the
/// filtered caustics, PhotonGi's filtered indirect light (with [`settings_json`] and
/// [`encode_added_light`], the one place that names outputs).
pub fn added_output(technique: CausticsTechnique) -> Output {
    match technique {
        CausticsTechnique::PhotonGi => Output::FilteredIndirect,
        _ => Output::FilteredCaustics,
    }
}

/// Writes the output the plugin adds into `texture`, in `encoder`; false when the
/// technique's plan knows it is zero (it has no image).
fn encode_added_light(
    technique: &dyn Technique,
    kind: CausticsTechnique,
    backend: &mut WgpuBackend,
    texture: &wgpu::Texture,
    encoder: &mut wgpu::CommandEncoder,
) -> Result<bool, String> {
    match technique
        .output_image(added_output(kind))
        .map_err(|e| e.to_string())?
    {
        Some(image) => {
            backend
                .encode_image_to_texture(image, texture, encoder)
                .map_err(|e| e.to_string())?;
            Ok(true)
        }
        None => Ok(false),
    }
}

/// A technique that may live in a Bevy resource.
type BoxedTechnique = Box<dyn Technique + Send + Sync>;

/// What a view's technique was last given (to tell what changed).
struct Applied {
    entities: Vec<Entity>,
    objects: Vec<crate::world::ObjectSnap>,
    lights: Vec<caustica::scene::Light>,
    camera: CCamera,
    caustics: Caustics,
}

struct ViewState {
    technique: Option<BoxedTechnique>,
    applied: Option<Applied>,
    /// The caustics in the view's size, written by caustica, read by the composite pass.
    texture: Option<(
        wgpu::Texture,
        wgpu::TextureView,
        wgpu::BindGroup,
        (u32, u32),
    )>,
    params: wgpu::Buffer,
    /// A reason the view renders nothing until its inputs change (logged once).
    blocked: Option<(String, u64)>,
    /// Tickets recorded this frame, not yet handed to the backend as submitted.
    unsubmitted: Vec<FrameTicket>,
    /// Submitted tickets whose statistics have not come back yet.
    in_flight: Vec<FrameTicket>,
    /// Whether this frame records (set by prepare).
    ready: bool,
    /// The camera in the main world.
    main: Entity,
    viewport_origin: (u32, u32),
}

/// The composite pipeline per target format and sample count.
struct Composite {
    layout: wgpu::BindGroupLayout,
    shader: wgpu::ShaderModule,
    pipeline_layout: wgpu::PipelineLayout,
    pipelines: HashMap<(wgpu::TextureFormat, u32), wgpu::RenderPipeline>,
}

#[derive(Resource)]
pub(crate) struct CausticaRender {
    backend: Option<WgpuBackend>,
    /// Why there is no backend (logged once).
    no_backend: Option<String>,
    tried_backend: bool,
    composite: Option<Composite>,
    views: HashMap<Entity, ViewState>,
    /// Frames of views that went away, collected without a wait like the others.
    orphans: Vec<FrameTicket>,
    snapshot: Arc<WorldSnapshot>,
    /// Bumped whenever the snapshot changes.
    snapshot_version: u64,
    cameras: HashMap<Entity, Caustics>,
    stats: CausticaStats,
    warned: HashSet<String>,
}

impl CausticaRender {
    fn warn_once(&mut self, key: String, line: impl FnOnce() -> String) {
        if self.warned.insert(key) {
            warn!("bevy_caustica: {}", line());
        }
    }
}

impl Drop for CausticaRender {
    fn drop(&mut self) {
        let Some(backend) = self.backend.as_mut() else {
            return;
        };
        for (_, mut v) in self.views.drain() {
            if let Some(t) = v.technique.take() {
                let _ = t.free(backend);
            }
        }
    }
}

pub(crate) fn build(app: &mut App, stats: CausticaStats) {
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else {
        warn!("bevy_caustica: no RenderApp (RenderPlugin missing): the plugin does nothing");
        return;
    };
    render_app
        .insert_resource(CausticaRender {
            backend: None,
            no_backend: None,
            tried_backend: false,
            composite: None,
            views: HashMap::new(),
            orphans: Vec::new(),
            snapshot: Arc::new(WorldSnapshot::default()),
            snapshot_version: 0,
            cameras: HashMap::new(),
            stats,
            warned: HashSet::new(),
        })
        .add_systems(ExtractSchedule, extract_caustica)
        .add_systems(
            Render,
            prepare_caustica.in_set(RenderSystems::PrepareResources),
        )
        .add_systems(
            Core3d,
            caustica_view
                .after(Core3dSystems::MainPass)
                .before(Core3dSystems::EarlyPostProcess),
        )
        .add_systems(
            RenderGraph,
            collect_frames.in_set(RenderGraphSystems::Finish),
        );
}

fn extract_caustica(
    mut state: ResMut<CausticaRender>,
    snapshot: Extract<Res<WorldSnapshot>>,
    cameras: Extract<Query<(Entity, &Caustics)>>,
) {
    if snapshot.is_changed() {
        state.snapshot = Arc::new(snapshot.clone());
        state.snapshot_version += 1;
    }
    state.cameras = cameras.iter().map(|(e, c)| (e, c.clone())).collect();
}

/// caustica's settings JSON for `c`: the user's own settings (laid over the technique's
/// defaults when it is made), with the camera's photon grid and only the output the
/// plugin adds (no direct light or composite: Bevy does those).
fn settings_json(c: &Caustics) -> serde_json::Value {
    let mut s = c.settings.as_object().cloned().unwrap_or_default();
    let side = c.photons.max(1);
    put_setting(&mut s, "frame.photons_w", side.into());
    put_setting(&mut s, "frame.photons_h", side.into());
    put_setting(
        &mut s,
        "frame.outputs",
        serde_json::json!([added_output(c.technique)]),
    );
    serde_json::Value::Object(s)
}

fn create_technique(
    backend: &mut WgpuBackend,
    scene: &Scene,
    c: &Caustics,
) -> Result<BoxedTechnique, String> {
    use caustica::{
        AdaptiveCaustics, AdaptiveCausticsSettings, CausticMap, CausticMapSettings, PhotonGi,
        PhotonGiSettings, Sspm, SspmSettings,
    };
    let json = settings_json(c);
    let bad = |e: serde_json::Error| format!("settings {json}: {e}");
    let err = |e: caustica::Error| e.to_string();
    Ok(match c.technique {
        CausticsTechnique::Sspm => {
            let s: SspmSettings = serde_json::from_value(json.clone()).map_err(bad)?;
            Box::new(Sspm::new(backend, scene, s).map_err(err)?)
        }
        CausticsTechnique::CausticMap => {
            let s: CausticMapSettings = serde_json::from_value(json.clone()).map_err(bad)?;
            Box::new(CausticMap::new(backend, scene, s).map_err(err)?)
        }
        CausticsTechnique::AdaptiveCaustics => {
            let s: AdaptiveCausticsSettings = serde_json::from_value(json.clone()).map_err(bad)?;
            Box::new(AdaptiveCaustics::new(backend, scene, s).map_err(err)?)
        }
        CausticsTechnique::PhotonGi => {
            let s: PhotonGiSettings = serde_json::from_value(json.clone()).map_err(bad)?;
            Box::new(PhotonGi::new(backend, scene, s).map_err(err)?)
        }
    })
}

fn material_name(i: usize) -> String {
    format!("m{i}")
}

/// caustica's scene of the snapshot seen by `camera`: every object an instance (so that
/// a move is an update), with a material of its own.
fn scene_of(snapshot: &WorldSnapshot, camera: &CCamera) -> Scene {
    let mut materials = BTreeMap::new();
    let mut objects = Vec::new();
    for (i, (entity, o)) in snapshot.objects.iter().enumerate() {
        materials.insert(material_name(i), o.material.clone());
        objects.push(Object {
            name: format!("{entity}"),
            material: material_name(i),
            shape: mesh_shape(&o.mesh),
            transform: Some(o.transform),
        });
    }
    Scene {
        name: "bevy".into(),
        description: "a Bevy world, read by bevy_caustica".into(),
        camera: camera.clone(),
        materials,
        objects,
        lights: snapshot.lights.clone(),
    }
}

/// A mesh read from Bevy as caustica's shape.
fn mesh_shape(m: &MeshGeometry) -> Shape {
    Shape::Mesh {
        positions: m.positions.clone(),
        normals: m.normals.clone(),
        uvs: m.uvs.clone(),
        indices: m.indices.clone(),
    }
}

fn same_kind(a: &Material, b: &Material) -> bool {
    std::mem::discriminant(a) == std::mem::discriminant(b)
}

/// Brings `view`'s technique to the snapshot, the camera and the settings: updates where
/// caustica has them, a new technique otherwise. Returns an error line (the view then
/// renders nothing until something changes).
fn bring_up_to_date(
    backend: &mut WgpuBackend,
    view: &mut ViewState,
    snapshot: &WorldSnapshot,
    camera: &CCamera,
    caustics: &Caustics,
    stats: &mut CameraCaustics,
) -> Result<(), String> {
    let entities: Vec<Entity> = snapshot.objects.keys().copied().collect();
    let objects: Vec<_> = snapshot.objects.values().cloned().collect();
    let rebuild = match (&view.applied, &view.technique) {
        (Some(a), Some(_)) => {
            a.entities != entities
                || a.caustics.technique != caustics.technique
                || a.lights.is_empty() != snapshot.lights.is_empty()
                || a.objects
                    .iter()
                    .zip(&objects)
                    .any(|(x, y)| !same_kind(&x.material, &y.material))
        }
        _ => true,
    };
    if !rebuild {
        let t = view.technique.as_mut().expect("checked");
        let a = view.applied.as_ref().expect("checked");
        let e = |e: caustica::Error| e.to_string();
        // `strength` is the composite's alone
        if (a.caustics.photons, &a.caustics.settings) != (caustics.photons, &caustics.settings) {
            t.set_settings(backend, &settings_json(caustics))
                .map_err(e)?;
            stats.updates += 1;
        }
        if a.camera != *camera {
            t.set_camera(backend, camera).map_err(e)?;
            stats.updates += 1;
        }
        if a.lights != snapshot.lights {
            t.set_lights(backend, &snapshot.lights).map_err(e)?;
            stats.updates += 1;
        }
        for (i, (x, y)) in a.objects.iter().zip(&objects).enumerate() {
            if Arc::ptr_eq(&x.mesh, &y.mesh) {
                continue;
            }
            if x.mesh.positions.len() == y.mesh.positions.len() && x.mesh.indices == y.mesh.indices
            {
                t.set_object_vertices(backend, i, &y.mesh.positions, &y.mesh.normals)
                    .map_err(e)?;
            } else {
                // another topology: that object's BVH alone is built
                t.set_object_shape(backend, i, &mesh_shape(&y.mesh))
                    .map_err(e)?;
            }
            stats.updates += 1;
        }
        let moves: Vec<_> = a
            .objects
            .iter()
            .zip(&objects)
            .enumerate()
            .filter(|(_, (x, y))| x.transform != y.transform)
            .map(|(i, (_, y))| (i, y.transform))
            .collect();
        if !moves.is_empty() {
            t.set_object_transforms(backend, &moves).map_err(e)?;
            stats.updates += 1;
        }
        if a.objects
            .iter()
            .zip(&objects)
            .any(|(x, y)| x.material != y.material)
        {
            let materials: BTreeMap<_, _> = objects
                .iter()
                .enumerate()
                .map(|(i, o)| (material_name(i), o.material.clone()))
                .collect();
            t.set_materials(backend, &materials).map_err(e)?;
            stats.updates += 1;
        }
    } else {
        if let Some(old) = view.technique.take() {
            old.free(backend).map_err(|e| e.to_string())?;
        }
        view.texture = None;
        let scene = scene_of(snapshot, camera);
        view.technique = Some(create_technique(backend, &scene, caustics)?);
        stats.builds += 1;
    }
    view.applied = Some(Applied {
        entities,
        objects,
        lights: snapshot.lights.clone(),
        camera: camera.clone(),
        caustics: caustics.clone(),
    });
    Ok(())
}

const SHADER: &str = include_str!("composite.wgsl");

fn make_composite(device: &wgpu::Device) -> Composite {
    let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some("bevy_caustica composite"),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Uniform,
                    has_dynamic_offset: false,
                    min_binding_size: None,
                },
                count: None,
            },
        ],
    });
    let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("bevy_caustica composite"),
        source: wgpu::ShaderSource::Wgsl(SHADER.into()),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("bevy_caustica composite"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    Composite {
        layout,
        shader,
        pipeline_layout,
        pipelines: HashMap::new(),
    }
}

impl Composite {
    fn pipeline(
        &mut self,
        device: &wgpu::Device,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> &wgpu::RenderPipeline {
        self.pipelines.entry((format, samples)).or_insert_with(|| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some("bevy_caustica composite"),
                layout: Some(&self.pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &self.shader,
                    entry_point: Some("vs"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                fragment: Some(wgpu::FragmentState {
                    module: &self.shader,
                    entry_point: Some("fs"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        // added to what Bevy rendered; its alpha kept
                        blend: Some(wgpu::BlendState {
                            color: wgpu::BlendComponent {
                                src_factor: wgpu::BlendFactor::One,
                                dst_factor: wgpu::BlendFactor::One,
                                operation: wgpu::BlendOperation::Add,
                            },
                            alpha: wgpu::BlendComponent {
                                src_factor: wgpu::BlendFactor::Zero,
                                dst_factor: wgpu::BlendFactor::One,
                                operation: wgpu::BlendOperation::Add,
                            },
                        }),
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                primitive: Default::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState {
                    count: samples,
                    ..Default::default()
                },
                multiview_mask: None,
                cache: None,
            })
        })
    }
}

/// `f`'s result, with the validation errors that wgpu reports for what `f` did on this
/// thread (an error scope) made part of it.
fn scoped<T>(device: &wgpu::Device, f: impl FnOnce() -> Result<T, String>) -> Result<T, String> {
    let guard = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let result = f();
    let mut pop = std::pin::pin!(guard.pop());
    let mut cx = std::task::Context::from_waker(std::task::Waker::noop());
    // native wgpu resolves a popped scope at once
    let error = match pop.as_mut().poll(&mut cx) {
        std::task::Poll::Ready(e) => e,
        std::task::Poll::Pending => None,
    };
    match (result, error) {
        (Err(e), _) => Err(e),
        (Ok(_), Some(e)) => Err(format!("wgpu: {e}")),
        (Ok(v), None) => Ok(v),
    }
}

fn open_backend(device: &RenderDevice, queue: &RenderQueue) -> Result<WgpuBackend, String> {
    let d: wgpu::Device = device.wgpu_device().clone();
    let q: wgpu::Queue = (**queue).clone();
    WgpuBackend::from_device(d, q, "Bevy's RenderDevice").map_err(|e| e.to_string())
}

/// Per frame, for every camera with `Caustics`: opens the backend on the first frame that
/// needs it (a failure is logged once and the plugin stands aside), checks what the
/// camera can take, brings its technique up to date and prepares its composite.
fn prepare_caustica(
    mut state: ResMut<CausticaRender>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    views: Query<(Entity, &MainEntity, &ExtractedCamera, &ExtractedView)>,
) {
    let state = &mut *state;
    for v in state.views.values_mut() {
        v.ready = false;
    }
    if state.cameras.is_empty() {
        free_unused(state, &HashSet::new());
        return;
    }
    if !state.tried_backend {
        state.tried_backend = true;
        let opened = open_backend(&device, &queue);
        // Bevy's device keeps Bevy's own uncaptured-error handler (caustica installs none
        // on a host's device); caustica's errors in the plugin's calls are caught by the
        // error scopes around them (`scoped`).
        match opened {
            Ok(b) => {
                state.backend = Some(b);
                state.composite = Some(make_composite(device.wgpu_device()));
            }
            Err(why) => {
                error!(
                    "bevy_caustica: caustica cannot run on Bevy's device ({why}); the plugin adds nothing"
                );
                state.no_backend = Some(why);
            }
        }
    }
    let mut live = HashSet::new();
    for (render_entity, main, cam, ext) in &views {
        let main = main.id();
        let Some(caustics) = state.cameras.get(&main).cloned() else {
            continue;
        };
        live.insert(render_entity);
        let stats = state.stats.clone();
        let status = |s: CausticsStatus| {
            stats.with(main, |c| {
                c.technique = caustics.technique.registry_name();
                c.status = s;
            })
        };
        if let Some(why) = &state.no_backend {
            status(CausticsStatus::Inactive(format!("no backend: {why}")));
            continue;
        }
        if !cam.hdr {
            state.warn_once(format!("hdr {main}"), || {
                format!("camera {main} has Caustics but no Hdr: there is no linear target to add caustics to; its image is left alone")
            });
            status(CausticsStatus::Inactive("the camera has no Hdr".into()));
            continue;
        }
        let Some(size) = cam.physical_viewport_size.filter(|s| s.x > 0 && s.y > 0) else {
            continue;
        };
        let origin = cam
            .viewport
            .as_ref()
            .map(|v| (v.physical_position.x, v.physical_position.y))
            .unwrap_or((0, 0));
        let camera = match crate::convert::camera(
            ext.world_from_view.to_matrix().to_cols_array(),
            ext.clip_from_view.to_cols_array(),
            size.x,
            size.y,
        ) {
            Ok(c) => c,
            Err(why) => {
                state.warn_once(format!("camera {main} {why}"), || {
                    format!("camera {main}: {why}; its image is left alone")
                });
                status(CausticsStatus::Inactive(why));
                continue;
            }
        };
        let snapshot = Arc::clone(&state.snapshot);
        let inactive = if snapshot.lights.is_empty() {
            Some("no light".to_string())
        } else if !snapshot.objects.values().any(|o| o.material.is_specular()) {
            Some("no specular object (glass or mirror) in the scene".to_string())
        } else {
            None
        };
        if let Some(why) = inactive {
            if caustics.technique != CausticsTechnique::PhotonGi || snapshot.lights.is_empty() {
                state.warn_once(format!("inactive {main} {why}"), || {
                    format!("camera {main}: {why}: nothing to add")
                });
                status(CausticsStatus::Inactive(why));
                continue;
            }
        }
        let version = state.snapshot_version;
        let backend = state.backend.as_mut().expect("checked");
        let view = state
            .views
            .entry(render_entity)
            .or_insert_with(|| ViewState {
                technique: None,
                applied: None,
                texture: None,
                params: device.wgpu_device().create_buffer(&wgpu::BufferDescriptor {
                    label: Some("bevy_caustica composite params"),
                    size: 16,
                    usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
                    mapped_at_creation: false,
                }),
                blocked: None,
                unsubmitted: Vec::new(),
                in_flight: Vec::new(),
                ready: false,
                main,
                viewport_origin: (0, 0),
            });
        // a failure blocks the view until the scene, its Caustics or its size change (not
        // on every camera move)
        let key = {
            use std::hash::{Hash, Hasher};
            let mut h = std::collections::hash_map::DefaultHasher::new();
            version.hash(&mut h);
            (size.x, size.y).hash(&mut h);
            format!("{caustics:?}").hash(&mut h);
            h.finish()
        };
        if let Some((why, k)) = &view.blocked {
            if *k == key {
                status(CausticsStatus::Inactive(why.clone()));
                continue;
            }
        }
        let mut cam_stats = state.stats.get(main).unwrap_or_default();
        let t0 = std::time::Instant::now();
        let updated = scoped(device.wgpu_device(), || {
            bring_up_to_date(backend, view, &snapshot, &camera, &caustics, &mut cam_stats)
        });
        match updated {
            Ok(()) => view.blocked = None,
            Err(why) => {
                if state.warned.insert(format!("failed {main} {why}")) {
                    error!(
                        "bevy_caustica: camera {main}: {} failed: {why}; its image is left alone until the scene or its Caustics change",
                        caustics.technique.registry_name()
                    );
                }
                if let Some(t) = view.technique.take() {
                    let _ = t.free(backend);
                }
                view.applied = None;
                view.blocked = Some((why.clone(), key));
                state.stats.with(main, |c| {
                    c.builds = cam_stats.builds;
                    c.updates = cam_stats.updates;
                    c.status = CausticsStatus::Inactive(why);
                });
                continue;
            }
        }
        let update_ms = t0.elapsed().as_secs_f64() * 1e3;
        state.stats.with(main, |c| {
            c.builds = cam_stats.builds;
            c.updates = cam_stats.updates;
            c.technique = caustics.technique.registry_name();
            c.host_update_ms = update_ms;
        });
        // the view's texture and bind group, in its size
        let (w, h) = (size.x, size.y);
        if view.texture.as_ref().is_none_or(|t| t.3 != (w, h)) {
            let d = device.wgpu_device();
            let texture = d.create_texture(&wgpu::TextureDescriptor {
                label: Some("bevy_caustica caustics"),
                size: wgpu::Extent3d {
                    width: w,
                    height: h,
                    depth_or_array_layers: 1,
                },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format: wgpu::TextureFormat::Rgba16Float,
                usage: wgpu::TextureUsages::STORAGE_BINDING | wgpu::TextureUsages::TEXTURE_BINDING,
                view_formats: &[],
            });
            let tv = texture.create_view(&Default::default());
            let composite = state.composite.as_ref().expect("with the backend");
            let bg = d.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("bevy_caustica composite"),
                layout: &composite.layout,
                entries: &[
                    wgpu::BindGroupEntry {
                        binding: 0,
                        resource: wgpu::BindingResource::TextureView(&tv),
                    },
                    wgpu::BindGroupEntry {
                        binding: 1,
                        resource: view.params.as_entire_binding(),
                    },
                ],
            });
            view.texture = Some((texture, tv, bg, (w, h)));
        }
        view.viewport_origin = origin;
        let params: [f32; 4] = [
            cam.exposure * caustics.strength,
            origin.0 as f32,
            origin.1 as f32,
            0.0,
        ];
        let bytes: Vec<u8> = params.iter().flat_map(|f| f.to_le_bytes()).collect();
        queue.write_buffer(&view.params, 0, &bytes);
        view.ready = true;
    }
    free_unused(state, &live);
}

/// Frees the techniques of views that no longer ask for caustics.
fn free_unused(state: &mut CausticaRender, live: &HashSet<Entity>) {
    let gone: Vec<Entity> = state
        .views
        .keys()
        .filter(|e| !live.contains(e))
        .copied()
        .collect();
    for e in gone {
        if let Some(mut v) = state.views.remove(&e) {
            if let (Some(t), Some(b)) = (v.technique.take(), state.backend.as_mut()) {
                let _ = t.free(b);
            }
            // still collected, so that the backend forgets them (never waited for)
            state.orphans.append(&mut v.in_flight);
        }
    }
}

/// Per view, in `Core3d` after the main passes: caustica's frame recorded into Bevy's
/// command encoder, its output written into the view's caustics texture, and that added
/// to the view's HDR target.
fn caustica_view(
    view: ViewQuery<(Entity, &MainEntity, &ViewTarget)>,
    mut state: ResMut<CausticaRender>,
    device: Res<RenderDevice>,
    mut ctx: RenderContext,
) {
    let (render_entity, main, target) = view.into_inner();
    let state = &mut *state;
    let Some(v) = state.views.get_mut(&render_entity) else {
        return;
    };
    if !v.ready {
        return;
    }
    let (Some(backend), Some(technique), Some((texture, _, bind_group, (w, h))), Some(composite)) = (
        state.backend.as_mut(),
        v.technique.as_mut(),
        v.texture.as_ref(),
        state.composite.as_mut(),
    ) else {
        return;
    };
    let main = main.id();
    let Some(caustics) = state.cameras.get(&main) else {
        return;
    };
    let kind = caustics.technique;
    let t0 = std::time::Instant::now();
    let result = scoped(device.wgpu_device(), || -> Result<bool, String> {
        let recorded = technique.record_frame(backend).map_err(|e| e.to_string())?;
        let encoder = ctx.command_encoder();
        let submission = backend
            .encode(&recorded.recording, &recorded.readbacks, encoder)
            .map_err(|e| e.to_string())?;
        // in Bevy's encoder now: it runs whatever follows
        v.unsubmitted.push(recorded.submitted(submission));
        encode_added_light(&**technique, kind, backend, texture, encoder)
    });
    let record_ms = t0.elapsed().as_secs_f64() * 1e3;
    state.stats.with(main, |c| c.host_record_ms = record_ms);
    match result {
        Ok(true) => {
            let format = target.main_texture_format();
            let blendable = format
                .guaranteed_format_features(device.features())
                .flags
                .contains(wgpu::TextureFormatFeatureFlags::BLENDABLE);
            if !blendable {
                let key = format!("format {main} {format:?}");
                if state.warned.insert(key) {
                    warn!("bevy_caustica: camera {main}: its target format {format:?} cannot be blended into; its image is left alone");
                }
                return;
            }
            let samples = 1;
            let pipeline = composite
                .pipeline(device.wgpu_device(), format, samples)
                .clone();
            let attachment = target.get_unsampled_color_attachment();
            let encoder = ctx.command_encoder();
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some("bevy_caustica composite"),
                color_attachments: &[Some(attachment)],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            let (ox, oy) = v.viewport_origin;
            pass.set_viewport(ox as f32, oy as f32, *w as f32, *h as f32, 0.0, 1.0);
            pass.set_pipeline(&pipeline);
            pass.set_bind_group(0, bind_group, &[]);
            pass.draw(0..3, 0..1);
            state.stats.with(main, |c| {
                c.frames_recorded += 1;
                c.status = CausticsStatus::Active;
            });
        }
        Ok(false) => {
            state.stats.with(main, |c| {
                c.frames_recorded += 1;
                c.status = CausticsStatus::Inactive(
                    "the technique's plan has no light to add (no photon reaches a caster)".into(),
                );
            });
        }
        Err(why) => {
            let key = format!("frame {main} {why}");
            if state.warned.insert(key) {
                error!("bevy_caustica: camera {main}: frame failed: {why}; nothing added");
            }
            v.ready = false;
            // a frame lost after its recording leaves the technique's device state
            // behind its updates: made anew with the next prepare
            if let Some(t) = v.technique.take() {
                let _ = t.free(backend);
            }
            v.applied = None;
            state.stats.with(main, |c| {
                c.status = CausticsStatus::Inactive(format!("frame failed: {why}"))
            });
        }
    }
}

/// After Bevy's submission: tells the backend the frames went to the queue (their
/// statistics' readbacks are mapped from now), then collects those the device has
/// finished, never waiting.
fn collect_frames(mut state: ResMut<CausticaRender>) {
    let state = &mut *state;
    let Some(backend) = state.backend.as_mut() else {
        return;
    };
    for v in state.views.values_mut() {
        for t in v.unsubmitted.drain(..) {
            let _ = backend.submitted(&Submission::pending(t.submission_id()), None);
            v.in_flight.push(t);
        }
    }
    let stats = state.stats.clone();
    for (render_entity, v) in state.views.iter_mut() {
        let mut keep = Vec::new();
        for mut t in v.in_flight.drain(..) {
            match t.stats(backend, false) {
                Ok(Some(s)) => {
                    stats.with(v.main, |c| {
                        c.frames_completed += 1;
                        c.last = Some(s);
                    });
                }
                Ok(None) => keep.push(t),
                Err(e) => {
                    warn!("bevy_caustica: view {render_entity}: a frame's statistics: {e}");
                }
            }
        }
        v.in_flight = keep;
    }
    state
        .orphans
        .retain_mut(|t| matches!(t.stats(backend, false), Ok(None)));
}
