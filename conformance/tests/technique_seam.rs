//! The `Technique` seam on every backend: a technique created by name runs a frame and
//! lists and reads its outputs; moving the camera or the lights between frames (no
//! rebuild), and adding or removing lights, gives, for every technique, bitwise the frame
//! a technique created for the moved scene gives; so do
//! new settings and a new image size (the frame's buffers remade, the scene kept); a
//! technique dropped without `free` is reported, never silently leaked.

use caustica_conformance::backends;
use caustica_conformance::techniques::frame_outputs;
use caustica_core::frame::error::Error;
use caustica_core::frame::image::Image;
use caustica_core::frame::output::Output;
use caustica_core::frame::technique::leaked_buffers;
use caustica_core::scene::builtin::builtin;
use caustica_core::scene::{Light, Scene};
use caustica_core::techniques::sspm::GatherFilter;
use caustica_core::techniques::{create, technique_names};
use caustica_core::{Backend, Technique};
use caustica_core::{FrameSettings, ScreenSettings};
use caustica_core::{Sspm, SspmSettings};
use glam::Vec3;

fn small(name: &str) -> Scene {
    let mut s = builtin(name).expect("built-in scene");
    s.camera.width = 64;
    s.camera.height = 36;
    s
}

fn settings() -> serde_json::Value {
    serde_json::json!({ "photons_w": 64, "photons_h": 64 })
}

/// [`settings`] for technique `name` (CausticMap at a 128^2 atlas; AdaptiveCaustics with
/// three levels, the error metric from the second, so that its coarse photons' quantum
/// and pyramid are exercised; PhotonGi without its temporal blend, whose second frame
/// blends the first by design and so never equals a fresh technique's first frame).
fn settings_for(name: &str) -> serde_json::Value {
    match name {
        "caustic-map" => serde_json::json!({ "photons_w": 64, "photons_h": 64, "atlas_size": 128 }),
        "adaptive-caustics" => serde_json::json!({
            "photons_w": 256, "photons_h": 256, "atlas_size": 128, "error_from_grid": 128
        }),
        "photon-gi" => serde_json::json!({
            "photons_w": 64, "photons_h": 64, "rsm_size": 32, "temporal": false
        }),
        _ => settings(),
    }
}

/// Every registered technique with [`settings_for`], and AdaptiveCaustics' screen target.
fn variants() -> Vec<(&'static str, serde_json::Value)> {
    let mut v: Vec<(&'static str, serde_json::Value)> = technique_names()
        .into_iter()
        .map(|n| (n, settings_for(n)))
        .collect();
    v.push((
        "adaptive-caustics",
        serde_json::json!({
            "photons_w": 256, "photons_h": 256, "error_from_grid": 128, "deposit": "screen"
        }),
    ));
    v
}

/// What a host writes once for all four techniques: a frame, then the caustics if the
/// technique has them.
fn caustics(t: &mut dyn Technique, b: &mut dyn Backend) -> Result<Option<Image>, Error> {
    t.frame(b, &mut |_| {})?;
    if !t
        .outputs()
        .iter()
        .any(|o| o.output == Output::FilteredCaustics)
    {
        return Ok(None);
    }
    t.read_output(b, Output::FilteredCaustics).map(Some)
}

#[test]
fn one_function_reads_the_caustics_of_every_technique() {
    for (bname, mut b) in backends() {
        for name in technique_names() {
            let mut t = create(name, b.as_mut(), &small("sphere"), &settings()).expect("create");
            let got = caustics(t.as_mut(), b.as_mut()).expect("caustics");
            let flux = |img: &Image| img.pixels.iter().map(|p| p[0] as f64).sum::<f64>();
            match (name, got) {
                ("photon-gi", None) => assert!(matches!(
                    t.read_output(b.as_mut(), Output::FilteredCaustics),
                    Err(Error::NoSuchOutput { .. })
                )),
                ("photon-gi", Some(_)) => panic!("{bname}: photon-gi has no caustics"),
                (_, Some(img)) => {
                    assert_eq!((img.width, img.height), (64, 36), "{bname}/{name}");
                    assert!(img.all_finite(), "{bname}/{name}");
                    // the glass ball focuses light on the plane: caustics are not black
                    assert!(flux(&img) > 0.0, "{bname}/{name}: black caustics");
                }
                (_, None) => panic!("{bname}/{name}: no caustics"),
            }
            t.free(b.as_mut()).expect("free");
        }
    }
}

#[test]
fn every_technique_by_name_renders_and_lists_its_outputs() {
    for (bname, mut b) in backends() {
        for name in technique_names() {
            let mut t = create(name, b.as_mut(), &small("sphere"), &settings()).expect("create");
            assert_eq!(t.name(), name);
            let outs = frame_outputs(t.as_mut(), b.as_mut());
            assert!(!outs.is_empty(), "{bname}/{name}: no output");
            for (o, px) in &outs {
                assert_eq!(px.len(), 64 * 36, "{bname}/{name}/{o}");
                assert!(
                    px.iter().flatten().all(|v| v.is_finite()),
                    "{bname}/{name}/{o}"
                );
            }
            let (filtered, raw) = t.estimate_outputs();
            assert!(
                outs.iter().any(|(o, _)| o == filtered.stem())
                    && outs.iter().any(|(o, _)| o == raw.stem())
            );
            let own: Vec<Output> = t.outputs().iter().map(|o| o.output).collect();
            for lacking in Output::ALL.into_iter().filter(|o| !own.contains(o)) {
                match t.read_output(b.as_mut(), lacking) {
                    Err(Error::NoSuchOutput {
                        technique,
                        output,
                        has,
                    }) => {
                        assert_eq!((technique, output), (name, lacking));
                        assert_eq!(has, own, "{bname}/{name}: the outputs it has");
                    }
                    other => panic!("{bname}/{name}/{lacking}: {other:?}"),
                }
                assert!(matches!(
                    t.output_image(lacking),
                    Err(Error::NoSuchOutput { .. })
                ));
            }
            t.free(b.as_mut()).expect("free");
        }
        assert!(create(
            "no_such_technique",
            b.as_mut(),
            &small("sphere"),
            &settings()
        )
        .is_err());
        assert!(
            create(
                "sspm",
                b.as_mut(),
                &small("sphere"),
                &serde_json::json!({"photons_ww": 1})
            )
            .is_err(),
            "{bname}: a misspelt setting must be an error"
        );
    }
}

#[test]
fn moved_camera_and_lights_equal_a_fresh_technique_bitwise() {
    for (bname, mut b) in backends() {
        let scene = small("sphere");
        let mut moved = scene.clone();
        moved.camera.position += Vec3::new(0.3, 0.1, -0.2);
        for l in &mut moved.lights {
            match l {
                Light::Point {
                    position,
                    intensity,
                } => {
                    *position += Vec3::new(0.2, 0.0, 0.1);
                    *intensity *= 1.5;
                }
                Light::Spot { position, .. } => *position += Vec3::new(0.2, 0.0, 0.1),
                Light::Directional { irradiance, .. } => *irradiance *= 1.5,
            }
        }
        for (name, settings) in variants() {
            let mut fresh = create(name, b.as_mut(), &moved, &settings).expect("create");
            let want = frame_outputs(fresh.as_mut(), b.as_mut());
            fresh.free(b.as_mut()).expect("free");

            let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
            frame_outputs(t.as_mut(), b.as_mut()); // a frame before the move
            t.set_camera(b.as_mut(), &moved.camera).expect("set_camera");
            t.set_lights(b.as_mut(), &moved.lights).expect("set_lights");
            let got = frame_outputs(t.as_mut(), b.as_mut());
            assert_eq!(
                got, want,
                "{bname}/{name}: moved technique differs from a fresh one"
            );

            assert!(
                t.set_lights(b.as_mut(), &[]).is_err(),
                "{bname}/{name}: a scene needs a light"
            );
            t.free(b.as_mut()).expect("free");
        }
    }
}

/// A new image size, for every technique: after a frame at 64x36, `set_camera` to 80x50
/// (and a moved eye) gives bitwise the frame of a technique created at that size; PhotonGi
/// also with its temporal blend (the remade history starts empty, as a fresh one does).
#[test]
fn a_new_image_size_equals_a_fresh_technique_bitwise_for_every_technique() {
    for (bname, mut b) in backends() {
        let scene = small("cornell");
        let mut bigger = scene.clone();
        (bigger.camera.width, bigger.camera.height) = (80, 50);
        bigger.camera.position += Vec3::new(0.1, 0.05, 0.0);
        let mut all = variants();
        all.push((
            "photon-gi",
            serde_json::json!({ "photons_w": 64, "photons_h": 64, "rsm_size": 32 }),
        ));
        for (name, settings) in all {
            let mut fresh = create(name, b.as_mut(), &bigger, &settings).expect("create");
            let want = frame_outputs(fresh.as_mut(), b.as_mut());
            fresh.free(b.as_mut()).expect("free");

            let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
            frame_outputs(t.as_mut(), b.as_mut()); // a frame at the old size
            t.set_camera(b.as_mut(), &bigger.camera).expect("resize");
            let got = frame_outputs(t.as_mut(), b.as_mut());
            assert!(
                got.iter().all(|(_, img)| img.len() == 80 * 50),
                "{bname}/{name}: outputs not at the new size"
            );
            assert!(
                got == want,
                "{bname}/{name}: a new image size differs from a fresh technique"
            );
            t.free(b.as_mut()).expect("free");
        }
    }
}

/// Every requested output of one Sspm frame, by name.
fn sspm_outputs(t: &mut Sspm, b: &mut dyn Backend) -> Vec<(String, Vec<[f32; 4]>)> {
    frame_outputs(t, b)
}

#[test]
fn new_settings_and_image_size_equal_a_fresh_technique_bitwise() {
    for (bname, mut b) in backends() {
        let scene = small("cornell");
        let before = SspmSettings {
            frame: FrameSettings {
                photons_w: 48,
                photons_h: 40,
                ..SspmSettings::default().frame
            },
            screen: ScreenSettings {
                filter: GatherFilter::Bilateral,
                ..SspmSettings::default().screen
            },
            ..SspmSettings::default()
        };
        let after = SspmSettings {
            frame: FrameSettings {
                photons_w: 96,
                photons_h: 64,
                ..SspmSettings::default().frame
            },
            screen: ScreenSettings {
                filter: GatherFilter::Density,
                knn_photons: 16,
                max_radius_px: 8,
                ..SspmSettings::default().screen
            },
            ..SspmSettings::default()
        };
        let mut bigger = scene.clone();
        bigger.camera.width = 80;
        bigger.camera.height = 50;

        let mut fresh = Sspm::new(b.as_mut(), &scene, after.clone()).expect("new");
        let want = sspm_outputs(&mut fresh, b.as_mut());
        fresh.free(b.as_mut()).expect("free");
        let mut fresh = Sspm::new(b.as_mut(), &bigger, after.clone()).expect("new");
        let want_bigger = sspm_outputs(&mut fresh, b.as_mut());
        fresh.free(b.as_mut()).expect("free");

        let mut t = Sspm::new(b.as_mut(), &scene, before).expect("new");
        sspm_outputs(&mut t, b.as_mut()); // a frame with the old settings
        t.set_settings(b.as_mut(), after.clone())
            .expect("set_settings");
        assert!(
            sspm_outputs(&mut t, b.as_mut()) == want,
            "{bname}: new settings differ from a fresh technique"
        );
        t.set_camera(b.as_mut(), &bigger.camera).expect("resize");
        assert!(
            sspm_outputs(&mut t, b.as_mut()) == want_bigger,
            "{bname}: a new image size differs from a fresh technique"
        );
        // a budget the built scene does not fit is refused, and nothing changes
        let tight = SspmSettings {
            frame: FrameSettings {
                max_triangles: 1,
                ..after.clone().frame
            },
            ..after.clone()
        };
        assert!(t.set_settings(b.as_mut(), tight).is_err(), "{bname}");
        assert!(
            sspm_outputs(&mut t, b.as_mut()) == want_bigger,
            "{bname}: a refused update changed the frame"
        );
        t.free(b.as_mut()).expect("free");
    }
}

/// `settings` with its JSON fields overridden by `changes`.
fn with(settings: &serde_json::Value, changes: serde_json::Value) -> serde_json::Value {
    let mut s = settings.clone();
    for (k, v) in changes.as_object().expect("an object") {
        s[k] = v.clone();
    }
    s
}

/// New settings through the seam, for every technique: the frame after
/// `set_settings` equals a fresh technique created with them, bitwise; settings that do
/// not parse, fail validation or do not fit the scene are refused and change nothing.
#[test]
fn new_settings_through_the_seam_equal_a_fresh_technique_for_every_technique() {
    for (bname, mut b) in backends() {
        let scene = small("cornell");
        for (name, before) in variants() {
            // more photons, another seed; AdaptiveCaustics fewer bounces, and its screen
            // target may change only its screen settings (Kim 2019's bilateral filter)
            let screen = before.get("deposit").is_some();
            let after = if screen {
                with(
                    &before,
                    serde_json::json!({ "screen": { "filter": "bilateral" } }),
                )
            } else if name == "adaptive-caustics" {
                // (the traversal is deterministic, no seed: one specular bounce at most)
                with(&before, serde_json::json!({ "max_bounces": 1 }))
            } else if name == "photon-gi" {
                with(
                    &before,
                    serde_json::json!({ "photons_w": 96, "seed": 9, "rsm_size": 64 }),
                )
            } else {
                with(
                    &before,
                    serde_json::json!({ "photons_w": 128, "photons_h": 128, "seed": 9 }),
                )
            };
            let mut fresh = create(name, b.as_mut(), &scene, &after).expect("create");
            let want = frame_outputs(fresh.as_mut(), b.as_mut());
            fresh.free(b.as_mut()).expect("free");

            let mut t = create(name, b.as_mut(), &scene, &before).expect("create");
            let first = frame_outputs(t.as_mut(), b.as_mut());
            t.set_settings(b.as_mut(), &after).expect("set_settings");
            let got = frame_outputs(t.as_mut(), b.as_mut());
            assert!(
                got == want,
                "{bname}/{name} ({after}): new settings differ from a fresh technique"
            );
            assert!(
                got != first,
                "{bname}/{name}: the new settings changed nothing (fresh with them: {})",
                if want == first {
                    "the same"
                } else {
                    "different"
                }
            );
            // refused: an unknown field, a bad value, a budget the scene exceeds
            for bad in [
                with(&after, serde_json::json!({ "no_such_setting": 1 })),
                with(&after, serde_json::json!({ "photons_w": 0 })),
                with(&after, serde_json::json!({ "max_triangles": 1 })),
            ] {
                assert!(
                    t.set_settings(b.as_mut(), &bad).is_err(),
                    "{bname}/{name}: {bad} was accepted"
                );
            }
            assert!(
                frame_outputs(t.as_mut(), b.as_mut()) == want,
                "{bname}/{name}: a refused update changed the frame"
            );
            t.free(b.as_mut()).expect("free");
        }
        eprintln!("{bname}: new settings through the seam equal fresh techniques, bitwise");
    }
}

#[test]
fn lights_added_and_removed_equal_a_fresh_technique_bitwise() {
    for (bname, mut b) in backends() {
        let scene = small("sphere");
        let mut more = scene.clone();
        more.lights.push(Light::Spot {
            position: Vec3::new(0.8, 2.5, 0.6),
            direction: Vec3::new(-0.3, -1.0, -0.2),
            intensity: Vec3::splat(4.0),
            inner_angle_deg: 15.0,
            outer_angle_deg: 30.0,
        });
        for (name, settings) in variants() {
            let fresh_outputs = |b: &mut dyn Backend, s: &Scene| {
                let mut t = create(name, b, s, &settings).expect("create");
                let out = frame_outputs(t.as_mut(), b);
                t.free(b).expect("free");
                out
            };
            let (want_more, want_one) = (
                fresh_outputs(b.as_mut(), &more),
                fresh_outputs(b.as_mut(), &scene),
            );
            let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
            frame_outputs(t.as_mut(), b.as_mut());
            t.set_lights(b.as_mut(), &more.lights).expect("add a light");
            assert!(
                frame_outputs(t.as_mut(), b.as_mut()) == want_more,
                "{bname}/{name}: a light added differs from a fresh technique"
            );
            t.set_lights(b.as_mut(), &scene.lights).expect("remove it");
            assert!(
                frame_outputs(t.as_mut(), b.as_mut()) == want_one,
                "{bname}/{name}: a light removed differs from a fresh technique"
            );
            t.free(b.as_mut()).expect("free");
        }
    }
}

/// AdaptiveCaustics' light moved into the casters' bounds (inside the glass ball): its
/// view planes become six cube faces, refitted to the traversal's pyramid with their
/// coarse photons' quantum, exactly as a fresh technique fits them.
#[test]
fn adaptive_light_moved_inside_the_casters_equals_a_fresh_technique_bitwise() {
    for (bname, mut b) in backends() {
        let scene = small("sphere");
        let mut inside = scene.clone();
        inside.lights = vec![Light::Point {
            position: Vec3::new(0.05, 1.02, -0.03),
            intensity: Vec3::splat(2.0),
        }];
        for (name, settings) in variants()
            .into_iter()
            .filter(|(n, _)| *n == "adaptive-caustics")
        {
            let mut fresh = create(name, b.as_mut(), &inside, &settings).expect("create");
            let want = frame_outputs(fresh.as_mut(), b.as_mut());
            fresh.free(b.as_mut()).expect("free");
            let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
            frame_outputs(t.as_mut(), b.as_mut());
            t.set_lights(b.as_mut(), &inside.lights)
                .expect("set_lights");
            let got = frame_outputs(t.as_mut(), b.as_mut());
            assert!(
                got == want,
                "{bname}/{name} {settings}: differs from a fresh technique"
            );
            t.free(b.as_mut()).expect("free");
        }
    }
}

/// New material parameters (the glass's IOR and the floor's albedo: the table uploaded in
/// place), then dispersion switched on (the plan and quanta change), each equal bitwise to
/// a fresh technique; a refused update (the floor made a mirror) leaves the frame as it
/// was.
#[test]
fn new_materials_equal_a_fresh_technique_bitwise() {
    use caustica_core::scene::Material;
    for (bname, mut b) in backends() {
        let scene = small("sphere");
        let mut tuned = scene.clone();
        if let Some(Material::Dielectric { ior, .. }) = tuned.materials.get_mut("glass") {
            *ior = 1.4;
        }
        tuned.materials.insert(
            "white".into(),
            Material::Diffuse {
                albedo: Vec3::new(0.7, 0.5, 0.3),
            },
        );
        let mut dispersive = tuned.clone();
        if let Some(Material::Dielectric { cauchy_b, .. }) = dispersive.materials.get_mut("glass") {
            *cauchy_b = 0.01;
        }
        let mut refused = tuned.materials.clone();
        refused.insert(
            "white".into(),
            Material::Mirror {
                reflectance: Vec3::splat(0.9),
            },
        );
        for (name, settings) in variants() {
            let fresh_outputs = |b: &mut dyn Backend, s: &Scene| {
                let mut t = create(name, b, s, &settings).expect("create");
                let out = frame_outputs(t.as_mut(), b);
                t.free(b).expect("free");
                out
            };
            let want_tuned = fresh_outputs(b.as_mut(), &tuned);
            let want_dispersive = fresh_outputs(b.as_mut(), &dispersive);
            let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
            frame_outputs(t.as_mut(), b.as_mut());
            t.set_materials(b.as_mut(), &tuned.materials)
                .expect("new parameters");
            let got = frame_outputs(t.as_mut(), b.as_mut());
            assert!(
                got == want_tuned,
                "{bname}/{name} {settings}: new parameters differ from a fresh technique"
            );
            let err = t.set_materials(b.as_mut(), &refused);
            assert!(
                err.is_err(),
                "{bname}/{name}: a diffuse floor cannot become a mirror"
            );
            assert!(
                frame_outputs(t.as_mut(), b.as_mut()) == want_tuned,
                "{bname}/{name}: a refused update changed the frame"
            );
            t.set_materials(b.as_mut(), &dispersive.materials)
                .expect("dispersion on");
            let got = frame_outputs(t.as_mut(), b.as_mut());
            assert!(
                got == want_dispersive,
                "{bname}/{name} {settings}: dispersion switched on differs from a fresh technique"
            );
            t.free(b.as_mut()).expect("free");
        }
    }
}

#[test]
fn a_technique_dropped_without_free_is_reported() {
    let (_, mut b) = backends().into_iter().next().expect("the cpu backend");
    let before = leaked_buffers();
    let t = create("sspm", b.as_mut(), &small("sphere"), &settings()).expect("create");
    drop(t);
    assert!(leaked_buffers() > before, "the leak was not counted");
    let t = create("sspm", b.as_mut(), &small("sphere"), &settings()).expect("create");
    let after_drop = leaked_buffers();
    t.free(b.as_mut()).expect("free");
    assert_eq!(
        leaked_buffers(),
        after_drop,
        "free() must not count as a leak"
    );
}

/// New settings keep the uploaded scene for every technique: no node
/// buffer is uploaded again (CausticMap and AdaptiveCaustics assemble their atlas and
/// images over the scene they have); a new triangle budget builds anew.
#[test]
fn new_settings_keep_the_uploaded_scene() {
    let mut b = caustica_conformance::harness::WatchedCpu::new(None);
    let scene = small("cornell");
    for (name, before) in variants() {
        let mut t = create(name, &mut b, &scene, &before).expect("create");
        assert_eq!(
            b.uploads_of("bvh nodes"),
            1,
            "{name}: created with one scene upload"
        );
        t.frame(&mut b, &mut |_| {}).expect("frame");
        let after = if before.get("deposit").is_some() {
            with(
                &before,
                serde_json::json!({ "screen": { "filter": "bilateral" } }),
            )
        } else if name == "adaptive-caustics" {
            with(&before, serde_json::json!({ "max_bounces": 1 }))
        } else {
            with(&before, serde_json::json!({ "seed": 9 }))
        };
        t.set_settings(&mut b, &after).expect("set_settings");
        t.frame(&mut b, &mut |_| {}).expect("frame");
        assert_eq!(
            b.uploads_of("bvh nodes"),
            1,
            "{name}: new settings uploaded the scene again"
        );
        t.free(&mut b).expect("free");
        b.uploads.clear();
    }
}

/// A reference image is checked whole when it is set (its size, its pixel count, finite
/// non-negative radiance); a refused one leaves the technique as it was, and a good one
/// gives the frame's error statistics.
#[test]
fn a_reference_image_is_checked_when_it_is_set() {
    let mut b = caustica_cpu::CpuBackend::new().expect("the CPU backend");
    let scene = small("sphere");
    let mut t = create("sspm", &mut b, &scene, &settings()).expect("sspm");
    let (w, h) = (scene.camera.width, scene.camera.height);
    let n = (w * h) as usize;
    let image = |pixels: Vec<[f32; 4]>| Image {
        width: w,
        height: h,
        pixels,
    };
    for (bad, why) in [
        (image(vec![[1.0; 4]; 3]), "3 pixels for 64x36"),
        (image(vec![[f32::NAN, 0.0, 0.0, 1.0]; n]), "pixel 0"),
        (image(vec![[-1.0, 0.0, 0.0, 1.0]; n]), "pixel 0"),
        (
            Image {
                width: w + 1,
                height: h,
                pixels: vec![[0.0; 4]; n],
            },
            "65x36",
        ),
    ] {
        let e = t.set_reference(Some(bad)).unwrap_err().to_string();
        assert!(e.contains("reference") && e.contains(why), "{e}");
    }
    let stats = t.frame(&mut b, &mut |_| {}).expect("a frame");
    assert!(stats.error.is_none(), "no reference was kept");
    let own = t
        .read_output(&mut b, Output::FilteredCaustics)
        .expect("the caustics");
    t.set_reference(Some(own)).expect("a whole reference");
    let stats = t.frame(&mut b, &mut |_| {}).expect("a frame");
    let error = stats.error.expect("error statistics against the reference");
    assert!(
        error.relative_mse.is_finite() && error.mask_pixels > 0,
        "{error:?}"
    );
    t.free(&mut b).expect("freed");
}

/// Between a new image size and the next frame the camera's images are still to be made:
/// reading one says so (not a missing resource); a new size the host cannot hold is
/// refused where the technique finds out when it is set, and the technique then renders
/// at its old size as before, bitwise (CPU backend: its buffers are held within the
/// host's available memory, so 16384^2 is refused without touching it).
#[test]
fn a_resize_reads_after_its_frame_and_a_refused_one_leaves_the_technique_whole() {
    let mut b = caustica_cpu::CpuBackend::new().expect("the CPU backend");
    let b: &mut dyn Backend = &mut b;
    let scene = small("cornell");
    let mut bigger = scene.camera.clone();
    (bigger.width, bigger.height) = (80, 50);
    let mut huge = scene.camera.clone();
    (huge.width, huge.height) = (16384, 16384);
    for (name, settings) in variants() {
        let mut t = create(name, b, &scene, &settings).expect("create");
        let before = frame_outputs(t.as_mut(), b);
        match t.set_camera(b, &huge) {
            Err(e) => {
                // refused now: the technique is as it was
                assert!(e.to_string().contains("out of memory"), "{name}: {e}");
                assert!(
                    frame_outputs(t.as_mut(), b) == before,
                    "{name}: changed by a refused resize"
                );
            }
            // (a technique whose own buffers do not grow with the image finds out in the
            // frame that makes the camera's images)
            Ok(()) => {
                let e = t
                    .frame(b, &mut |_| {})
                    .expect_err("a frame at 16384^2")
                    .to_string();
                assert!(e.contains("out of memory"), "{name}: {e}");
                t.set_camera(b, &scene.camera).expect("the old size back");
                frame_outputs(t.as_mut(), b);
            }
        }
        t.set_camera(b, &bigger).expect("resize");
        let early = t
            .read_output(b, Output::Composite)
            .expect_err("no frame yet")
            .to_string();
        assert!(early.contains("run a frame"), "{name}: {early}");
        let after = frame_outputs(t.as_mut(), b);
        assert!(after.iter().all(|(_, img)| img.len() == 80 * 50), "{name}");
        t.free(b).expect("free");
    }
}
