//! The screen group: the pixel footprint at the near and far extremes, and a camera inside
//! glass.

use super::runner::{outcome, run_checked};
use super::scenes::{settings, sphere_scene, transform_scene};
use super::{Outcome, GRID};
use crate::harness::tolerance;
use crate::harness::verdict::Verdict;
use crate::techniques::sspm::Frame;
use caustica_core::backend::Backend;
use caustica_core::device::layout::gbuffer_pixel_area;
use caustica_core::device::layout::{gbuffer_flags, GpuCamera};
use caustica_core::scene::{Scene, Shape};
use glam::Vec3;

/// Checks the footprint rule on every pixel: `L * A * pi / albedo` (the pixel's flux) is
/// finite and at most the frame's stored flux (plus 1e-5 relative: [`tolerance::RESOLVE_REL`]).
fn footprint_rule(scene: &Scene, f: &Frame, v: &mut Verdict) -> f64 {
    let cam = GpuCamera::from_camera(&scene.camera);
    let stored = f.stats.stored_flux[1];
    let mut max_flux = 0.0f64;
    let mut bad = 0;
    for (i, g) in f.gbuffer.iter().enumerate() {
        if g.flags & gbuffer_flags::RECEIVER == 0 || g.albedo[1] == 0.0 {
            continue;
        }
        let area = gbuffer_pixel_area(&cam, i as u32, g) as f64;
        let flux = f.raw.pixels[i][1] as f64 * area * std::f64::consts::PI / g.albedo[1] as f64;
        if !flux.is_finite() || flux > stored * (1.0 + tolerance::RESOLVE_REL as f64) {
            bad += 1;
        }
        max_flux = max_flux.max(flux);
    }
    v.check(bad == 0, || {
        format!("{bad} pixels carry more flux than was stored ({stored:.4e} W)")
    });
    max_flux
}

pub(super) fn near_plane(b: &mut dyn Backend) -> Result<Outcome, String> {
    // A pixel's footprint can only shrink while photons still land in it if the scene's
    // own coordinates shrink with it (f32 resolves 2^-23 of a coordinate, so a caustic is
    // never sharper than ~1e-7 of the scene). The sphere scene at 1e-9 scale, seen straight
    // down from 3e-10 above the caustic's centre: a pixel covers
    // (2 * 3e-10 * tan(22.5) / 64)^2 ~ 1.5e-23 units^2. A footprint below f32's normal
    // range (1.2e-38) with photons in it would need coordinates below ~1e-17, where the
    // ray/triangle determinants (~edge^2) leave the normal range too: outside the
    // library's geometric range (docs/stability.md).
    let s = 1e-9;
    let mut scene = transform_scene(&sphere_scene(), s, Vec3::ZERO);
    scene.camera.position = Vec3::new(0.0, 0.3 * s, 0.0);
    scene.camera.target = Vec3::new(0.0, -1.0, 0.0);
    scene.camera.up = Vec3::Z;
    let mut v = Verdict::new("near plane");
    let f = run_checked(b, &scene, &settings(GRID), &mut v)?;
    let max = footprint_rule(&scene, &f, &mut v);
    v.check(f.stats.photons_deposited > 0, || "nothing deposited".into());
    let peak = f.raw.pixels.iter().map(|p| p[1]).fold(0.0f32, f32::max);
    v.note(format!(
        "peak radiance {peak:.3e}, largest pixel flux {max:.3e} W"
    ));
    outcome(
        format!("deposited {}, peak L {peak:.2e}", f.stats.photons_deposited),
        v,
    )
}

pub(super) fn far_plane(b: &mut dyn Backend) -> Result<Outcome, String> {
    // Camera 1e6 away with the default 45-degree view: a pixel covers ~(2.2e4)^2 units^2
    // of the plane (enlarged to 2e6 across so that pixel centres see it), and the whole
    // caustic falls into one pixel.
    let mut scene = sphere_scene();
    scene.objects[0].shape = Shape::Quad {
        center: Vec3::ZERO,
        u: Vec3::new(1e6, 0.0, 0.0),
        v: Vec3::new(0.0, 0.0, -1e6),
    };
    scene.camera.position = Vec3::new(0.0, 8e5, 6e5);
    let mut v = Verdict::new("far plane");
    let f = run_checked(b, &scene, &settings(GRID), &mut v)?;
    let max = footprint_rule(&scene, &f, &mut v);
    outcome(
        format!(
            "deposited {}, max pixel flux {max:.3e} W",
            f.stats.photons_deposited
        ),
        v,
    )
}

pub(super) fn camera_inside_glass(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut scene = sphere_scene();
    scene.camera.position = Vec3::new(0.0, 1.1, 0.1);
    scene.camera.target = Vec3::new(0.0, 0.0, -0.3);
    let mut v = Verdict::new("camera inside glass");
    let f = run_checked(b, &scene, &settings(GRID), &mut v)?;
    let glass_px = f
        .gbuffer
        .iter()
        .filter(|g| g.flags & gbuffer_flags::RECEIVER == 0 && g.depth > 0.0)
        .count();
    v.check(glass_px == f.gbuffer.len(), || {
        format!("{glass_px} of {} pixels see the glass", f.gbuffer.len())
    });
    v.check(f.stats.photons_deposited == 0, || {
        format!(
            "{} photons deposited on glass pixels",
            f.stats.photons_deposited
        )
    });
    let lit = f.direct.pixels.iter().filter(|p| p[1] > 0.0).count();
    outcome(format!("{lit} pixels lit through the glass"), v)
}
