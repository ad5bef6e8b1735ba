//! Headless Bevy apps for the tests: a scene rendered by a camera into an `Rgba16Float`
//! image (Hdr, no tonemapping, no dithering, no MSAA: the image is the linear HDR target
//! times the exposure), read back every frame.

#![allow(dead_code)]

use bevy::camera::RenderTarget;
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::TextureFormat;
use bevy::render::view::{DebandDither, Msaa, Tonemapping};
use bevy::window::{ExitCondition, WindowPlugin};
use bevy_caustica::{CausticaPlugin, Caustics};
use std::sync::{Arc, Mutex};

/// Image size (a width of a multiple of 32 keeps Rgba16Float rows unpadded).
pub const W: u32 = 96;
pub const H: u32 = 64;

/// Tests share one process and one GPU: one app at a time.
pub static SERIAL: Mutex<()> = Mutex::new(());

pub fn serial() -> std::sync::MutexGuard<'static, ()> {
    SERIAL.lock().unwrap_or_else(|e| e.into_inner())
}

#[derive(Resource, Clone, Default)]
pub struct Frames(pub Arc<Mutex<Vec<Shot>>>);

/// A camera's tag and its image (linear RGBA).
pub type Shot = (u32, Vec<f32>);

#[derive(Component)]
pub struct Captured(pub u32);

#[derive(Component)]
pub struct TheLight;

#[derive(Component)]
pub struct TheBall;

/// An app with Bevy's default plugins (no window) and, if `plugin`, caustica's.
pub fn app(plugin: bool) -> App {
    app_on(plugin, None)
}

/// [`app`] on a device with `limits` (the adapter's limits at most).
pub fn app_on(plugin: bool, limits: Option<bevy::render::settings::WgpuLimits>) -> App {
    let mut app = App::new();
    let settings = bevy::render::settings::WgpuSettings {
        constrained_limits: limits,
        ..default()
    };
    app.add_plugins(
        DefaultPlugins
            .set(WindowPlugin {
                primary_window: None,
                exit_condition: ExitCondition::DontExit,
                ..default()
            })
            .set(bevy::render::RenderPlugin {
                render_creation: bevy::render::settings::RenderCreation::Automatic(Box::new(
                    settings,
                )),
                synchronous_pipeline_compilation: true,
                ..default()
            })
            .disable::<PipelinedRenderingPlugin>(),
    );
    if plugin {
        app.add_plugins(CausticaPlugin);
    }
    app.init_resource::<Frames>();
    app
}

/// A camera rendering into a new image; its readbacks land in `Frames` under `tag`.
pub fn camera(app: &mut App, hdr: bool, caustics: Option<Caustics>, tag: u32) -> Entity {
    let world = app.world_mut();
    let image = Image::new_target_texture(W, H, TextureFormat::Rgba16Float, None);
    let mut image = image;
    image.texture_descriptor.usage |= bevy::render::render_resource::TextureUsages::COPY_SRC;
    let handle = world.resource_mut::<Assets<Image>>().add(image);
    let mut e = world.spawn((
        Camera3d::default(),
        RenderTarget::Image(handle.clone().into()),
        Tonemapping::None,
        DebandDither::Disabled,
        Msaa::Off,
        Transform::from_xyz(0.0, 2.6, 3.2).looking_at(Vec3::new(0.0, 0.2, 0.0), Vec3::Y),
    ));
    if hdr {
        e.insert(bevy::camera::Hdr);
    }
    if let Some(c) = caustics {
        e.insert(c);
    }
    let cam = e.id();
    let frames = world.resource::<Frames>().clone();
    world
        .spawn((Readback::texture(handle), Captured(tag)))
        .observe(move |ev: On<ReadbackComplete>| {
            let px: Vec<f32> = ev
                .data
                .chunks_exact(2)
                .map(|b| f16_to_f32(u16::from_le_bytes([b[0], b[1]])))
                .collect();
            frames.0.lock().unwrap().push((tag, px));
        });
    cam
}

/// The floor (white, diffuse, 4 m square) and a point light 3 m above it.
pub fn floor_and_light(app: &mut App) {
    let world = app.world_mut();
    let plane = world
        .resource_mut::<Assets<Mesh>>()
        .add(Plane3d::default().mesh().size(4.0, 4.0));
    let white = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::WHITE,
            perceptual_roughness: 1.0,
            reflectance: 0.0,
            ..default()
        });
    world.spawn((Mesh3d(plane), MeshMaterial3d(white), Transform::default()));
    world.spawn((
        PointLight {
            intensity: 400_000.0,
            range: 30.0,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(0.0, 3.0, 0.0),
        TheLight,
    ));
}

/// A glass ball of radius 0.5 m, 1 m above the floor.
pub fn glass_ball(app: &mut App) -> Entity {
    let world = app.world_mut();
    let ball = world
        .resource_mut::<Assets<Mesh>>()
        .add(Sphere::new(0.5).mesh().uv(48, 24));
    let glass = world
        .resource_mut::<Assets<StandardMaterial>>()
        .add(StandardMaterial {
            base_color: Color::WHITE,
            specular_transmission: 1.0,
            ior: 1.5,
            thickness: 1.0,
            perceptual_roughness: 0.0,
            ..default()
        });
    world
        .spawn((
            Mesh3d(ball),
            MeshMaterial3d(glass),
            Transform::from_xyz(0.0, 1.0, 0.0),
            TheBall,
        ))
        .id()
}

/// Runs frames until Bevy has every pipeline and camera `tag`'s image shows the scene
/// (more than the clear colour), then `settle` more; returns that camera's last image and
/// the frames run.
pub fn run_until_lit(app: &mut App, tag: u32, settle: u32) -> (Vec<f32>, u32) {
    ready(app);
    let start = std::time::Instant::now();
    let mut frames = 0;
    loop {
        app.update();
        frames += 1;
        let waiting = app
            .sub_app(bevy::render::RenderApp)
            .world()
            .resource::<bevy::render::render_resource::PipelineCache>()
            .waiting_pipelines()
            .count();
        let contrast = latest(app, tag).is_some_and(|i| {
            let l = luminance(&i);
            let (lo, hi) = l
                .iter()
                .fold((f32::MAX, 0.0f32), |(a, b), &x| (a.min(x), b.max(x)));
            hi > 2.0 * lo + 1e-3
        });
        if waiting == 0 && contrast && frames > 3 {
            break;
        }
        assert!(
            frames < 600 && start.elapsed().as_secs() < 240,
            "camera {tag}: no lit image after {frames} frames"
        );
    }
    for _ in 0..settle {
        app.update();
        frames += 1;
    }
    (latest(app, tag).expect("an image"), frames)
}

/// Runs `n` frames; camera `tag`'s last image.
pub fn run(app: &mut App, tag: u32, n: u32) -> Vec<f32> {
    ready(app);
    for _ in 0..n {
        app.update();
    }
    latest(app, tag).expect("an image")
}

/// What `App::run` does before its first update: the plugins' `finish` and `cleanup`
/// (the renderer is initialised there).
pub fn ready(app: &mut App) {
    use bevy::app::PluginsState;
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    if app.plugins_state() == PluginsState::Ready {
        app.finish();
        app.cleanup();
    }
}

pub fn latest(app: &App, tag: u32) -> Option<Vec<f32>> {
    let f = app.world().resource::<Frames>();
    let v = f.0.lock().unwrap();
    v.iter()
        .rev()
        .find(|(t, _)| *t == tag)
        .map(|(_, p)| p.clone())
}

/// Luminance per pixel (Rec. 709 weights) of an RGBA image.
pub fn luminance(px: &[f32]) -> Vec<f32> {
    px.chunks_exact(4)
        .map(|p| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2])
        .collect()
}

pub fn lum_sum(px: &[f32]) -> f64 {
    luminance(px).iter().map(|&l| l as f64).sum()
}

/// `a - b`, luminance per pixel.
pub fn difference(a: &[f32], b: &[f32]) -> Vec<f32> {
    luminance(a)
        .iter()
        .zip(luminance(b))
        .map(|(x, y)| x - y)
        .collect()
}

/// The positive part's centroid (pixels).
pub fn centroid(d: &[f32]) -> Vec2 {
    let mut s = 0.0f64;
    let mut c = (0.0f64, 0.0f64);
    for (i, &v) in d.iter().enumerate() {
        if v > 0.0 {
            let (x, y) = ((i as u32 % W) as f64 + 0.5, (i as u32 / W) as f64 + 0.5);
            s += v as f64;
            c.0 += v as f64 * x;
            c.1 += v as f64 * y;
        }
    }
    Vec2::new((c.0 / s) as f32, (c.1 / s) as f32)
}

/// Where a world point lands in the camera's image (pixels).
pub fn project(app: &mut App, cam: Entity, p: Vec3) -> Vec2 {
    let mut q = app.world_mut().query::<(&Camera, &GlobalTransform)>();
    let (c, gt) = q.get(app.world(), cam).expect("the camera");
    c.world_to_viewport(gt, p).expect("in view")
}

pub fn f16_to_f32(h: u16) -> f32 {
    let s = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let e = ((h >> 10) & 0x1f) as i32;
    let m = (h & 0x3ff) as f32;
    s * match e {
        0 => m * 2f32.powi(-24),
        31 => {
            if m == 0.0 {
                f32::INFINITY
            } else {
                f32::NAN
            }
        }
        _ => (1.0 + m / 1024.0) * 2f32.powi(e - 15),
    }
}
