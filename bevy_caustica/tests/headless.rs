//! Headless Bevy apps on the machine's adapter (lavapipe in CI): a glass ball over a floor
//! under a point light, rendered into an image with the plugin and without it.

mod common;

use bevy::prelude::*;
use bevy_caustica::{Caustics, CausticaStats, CausticsStatus, CausticsTechnique};
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
    eprintln!("plugin off: {n} frames, {:.1} s", t0.elapsed().as_secs_f32());

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
    eprintln!("after the move: centroid {c2} (was {c}), builds {}, updates {}", s.builds, s.updates);
    assert_eq!(s.builds, 1, "a moved light rebuilds nothing");
    assert!(s.updates > updates, "the move went through set_lights");
    assert!(c2.x < c.x - 1.0, "the caustic moved away from the light: {c2} vs {c}");
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
        let glass = w.resource_mut::<Assets<StandardMaterial>>().add(StandardMaterial {
            specular_transmission: 1.0,
            ..default()
        });
        w.spawn((Mesh3d(lines), MeshMaterial3d(glass.clone()), Transform::default()));
        w.spawn((Mesh3d(empty), MeshMaterial3d(glass), Transform::default()));
    }
    let hdr = camera(&mut a, true, Some(caustics(CausticsTechnique::Sspm)), 0);
    let ldr = camera(&mut a, false, Some(caustics(CausticsTechnique::Sspm)), 1);
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
    // a glass ball arrives: the HDR camera starts adding light
    glass_ball(&mut a);
    run(&mut a, 0, 4);
    let s = stats(&a, hdr);
    assert_eq!(s.status, CausticsStatus::Active);
    eprintln!("degrade cases: {:.1} s", t0.elapsed().as_secs_f32());
}
