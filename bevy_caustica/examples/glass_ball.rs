//! A glass ball and a coloured glass block on a floor under a moving spot light, seen by
//! an orbiting camera, rendered by Bevy with caustica's caustics added. Headless (no
//! window: it runs on a machine without a display, lavapipe included): two cameras on the
//! same orbit render into images, one with `Caustics` and one without, and the last
//! frame of each is written as a PNG (`out/glass_ball.png`, `out/glass_ball_bevy_only.png`).
//!
//! Run: `cargo +nightly run --release --ignore-rust-version --example glass_ball --
//! [--frames N] [--size WxH] [--technique sspm|caustic-map|adaptive-caustics|photon-gi]
//! [--photons N] [--out DIR]`. In a window instead (the `window` feature: winit, X11 and
//! Wayland): `cargo +nightly run --release --ignore-rust-version --features window
//! --example glass_ball -- --window` (Space: caustica's light off and on).

use bevy::camera::{Hdr, RenderTarget};
use bevy::prelude::*;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::render_resource::{TextureFormat, TextureUsages};
use bevy::render::view::{DebandDither, Msaa, Tonemapping};
use bevy::window::{ExitCondition, WindowPlugin};
use bevy_caustica::{CausticaPlugin, CausticaStats, Caustics, CausticsTechnique};
use std::sync::{Arc, Mutex};

struct Args {
    frames: u32,
    w: u32,
    h: u32,
    technique: CausticsTechnique,
    photons: u32,
    out: std::path::PathBuf,
    window: bool,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        frames: 90,
        w: 640,
        h: 384,
        technique: CausticsTechnique::Sspm,
        photons: 512,
        out: "out".into(),
        window: false,
    };
    let v: Vec<String> = std::env::args().skip(1).collect();
    let mut i = 0;
    while i < v.len() {
        if v[i] == "--window" {
            a.window = true;
            i += 1;
            continue;
        }
        let val = v.get(i + 1).ok_or(format!("{} needs a value", v[i]))?;
        match v[i].as_str() {
            "--frames" => a.frames = val.parse().map_err(|e| format!("--frames: {e}"))?,
            "--photons" => a.photons = val.parse().map_err(|e| format!("--photons: {e}"))?,
            "--out" => a.out = val.into(),
            "--size" => {
                let (w, h) = val.split_once('x').ok_or("--size WxH")?;
                a.w = w.parse().map_err(|e| format!("--size: {e}"))?;
                a.h = h.parse().map_err(|e| format!("--size: {e}"))?;
                // rows of Rgba16Float texels read back unpadded: a multiple of 32
                a.w = a.w.next_multiple_of(32);
            }
            "--technique" => {
                a.technique = CausticsTechnique::ALL
                    .into_iter()
                    .find(|t| t.registry_name() == val)
                    .ok_or_else(|| {
                        "--technique: one of sspm, caustic-map, adaptive-caustics, photon-gi"
                            .to_string()
                    })?
            }
            other => return Err(format!("unknown argument {other}")),
        }
        i += 2;
    }
    Ok(a)
}

#[derive(Resource)]
struct Setup {
    frames: u32,
    size: (u32, u32),
}

#[derive(Component)]
struct Orbit;

#[derive(Component)]
struct Sweep;

#[derive(Resource, Clone, Default)]
struct Shots(Arc<Mutex<[Option<Vec<f32>>; 2]>>);

fn main() -> Result<(), String> {
    let a = args()?;
    if a.window {
        return windowed(a);
    }
    let mut app = App::new();
    app.add_plugins((
        DefaultPlugins.set(WindowPlugin {
            primary_window: None,
            exit_condition: ExitCondition::DontExit,
            ..default()
        }),
        CausticaPlugin,
    ))
    .insert_resource(Setup {
        frames: a.frames,
        size: (a.w, a.h),
    })
    .init_resource::<Shots>()
    .add_systems(Update, animate);

    let world = app.world_mut();
    spawn_scene(world);

    // two cameras on one orbit: with caustica's light and without
    let shots = world.resource::<Shots>().clone();
    for (k, with) in [(0usize, true), (1, false)] {
        let mut image = Image::new_target_texture(a.w, a.h, TextureFormat::Rgba16Float, None);
        image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        let handle = world.resource_mut::<Assets<Image>>().add(image);
        let mut e = world.spawn((
            Camera3d::default(),
            Hdr,
            RenderTarget::Image(handle.clone().into()),
            Tonemapping::None,
            DebandDither::Disabled,
            Msaa::Off,
            Transform::default(),
            Orbit,
        ));
        if with {
            e.insert(Caustics {
                technique: a.technique,
                photons: a.photons,
                ..default()
            });
        }
        let shots = shots.clone();
        world
            .spawn(Readback::texture(handle))
            .observe(move |ev: On<ReadbackComplete>| {
                let px = ev
                    .data
                    .chunks_exact(2)
                    .map(|b| half_to_f32(u16::from_le_bytes([b[0], b[1]])))
                    .collect();
                shots.0.lock().unwrap()[k] = Some(px);
            });
    }

    // what App::run does before its first update, then the frames
    while app.plugins_state() == bevy::app::PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();
    let start = std::time::Instant::now();
    for f in 0..a.frames {
        app.update();
        if f % 30 == 29 {
            for (cam, s) in app.world().resource::<CausticaStats>().all() {
                if let Some(last) = &s.last {
                    println!(
                        "frame {}: camera {cam}: {} {:?}, {} photons stored, passes {:.2} ms on the device, host waits {}; host: updates {:.2} ms, record and encode {:.2} ms",
                        f + 1,
                        s.technique,
                        s.status,
                        last.photons_stored,
                        last.passes.iter().map(|p| p.ms).sum::<f64>(),
                        last.host_waits,
                        s.host_update_ms,
                        s.host_record_ms
                    );
                }
            }
        }
    }
    // a few more frames so that the last readbacks land (the render world runs a frame
    // behind with Bevy's pipelined rendering)
    for _ in 0..4 {
        app.update();
    }
    println!(
        "{} frames at {}x{} in {:.1} s",
        a.frames + 4,
        a.w,
        a.h,
        start.elapsed().as_secs_f32()
    );
    let stats = app.world().resource::<CausticaStats>().all();
    if !stats
        .values()
        .any(|s| s.status == bevy_caustica::CausticsStatus::Active)
    {
        return Err(format!("caustica added no light: {stats:?}"));
    }
    std::fs::create_dir_all(&a.out).map_err(|e| e.to_string())?;
    let shots = app.world().resource::<Shots>().0.lock().unwrap().clone();
    for (k, name) in [(0, "glass_ball.png"), (1, "glass_ball_bevy_only.png")] {
        let px = shots[k].clone().ok_or("no image came back")?;
        let pixels = px
            .chunks_exact(4)
            .map(|p| [p[0], p[1], p[2], 1.0])
            .collect();
        let img = caustica::Image::new(a.w, a.h, pixels);
        let path = a.out.join(name);
        caustica::output::write_png(&path, &img, 1.0)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

/// In a window (the `window` feature): one camera on the orbit, the light sweeping, for
/// ever; Space switches caustica's light off and on.
#[cfg(feature = "window")]
fn windowed(a: Args) -> Result<(), String> {
    let caustics = Caustics {
        technique: a.technique,
        photons: a.photons,
        ..default()
    };
    let mut app = App::new();
    app.add_plugins((DefaultPlugins, CausticaPlugin))
        .insert_resource(Setup {
            frames: 1200,
            size: (a.w, a.h),
        })
        .insert_resource(Toggle(caustics.clone()))
        .add_systems(Update, (animate, toggle));
    let world = app.world_mut();
    spawn_scene(world);
    world.spawn((
        Camera3d::default(),
        Hdr,
        // no tonemapping LUTs in this build: a curve without one
        Tonemapping::AcesFitted,
        Transform::default(),
        Orbit,
        caustics,
    ));
    app.run();
    Ok(())
}

#[cfg(not(feature = "window"))]
fn windowed(_: Args) -> Result<(), String> {
    Err("--window needs the `window` feature: cargo +nightly run --release --ignore-rust-version --features window --example glass_ball -- --window".into())
}

#[cfg(feature = "window")]
#[derive(Resource)]
struct Toggle(Caustics);

#[cfg(feature = "window")]
fn toggle(
    keys: Res<ButtonInput<KeyCode>>,
    on: Res<Toggle>,
    cams: Query<(Entity, Has<Caustics>), With<Orbit>>,
    mut commands: Commands,
) {
    if keys.just_pressed(KeyCode::Space) {
        for (e, has) in &cams {
            if has {
                commands.entity(e).remove::<Caustics>();
            } else {
                commands.entity(e).insert(on.0.clone());
            }
        }
    }
}

/// The floor, a glass ball, an amber glass block and the spot light.
fn spawn_scene(world: &mut World) {
    let (floor, ball, block) = {
        let mut meshes = world.resource_mut::<Assets<Mesh>>();
        (
            meshes.add(Plane3d::default().mesh().size(6.0, 6.0)),
            meshes.add(Sphere::new(0.5).mesh().uv(96, 48)),
            meshes.add(Cuboid::new(0.6, 0.6, 0.6)),
        )
    };
    let (stone, glass, amber) = {
        let mut m = world.resource_mut::<Assets<StandardMaterial>>();
        (
            m.add(StandardMaterial {
                base_color: Color::srgb(0.8, 0.8, 0.78),
                perceptual_roughness: 0.9,
                ..default()
            }),
            m.add(StandardMaterial {
                base_color: Color::WHITE,
                specular_transmission: 1.0,
                ior: 1.5,
                thickness: 1.0,
                perceptual_roughness: 0.02,
                ..default()
            }),
            m.add(StandardMaterial {
                base_color: Color::WHITE,
                specular_transmission: 1.0,
                ior: 1.5,
                thickness: 0.6,
                perceptual_roughness: 0.02,
                attenuation_color: Color::srgb(1.0, 0.55, 0.1),
                attenuation_distance: 0.4,
                ..default()
            }),
        )
    };
    world.spawn((Mesh3d(floor), MeshMaterial3d(stone), Transform::default()));
    world.spawn((
        Mesh3d(ball),
        MeshMaterial3d(glass),
        Transform::from_xyz(-0.6, 0.75, 0.0),
    ));
    world.spawn((
        Mesh3d(block),
        MeshMaterial3d(amber),
        Transform::from_xyz(0.7, 0.45, 0.3).with_rotation(Quat::from_rotation_y(0.5)),
    ));
    world.spawn((
        SpotLight {
            intensity: 600_000.0,
            range: 30.0,
            outer_angle: 0.7,
            inner_angle: 0.5,
            shadow_maps_enabled: true,
            ..default()
        },
        Transform::from_xyz(1.5, 3.5, 1.0).looking_at(Vec3::ZERO, Vec3::Y),
        Sweep,
    ));
}

/// The camera orbits the scene and the spot light sweeps around it.
fn animate(
    setup: Res<Setup>,
    mut frame: Local<u32>,
    mut cams: Query<&mut Transform, (With<Orbit>, Without<Sweep>)>,
    mut light: Query<&mut Transform, (With<Sweep>, Without<Orbit>)>,
) {
    let t = (*frame % setup.frames.max(1)) as f32 / setup.frames.max(1) as f32;
    *frame += 1;
    let _ = setup.size;
    let a = 0.6 + 0.8 * t;
    for mut c in &mut cams {
        *c = Transform::from_xyz(4.2 * a.sin(), 2.6, 4.2 * a.cos())
            .looking_at(Vec3::new(0.0, 0.3, 0.0), Vec3::Y);
    }
    let b = std::f32::consts::TAU * t * 0.5;
    for mut l in &mut light {
        *l = Transform::from_xyz(1.8 * b.cos(), 3.5, 1.8 * b.sin()).looking_at(Vec3::ZERO, Vec3::Y);
    }
}

fn half_to_f32(h: u16) -> f32 {
    let s = if h & 0x8000 != 0 { -1.0 } else { 1.0 };
    let e = ((h >> 10) & 0x1f) as i32;
    let m = (h & 0x3ff) as f32;
    s * match e {
        0 => m * 2f32.powi(-24),
        31 => f32::NAN,
        _ => (1.0 + m / 1024.0) * 2f32.powi(e - 15),
    }
}
