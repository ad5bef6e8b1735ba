//! A real-time host's frame loop, headless: the "renderer" owns the wgpu device, its
//! queue and an `Rgba16Float` texture. It drives each of the four techniques in turn:
//! every frame it moves the light and the glass ball (an instance) through caustica's
//! update API, records the technique's whole frame into *its own* command encoder, has
//! the technique's filtered light (caustics, or PhotonGi's indirect light:
//! `Technique::output_image`) written into its texture in the same encoder, and submits
//! once. Each frame's statistics (pass times, photon counts) are collected a few
//! frames later, when the device has finished that frame. It prints the update (its
//! median, then the medians of `set_lights` and of `set_object_transforms` in brackets)
//! and record times and the host waits inside `record_frame` per frame (device waits and
//! blocking readbacks a technique still needs while recording).
//! Run: `cargo run --release -p caustica --example frame_loop -- [WxH] [PHOTONS] [FRAMES]`.

use caustica::backends::wgpu::WgpuBackend;
use caustica::scene::builtin::builtin;
use caustica::scene::{Light, Shape, Transform};
use caustica::{glam, wgpu};
use caustica::{FrameTicket, Output};
use std::collections::VecDeque;
use std::time::Instant;

/// Frames the host lets the device run behind before it waits for the oldest.
const MAX_IN_FLIGHT: usize = 2;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (w, h): (u32, u32) = match args.first() {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("size is WxH")?;
            (a.parse()?, b.parse()?)
        }
        None => (640, 360),
    };
    let side: u32 = args.get(1).map_or(Ok(512), |s| s.parse())?;
    let frames: usize = args.get(2).map_or(Ok(100), |s| s.parse())?;

    // --- the host renderer's device, queue and texture --------------------------------
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor {
        backends: wgpu::Backends::PRIMARY,
        ..wgpu::InstanceDescriptor::new_without_display_handle()
    });
    let adapter =
        pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions::default()))?;
    let (device, queue) = pollster::block_on(adapter.request_device(&wgpu::DeviceDescriptor {
        required_limits: adapter.limits(),
        required_features: adapter.features() & wgpu::Features::TIMESTAMP_QUERY,
        ..Default::default()
    }))?;
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("renderer's caustics texture"),
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

    // --- caustica on the renderer's device: `sphere`, its glass ball an instance --------
    let name = adapter.get_info().name;
    let mut backend = WgpuBackend::from_device(device.clone(), queue.clone(), &name)?;
    let mut scene = builtin("sphere").ok_or("no sphere scene")?;
    scene.camera.width = w;
    scene.camera.height = h;
    let ball = 1;
    let Shape::Sphere { center, .. } = &mut scene.objects[ball].shape else {
        return Err("sphere's object 1 is its glass ball".into());
    };
    let home = std::mem::replace(center, glam::Vec3::ZERO);
    scene.objects[ball].transform = Some(Transform::from_translation(home));
    println!("{name}: {frames} frames a technique at {w}x{h}, {side}x{side} photons, moving light and ball");

    for technique in ["sspm", "caustic-map", "adaptive-caustics", "photon-gi"] {
        // the renderer does its own direct light: only the technique's filtered light
        let light = if technique == "photon-gi" {
            Output::FilteredIndirect
        } else {
            Output::FilteredCaustics
        };
        let mut settings = serde_json::json!({
            "frame": { "photons_w": side, "photons_h": side, "outputs": [light] }
        });
        if technique.contains("caustic") {
            // an atlas of 512^2 texels over the two receivers
            settings["atlas"] = serde_json::json!({ "atlas_size": 512 });
        }
        let mut t = caustica::techniques::create(technique, &mut backend, &scene, &settings)?;
        // the device image the host copies into its texture each frame (`None`: no light
        // reaches a caster, the image is black)
        let added = t.output_image(light)?;
        let mut l = Loop::default();
        let mut in_flight: VecDeque<FrameTicket> = VecDeque::new();
        let start = Instant::now();
        for f in 0..frames {
            let phase = f as f32 / frames as f32 * std::f32::consts::TAU;
            // updates: the light circles, the ball bobs and turns (no rebuild)
            let t0 = Instant::now();
            let mut lights = scene.lights.clone();
            if let Light::Point { position, .. } = &mut lights[0] {
                *position += glam::Vec3::new(0.4 * phase.cos(), 0.0, 0.4 * phase.sin());
            }
            t.set_lights(&mut backend, &lights)?;
            let t_lights = Instant::now();
            let placement = Transform {
                translation: home + glam::Vec3::new(0.0, 0.15 * phase.sin(), 0.0),
                rotation: glam::Quat::from_rotation_y(phase),
                scale: glam::Vec3::ONE,
            };
            t.set_object_transforms(&mut backend, &[(ball, placement)])?;
            let t1 = Instant::now();

            // the frame, into the host's encoder, with the host's own work after it
            let recorded = t.record_frame(&mut backend)?;
            l.host_waits.push(recorded.stats.host_waits as f64);
            let mut encoder = device.create_command_encoder(&Default::default());
            let submission =
                backend.encode(&recorded.recording, &recorded.readbacks, &mut encoder)?;
            if let Some(c) = added {
                backend.encode_image_to_texture(c, &texture, &mut encoder)?;
            }
            let index = queue.submit([encoder.finish()]);
            backend.submitted(&submission, Some(index))?;
            in_flight.push_back(recorded.submitted(submission));
            let t2 = Instant::now();
            l.update_ms.push((t1 - t0).as_secs_f64() * 1e3);
            l.lights_ms.push((t_lights - t0).as_secs_f64() * 1e3);
            l.moves_ms.push((t1 - t_lights).as_secs_f64() * 1e3);
            l.record_ms.push((t2 - t1).as_secs_f64() * 1e3);

            // statistics of earlier frames, if the device has finished them (never waits)
            while let Some(ticket) = in_flight.front_mut() {
                if !l.collect(ticket, &mut backend, false)? {
                    break;
                }
                in_flight.pop_front();
            }
            // frame pacing, as a presenting host gets from its swap chain: at most
            // MAX_IN_FLIGHT frames on the device, else the host waits for the oldest
            if in_flight.len() > MAX_IN_FLIGHT {
                let t3 = Instant::now();
                let mut ticket = in_flight.pop_front().expect("not empty");
                l.collect(&mut ticket, &mut backend, true)?;
                l.paced_ms += t3.elapsed().as_secs_f64() * 1e3;
            }
        }
        let loop_ms = start.elapsed().as_secs_f64() * 1e3 / frames as f64;
        for ticket in in_flight.iter_mut() {
            l.collect(ticket, &mut backend, true)?;
        }
        t.free(&mut backend)?;
        l.print(technique, loop_ms, frames);
        if l.stored == 0 {
            return Err(format!("{technique}: no photon was stored").into());
        }
    }
    Ok(())
}

/// One technique's loop: per-frame figures and photon totals.
#[derive(Default)]
struct Loop {
    update_ms: Vec<f64>,
    lights_ms: Vec<f64>,
    moves_ms: Vec<f64>,
    record_ms: Vec<f64>,
    device_ms: Vec<f64>,
    host_waits: Vec<f64>,
    paced_ms: f64,
    stored: u64,
}

impl Loop {
    /// Collects a finished frame's statistics (`wait`: wait for it); whether it had
    /// finished.
    fn collect(
        &mut self,
        t: &mut FrameTicket,
        b: &mut WgpuBackend,
        wait: bool,
    ) -> Result<bool, caustica::Error> {
        Ok(t.stats(b, wait)?.is_some_and(|s| {
            self.stored += s.photons_stored;
            self.device_ms
                .push(s.passes.iter().map(|p| p.ms).sum::<f64>());
            true
        }))
    }

    fn print(&mut self, technique: &str, loop_ms: f64, frames: usize) {
        let stat = |v: &mut Vec<f64>| {
            v.sort_by(f64::total_cmp);
            let n = v.len().max(1);
            (
                v.get(n / 2).copied().unwrap_or(0.0),
                v.last().copied().unwrap_or(0.0),
            )
        };
        let (u_med, u_max) = stat(&mut self.update_ms);
        let (l_med, _) = stat(&mut self.lights_ms);
        let (m_med, _) = stat(&mut self.moves_ms);
        let (r_med, r_max) = stat(&mut self.record_ms);
        let (d_med, d_max) = stat(&mut self.device_ms);
        let (w_med, w_max) = stat(&mut self.host_waits);
        println!("{technique}:");
        println!("  update (set_lights + set_object_transforms), host: median {u_med:.3} ms ({l_med:.3} + {m_med:.3}), max {u_max:.3} ms");
        println!("  frame record + encode + submit, host:             median {r_med:.3} ms, max {r_max:.3} ms");
        println!(
            "  host waits inside record_frame, per frame:        median {w_med:.0}, max {w_max:.0}"
        );
        if self.device_ms.iter().any(|&d| d > 0.0) {
            println!("  frame passes on the device (timestamps):          median {d_med:.3} ms, max {d_max:.3} ms");
        } else {
            println!(
                "  frame passes on the device: not timed (the adapter has no timestamp queries)"
            );
        }
        println!(
            "  loop {loop_ms:.1} ms/frame on the host; frame pacing (at most {MAX_IN_FLIGHT} in \
             flight): the host waited {:.1} ms/frame; {} photons stored in all",
            self.paced_ms / frames as f64,
            self.stored
        );
    }
}
