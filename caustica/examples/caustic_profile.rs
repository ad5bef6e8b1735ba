//! The radial profile of `sphere`'s caustic in an image against a reference: relative
//! MSE over the reference's caustic mask, and per ring of the plane around the ball's
//! axis (scene units, the pixel centre's ray met with the plane y = 0) the summed
//! radiance of both and the ring's share of the squared error.
//!
//! `cargo run --release -p caustica --example caustic_profile -- REFERENCE.exr IMAGE.exr [RING]`
//! (`RING`: ring width, scene units, default 0.01). The camera is `sphere`'s: (0, 4, 3)
//! looking at the origin, 45 degrees vertical field of view.

use caustica_core::frame::image::Image;
use caustica_core::frame::metrics::{relative_mse, CausticMask};
use glam::Vec3;

fn read_exr(path: &str) -> Image {
    caustica::output::read_exr(std::path::Path::new(path)).unwrap_or_else(|e| panic!("{e}"))
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.len() < 3 {
        eprintln!("usage: caustic_profile REFERENCE.exr IMAGE.exr [RING]");
        std::process::exit(2);
    }
    if let Ok(row) = std::env::var("ROW") {
        // one row of an image (e.g. the atlas): ROW=y COLS=a-b caustic_profile _ IMAGE.exr
        let img = read_exr(&args[2]);
        let y: usize = row.parse().unwrap();
        let cols = std::env::var("COLS").unwrap_or("0-16".into());
        let (a, b) = cols.split_once('-').unwrap();
        for x in a.parse::<usize>().unwrap()..=b.parse::<usize>().unwrap() {
            let p = img.pixels[y * img.width as usize + x];
            println!("{x} {:.2}", p[0] + p[1] + p[2]);
        }
        return;
    }
    let (r, x) = (read_exr(&args[1]), read_exr(&args[2]));
    let ring: f32 = args.get(3).and_then(|s| s.parse().ok()).unwrap_or(0.01);
    assert_eq!((r.width, r.height), (x.width, x.height), "sizes differ");
    let mask = CausticMask::from_reference(&r);
    let e = relative_mse(&x, &r, &mask);
    let (w, h) = (r.width as usize, r.height as usize);
    let eye = Vec3::new(0.0, 4.0, 3.0);
    let f = (-eye).normalize();
    let right = f.cross(Vec3::Y).normalize();
    let up = right.cross(f);
    let t = (22.5f32).to_radians().tan();
    let aspect = w as f32 / h as f32;
    let bins = 40usize;
    let mut sum_r = vec![0.0f64; bins + 1];
    let mut sum_x = vec![0.0f64; bins + 1];
    let mut err = vec![0.0f64; bins + 1];
    let mut pixels = vec![0usize; bins + 1];
    let (mut total_err, mut total_ref2, mut flux_r, mut flux_x) = (0.0f64, 0.0f64, 0.0, 0.0);
    for py in 0..h {
        for px in 0..w {
            let i = py * w + px;
            if !mask.inside[i] {
                continue;
            }
            let sx = (2.0 * (px as f32 + 0.5) / w as f32 - 1.0) * t * aspect;
            let sy = (1.0 - 2.0 * (py as f32 + 0.5) / h as f32) * t;
            let d = f + right * sx + up * sy;
            let hit = eye + d * (-eye.y / d.y);
            let rad = (hit.x * hit.x + hit.z * hit.z).sqrt();
            let b = ((rad / ring) as usize).min(bins);
            let (p, q) = (x.pixels[i], r.pixels[i]);
            for c in 0..3 {
                let d = p[c] as f64 - q[c] as f64;
                err[b] += d * d;
                total_err += d * d;
                total_ref2 += (q[c] as f64).powi(2);
                sum_r[b] += q[c] as f64;
                sum_x[b] += p[c] as f64;
                flux_r += q[c] as f64;
                flux_x += p[c] as f64;
            }
            pixels[b] += 1;
        }
    }
    println!(
        "relMSE {e:.4e}  rel L2 {:.5}  mask {} px  image/reference sum {:.5}",
        e.sqrt(),
        mask.count,
        flux_x / flux_r
    );
    if std::env::var("DUMP").is_ok() {
        let xi = &x;
        let lum = |p: [f32; 4]| p[0] + p[1] + p[2];
        let peak = (0..w * h)
            .max_by(|&a, &b| lum(r.pixels[a]).total_cmp(&lum(r.pixels[b])))
            .unwrap();
        let (cx, cy) = (peak % w, peak / w);
        println!("peak at ({cx}, {cy}): reference sum rgb, then image / reference");
        for y in cy - 4..=cy + 4 {
            let row: Vec<String> = (cx - 4..=cx + 4)
                .map(|x| format!("{:9.1}", lum(r.pixels[y * w + x])))
                .collect();
            println!("{}", row.join(" "));
        }
        for y in cy - 4..=cy + 4 {
            let row: Vec<String> = (cx - 4..=cx + 4)
                .map(|x| {
                    format!(
                        "{:9.4}",
                        lum(xi.pixels[y * w + x]) / lum(r.pixels[y * w + x])
                    )
                })
                .collect();
            println!("{}", row.join(" "));
        }
    }
    println!("ring (units) | pixels | image/reference | share of squared error | relMSE of ring vs total ref^2");
    for b in 0..=bins {
        if pixels[b] == 0 {
            continue;
        }
        println!(
            "{:.3}-{:.3} | {} | {:.4} | {:.3} | {:.3e}",
            b as f32 * ring,
            (b + 1) as f32 * ring,
            pixels[b],
            sum_x[b] / sum_r[b].max(1e-30),
            err[b] / total_err.max(1e-30),
            err[b] / total_ref2.max(1e-30)
        );
    }
}
