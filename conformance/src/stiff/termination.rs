//! The termination group: paths that never leave two facing mirrors end at the bounce limit.

use super::runner::{outcome, run_checked, stored_fraction};
use super::scenes::{obj, settings, sphere_scene};
use super::{Outcome, GRID};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;
use caustica_core::scene::{Light, Material, Shape};
use glam::Vec3;

pub(super) fn facing_mirrors(b: &mut dyn Backend) -> Result<Outcome, String> {
    let mut scene = sphere_scene();
    scene.materials.insert(
        "mirror".into(),
        Material::Mirror {
            reflectance: Vec3::ONE,
        },
    );
    scene.objects.truncate(1);
    for x in [-0.5f32, 0.5] {
        scene.objects.push(obj(
            "mirror",
            "mirror",
            Shape::Quad {
                center: Vec3::new(x, 1.0, 0.0),
                u: Vec3::new(0.0, 0.9, 0.0),
                v: Vec3::new(0.0, 0.0, 0.9 * x.signum()),
            },
        ));
    }
    scene.lights = vec![Light::Point {
        position: Vec3::new(0.0, 1.0, 0.0),
        intensity: Vec3::splat(10.0),
    }];
    let mut v = Verdict::new("facing mirrors");
    let f = run_checked(b, &scene, &settings(GRID), &mut v)?;
    let s = &f.stats;
    v.check(s.discarded.bounce_limit > 0, || {
        "no photon reached the bounce limit".into()
    });
    outcome(
        format!(
            "bounce limit {} of {}, stored/emitted {:.3}",
            s.discarded.bounce_limit,
            s.photons_emitted,
            stored_fraction(&f)
        ),
        v,
    )
}
