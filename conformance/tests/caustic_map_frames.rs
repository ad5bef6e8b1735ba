//! CausticMap's frames on every backend:
//!
//! - a frame after a camera-only change runs no photon pass (the stats say why) and its
//!   images equal, bitwise, those of a technique created fresh with that camera (the
//!   atlas does not depend on the camera; the same photons, the same integer sums);
//! - the gather keeps the flux: over `sphere`'s receiver (a plane whose tile its two UV
//!   triangles cover entirely) the gathered map's flux, `sum E x texel area`, equals the
//!   raw map's within 1e-4 relative (f32 sums of ~16k texels in a fixed order: ~16k x
//!   2^-24 = 1e-3 worst case, about sqrt(16k) x 2^-24 = 8e-6 typical; the texel areas are
//!   equal on a plane, so the check is of the gather's normalisation, not of the areas);
//! - the caustic of `sphere` is seen through the ball: some of the 7x7 pixels around the
//!   ball's centre in the image (camera rays that meet the glass first) get caustic
//!   radiance from the map (Sspm's screen deposit cannot give them any). This checks
//!   presence, not the value against a traced reference (TODO(issue 16)).

use caustica_conformance::backends;
use caustica_core::frame::technique::Technique;
use caustica_core::scene::builtin::builtin;
use caustica_core::techniques::caustic_map::{CausticMap, CausticMapSettings};

fn settings() -> CausticMapSettings {
    CausticMapSettings {
        photons_w: 128,
        photons_h: 128,
        atlas_size: 128,
        ..Default::default()
    }
}

#[test]
fn a_camera_move_reuses_the_atlas_and_equals_a_fresh_frame() {
    let mut scene = builtin("sphere").expect("built-in");
    (scene.camera.width, scene.camera.height) = (96, 54);
    let mut moved = scene.camera.clone();
    moved.position += glam::Vec3::new(0.4, 0.2, -0.3);
    for (name, mut b) in backends() {
        let mut t = CausticMap::new(b.as_mut(), &scene, settings()).expect("scene");
        t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        t.set_camera(b.as_mut(), &moved).expect("camera");
        let stats = t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        assert!(
            !stats.passes.iter().any(|p| p.name == "trace_photons"),
            "{name}: a camera-only frame traced photons"
        );
        assert!(
            stats
                .skipped
                .iter()
                .any(|s| s.name == "trace_photons" && s.reason.contains("only the camera")),
            "{name}: the stats do not say why the photon pass was skipped: {:?}",
            stats.skipped
        );
        let mut fresh_scene = scene.clone();
        fresh_scene.camera = moved.clone();
        let mut f = CausticMap::new(b.as_mut(), &fresh_scene, settings()).expect("scene");
        f.frame(b.as_mut(), &mut |_| {}).expect("frame");
        for out in [
            "composite",
            "caustics_filtered",
            "caustics_raw",
            "caustic_atlas",
        ] {
            let a = t.read_output(b.as_mut(), out).expect("read");
            let c = f.read_output(b.as_mut(), out).expect("read");
            assert!(
                a.pixels
                    .iter()
                    .zip(&c.pixels)
                    .all(|(x, y)| x.map(f32::to_bits) == y.map(f32::to_bits)),
                "{name}: {out} after a camera move differs from a fresh frame"
            );
        }
        Box::new(t).free(b.as_mut()).expect("free");
        Box::new(f).free(b.as_mut()).expect("free");
    }
}

#[test]
fn the_gather_keeps_the_flux_and_the_ball_shows_the_caustic_behind_it() {
    let mut scene = builtin("sphere").expect("built-in");
    (scene.camera.width, scene.camera.height) = (96, 54);
    for (name, mut b) in backends() {
        let mut t = CausticMap::new(
            b.as_mut(),
            &scene,
            CausticMapSettings {
                photons_w: 256,
                photons_h: 256,
                ..settings()
            },
        )
        .expect("scene");
        t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        // the atlas output is the gathered map; the raw map is what caustics_raw samples:
        // compare their flux through a frame with gather width 1
        let map = t.read_output(b.as_mut(), "caustic_atlas").expect("atlas");
        let gathered: f64 = map.pixels.iter().map(|p| p[0] as f64).sum();
        let mut raw_t = CausticMap::new(
            b.as_mut(),
            &scene,
            CausticMapSettings {
                photons_w: 256,
                photons_h: 256,
                gather_width: 1,
                ..settings()
            },
        )
        .expect("scene");
        raw_t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        let raw_map = raw_t
            .read_output(b.as_mut(), "caustic_atlas")
            .expect("atlas");
        let raw: f64 = raw_map.pixels.iter().map(|p| p[0] as f64).sum();
        assert!(raw > 0.0, "{name}: the raw map is dark");
        assert!(
            ((gathered - raw) / raw).abs() < 1e-4,
            "{name}: gathered irradiance sum {gathered} vs raw {raw}"
        );
        // through the ball: the pixels where the composite shows the glass (no direct
        // diffuse shading on their first hit) still carry caustic radiance
        let caustics = t
            .read_output(b.as_mut(), "caustics_filtered")
            .expect("caustics");
        let direct = t.read_output(b.as_mut(), "direct").expect("direct");
        let (cx, cy) = (48u32, 22u32); // the ball's centre in sphere's camera, 96x54
        let mut lit = 0;
        for y in cy - 3..=cy + 3 {
            for x in cx - 3..=cx + 3 {
                lit += (caustics.at(x, y)[0] > 0.0) as u32;
            }
        }
        assert!(
            lit > 0 && direct.all_finite(),
            "{name}: no caustic seen through the ball around ({cx}, {cy})"
        );
        Box::new(t).free(b.as_mut()).expect("free");
        Box::new(raw_t).free(b.as_mut()).expect("free");
    }
}

/// `cornell`'s mirror ball shows caustics (the glass ball's on the floor and walls): some
/// pixels of the mirror ball's disc in the image carry caustic radiance from the map,
/// where Sspm's screen deposit has none (its photons land on the receivers the camera
/// sees directly).
#[test]
fn the_mirror_ball_shows_caustics_sspm_cannot() {
    use caustica_core::device::layout::{project_to_pixel, GpuCamera};
    use caustica_core::techniques::create;
    let mut scene = builtin("cornell").expect("built-in");
    (scene.camera.width, scene.camera.height) = (96, 54);
    let cam = GpuCamera::from_camera(&scene.camera);
    let (cx, cy, _) = project_to_pixel(&cam, glam::Vec3::new(0.45, 0.35, 0.3)).expect("on screen");
    // the ball (r 0.35 at ~3.3) spans ~8 pixels of radius at 96x54: pixels within 6 of
    // its centre see the mirror
    let around = |img: &caustica_core::frame::image::Image| {
        let mut lit = 0;
        for y in cy - 6..=cy + 6 {
            for x in cx - 6..=cx + 6 {
                let (dx, dy) = (x as i32 - cx as i32, y as i32 - cy as i32);
                if dx * dx + dy * dy <= 36 {
                    lit += (img.at(x, y)[0] > 0.0) as u32;
                }
            }
        }
        lit
    };
    for (name, mut b) in backends() {
        let mut t = CausticMap::new(
            b.as_mut(),
            &scene,
            CausticMapSettings {
                photons_w: 256,
                photons_h: 256,
                ..settings()
            },
        )
        .expect("scene");
        t.frame(b.as_mut(), &mut |_| {}).expect("frame");
        let caustics = t
            .read_output(b.as_mut(), "caustics_filtered")
            .expect("caustics");
        Box::new(t).free(b.as_mut()).expect("free");
        let mut s = create(
            "sspm",
            b.as_mut(),
            &scene,
            &serde_json::json!({ "photons_w": 256, "photons_h": 256 }),
        )
        .expect("sspm");
        s.frame(b.as_mut(), &mut |_| {}).expect("frame");
        let screen = s
            .read_output(b.as_mut(), "caustics_filtered")
            .expect("caustics");
        s.free(b.as_mut()).expect("free");
        assert!(
            around(&caustics) > 0,
            "{name}: no caustic seen in the mirror ball around ({cx}, {cy})"
        );
        assert_eq!(
            around(&screen),
            0,
            "{name}: Sspm shows light in the mirror ball: the test does not look at the mirror"
        );
    }
}
