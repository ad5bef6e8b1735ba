//! The density gather keeps the raw deposit's flux, on every backend
//! found, on every built-in scene with caustics, framed twice: as built, and zoomed in
//! 2x about the view axis so that caustics run off the image and the gather's windows
//! are clipped by the border. The flux of an image is `sum L pi A / albedo` over the
//! receiver pixels (per channel, albedo > 0), with `A` the pixel's surface area from the
//! backend's own G-buffer: the irradiance times the area, the quantity the gather moves.
//!
//! Tolerance: `|filtered / raw - 1| <= FLUX_REL = 1e-4`. In real arithmetic the two are
//! equal (each pass normalises every source over the destinations that exist: receivers
//! inside the image, with the edge weights; `caustica_core::math::density_gather`). In
//! f32 each source's shares `F w_ij / W` sum to `F` within the rounding of a <= 33-term sum
//! and a division, ~35 ulp ~ 2e-6 per pass; the raw resolve and the last pass convert
//! flux to radiance with the pixel's area (~1e-5 relative each, `RESOLVE_REL`), which the
//! test inverts with the CPU's area. ~3e-5 in all, hence 1e-4 (the filter's target is 0.5%).
//!
//! The test also measures, and requires to be non-zero over the cases, the share of the
//! raw flux that lies within the gather's reach of the image border and of a depth or
//! receiver edge, so that both situations are exercised, not assumed.

use caustica_conformance::backends;
use caustica_conformance::harness::Report;
use caustica_conformance::harness::Verdict;
use caustica_conformance::techniques::sspm::{render_frame, Frame};
use caustica_core::device::layout::{gbuffer_flags, gbuffer_pixel_area, GpuCamera};
use caustica_core::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica_core::scene::Scene;
use caustica_core::{FrameSettings, ScreenSettings};
use caustica_core::{GatherFilter, SspmSettings};

const FLUX_REL: f64 = 1e-4;

/// Incident flux per channel of an image (W): `sum L pi A / albedo` over receivers.
fn image_flux(scene: &Scene, f: &Frame, img: &[[f32; 4]]) -> [f64; 3] {
    let cam = GpuCamera::from_camera(&scene.camera);
    let mut flux = [0.0f64; 3];
    for (i, g) in f.gbuffer.iter().enumerate() {
        if g.flags & gbuffer_flags::RECEIVER == 0 {
            continue;
        }
        let a = gbuffer_pixel_area(&cam, i as u32, g) as f64;
        for c in 0..3 {
            if g.albedo[c] > 0.0 {
                flux[c] += img[i][c] as f64 * std::f64::consts::PI * a / g.albedo[c] as f64;
            }
        }
    }
    flux
}

/// Share of the raw flux (summed channels) on pixels within `reach` of the image border,
/// and within `reach` (along a row or column) of a depth or receiver edge.
fn edge_shares(scene: &Scene, f: &Frame, reach: i32) -> (f64, f64) {
    let cam = GpuCamera::from_camera(&scene.camera);
    let (w, h) = (cam.width as i32, cam.height as i32);
    let g = &f.gbuffer;
    // an edge lies between two adjacent pixels that differ in receiver flag or material,
    // or whose normals turn by more than ~25 degrees (a silhouette or a crease)
    let edge_between = |i: usize, j: usize| {
        let (a, b) = (&g[i], &g[j]);
        let dot = a.normal[0] * b.normal[0] + a.normal[1] * b.normal[1] + a.normal[2] * b.normal[2];
        (a.flags & gbuffer_flags::RECEIVER) != (b.flags & gbuffer_flags::RECEIVER)
            || a.material != b.material
            || dot < 0.9
    };
    let (mut total, mut border, mut edge) = (0.0f64, 0.0f64, 0.0f64);
    for y in 0..h {
        for x in 0..w {
            let i = (y * w + x) as usize;
            let v: f64 = f.raw.pixels[i][..3].iter().map(|&c| c as f64).sum();
            if v <= 0.0 {
                continue;
            }
            total += v;
            if x < reach || y < reach || x >= w - reach || y >= h - reach {
                border += v;
            }
            let inside = |qx: i32, qy: i32| qx >= 0 && qy >= 0 && qx < w && qy < h;
            let near_edge = (-reach..reach).any(|d| {
                [((x + d, y), (x + d + 1, y)), ((x, y + d), (x, y + d + 1))]
                    .iter()
                    .any(|&((ax, ay), (bx, by))| {
                        inside(ax, ay)
                            && inside(bx, by)
                            && edge_between((ay * w + ax) as usize, (by * w + bx) as usize)
                    })
            });
            if near_edge {
                edge += v;
            }
        }
    }
    if total > 0.0 {
        (border / total, edge / total)
    } else {
        (0.0, 0.0)
    }
}

#[test]
fn density_gather_keeps_the_raw_flux_on_every_backend() {
    let mut report = Report::new("filtered flux = raw flux");
    let settings = SspmSettings {
        frame: FrameSettings {
            photons_w: 128,
            photons_h: 128,
            ..SspmSettings::default().frame
        },
        screen: ScreenSettings {
            filter: GatherFilter::Density,
            ..SspmSettings::default().screen
        },
        ..SspmSettings::default()
    };
    let reach = settings.screen.max_radius_px as i32;
    let (mut border_seen, mut edge_seen) = (0.0f64, 0.0f64);
    let mut all = backends();
    for name in BUILTIN_SCENES.iter().filter(|n| **n != "plain") {
        for zoom in [1.0f32, 2.0] {
            let mut scene = builtin(name).expect("built-in");
            (scene.camera.width, scene.camera.height) = (160, 90);
            let half = (scene.camera.fov_y_deg.to_radians() / 2.0).tan() / zoom;
            scene.camera.fov_y_deg = (2.0 * half.atan()).to_degrees();
            let case = format!("{name} zoom {zoom}");
            for (bname, b) in all.iter_mut() {
                let f = match render_frame(b.as_mut(), &scene, &settings) {
                    Ok(f) => f,
                    Err(e) => {
                        report.error(bname, &case, e);
                        continue;
                    }
                };
                let raw = image_flux(&scene, &f, &f.raw.pixels);
                let filtered = image_flux(&scene, &f, &f.filtered.pixels);
                let mut v = Verdict::new("filtered flux");
                for c in 0..3 {
                    let rel = if raw[c] > 0.0 {
                        filtered[c] / raw[c] - 1.0
                    } else {
                        filtered[c]
                    };
                    v.check(rel.abs() <= FLUX_REL, || {
                        format!(
                            "channel {c}: filtered {:.9e} W, raw {:.9e} W ({rel:+.2e}, allowed {FLUX_REL:.0e})",
                            filtered[c], raw[c]
                        )
                    });
                }
                let (bs, es) = edge_shares(&scene, &f, reach);
                border_seen += bs;
                edge_seen += es;
                v.note(if raw[0] > 0.0 {
                    format!(
                        "raw {:.6e} W, filtered / raw - 1 = {:+.2e}; {:.1}% of the raw flux within {reach} px of the border, {:.1}% of an edge",
                        raw[0],
                        filtered[0] / raw[0] - 1.0,
                        100.0 * bs,
                        100.0 * es
                    )
                } else {
                    format!("no caustic in view: filtered {:.3e} W", filtered[0])
                });
                report.add(bname, &case, v);
            }
        }
    }
    assert!(
        border_seen > 0.0 && edge_seen > 0.0,
        "the cases must put flux near the border ({border_seen}) and near edges ({edge_seen})"
    );
    report.finish();
}
