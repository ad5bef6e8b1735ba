//! OBJ meshes in scene files: a JSON scene whose glass object is an
//! `obj_file` shape loads the OBJ's triangles (faces triangulated, normals kept or
//! generated) and renders as the same scene with the mesh written inline; bad OBJ files
//! are errors located at the shape's `path`.
#![cfg(feature = "obj")]

mod common;

use caustica::scene::builtin::builtin;
use caustica::scene::shapes::tessellate;
use caustica::scene::{Object, Shape};
use caustica::scene_file::load_scene_file;
use std::fmt::Write;

fn dir() -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("caustica-obj-{}", std::process::id()));
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// `sphere` with its ball written to `ball.obj` (as quads where the tessellation pairs
/// triangles would be needed to test triangulation: here triangles and one quad cap).
fn scene_with_obj(d: &std::path::Path) -> (caustica::Scene, caustica::Scene) {
    let s = builtin("sphere").unwrap();
    let k = s.objects.iter().position(|o| o.name == "ball").unwrap();
    let m = tessellate(&s.objects[k].shape);
    let mut obj = String::from("# the sphere scene's ball\no ball\n");
    for p in &m.positions {
        writeln!(obj, "v {} {} {}", p.x, p.y, p.z).unwrap();
    }
    for n in &m.normals {
        writeln!(obj, "vn {} {} {}", n.x, n.y, n.z).unwrap();
    }
    for t in &m.indices {
        let [a, b, c] = t.map(|i| i + 1);
        writeln!(obj, "f {a}//{a} {b}//{b} {c}//{c}").unwrap();
    }
    std::fs::write(d.join("ball.obj"), obj).unwrap();
    let mut with_obj = s.clone();
    with_obj.objects[k] = Object {
        name: "ball".into(),
        material: s.objects[k].material.clone(),
        shape: Shape::ObjFile {
            path: "ball.obj".into(),
        },
        transform: None,
    };
    // the inline twin: the same triangles as a mesh (no uvs: OBJ has none here)
    let mut inline = s.clone();
    inline.objects[k].shape = Shape::Mesh {
        positions: m.positions.clone().into(),
        normals: m.normals.clone().into(),
        uvs: Vec::new().into(),
        indices: m.indices.clone().into(),
    };
    (with_obj, inline)
}

#[test]
fn an_obj_ball_renders_as_its_inline_mesh() {
    let d = dir();
    let (with_obj, inline) = scene_with_obj(&d);
    let path = d.join("sphere-obj.json");
    std::fs::write(&path, caustica::scene::format::to_json(&with_obj)).unwrap();
    let loaded = load_scene_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let k = loaded
        .scene
        .objects
        .iter()
        .position(|o| o.name == "ball")
        .unwrap();
    match (&loaded.scene.objects[k].shape, &inline.objects[k].shape) {
        (
            Shape::Mesh {
                positions: a,
                indices: ia,
                ..
            },
            Shape::Mesh {
                positions: b,
                indices: ib,
                ..
            },
        ) => {
            // the same triangles, corner by corner (tobj renumbers the vertices in the
            // order faces first use them); OBJ's decimal text of an f32 reads back to the
            // same f32
            assert_eq!(ia.len(), ib.len());
            for (ta, tb) in ia.iter().zip(ib.iter()) {
                for c in 0..3 {
                    assert_eq!(a[ta[c] as usize], b[tb[c] as usize]);
                }
            }
        }
        other => panic!("{other:?}"),
    }
    assert!(
        common::render_small(&loaded.scene) == common::render_small(&inline),
        "the OBJ scene renders differently"
    );
}

#[test]
fn quads_are_triangulated_and_missing_normals_generated() {
    let d = dir();
    std::fs::write(
        d.join("quad.obj"),
        "v -1 0 -1\nv 1 0 -1\nv 1 0 1\nv -1 0 1\nf 1 4 3 2\n",
    )
    .unwrap();
    let shape = caustica::scene_file::load_obj(&d.join("quad.obj")).unwrap();
    let m = tessellate(&shape);
    assert_eq!(m.indices.len(), 2);
    // generated normals: the faces' (counter-clockwise seen from +y)
    assert!(
        m.normals.iter().all(|n| (n.y - 1.0).abs() < 1e-6),
        "{:?}",
        m.normals
    );
}

#[test]
fn bad_obj_files_are_located_errors() {
    let d = dir();
    let mut s = builtin("sphere").unwrap();
    s.objects[1].shape = Shape::ObjFile {
        path: "nowhere.obj".into(),
    };
    let path = d.join("missing.json");
    std::fs::write(&path, caustica::scene::format::to_json(&s)).unwrap();
    let e = load_scene_file(&path).unwrap_err();
    assert!(e.line > 0, "{e}");
    assert!(
        e.reason.contains("objects[1].shape.path") && e.reason.contains("nowhere.obj"),
        "{e}"
    );

    std::fs::write(d.join("garbage.obj"), "v 1 2\nf 1 2 3\n").unwrap();
    s.objects[1].shape = Shape::ObjFile {
        path: "garbage.obj".into(),
    };
    std::fs::write(&path, caustica::scene::format::to_json(&s)).unwrap();
    let e = load_scene_file(&path).unwrap_err();
    assert!(e.reason.contains("garbage.obj"), "{e}");
    // without the loader (core's parse_scene), an obj_file shape is a clear error
    let e = caustica::scene::format::parse_scene(&caustica::scene::format::to_json(&s), "x.json")
        .unwrap_err();
    assert!(e.reason.contains("obj"), "{e}");
}
