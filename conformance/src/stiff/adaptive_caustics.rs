//! The adaptive-caustics group: AdaptiveCaustics' own extremes, on every
//! backend. Each case runs the traversal through the caustic-map group's checks
//! ([`checked_with`]: finite outputs, accounting over every photon traced, stored flux
//! at most emitted, no saturation, agreement with the CPU's frame) and compares the
//! maximal-traversal-level metric with the dense grid of the same finest level on the
//! same backend: with the conservative relevance (the casters' projected bounds) they
//! must store the same photons, so the stored flux and the atlas are **bitwise** equal.
//! Each case also runs the screen target (`deposit: screen`) under the same settings: it
//! must receive exactly the atlas target's photons (bitwise the same stored flux and
//! count), account for every one in `deposit_screen` and give finite images.

use super::caustic_map::{checked_with, render, MapFrame};
use super::runner::outcome;
use super::scenes::{ball, glass, obj, sized, sphere_scene};
use super::{Outcome, SIZE};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;
use caustica_core::scene::{builtin, Light, Scene, Shape};
use caustica_core::techniques::adaptive_caustics::AdaptiveStats;
use caustica_core::techniques::adaptive_caustics::{
    AdaptiveCaustics, AdaptiveCausticsSettings, AdaptiveMetric, ClusterRelevance,
};
use caustica_core::techniques::caustic_map::{CausticMapSettings, EmissionPlane};
use caustica_core::{AtlasSettings, FrameSettings, PlaneSettings, TraversalSettings};
use glam::Vec3;

fn map(n: u32, plane: EmissionPlane) -> CausticMapSettings {
    CausticMapSettings {
        frame: FrameSettings {
            photons_w: n,
            photons_h: n,
            ..CausticMapSettings::default().frame
        },
        atlas: AtlasSettings {
            atlas_size: 256,
            ..CausticMapSettings::default().atlas
        },
        planes: PlaneSettings {
            emission_plane: plane,
            ..CausticMapSettings::default().planes
        },
        ..CausticMapSettings::default()
    }
}

fn level(n: u32, plane: EmissionPlane, relevance: ClusterRelevance) -> AdaptiveCausticsSettings {
    AdaptiveCausticsSettings {
        traversal: TraversalSettings {
            metric: AdaptiveMetric::Level,
            relevance,
            ..AdaptiveCausticsSettings::default().traversal
        },
        ..crate::adaptive_over(&map(n, plane))
    }
}

/// The traversal under `s`, checked (see the module doc).
fn adaptive(
    b: &mut dyn Backend,
    scene: &Scene,
    s: &AdaptiveCausticsSettings,
    v: &mut Verdict,
) -> Result<MapFrame, String> {
    checked_with(
        b,
        scene,
        &|b, sc| Ok(Box::new(AdaptiveCaustics::new(b, sc, s.clone())?)),
        v,
    )
}

/// The screen target under `s` against the atlas target's frame `atlas` (same backend):
/// the same photons (bitwise stored flux and count), every one accounted for by
/// `deposit_screen`, finite images.
fn screen_target(
    b: &mut dyn Backend,
    scene: &Scene,
    s: &AdaptiveCausticsSettings,
    atlas: &MapFrame,
    v: &mut Verdict,
) -> Result<(), String> {
    use caustica_core::techniques::sspm::Output;
    let mut t = AdaptiveCaustics::new(
        b,
        scene,
        AdaptiveCausticsSettings {
            deposit: caustica_core::techniques::adaptive_caustics::AdaptiveDeposit::Screen,
            ..s.clone()
        },
    )
    .map_err(|e| e.to_string())?;
    let st = t.frame(b, &mut |_| {}).map_err(|e| e.to_string())?;
    let images = [
        Output::RawCaustics,
        Output::FilteredCaustics,
        Output::Composite,
    ]
    .map(|o| t.read_output(b, o).map_err(|e| e.to_string()));
    t.free(b).map_err(|e| e.to_string())?;
    for img in images {
        v.check(img?.all_finite(), || {
            "screen target: an image is not finite".into()
        });
    }
    v.check(st.stored_flux == atlas.stats.stored_flux, || {
        format!(
            "screen target: stored flux {:?}, the atlas target's {:?}",
            st.stored_flux, atlas.stats.stored_flux
        )
    });
    v.check(st.photons_stored == atlas.stats.photons_stored, || {
        format!(
            "screen target: {} photons stored, the atlas target's {}",
            st.photons_stored, atlas.stats.photons_stored
        )
    });
    let d = &st.discarded;
    v.check(
        st.photons_deposited + d.off_screen + d.depth_mismatch == st.photons_stored,
        || "screen target: output photons unaccounted for by deposit_screen".into(),
    );
    Ok(())
}

/// The level metric against the dense grid `dense` on the same backend: bitwise equal.
fn equals_dense(what: &str, a: &MapFrame, dense: &MapFrame, v: &mut Verdict) {
    v.check(a.stats.stored_flux == dense.stats.stored_flux, || {
        format!(
            "{what}: stored flux {:?} vs dense {:?}",
            a.stats.stored_flux, dense.stats.stored_flux
        )
    });
    let same = a
        .atlas
        .pixels
        .iter()
        .zip(&dense.atlas.pixels)
        .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits));
    v.check(same, || {
        format!("{what}: the atlas differs from the dense grid's")
    });
}

pub(super) fn small_caster(b: &mut dyn Backend) -> Result<Outcome, String> {
    // spot-glass's light over its floor, the only caster a glass bead of radius 0.012 at
    // 3.2 from the light: 0.0075 rad across, a tenth of a start-grid cluster (2 texels of
    // 2 tan(50 deg) / 64 = 0.037); the plane covers the whole cone, so Wyman 2009's photon test
    // almost surely discards it at the start grid
    let mut scene = sized(builtin::spot_glass(), SIZE);
    scene.objects[1].shape = Shape::Sphere {
        center: Vec3::new(-1.0, 1.0, -0.6),
        radius: 0.012,
        segments: 32,
    };
    let plane = EmissionPlane::LightCone;
    let mut v = Verdict::new("caster smaller than a start cell");
    let dense = render(b, &scene, &map(512, plane)).map_err(|e| e.to_string())?;
    v.check(dense.stats.photons_stored > 0, || {
        "the dense grid stores nothing from the bead".into()
    });
    let bounds = adaptive(
        b,
        &scene,
        &level(512, plane, ClusterRelevance::Bounds),
        &mut v,
    )?;
    equals_dense("bounds", &bounds, &dense, &mut v);
    screen_target(
        b,
        &scene,
        &level(512, plane, ClusterRelevance::Bounds),
        &bounds,
        &mut v,
    )?;
    let photons = adaptive(
        b,
        &scene,
        &level(512, plane, ClusterRelevance::Photons),
        &mut v,
    )?;
    let (kept, all) = (photons.stats.stored_flux[0], dense.stats.stored_flux[0]);
    v.check(kept < all, || {
        format!("Wyman 2009's photon test kept the bead's caustic ({kept:e} of {all:e}): the case does not test a miss")
    });
    outcome(
        format!(
            "bounds: {} photons traced, = dense; photons: {:.3} of the flux",
            bounds.stats.photons_emitted,
            kept / all
        ),
        v,
    )
}

pub(super) fn grazing_caster(b: &mut dyn Backend) -> Result<Outcome, String> {
    // a glass slab 0.02 thick lit by a sun 3 degrees above its top face: Fresnel near 1
    // (R = 0.83), the photons that enter leave through the bottom as steeply as they came
    // and land on a floor 12 units wide on each side, ~9.6 units away
    let mut scene = sphere_scene();
    scene.objects[0].shape = Shape::Quad {
        center: Vec3::ZERO,
        u: Vec3::new(12.0, 0.0, 0.0),
        v: Vec3::new(0.0, 0.0, -12.0),
    };
    scene.objects[1].shape = Shape::Cuboid {
        min: Vec3::new(-0.5, 0.5, -0.5),
        max: Vec3::new(0.5, 0.52, 0.5),
    };
    scene.lights = vec![Light::Directional {
        direction: Vec3::new(1.0, -0.0524, 0.0),
        irradiance: Vec3::ONE,
        projection_volume: None,
    }];
    let plane = EmissionPlane::Casters;
    let mut v = Verdict::new("grazing caster");
    let dense = render(b, &scene, &map(256, plane)).map_err(|e| e.to_string())?;
    let a = adaptive(
        b,
        &scene,
        &level(256, plane, ClusterRelevance::Bounds),
        &mut v,
    )?;
    equals_dense("level metric", &a, &dense, &mut v);
    screen_target(
        b,
        &scene,
        &level(256, plane, ClusterRelevance::Bounds),
        &a,
        &mut v,
    )?;
    v.check(a.stats.photons_stored > 0, || {
        "nothing stored: the case tests nothing".into()
    });
    outcome(format!("stored {}", a.stats.photons_stored), v)
}

pub(super) fn light_inside_casters(b: &mut dyn Backend) -> Result<Outcome, String> {
    // a point light between two glass balls, inside their bounding sphere: six cube faces
    // of 512 / sqrt 6 texels, which the pyramid rounds to 256 (4 levels under 64^2); the
    // dense grid of 627^2 has faces of round(627 / sqrt 6) = 256 texels too
    let mut scene = sphere_scene();
    scene.materials.insert("glass".into(), glass(1.5));
    scene.objects[1].shape = ball(Vec3::new(-0.6, 1.0, 0.0), 0.4);
    scene
        .objects
        .push(obj("ball 2", "glass", ball(Vec3::new(0.6, 1.0, 0.0), 0.4)));
    scene.lights = vec![Light::Point {
        position: Vec3::new(0.0, 1.0, 0.0),
        intensity: Vec3::splat(5.0),
    }];
    let mut v = Verdict::new("light inside the casters' bounds");
    let dense = render(b, &scene, &map(627, EmissionPlane::Casters)).map_err(|e| e.to_string())?;
    let a = adaptive(
        b,
        &scene,
        &level(512, EmissionPlane::Casters, ClusterRelevance::Bounds),
        &mut v,
    )?;
    let planes = AdaptiveStats::of(&a.stats)
        .as_ref()
        .map_or(0, |s| s.dense_equivalent_photons);
    v.check(planes == 6 * 256 * 256, || {
        format!("dense-equivalent photons {planes}, six faces of 256^2 expected")
    });
    equals_dense("level metric", &a, &dense, &mut v);
    let s = level(512, EmissionPlane::Casters, ClusterRelevance::Bounds);
    screen_target(b, &scene, &s, &a, &mut v)?;
    outcome(format!("six faces, stored {}", a.stats.photons_stored), v)
}

pub(super) fn far_from_origin(b: &mut dyn Backend) -> Result<Outcome, String> {
    // a glass cube (it fills its bounding box: photons that graze its edges start on the
    // rectangle's border) under a sun (its orthographic plane places each photon's origin
    // in world space), the whole scene moved by 1e4 along every axis, where f32 resolves
    // 1e-3; the plane over the light's whole footprint, the cube's rectangle a part of it.
    // The bounds seed lists only clusters that overlap a rectangle, so the rectangles'
    // padding (which takes that rounding) must keep every cluster whose photons meet the
    // cube: the seeded level metric stores bitwise the dense grid's photons
    let mut cube = sphere_scene();
    cube.objects[1].shape = Shape::Cuboid {
        min: Vec3::new(-0.4, 0.6, -0.4),
        max: Vec3::new(0.4, 1.4, 0.4),
    };
    cube.lights = vec![Light::Directional {
        direction: Vec3::new(0.3, -1.0, 0.2).normalize(),
        irradiance: Vec3::ONE,
        projection_volume: None,
    }];
    let scene = super::scenes::transform_scene(&cube, 1.0, Vec3::splat(1e4));
    let plane = EmissionPlane::LightCone;
    let mut v = Verdict::new("far from the origin");
    let dense = render(b, &scene, &map(256, plane)).map_err(|e| e.to_string())?;
    v.check(dense.stats.photons_stored > 0, || {
        "the dense grid stores nothing: the case tests nothing".into()
    });
    let a = adaptive(
        b,
        &scene,
        &level(256, plane, ClusterRelevance::Bounds),
        &mut v,
    )?;
    let seeded = AdaptiveStats::of(&a.stats).map_or(0, |s| s.levels_seeded);
    v.check(seeded > 0, || {
        "no level seeded: the case tests nothing".into()
    });
    equals_dense("level metric", &a, &dense, &mut v);
    outcome(
        format!("stored {}, {seeded} levels seeded", a.stats.photons_stored),
        v,
    )
}
