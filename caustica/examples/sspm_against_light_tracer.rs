//! Sspm's raw estimate (one frame, the caustic reference's settings) on the CPU backend
//! against the independent light-tracer reference, at several photon grids:
//!
//! `cargo run --release -p caustica --example sspm_against_light_tracer -- SCENE WxH
//! LT_PHOTONS LT_BATCHES SIDE[,SIDE...] SEEDS [mesh|analytic] [eye-visible|centre-surface]`
//!
//! prints, per photon grid, the relative L2 error (sqrt of the relative MSE over the
//! reference's caustic mask) of each seed's frame, and the reference's own noise.

use caustica::backends::cpu::CpuBackend;
use caustica::metrics::{relative_mse, CausticMask};
use caustica::reference::light_tracer::{
    load_or_compute, silhouette_pixels, LightTracerSpec, SilhouetteDefinition, SphereModel,
};
use caustica::reference::CAUSTIC_REFERENCE;
use caustica::techniques::create;
use std::path::Path;

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
    let spec = LightTracerSpec {
        width: w,
        height: h,
        photons: arg(2, "4194304").parse().map_err(|_| "photons")?,
        batches: arg(3, "8").parse().map_err(|_| "batches")?,
        spheres: if arg(6, "mesh") == "analytic" {
            SphereModel::Analytic
        } else {
            SphereModel::Mesh
        },
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
    let (reference, info) = load_or_compute(
        Path::new("out/references"),
        &scene,
        &spec,
        &mut |k, n, e| eprintln!("light tracer batch {k}/{n}: noise {e:.5}"),
    )?;
    println!(
        "light tracer ({:?}, silhouette pixels {}): {} photons, noise {:.5}",
        spec.spheres, spec.silhouette, info.photons, info.noise
    );
    let mask = CausticMask::from_reference(&reference);
    // the same mask without the silhouette pixels, where Sspm's store test keeps photons
    // the ball hides from the eye and the light tracer does not
    let silhouette = silhouette_pixels(&scene, &spec)?;
    let mut inner = reference.clone();
    for (p, s) in inner.pixels.iter_mut().zip(&silhouette) {
        if *s {
            *p = [0.0; 4];
        }
    }
    let inner_mask = CausticMask::from_reference(&inner);
    scene.camera.width = w;
    scene.camera.height = h;
    let (name, overrides) = caustica::technique_spec::technique_spec(CAUSTIC_REFERENCE)?;
    let mut b = CpuBackend::new().map_err(|e| e.to_string())?;
    for side in sides {
        let mut settings = serde_json::Map::new();
        settings.insert("photons_w".into(), side.into());
        settings.insert("photons_h".into(), side.into());
        settings.extend(overrides.clone());
        let settings = serde_json::Value::Object(settings);
        let mut t = create(name, &mut b, &scene, &settings).map_err(|e| e.to_string())?;
        let (_, raw) = t.estimate_outputs();
        let (mut errs, mut inner_errs) = (Vec::new(), Vec::new());
        let mut sum: Vec<[f64; 3]> = vec![[0.0; 3]; (w * h) as usize];
        for seed in 1..=seeds {
            t.set_seed(seed);
            t.frame(&mut b, &mut |_| {}).map_err(|e| e.to_string())?;
            let img = t.read_output(&mut b, raw).map_err(|e| e.to_string())?;
            errs.push(relative_mse(&img, &reference, &mask).sqrt());
            inner_errs.push(relative_mse(&img, &inner, &inner_mask).sqrt());
            for (s, p) in sum.iter_mut().zip(&img.pixels) {
                for c in 0..3 {
                    s[c] += p[c] as f64 / seeds as f64;
                }
            }
        }
        t.free(&mut b).map_err(|e| e.to_string())?;
        let mean = caustica::Image::new(
            w,
            h,
            sum.iter()
                .map(|s| [s[0] as f32, s[1] as f32, s[2] as f32, 1.0])
                .collect(),
        );
        let list = |v: &[f64]| {
            v.iter()
                .map(|e| format!("{e:.4}"))
                .collect::<Vec<_>>()
                .join(" ")
        };
        println!(
            "sspm raw {side}x{side}: rel L2 {} (mean of the {seeds} frames {:.4}); \
             without silhouette pixels {} (mean {:.4})",
            list(&errs),
            relative_mse(&mean, &reference, &mask).sqrt(),
            list(&inner_errs),
            relative_mse(&mean, &inner, &inner_mask).sqrt(),
        );
    }
    Ok(())
}
