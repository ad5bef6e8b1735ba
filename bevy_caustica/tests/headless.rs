//! Headless Bevy apps on the machine's adapter (lavapipe in CI): a glass ball over a floor
//! under a point light, rendered into an image with the plugin and without it.

mod common;

use bevy::prelude::*;
use bevy_caustica::{CausticaStats, Caustics, CausticsStatus, CausticsTechnique};
use common::*;

fn caustics(t: CausticsTechnique) -> Caustics {
    Caustics {
        technique: t,
        photons: 256,
        ..default()
    }
}

fn stats(app: &App, cam: Entity) -> bevy_caustica::CameraCaustics {
    app.world()
        .resource::<CausticaStats>()
        .get(cam)
        .expect("the camera's figures")
}

/// caustica's render of the test scene (its own shapes, the Bevy camera's view and
/// projection), caustics only: linear RGBA, row-major from the top left.
fn caustica_reference(app: &mut App, cam: Entity, seed: u32) -> Vec<f32> {
    use bevy_caustica::convert;
    use caustica::glam::Vec3 as V;
    use caustica::scene::{Material, Object, Scene, Shape};
    let (clip_from_view, world_from_view) = {
        let mut q = app.world_mut().query::<(&Camera, &GlobalTransform)>();
        let (c, gt) = q.get(app.world(), cam).expect("the camera");
        (c.clip_from_view(), gt.to_matrix())
    };
    let camera = convert::camera(
        world_from_view.to_cols_array(),
        clip_from_view.to_cols_array(),
        W,
        H,
    )
    .expect("a pinhole");
    let scene = Scene {
        name: "bevy-test".into(),
        description: String::new(),
        camera,
        materials: [
            ("floor".to_string(), Material::Diffuse { albedo: V::ONE }),
            (
                "glass".to_string(),
                Material::Dielectric {
                    ior: 1.5,
                    cauchy_b: 0.0,
                    absorption: V::ZERO,
                    ior_model: Default::default(),
                },
            ),
        ]
        .into(),
        objects: vec![
            Object {
                name: "floor".into(),
                material: "floor".into(),
                shape: Shape::Quad {
                    center: V::ZERO,
                    u: V::new(2.0, 0.0, 0.0),
                    v: V::new(0.0, 0.0, -2.0),
                },
                transform: None,
            },
            Object {
                name: "ball".into(),
                material: "glass".into(),
                shape: Shape::Sphere {
                    center: V::new(0.0, 1.0, 0.0),
                    radius: 0.5,
                    segments: 96,
                },
                transform: None,
            },
        ],
        lights: vec![convert::light(&convert::LightInput::Point {
            color: [1.0; 3],
            intensity: 400_000.0,
            position: [0.0, 3.0, 0.0],
        })],
    };
    let mut backend = caustica::backends::wgpu::WgpuBackend::new().expect("a wgpu adapter");
    use caustica::TechniqueSettings;
    let settings = caustica::SspmSettings::default()
        .with_photons(256, 256)
        .with_seed(seed)
        .with_outputs(caustica::Outputs::CAUSTICS_ONLY);
    let mut t = caustica::Sspm::new(&mut backend, &scene, settings).expect("sspm");
    t.frame(&mut backend, &mut |_| {}).expect("a frame");
    let img = t
        .read_output(&mut backend, caustica::Output::FilteredCaustics)
        .expect("the caustics");
    caustica::Technique::free(Box::new(t), &mut backend).expect("free");
    img.pixels
        .iter()
        .flat_map(|p| [p[0], p[1], p[2], 0.0])
        .collect()
}

fn rel_l2(a: &[f32], reference: &[f32]) -> f64 {
    let (mut num, mut den) = (0.0f64, 0.0f64);
    for (x, y) in a.iter().zip(reference) {
        num += ((x - y) as f64).powi(2);
        den += (*y as f64).powi(2);
    }
    (num / den.max(1e-30)).sqrt()
}

fn move_light(app: &mut App) {
    let w = app.world_mut();
    let mut q = w.query_filtered::<&mut Transform, With<TheLight>>();
    q.single_mut(w).expect("one light").translation.x += 1.0;
}

#[test]
fn the_caustic_adds_light_under_the_glass_ball_and_moves_with_the_light() {
    let _g = serial();
    let t0 = std::time::Instant::now();
    // Bevy alone
    let mut off = app(false);
    floor_and_light(&mut off);
    glass_ball(&mut off);
    camera(&mut off, true, None, 0);
    let (bevy_only, n) = run_until_lit(&mut off, 0, 3);
    move_light(&mut off);
    let bevy_only_moved = run(&mut off, 0, 4);
    drop(off);
    eprintln!(
        "plugin off: {n} frames, {:.1} s",
        t0.elapsed().as_secs_f32()
    );

    let t1 = std::time::Instant::now();
    let mut on = app(true);
    floor_and_light(&mut on);
    glass_ball(&mut on);
    let cam = camera(&mut on, true, Some(caustics(CausticsTechnique::Sspm)), 0);
    let (with, n) = run_until_lit(&mut on, 0, 6);
    eprintln!("plugin on: {n} frames, {:.1} s", t1.elapsed().as_secs_f32());

    let d = difference(&with, &bevy_only);
    let added: f64 = d.iter().map(|&x| x as f64).sum();
    let lost: f64 = d.iter().filter(|&&x| x < 0.0).map(|&x| -x as f64).sum();
    let below = project(&mut on, cam, Vec3::ZERO);
    let c = centroid(&d);
    eprintln!(
        "added {added:.3} (Bevy's image {:.3}), lost {lost:.5}, centroid {c}, below the ball {below}",
        lum_sum(&bevy_only)
    );
    assert!(added > 0.01 * lum_sum(&bevy_only), "the caustic adds light");
    assert!(lost < 1e-3 * added, "the plugin only adds");
    assert!(
        c.distance(below) < 0.15 * W as f32,
        "the caustic lies under the ball: centroid {c}, below the ball {below}"
    );

    // the light the plugin added against caustica's own render of the same scene through
    // caustica::scene (its own sphere and floor, the Bevy camera's matrices), on a wgpu
    // device of caustica's own
    let exposure = bevy::camera::Exposure::default().exposure();
    let added_rgb: Vec<f32> = with
        .iter()
        .zip(&bevy_only)
        .enumerate()
        .map(|(i, (a, b))| if i % 4 == 3 { 0.0 } else { (a - b) / exposure })
        .collect();
    let r1 = caustica_reference(&mut on, cam, 0);
    let r2 = caustica_reference(&mut on, cam, 1);
    let noise = rel_l2(&r2, &r1);
    let err = rel_l2(&added_rgb, &r1);
    eprintln!("rel L2: Bevy's added light vs caustica's render {err:.4}; caustica seed 0 vs seed 1 {noise:.4}");
    // Both are Sspm frames of 256^2 photons of one scene; they differ by the photons'
    // seeds and the meshes (Bevy's 48x24 UV sphere and 4 m plane against caustica's
    // 96-segment sphere and quad). Two of caustica's own frames that differ only by the
    // seed differ by `noise` (the photon noise of one frame); two independent frames
    // differ by sqrt(2) times either's error, so a difference within 2x `noise` plus 5%
    // for the tessellation says the plugin adds caustica's light, in its units, where
    // caustica puts it.
    assert!(
        err < 2.0 * noise + 0.05,
        "the plugin's light differs from caustica's own render: {err} (noise {noise})"
    );

    // statistics came back, a frame or more later, without a wait
    let s = stats(&on, cam);
    assert_eq!(s.status, CausticsStatus::Active);
    assert_eq!(s.builds, 1);
    assert!(s.frames_completed > 0 && s.frames_completed <= s.frames_recorded);
    let last = s.last.expect("a finished frame's statistics");
    assert!(last.photons_stored > 0, "{last:?}");
    assert_eq!(last.host_waits, 0);

    // the light moves 1 m along +x: an update, no rebuild, and the caustic follows (-x)
    let updates = s.updates;
    move_light(&mut on);
    let moved = run(&mut on, 0, 4);
    let d2 = difference(&moved, &bevy_only_moved);
    let c2 = centroid(&d2);
    let s = stats(&on, cam);
    eprintln!(
        "after the move: centroid {c2} (was {c}), builds {}, updates {}",
        s.builds, s.updates
    );
    assert_eq!(s.builds, 1, "a moved light rebuilds nothing");
    assert!(s.updates > updates, "the move went through set_lights");
    assert!(
        c2.x < c.x - 1.0,
        "the caustic moved away from the light: {c2} vs {c}"
    );
}

#[test]
fn without_hdr_or_specular_objects_or_with_unusable_meshes_nothing_breaks() {
    let _g = serial();
    let t0 = std::time::Instant::now();
    let mut a = app(true);
    floor_and_light(&mut a);
    // a line mesh and a mesh without positions beside the floor
    {
        use bevy::asset::RenderAssetUsages;
        use bevy::mesh::PrimitiveTopology;
        let w = a.world_mut();
        let lines = Mesh::new(PrimitiveTopology::LineList, RenderAssetUsages::default())
            .with_inserted_attribute(
                Mesh::ATTRIBUTE_POSITION,
                vec![[0.0f32, 0.1, 0.0], [1.0, 0.1, 0.0]],
            );
        let lines = w.resource_mut::<Assets<Mesh>>().add(lines);
        let empty = w.resource_mut::<Assets<Mesh>>().add(Mesh::new(
            PrimitiveTopology::TriangleList,
            RenderAssetUsages::default(),
        ));
        let glass = w
            .resource_mut::<Assets<StandardMaterial>>()
            .add(StandardMaterial {
                specular_transmission: 1.0,
                ..default()
            });
        w.spawn((
            Mesh3d(lines),
            MeshMaterial3d(glass.clone()),
            Transform::default(),
        ));
        // Bevy cannot draw a mesh without positions itself (its prepass pipeline fails
        // validation and Bevy's error policy stops the app, with or without the plugin), so
        // it is hidden here; the plugin's refusal of such a mesh is the unit test
        // `meshes_caustica_cannot_take_are_refused`
        w.spawn((
            Mesh3d(empty),
            MeshMaterial3d(glass),
            Transform::default(),
            Visibility::Hidden,
        ));
    }
    let hdr = camera(&mut a, true, Some(caustics(CausticsTechnique::Sspm)), 0);
    let ldr = camera(&mut a, false, Some(caustics(CausticsTechnique::Sspm)), 1);
    let ortho = camera(&mut a, true, Some(caustics(CausticsTechnique::Sspm)), 2);
    a.world_mut()
        .entity_mut(ortho)
        .insert(Projection::Orthographic(
            OrthographicProjection::default_3d(),
        ));
    run_until_lit(&mut a, 0, 2);
    run_until_lit(&mut a, 1, 2);
    let s = stats(&a, hdr);
    assert!(
        matches!(&s.status, CausticsStatus::Inactive(w) if w.contains("specular")),
        "{:?}",
        s.status
    );
    let s = stats(&a, ldr);
    assert!(
        matches!(&s.status, CausticsStatus::Inactive(w) if w.contains("Hdr")),
        "{:?}",
        s.status
    );
    // a glass ball arrives: the HDR camera starts adding light; the orthographic one
    // cannot (caustica's camera is a pinhole)
    glass_ball(&mut a);
    run(&mut a, 0, 4);
    let s = stats(&a, hdr);
    assert_eq!(s.status, CausticsStatus::Active);
    let s = stats(&a, ortho);
    assert!(
        matches!(&s.status, CausticsStatus::Inactive(w) if w.contains("perspective")),
        "{:?}",
        s.status
    );
    eprintln!("degrade cases: {:.1} s", t0.elapsed().as_secs_f32());
}

fn status_line(app: &App, cam: Entity) -> String {
    let s = stats(app, cam);
    format!(
        "{} {:?} builds {} updates {} frames {}/{}",
        s.technique, s.status, s.builds, s.updates, s.frames_completed, s.frames_recorded
    )
}

#[test]
fn every_technique_per_camera_and_scene_changes_through_updates() {
    let _g = serial();
    let t0 = std::time::Instant::now();
    let mut a = app(true);
    floor_and_light(&mut a);
    let ball = glass_ball(&mut a);
    let cam_a = camera(&mut a, true, Some(caustics(CausticsTechnique::Sspm)), 0);
    let cam_b = camera(
        &mut a,
        true,
        Some(caustics(CausticsTechnique::CausticMap)),
        1,
    );
    camera(&mut a, true, None, 2);
    // Bevy's default MSAA (4 samples): the light goes into the resolved target
    let cam_msaa = camera(&mut a, true, Some(caustics(CausticsTechnique::Sspm)), 3);
    let plain_msaa = camera(&mut a, true, None, 4);
    for c in [cam_msaa, plain_msaa] {
        a.world_mut()
            .entity_mut(c)
            .insert(bevy::render::view::Msaa::Sample4);
    }
    run_until_lit(&mut a, 0, 4);
    {
        let d = difference(
            &latest(&a, 3).expect("msaa"),
            &latest(&a, 4).expect("msaa plain"),
        );
        let add: f64 = d.iter().map(|&x| x as f64).sum();
        eprintln!(
            "with MSAA x4: adds {add:.2}, {:?}",
            stats(&a, cam_msaa).status
        );
        assert!(add > 100.0, "MSAA: the light is added");
        assert!(d.iter().all(|&x| x > -1e-3), "MSAA: only added");
    }
    // the light a camera's technique adds: its image minus the plain camera's
    let added = |a: &App, tag: u32| {
        let plain = latest(a, 2).expect("the plain camera's image");
        let d = difference(&latest(a, tag).expect("an image"), &plain);
        (d.iter().map(|&x| x as f64).sum::<f64>(), lum_sum(&plain))
    };
    for cam in [cam_a, cam_b] {
        let s = stats(&a, cam);
        eprintln!("{}", status_line(&a, cam));
        assert_eq!(s.status, CausticsStatus::Active, "{}", status_line(&a, cam));
        assert_eq!(s.builds, 1);
        assert!(s.frames_completed > 0);
    }
    for tag in [0, 1] {
        let (add, plain) = added(&a, tag);
        eprintln!("camera {tag}: adds {add:.2} to {plain:.2}");
        assert!(add > 0.01 * plain, "camera {tag} adds light");
    }

    // camera A goes through the other techniques; camera B's technique stays as it was
    for (k, t) in [
        CausticsTechnique::AdaptiveCaustics,
        CausticsTechnique::PhotonGi,
        CausticsTechnique::Sspm,
    ]
    .into_iter()
    .enumerate()
    {
        a.world_mut().entity_mut(cam_a).insert(caustics(t));
        run(&mut a, 0, 4);
        let s = stats(&a, cam_a);
        eprintln!("{}", status_line(&a, cam_a));
        assert_eq!(s.technique, t.registry_name());
        assert_eq!(
            s.status,
            CausticsStatus::Active,
            "{}",
            status_line(&a, cam_a)
        );
        assert_eq!(s.builds, 2 + k as u64, "a new technique for a new kind");
        assert!(s.frames_completed > 0);
        let (add, plain) = added(&a, 0);
        eprintln!("{}: adds {add:.2} to {plain:.2}", t.registry_name());
        // PhotonGi adds the floor's light reflected back onto it: little, in this scene
        let least = if t == CausticsTechnique::PhotonGi {
            1e-3
        } else {
            1e-2
        };
        assert!(add > least * plain, "{} adds light", t.registry_name());
        assert_eq!(stats(&a, cam_b).builds, 1, "camera B is untouched");
    }
    // more photons: the same technique, its settings in place
    let before = stats(&a, cam_a);
    a.world_mut().entity_mut(cam_a).insert(Caustics {
        photons: 128,
        ..caustics(CausticsTechnique::Sspm)
    });
    run(&mut a, 0, 3);
    let s = stats(&a, cam_a);
    assert_eq!(s.builds, before.builds, "{}", status_line(&a, cam_a));
    assert!(s.updates > before.updates);

    // the ball moves, then its mesh changes (same triangles): updates, no build
    let builds = (stats(&a, cam_a).builds, stats(&a, cam_b).builds);
    a.world_mut()
        .get_mut::<Transform>(ball)
        .expect("the ball")
        .translation
        .x += 0.3;
    run(&mut a, 0, 3);
    let mesh = a.world().get::<Mesh3d>(ball).expect("a mesh").0.clone();
    {
        let mut meshes = a.world_mut().resource_mut::<Assets<Mesh>>();
        let mut m = meshes.get_mut(&mesh).expect("the ball's mesh");
        if let Some(bevy::mesh::VertexAttributeValues::Float32x3(p)) =
            m.attribute_mut(Mesh::ATTRIBUTE_POSITION)
        {
            for v in p.iter_mut() {
                v[1] *= 0.8; // squashed
            }
        }
    }
    run(&mut a, 0, 3);
    for (cam, b) in [(cam_a, builds.0), (cam_b, builds.1)] {
        let s = stats(&a, cam);
        eprintln!(
            "after the move and the deformation: {}",
            status_line(&a, cam)
        );
        assert_eq!(s.builds, b, "moves and deformations rebuild nothing");
        assert_eq!(s.status, CausticsStatus::Active);
    }

    // the ball's mesh gets other triangles (a coarser sphere): its shape replaced, no
    // build of the technique
    let before = (stats(&a, cam_a), stats(&a, cam_b));
    *a.world_mut()
        .resource_mut::<Assets<Mesh>>()
        .get_mut(&mesh)
        .expect("the ball's mesh") = Sphere::new(0.5).mesh().uv(24, 12);
    run(&mut a, 0, 3);
    for (cam, b) in [(cam_a, &before.0), (cam_b, &before.1)] {
        let s = stats(&a, cam);
        eprintln!("after the new topology: {}", status_line(&a, cam));
        assert_eq!(
            s.builds, b.builds,
            "a mesh of other triangles rebuilds its shape alone"
        );
        assert!(s.updates > b.updates);
        assert_eq!(s.status, CausticsStatus::Active);
    }

    // the floor turns grey: new material parameters, no build
    let floor_material = {
        let w = a.world_mut();
        let mut q = w.query::<(&MeshMaterial3d<StandardMaterial>, &Mesh3d)>();
        let meshes = w.resource::<Assets<Mesh>>();
        q.iter(w)
            .find(|(_, m)| meshes.get(&m.0).is_some_and(|m| m.count_vertices() == 4))
            .map(|(mat, _)| mat.0.clone())
            .expect("the floor")
    };
    let before = (stats(&a, cam_a), stats(&a, cam_b));
    a.world_mut()
        .resource_mut::<Assets<StandardMaterial>>()
        .get_mut(&floor_material)
        .expect("the floor's material")
        .base_color = Color::srgb(0.5, 0.5, 0.5);
    run(&mut a, 0, 3);
    for (cam, b) in [(cam_a, &before.0), (cam_b, &before.1)] {
        let s = stats(&a, cam);
        eprintln!("after the floor's new colour: {}", status_line(&a, cam));
        assert_eq!(
            s.builds, b.builds,
            "a material's new parameters rebuild nothing"
        );
        assert!(s.updates > b.updates);
    }

    // a second ball arrives, then leaves: each a new scene for both cameras' techniques
    let b0 = (stats(&a, cam_a).builds, stats(&a, cam_b).builds);
    let second = glass_ball(&mut a);
    a.world_mut()
        .get_mut::<Transform>(second)
        .expect("a ball")
        .translation = Vec3::new(-1.2, 0.8, -0.5);
    run(&mut a, 0, 3);
    a.world_mut().entity_mut(second).despawn();
    run(&mut a, 0, 3);
    for (cam, b) in [(cam_a, b0.0), (cam_b, b0.1)] {
        let s = stats(&a, cam);
        eprintln!(
            "after a second ball came and went: {}",
            status_line(&a, cam)
        );
        assert_eq!(
            s.builds,
            b + 2,
            "an added and a removed object: a build each"
        );
        assert_eq!(s.status, CausticsStatus::Active);
    }

    // the ball leaves: caustica's scene has no caster left
    a.world_mut().entity_mut(ball).despawn();
    run(&mut a, 0, 3);
    for cam in [cam_a, cam_b] {
        let s = stats(&a, cam);
        eprintln!("after the despawn: {}", status_line(&a, cam));
        assert!(
            matches!(&s.status, CausticsStatus::Inactive(w) if w.contains("specular")),
            "{}",
            status_line(&a, cam)
        );
    }
    eprintln!(
        "techniques and updates: {:.1} s",
        t0.elapsed().as_secs_f32()
    );
}

#[test]
fn a_device_caustica_cannot_run_on_leaves_bevys_image_alone() {
    let _g = serial();
    // Bevy's device with WebGPU's 8 storage buffers per shader stage: enough for Bevy,
    // fewer than caustica's kernels bind (trace_photons binds 19): caustica cannot open
    use caustica::wgpu;
    let instance = wgpu::Instance::new(wgpu::InstanceDescriptor::new_without_display_handle());
    let adapter = bevy::tasks::futures_lite::future::block_on(
        instance.request_adapter(&wgpu::RequestAdapterOptions::default()),
    )
    .expect("an adapter");
    let limits = wgpu::Limits {
        max_storage_buffers_per_shader_stage: 8,
        ..adapter.limits()
    };
    drop((adapter, instance));
    let mut images = Vec::new();
    for plugin in [false, true] {
        let mut a = app_on(plugin, Some(limits.clone()));
        floor_and_light(&mut a);
        glass_ball(&mut a);
        let cam = camera(&mut a, true, Some(caustics(CausticsTechnique::Sspm)), 0);
        let (img, _) = run_until_lit(&mut a, 0, 3);
        if plugin {
            let s = stats(&a, cam);
            eprintln!("{:?}", s.status);
            assert!(
                matches!(&s.status, CausticsStatus::Inactive(w) if w.contains("no backend")),
                "{:?}",
                s.status
            );
        }
        images.push(img);
    }
    assert_eq!(images[0], images[1], "Bevy's image as without the plugin");
}

#[test]
fn a_viewport_gets_the_light_inside_it_and_nothing_outside() {
    let _g = serial();
    let mut a = app(true);
    floor_and_light(&mut a);
    glass_ball(&mut a);
    let cam = camera(&mut a, true, Some(caustics(CausticsTechnique::Sspm)), 0);
    let plain = camera(&mut a, true, None, 1);
    let (x0, y0, w, h) = (24u32, 8u32, 60u32, 48u32);
    for c in [cam, plain] {
        a.world_mut()
            .get_mut::<Camera>(c)
            .expect("a camera")
            .viewport = Some(bevy::camera::Viewport {
            physical_position: UVec2::new(x0, y0),
            physical_size: UVec2::new(w, h),
            ..default()
        });
    }
    run_until_lit(&mut a, 0, 4);
    let d = difference(
        &latest(&a, 0).expect("image"),
        &latest(&a, 1).expect("plain"),
    );
    let (mut inside, mut outside) = (0.0f64, 0.0f64);
    for (i, &v) in d.iter().enumerate() {
        let (x, y) = (i as u32 % W, i as u32 / W);
        if (x0..x0 + w).contains(&x) && (y0..y0 + h).contains(&y) {
            inside += v as f64;
        } else {
            outside += v.abs() as f64;
        }
    }
    let c = centroid(&d);
    let below = project(&mut a, cam, Vec3::ZERO);
    eprintln!(
        "viewport: inside {inside:.2}, outside {outside}, centroid {c}, below the ball {below}"
    );
    assert_eq!(stats(&a, cam).status, CausticsStatus::Active);
    assert!(inside > 10.0, "the viewport gets the caustic");
    assert_eq!(outside, 0.0, "nothing outside the viewport");
    assert!(
        c.distance(below) < 6.0,
        "where the viewport's camera sees it: {c} vs {below}"
    );
}
