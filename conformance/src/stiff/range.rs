//! The dynamic-range group: very dim and very bright lights, alone and in one frame.

use super::runner::{outcome, run_checked};
use super::scenes::{settings, sphere_scene};
use super::{Outcome, GRID};
use crate::harness::measure::relative_l2;
use crate::harness::tolerance;
use crate::harness::verdict::Verdict;
use crate::techniques::sspm;
use caustica_core::backend::Backend;
use caustica_core::scene::Light;
use glam::Vec3;

fn intensity_case(b: &mut dyn Backend, intensity: f32) -> Result<Outcome, String> {
    let base = sphere_scene();
    let mut scene = base.clone();
    scene.lights = vec![Light::Point {
        position: Vec3::new(0.0, 3.0, 0.0),
        intensity: Vec3::splat(intensity),
    }];
    let st = settings(GRID);
    let mut v = Verdict::new(format!("intensity {intensity:e}"));
    let f = run_checked(b, &scene, &st, &mut v)?;
    let s = &f.stats;
    v.check(
        s.fixed_point_underflow == 0 && s.fixed_point_saturated == 0,
        || {
            format!(
                "underflow {} saturated {}",
                s.fixed_point_underflow, s.fixed_point_saturated
            )
        },
    );
    // Same paths as at 10 W/sr (intensity does not enter any decision); each photon's
    // units are its flux over a power-of-two quantum, 2^24..2^25 units for the brightest:
    // the same up to one rounding in 2^24, so the raw radiance agrees to RESOLVE_REL.
    let r = sspm::render_frame(b, &base, &st)?;
    let k = 10.0 / intensity;
    let scaled: Vec<[f32; 4]> = f
        .raw
        .pixels
        .iter()
        .map(|p| [p[0] * k, p[1] * k, p[2] * k, p[3]])
        .collect();
    let e = relative_l2(&r.raw.pixels, &scaled, None);
    v.check(e <= tolerance::RESOLVE_REL as f64, || {
        format!("raw caustics x {k:e}: relative L2 {e:.3e} vs 10 W/sr")
    });
    v.check(s.photons_deposited > 0, || "nothing deposited".into());
    outcome(format!("under/sat 0/0, rel L2 {e:.1e} vs 10 W/sr"), v)
}

pub(super) fn intensity_tiny(b: &mut dyn Backend) -> Result<Outcome, String> {
    intensity_case(b, 1e-6)
}

pub(super) fn intensity_huge(b: &mut dyn Backend) -> Result<Outcome, String> {
    intensity_case(b, 1e9)
}

pub(super) fn dynamic_range_mixed(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut scene = sphere_scene();
    scene.lights = vec![
        Light::Point {
            position: Vec3::new(0.0, 3.0, 0.0),
            intensity: Vec3::splat(1e9),
        },
        Light::Point {
            position: Vec3::new(0.5, 3.0, 0.0),
            intensity: Vec3::splat(1e-6),
        },
    ];
    let mut v = Verdict::new("mixed range");
    let f = run_checked(b, &scene, &settings(GRID), &mut v)?;
    let s = &f.stats;
    v.check(s.fixed_point_underflow > 0, || {
        "dim photons (1e-15 of the brightest) did not count as underflow".into()
    });
    outcome(
        format!(
            "underflow {} (counted), saturated {}",
            s.fixed_point_underflow, s.fixed_point_saturated
        ),
        v,
    )
}
