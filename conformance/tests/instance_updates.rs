//! Instances moved between frames, on every backend: an object with a
//! transform is an instance over the two-level acceleration structure, and
//! `set_object_transforms` moves it without rebuilding a BVH. For every technique (and
//! AdaptiveCaustics' two targets) the
//! frame after a move (of casters, and for CausticMap of a receiver whose area changes)
//! equals, bitwise, the frame of a technique created for the moved scene; moving a static
//! object, an unknown one or with a bad transform is a clear error that changes nothing;
//! and an instance placed by the identity transform renders as the same object in the
//! static level does.

use caustica_conformance::backends;
use caustica_conformance::techniques::frame_outputs;
use caustica_core::scene::builtin::builtin;
use caustica_core::scene::{Light, Scene, Shape, Transform};
use caustica_core::techniques::create;
use caustica_core::Backend;
use glam::{Quat, Vec3};

fn small(name: &str) -> Scene {
    let mut s = builtin(name).expect("built-in scene");
    s.camera.width = 64;
    s.camera.height = 36;
    s
}

/// Object `k` as an instance: a sphere or quad re-centred at the origin, its centre the
/// translation (the same world geometry up to the transform's rounding).
fn instanced(mut scene: Scene, k: usize) -> Scene {
    let o = &mut scene.objects[k];
    let center = match &mut o.shape {
        Shape::Sphere { center, .. } | Shape::Quad { center, .. } => {
            std::mem::replace(center, Vec3::ZERO)
        }
        other => panic!("instanced: {other:?} is not a sphere or quad"),
    };
    o.transform = Some(Transform::from_translation(center));
    scene
}

/// A move of an instance: shifted, turned 30 degrees and scaled by `scale`.
fn moved(t: Transform, shift: Vec3, scale: f32) -> Transform {
    Transform {
        translation: t.translation + shift,
        rotation: Quat::from_axis_angle(
            Vec3::new(1.0, 2.0, 0.5).normalize(),
            std::f32::consts::FRAC_PI_6,
        ) * t.rotation,
        scale: t.scale * scale,
    }
}

/// Every technique with small settings, AdaptiveCaustics with both targets.
fn variants() -> Vec<(&'static str, serde_json::Value)> {
    let mut v: Vec<(&'static str, serde_json::Value)> = ["sspm", "caustic-map", "photon-gi"]
        .into_iter()
        .map(|n| (n, settings_for(n)))
        .collect();
    // as technique_seam.rs: three levels, the error metric from the second
    v.push((
        "adaptive-caustics",
        serde_json::json!({
            "photons_w": 256, "photons_h": 256, "atlas_size": 128, "error_from_grid": 128
        }),
    ));
    v.push((
        "adaptive-caustics",
        serde_json::json!({
            "photons_w": 256, "photons_h": 256, "error_from_grid": 128, "deposit": "screen"
        }),
    ));
    v
}

/// Small settings per technique (as technique_seam.rs: PhotonGi without its temporal
/// blend, whose second frame blends the first by design).
fn settings_for(name: &str) -> serde_json::Value {
    match name {
        "caustic-map" => serde_json::json!({ "photons_w": 64, "photons_h": 64, "atlas_size": 128 }),
        "photon-gi" => serde_json::json!({
            "photons_w": 64, "photons_h": 64, "rsm_size": 32, "temporal": false
        }),
        _ => serde_json::json!({ "photons_w": 64, "photons_h": 64 }),
    }
}

/// The outputs of the first frame of technique `name` created for `scene`.
fn fresh_outputs(
    b: &mut dyn Backend,
    name: &str,
    scene: &Scene,
    settings: &serde_json::Value,
) -> Vec<(String, Vec<[f32; 4]>)> {
    let mut fresh = create(name, b, scene, settings).expect("create");
    let want = frame_outputs(fresh.as_mut(), b);
    fresh.free(b).expect("free");
    want
}

/// `got` (the frame after an update) equals `want` (a fresh technique's) and differs from
/// `before` (the frame before the update). (No `assert_eq!`: it would print every pixel.)
fn same_as_fresh<T: PartialEq>(got: &T, want: &T, before: &T, what: &str) {
    assert!(
        got == want,
        "{what}: the technique differs from a fresh one"
    );
    assert!(
        got != before,
        "{what}: the update changed nothing in the image"
    );
}

/// A scene, the instances moved in it and, optionally, its lights moved too.
type Case = (
    &'static str,
    Scene,
    Vec<(usize, Transform)>,
    Option<Vec<Light>>,
);

/// The scenes and moves: `sphere` with its glass ball an instance (moved, turned, shrunk;
/// the light moved too), and `cornell` with both balls and the back wall instances (the
/// wall, a CausticMap receiver, moved forward and grown, so that its atlas tile grows).
fn cases() -> Vec<Case> {
    let sphere = instanced(small("sphere"), 1);
    let t = sphere.objects[1].transform.unwrap();
    let mut lights = sphere.lights.clone();
    if let Light::Point { position, .. } = &mut lights[0] {
        *position += Vec3::new(0.4, -0.2, 0.3);
    }
    let sphere_moves = vec![(1, moved(t, Vec3::new(0.3, 0.1, -0.2), 0.9))];
    let cornell = instanced(instanced(instanced(small("cornell"), 2), 5), 6);
    let cornell_moves = vec![
        (
            5,
            moved(
                cornell.objects[5].transform.unwrap(),
                Vec3::new(0.2, 0.1, 0.1),
                0.8,
            ),
        ),
        (
            2,
            Transform {
                translation: cornell.objects[2].transform.unwrap().translation + 0.1 * Vec3::Z,
                scale: Vec3::new(1.0, 1.1, 1.0),
                ..Transform::IDENTITY
            },
        ),
    ];
    vec![
        ("sphere", sphere, sphere_moves, Some(lights)),
        ("cornell", cornell, cornell_moves, None),
    ]
}

fn apply(scene: &Scene, moves: &[(usize, Transform)], lights: &Option<Vec<Light>>) -> Scene {
    let mut s = scene.clone();
    for (k, t) in moves {
        s.objects[*k].transform = Some(*t);
    }
    if let Some(l) = lights {
        s.lights = l.clone();
    }
    s
}

#[test]
fn moved_instances_equal_a_fresh_technique_bitwise_for_every_technique() {
    for (bname, mut b) in backends() {
        for (sname, scene, moves, lights) in cases() {
            let target = apply(&scene, &moves, &lights);
            for (name, settings) in variants() {
                let want = fresh_outputs(b.as_mut(), name, &target, &settings);

                let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
                let before = frame_outputs(t.as_mut(), b.as_mut());
                t.set_object_transforms(b.as_mut(), &moves)
                    .expect("set_object_transforms");
                if let Some(l) = &lights {
                    t.set_lights(b.as_mut(), l).expect("set_lights");
                }
                let got = frame_outputs(t.as_mut(), b.as_mut());
                same_as_fresh(
                    &got,
                    &want,
                    &before,
                    &format!("{bname}/{name}/{sname}: moved"),
                );
                // and back: the first placement again equals the first frame
                let back: Vec<(usize, Transform)> = moves
                    .iter()
                    .map(|(k, _)| (*k, scene.objects[*k].transform.unwrap()))
                    .collect();
                t.set_object_transforms(b.as_mut(), &back)
                    .expect("move back");
                t.set_lights(b.as_mut(), &scene.lights)
                    .expect("lights back");
                let again = frame_outputs(t.as_mut(), b.as_mut());
                assert!(
                    again == before,
                    "{bname}/{name}/{sname} ({settings}): moved back, the frame differs from the first"
                );
                t.free(b.as_mut()).expect("free");
            }
            eprintln!("{bname}: moved instances of {sname} equal fresh techniques, bitwise");
        }
    }
}

#[test]
fn static_objects_unknown_objects_and_bad_transforms_are_refused() {
    for (bname, mut b) in backends() {
        let scene = instanced(small("sphere"), 1);
        for (name, settings) in variants() {
            let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
            let before = frame_outputs(t.as_mut(), b.as_mut());
            let bad: [(Vec<(usize, Transform)>, &str); 4] = [
                (vec![(0, Transform::IDENTITY)], "static level"),
                (vec![(7, Transform::IDENTITY)], "does not exist"),
                (
                    vec![(
                        1,
                        Transform::from_translation(Vec3::new(f32::NAN, 0.0, 0.0)),
                    )],
                    "translation",
                ),
                (
                    vec![(
                        1,
                        Transform {
                            scale: Vec3::new(1.0, -1.0, 1.0),
                            ..Transform::IDENTITY
                        },
                    )],
                    "mirrors",
                ),
            ];
            for (moves, says) in bad {
                let e = t
                    .set_object_transforms(b.as_mut(), &moves)
                    .expect_err("a bad move must be refused")
                    .to_string();
                assert!(
                    e.contains(says),
                    "{bname}/{name}: '{e}' should say '{says}'"
                );
            }
            assert!(
                frame_outputs(t.as_mut(), b.as_mut()) == before,
                "{bname}/{name}: a refused move changed the frame"
            );
            t.free(b.as_mut()).expect("free");
        }
        eprintln!("{bname}: bad moves are refused and change nothing");
    }
}

/// The identity placement: `sphere` with its ball an instance at the ball's centre (so
/// object and world coordinates differ by that translation) against the static ball. Not
/// bitwise: the instance's triangles are tested in object space, whose coordinates round
/// differently from the world ones (a few ulps of the ball's 1-unit centre), so a photon
/// may hit a triangle a few ulps elsewhere and land in a neighbouring pixel. What must
/// hold is the energy: the total caustic flux over the image (every photon counted once,
/// wherever it lands) within 1% (at 64^2 photons a handful of photons changing pixels or
/// fate moves the total by far less), and the direct image, where no photon is involved,
/// within 2^-13 of its peak per pixel (argued below).
#[test]
fn an_instance_renders_as_the_same_object_in_the_static_level() {
    for (bname, mut b) in backends() {
        let plain = small("sphere");
        let inst = instanced(plain.clone(), 1);
        let settings = settings_for("sspm");
        let mut outs = Vec::new();
        for s in [&plain, &inst] {
            let mut t = create("sspm", b.as_mut(), s, &settings).expect("create");
            outs.push(frame_outputs(t.as_mut(), b.as_mut()));
            t.free(b.as_mut()).expect("free");
        }
        let get = |k: usize, n: &str| {
            outs[k]
                .iter()
                .find(|(name, _)| name == n)
                .map(|(_, p)| p.clone())
                .expect("output")
        };
        let total = |p: &[[f32; 4]]| p.iter().map(|t| (t[0] + t[1] + t[2]) as f64).sum::<f64>();
        let (a, c) = (
            total(&get(0, "caustics_raw")),
            total(&get(1, "caustics_raw")),
        );
        assert!(a > 0.0, "{bname}: no caustic");
        assert!(
            (a - c).abs() <= 0.01 * a,
            "{bname}: caustic flux {c} vs static {a}"
        );
        let (dp, dq) = (get(0, "direct"), get(1, "direct"));
        let peak = dp
            .iter()
            .map(|p| p[0].max(p[1]).max(p[2]))
            .fold(0.0f32, f32::max);
        let mut worst = 0.0f32;
        let mut differing = 0;
        for (p, q) in dp.iter().zip(&dq) {
            let d = (0..3).map(|k| (p[k] - q[k]).abs()).fold(0.0f32, f32::max);
            worst = worst.max(d / peak);
            differing += (d > 0.0) as usize;
        }
        eprintln!(
            "{bname}: direct: {differing} of {} pixels differ, worst {worst:e} of the peak",
            dp.len()
        );
        // The instance's barycentrics come from object-space coordinates (magnitude <= 0.5)
        // instead of world ones (<= 1.5): each carries a relative error of a few ulps of
        // the coordinates over the triangle's edge (2 pi 0.5 / 384 = 0.008), about 2^-15;
        // the shading normal then moves by that fraction of its change across one triangle
        // (<= 2 pi / 384 = 0.016 rad), i.e. by ~5e-7 rad, and the radiance (albedo/pi E
        // cos) by that fraction of the peak. 2^-13 of the peak is 250x that; a shadow
        // ray flipping at a shadow edge would exceed it (and be worth a look).
        assert!(
            worst <= 1.0 / 8192.0,
            "{bname}: the instance's direct light differs by {worst:e} of the peak"
        );
        eprintln!("{bname}: the identity-placed instance renders as the static object");
    }
}

/// Object `k`'s tessellated vertices (object space) deformed: stretched, squashed,
/// rippled and bent out of their plane, by `amount` (0: as they are).
fn deformed_positions(scene: &Scene, k: usize, amount: f32) -> Vec<Vec3> {
    caustica_core::scene::shapes::tessellate(&scene.objects[k].shape)
        .positions
        .iter()
        .map(|p| {
            *p + amount
                * Vec3::new(
                    0.1 * p.x,
                    -0.2 * p.y + 0.05 * (3.0 * p.x).sin(),
                    0.05 * p.x * p.y,
                )
        })
        .collect()
}

/// `scene` with object `k` replaced by the mesh `set_object_vertices` makes of it.
fn with_mesh(scene: &Scene, k: usize, positions: &[Vec3]) -> Scene {
    let m = caustica_core::scene::shapes::tessellate(&scene.objects[k].shape);
    let mut s = scene.clone();
    s.objects[k].shape = Shape::Mesh {
        positions: positions.to_vec().into(),
        normals: Vec::new().into(),
        uvs: m.uvs.into(),
        indices: m.indices.into(),
    };
    s
}

/// Deformed instances (the bottom level of deformed meshes only): for
/// every technique the frame after `set_object_vertices` equals, bitwise, the frame of a
/// technique created for the deformed scene: `sphere`'s glass ball (a caster), and
/// `cornell`'s back wall (a CausticMap receiver, bent out of its plane, so its atlas tile
/// and texel areas change) with a ball. Going back to the first vertices gives the first
/// frame again; a static object, another vertex count and an unknown object are clear
/// errors that change nothing.
#[test]
fn deformed_instances_equal_a_fresh_technique_bitwise_for_every_technique() {
    for (bname, mut b) in backends() {
        let cases = [
            ("sphere", instanced(small("sphere"), 1), vec![1]),
            (
                "cornell",
                instanced(instanced(small("cornell"), 2), 5),
                vec![2, 5],
            ),
        ];
        for (sname, scene, objects) in cases {
            let mut target = scene.clone();
            for &k in &objects {
                target = with_mesh(&target, k, &deformed_positions(&scene, k, 1.0));
            }
            for (name, settings) in variants() {
                let want = fresh_outputs(b.as_mut(), name, &target, &settings);

                let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
                let before = frame_outputs(t.as_mut(), b.as_mut());
                for &k in &objects {
                    t.set_object_vertices(b.as_mut(), k, &deformed_positions(&scene, k, 1.0), &[])
                        .expect("set_object_vertices");
                }
                let got = frame_outputs(t.as_mut(), b.as_mut());
                same_as_fresh(
                    &got,
                    &want,
                    &before,
                    &format!("{bname}/{name}/{sname}: deformed"),
                );
                // refused, and nothing changes: a static object (the floor), another
                // vertex count, an unknown object
                let p = deformed_positions(&scene, objects[0], 1.0);
                assert!(t.set_object_vertices(b.as_mut(), 0, &p, &[]).is_err());
                assert!(t
                    .set_object_vertices(b.as_mut(), objects[0], &p[1..], &[])
                    .is_err());
                assert!(t.set_object_vertices(b.as_mut(), 999, &p, &[]).is_err());
                let again = frame_outputs(t.as_mut(), b.as_mut());
                assert!(
                    again == want,
                    "{bname}/{name}/{sname}: a refused deformation changed the frame"
                );
                // back to the first vertices and normals: the first frame
                for &k in &objects {
                    let m = caustica_core::scene::shapes::tessellate(&scene.objects[k].shape);
                    t.set_object_vertices(b.as_mut(), k, &m.positions, &m.normals)
                        .expect("deform back");
                }
                let back = frame_outputs(t.as_mut(), b.as_mut());
                assert!(
                    back == before,
                    "{bname}/{name}/{sname} ({settings}): deformed back, the frame differs from the first"
                );
                t.free(b.as_mut()).expect("free");
            }
            eprintln!("{bname}: deformed instances of {sname} equal fresh techniques, bitwise");
        }
    }
}

/// Replaced shapes (another triangle count: a mesh whose topology changed): for every
/// technique the frame after `set_object_shape` equals, bitwise, the frame of a technique
/// created for the changed scene: `sphere`'s glass ball made coarser (a caster), and
/// `cornell`'s back wall (a CausticMap receiver) made a box, with a ball a cube; a static
/// object (the floor) may change too. The old shape back gives the first frame again; an
/// unknown object and an invalid shape are clear errors that change nothing.
#[test]
fn replaced_shapes_equal_a_fresh_technique_bitwise_for_every_technique() {
    let ball = Shape::Sphere {
        center: Vec3::ZERO,
        radius: 0.5,
        segments: 24,
    };
    // the static level's floor: a smaller quad
    let floor_of = |h: f32| Shape::Quad {
        center: Vec3::ZERO,
        u: Vec3::new(h, 0.0, 0.0),
        v: Vec3::new(0.0, 0.0, -h),
    };
    let cube = |h: f32| Shape::Cuboid {
        min: Vec3::splat(-h),
        max: Vec3::splat(h),
    };
    for (bname, mut b) in backends() {
        let cases = [
            (
                "sphere",
                instanced(small("sphere"), 1),
                vec![(1, ball.clone()), (0, floor_of(1.5))],
            ),
            (
                "cornell",
                instanced(instanced(small("cornell"), 2), 5),
                vec![(2, cube(0.3)), (5, cube(0.2))],
            ),
        ];
        for (sname, scene, changes) in cases {
            let mut target = scene.clone();
            for (k, shape) in &changes {
                target.objects[*k].shape = shape.clone();
            }
            for (name, settings) in variants() {
                let want = fresh_outputs(b.as_mut(), name, &target, &settings);
                let mut t = create(name, b.as_mut(), &scene, &settings).expect("create");
                let before = frame_outputs(t.as_mut(), b.as_mut());
                for (k, shape) in &changes {
                    t.set_object_shape(b.as_mut(), *k, shape)
                        .expect("set_object_shape");
                }
                let got = frame_outputs(t.as_mut(), b.as_mut());
                same_as_fresh(
                    &got,
                    &want,
                    &before,
                    &format!("{bname}/{name}/{sname}: replaced"),
                );
                // refused, and nothing changes: an unknown object, a degenerate shape
                assert!(t.set_object_shape(b.as_mut(), 999, &ball).is_err());
                let flat = Shape::Sphere {
                    center: Vec3::ZERO,
                    radius: 0.0,
                    segments: 24,
                };
                assert!(t.set_object_shape(b.as_mut(), changes[0].0, &flat).is_err());
                let again = frame_outputs(t.as_mut(), b.as_mut());
                assert!(
                    again == want,
                    "{bname}/{name}/{sname}: a refused replacement changed the frame"
                );
                for (k, _) in &changes {
                    t.set_object_shape(b.as_mut(), *k, &scene.objects[*k].shape)
                        .expect("shape back");
                }
                let back = frame_outputs(t.as_mut(), b.as_mut());
                assert!(
                    back == before,
                    "{bname}/{name}/{sname} ({settings}): shape back, the frame differs from the first"
                );
                t.free(b.as_mut()).expect("free");
            }
            eprintln!("{bname}: replaced shapes of {sname} equal fresh techniques, bitwise");
        }
    }
}
