//! Sspm's raw and filtered estimates (the caustic reference's settings) on the CPU backend
//! against the independent light-tracer reference, at several photon grids:
//!
//! `cargo run --release -p caustica --example sspm_against_light_tracer -- SCENE WxH
//! LT_PHOTONS LT_BATCHES SIDE[,SIDE...] SEEDS [mesh|analytic|both]
//! [eye-visible|centre-surface] [FRAMES] [SEGMENTS]`
//!
//! prints the tracer's own noise (relative standard error of its mean over the caustic
//! mask) and, per photon grid, each seed's relative L2 error (sqrt of the relative MSE over
//! the reference's caustic mask) of the raw deposit and of the filtered output, the mean of
//! the seeds' frames, the flux ratio (the image's radiance summed over every pixel, over
//! the tracer's: both images share the pixels' areas) and the peak ratio. `FRAMES` > 1
//! accumulates that many frames per seed (`frame.accumulate`: one estimate of all their
//! photons). `both` computes the tracer with the tessellated ball and with the exact
//! sphere, prints the mesh's difference from the sphere (the faceting's share, beside the
//! two tracers' combined noise) and measures Sspm against each. `SEGMENTS` retessellates
//! every sphere shape of the scene with that many segments (the scene's own by default).

use caustica::backends::cpu::CpuBackend;
use caustica::metrics::{peak_ratio, relative_mse, CausticMask};
use caustica::reference::light_tracer::{
    load_or_compute, silhouette_pixels, LightTracerInfo, LightTracerSpec, SilhouetteDefinition,
    SphereModel,
};
use caustica::reference::CAUSTIC_REFERENCE;
use caustica::technique_spec::put_setting;
use caustica::techniques::create;
use caustica::Image;
use std::path::Path;

/// One tracer reference with its masks (with and without the silhouette pixels).
struct Reference {
    model: SphereModel,
    image: Image,
    info: LightTracerInfo,
    mask: CausticMask,
    inner: Image,
    inner_mask: CausticMask,
}

/// Sum of the three channels over every pixel.
fn total(img: &Image) -> f64 {
    img.pixels
        .iter()
        .map(|p| p[0] as f64 + p[1] as f64 + p[2] as f64)
        .sum()
}

fn mean_image(frames: &[Image]) -> Image {
    let (w, h) = (frames[0].width, frames[0].height);
    let mut sum: Vec<[f64; 3]> = vec![[0.0; 3]; (w * h) as usize];
    for img in frames {
        for (s, p) in sum.iter_mut().zip(&img.pixels) {
            for c in 0..3 {
                s[c] += p[c] as f64 / frames.len() as f64;
            }
        }
    }
    Image::new(
        w,
        h,
        sum.iter()
            .map(|s| [s[0] as f32, s[1] as f32, s[2] as f32, 1.0])
            .collect(),
    )
}

fn list(v: &[f64]) -> String {
    v.iter()
        .map(|e| format!("{e:.4}"))
        .collect::<Vec<_>>()
        .join(" ")
}

fn main() -> Result<(), String> {
    let a: Vec<String> = std::env::args().skip(1).collect();
    let arg = |i: usize, d: &str| a.get(i).cloned().unwrap_or_else(|| d.to_string());
    let mut scene =
        caustica::scene::builtin::builtin(&arg(0, "sphere")).ok_or("unknown built-in scene")?;
    let size = arg(1, "160x90");
    let (w, h) = size
        .split_once('x')
        .and_then(|(w, h)| Some((w.parse::<u32>().ok()?, h.parse::<u32>().ok()?)))
        .ok_or("size WxH")?;
    let models = match arg(6, "mesh").as_str() {
        "analytic" => vec![SphereModel::Analytic],
        "mesh" => vec![SphereModel::Mesh],
        "both" => vec![SphereModel::Mesh, SphereModel::Analytic],
        other => return Err(format!("sphere model '{other}': mesh, analytic or both")),
    };
    let base = LightTracerSpec {
        width: w,
        height: h,
        photons: arg(2, "4194304").parse().map_err(|_| "photons")?,
        batches: arg(3, "8").parse().map_err(|_| "batches")?,
        silhouette: arg(7, "eye-visible")
            .parse::<SilhouetteDefinition>()
            .map_err(|e| e.to_string())?,
        ..LightTracerSpec::default()
    };
    let sides: Vec<u32> = arg(4, "256,512,1024")
        .split(',')
        .map(|s| s.parse().map_err(|_| "side"))
        .collect::<Result<_, _>>()?;
    let seeds: u32 = arg(5, "2").parse().map_err(|_| "seeds")?;
    let frames: u32 = arg(8, "1").parse().map_err(|_| "frames")?;
    if seeds == 0 || frames == 0 {
        return Err("seeds and frames must be positive".into());
    }
    if let Some(n) = a.get(9) {
        let n: u32 = n.parse().map_err(|_| "segments")?;
        for o in &mut scene.objects {
            if let caustica::scene::Shape::Sphere { segments, .. } = &mut o.shape {
                *segments = n;
            }
        }
        println!("sphere shapes tessellated with {n} segments");
    }
    let mut refs = Vec::new();
    for model in models {
        let spec = LightTracerSpec {
            spheres: model,
            ..base.clone()
        };
        let (image, info) = load_or_compute(
            Path::new("out/references"),
            &scene,
            &spec,
            &mut |k, n, e| {
                eprintln!(
                    "light tracer ({}) batch {k}/{n}: noise {e:.5}",
                    model.name()
                )
            },
        )?;
        println!(
            "light tracer ({}, silhouette pixels {}): {} photons, noise {:.5}, flux (sum) {:.6e}",
            model.name(),
            spec.silhouette,
            info.photons,
            info.noise,
            total(&image)
        );
        let mask = CausticMask::from_reference(&image);
        // the same mask without the silhouette pixels, where Sspm's store test keeps
        // photons the ball hides from the eye and the light tracer does not
        let silhouette = silhouette_pixels(&scene, &spec)?;
        let mut inner = image.clone();
        for (p, s) in inner.pixels.iter_mut().zip(&silhouette) {
            if *s {
                *p = [0.0; 4];
            }
        }
        let inner_mask = CausticMask::from_reference(&inner);
        refs.push(Reference {
            model,
            image,
            info,
            mask,
            inner,
            inner_mask,
        });
    }
    if let [m, s] = &refs[..] {
        println!(
            "tracer mesh against tracer analytic: rel L2 {:.4} (without silhouette pixels \
             {:.4}), combined noise {:.4}, flux ratio {:.5}, peak ratio {:.4}",
            relative_mse(&m.image, &s.image, &s.mask).sqrt(),
            relative_mse(&m.inner, &s.inner, &s.inner_mask).sqrt(),
            (m.info.noise.powi(2) + s.info.noise.powi(2)).sqrt(),
            total(&m.image) / total(&s.image),
            peak_ratio(&m.image, &s.image, &s.mask),
        );
    }
    scene.camera.width = w;
    scene.camera.height = h;
    let (name, overrides) = caustica::technique_spec::technique_spec(CAUSTIC_REFERENCE)?;
    let mut b = CpuBackend::new().map_err(|e| e.to_string())?;
    for side in sides {
        let mut settings = serde_json::Map::new();
        settings.extend(overrides.clone());
        put_setting(&mut settings, "frame.photons_w", side.into());
        put_setting(&mut settings, "frame.photons_h", side.into());
        if frames > 1 {
            put_setting(&mut settings, "frame.accumulate", true.into());
        }
        let settings = serde_json::Value::Object(settings);
        let (mut raws, mut filtereds) = (Vec::new(), Vec::new());
        for seed in 1..=seeds {
            // an accumulation of its own per seed
            let mut t = create(name, &mut b, &scene, &settings).map_err(|e| e.to_string())?;
            let (filtered, raw) = t.estimate_outputs();
            t.set_seed(seed);
            for _ in 0..frames {
                t.frame(&mut b, &mut |_| {}).map_err(|e| e.to_string())?;
            }
            raws.push(t.read_output(&mut b, raw).map_err(|e| e.to_string())?);
            filtereds.push(t.read_output(&mut b, filtered).map_err(|e| e.to_string())?);
            t.free(&mut b).map_err(|e| e.to_string())?;
        }
        for r in &refs {
            for (what, imgs) in [("raw", &raws), ("filtered", &filtereds)] {
                let errs: Vec<f64> = imgs
                    .iter()
                    .map(|i| relative_mse(i, &r.image, &r.mask).sqrt())
                    .collect();
                let inner: Vec<f64> = imgs
                    .iter()
                    .map(|i| relative_mse(i, &r.inner, &r.inner_mask).sqrt())
                    .collect();
                let flux: Vec<f64> = imgs.iter().map(|i| total(i) / total(&r.image)).collect();
                let peak: Vec<f64> = imgs
                    .iter()
                    .map(|i| peak_ratio(i, &r.image, &r.mask))
                    .collect();
                let mean = mean_image(imgs);
                println!(
                    "sspm {what} {side}x{side} x {frames} frame(s) vs {} tracer: rel L2 {} \
                     (mean of the {seeds} seeds {:.4}); without silhouette pixels {} \
                     (mean {:.4}); flux ratio {}; peak ratio {}",
                    r.model.name(),
                    list(&errs),
                    relative_mse(&mean, &r.image, &r.mask).sqrt(),
                    list(&inner),
                    relative_mse(&mean, &r.inner, &r.inner_mask).sqrt(),
                    list(&flux),
                    list(&peak),
                );
            }
        }
    }
    Ok(())
}
