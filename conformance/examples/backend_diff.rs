//! Renders every built-in scene on every backend found and prints, per output image, the
//! relative L2 difference from the CPU backend, plus photon counts and stored flux.
//! `cargo run --release -p caustica-conformance --example backend_diff -- [WxH] [PWxPH]`
//! (defaults 320x180 and 256x256).

use caustica_conformance::{backends, render, small_settings};
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};

fn parse(s: Option<String>, default: (u32, u32)) -> (u32, u32) {
    s.and_then(|s| {
        let (a, b) = s.split_once('x')?;
        Some((a.parse().ok()?, b.parse().ok()?))
    })
    .unwrap_or(default)
}

/// sqrt(sum |a - b|^2 / sum |b|^2) over rgb (0 when both are black).
fn relative_l2(
    a: &caustica_core::frame::image::Image,
    b: &caustica_core::frame::image::Image,
) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (p, q) in a.pixels.iter().zip(&b.pixels) {
        for c in 0..3 {
            num += (p[c] as f64 - q[c] as f64).powi(2);
            den += (q[c] as f64).powi(2);
        }
    }
    if den == 0.0 {
        num.sqrt()
    } else {
        (num / den).sqrt()
    }
}

fn main() {
    let mut args = std::env::args().skip(1);
    let (w, h) = parse(args.next(), (320, 180));
    let (pw, _ph) = parse(args.next(), (256, 256));
    let mut all = backends();
    println!(
        "{:<8} {:<8} {:>9} {:>9} {:>11} {:>11} {:>11} {:>11}",
        "scene", "backend", "stored", "deposited", "composite", "raw", "filtered", "direct"
    );
    for name in BUILTIN_SCENES {
        let scene = builtin(name).expect("built-in scene");
        let mut reference = None;
        for (bname, backend) in all.iter_mut() {
            let (stats, images) = render(backend.as_mut(), &scene, small_settings(pw), w, h);
            let reference = reference.get_or_insert_with(|| images.clone());
            let d: Vec<f64> = images
                .iter()
                .zip(reference.iter())
                .map(|(a, b)| relative_l2(a, b))
                .collect();
            println!(
                "{name:<8} {bname:<8} {:>9} {:>9} {:>11.3e} {:>11.3e} {:>11.3e} {:>11.3e}",
                stats.photons_stored, stats.photons_deposited, d[0], d[1], d[2], d[3]
            );
        }
    }
}
