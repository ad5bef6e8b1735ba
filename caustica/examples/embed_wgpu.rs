//! Embedding caustica in a wgpu renderer, headless: the "renderer" below owns the wgpu
//! device, queue and an `Rgba16Float` texture; caustica renders the `sphere` scene's
//! caustics on that device and writes them into the renderer's texture, which the
//! renderer then reads back here to show that the texels arrived. `frame` still submits
//! and waits on the renderer's queue (recording into the host's own encoder without a
//! CPU wait is the `frame_loop` example).
//! Run: `cargo run --release -p caustica --example embed_wgpu -- [WxH] [PHOTONS]`.

use caustica::backends::wgpu::WgpuBackend;
use caustica::scene::builtin::builtin;
use caustica::wgpu;
use caustica::{Output, Outputs, Sspm, SspmSettings, TechniqueSettings};

fn main() -> Result<(), Box<dyn std::error::Error>> {
    // --- the host renderer's own device and texture -------------------------------
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
    let args: Vec<String> = std::env::args().skip(1).collect();
    let (w, h): (u32, u32) = match args.first() {
        Some(s) => {
            let (a, b) = s.split_once('x').ok_or("size is WxH")?;
            (a.parse()?, b.parse()?)
        }
        None => (320, 180),
    };
    let side: u32 = args.get(1).map_or(Ok(512), |s| s.parse())?;
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
        usage: wgpu::TextureUsages::STORAGE_BINDING
            | wgpu::TextureUsages::TEXTURE_BINDING
            | wgpu::TextureUsages::COPY_SRC,
        view_formats: &[],
    });

    // --- caustica on the renderer's device -----------------------------------------
    let name = adapter.get_info().name;
    let mut backend = WgpuBackend::from_device(device.clone(), queue.clone(), &name)?;
    let mut scene = builtin("sphere").ok_or("no sphere scene")?;
    scene.camera.width = w;
    scene.camera.height = h;
    // the renderer does its own direct light: no direct_light or composite pass
    let settings = SspmSettings::default()
        .with_photons(side, side)
        .with_outputs(Outputs::CAUSTICS_ONLY);
    let mut sspm = Sspm::new(&mut backend, &scene, settings)?;
    let stats = sspm.frame(&mut backend, &mut |_| {})?;
    // `None` when no light reaches a caustic caster (the caustics are zero)
    let caustics = sspm
        .output_image(Output::FilteredCaustics)?
        .ok_or("no light reaches a caustic caster")?;
    backend.write_image_to_texture(caustics, &texture)?;
    sspm.free(&mut backend)?;
    println!(
        "{name}: {} photons stored, {} deposited, frame {:.1} ms ({})",
        stats.photons_stored, stats.photons_deposited, stats.frame_ms, stats.timing
    );

    // --- the renderer reads its texture back (only to show that it was written) ------
    let row = (w * 8).next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("texture readback"),
        size: (row * h) as u64,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut enc = device.create_command_encoder(&Default::default());
    enc.copy_texture_to_buffer(
        texture.as_image_copy(),
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(row),
                rows_per_image: Some(h),
            },
        },
        texture.size(),
    );
    queue.submit([enc.finish()]);
    staging.slice(..).map_async(wgpu::MapMode::Read, |_| {});
    device.poll(wgpu::PollType::wait_indefinitely())?;
    let data = staging.slice(..).get_mapped_range()?;
    let lit = (0..h)
        .flat_map(|y| (0..w).map(move |x| (y * row + x * 8) as usize))
        .filter(|&o| u16::from_le_bytes([data[o], data[o + 1]]) != 0)
        .count();
    println!("texture: {lit} of {} texels carry caustic radiance", w * h);
    Ok(())
}
