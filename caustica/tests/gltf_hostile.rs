//! Hostile glTF files: node hierarchies that are not trees (a cycle, a node with two
//! parents, a diamond of shared children 40 levels deep) are refused before anything
//! walks them; a legal chain 100 000 nodes deep imports without recursion; accessors of
//! a type the reader does not expect (FLOAT indices, VEC2 positions, ...) are refused
//! with an error naming the mesh and primitive instead of panicking in the `gltf`
//! crate; a file that places one mesh by many nodes is refused from the accessors'
//! sizes before it is read. Each file is written to a temporary folder and read with
//! `load_gltf`, as the CLI reads it.
#![cfg(feature = "gltf")]

use caustica::glam::Vec3;
use caustica::gltf_scene::{load_gltf, GltfImport, MAX_IMPORT_TRIANGLES};
use caustica::scene::format::SceneFileError;
use caustica::scene::shapes::tessellate;
use caustica::scene::Shape;
use serde_json::{json, Value};
use std::f32::consts::FRAC_1_SQRT_2;
use std::path::PathBuf;

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

/// `data` as standard base64 (with padding).
fn base64(data: &[u8]) -> String {
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= c.len() {
                s.push(B64[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                s.push('=');
            }
        }
    }
    s
}

/// A legal document: mesh 0 is a unit quad in y = 0 (4 vertices with normals and UVs,
/// two triangles by UNSIGNED_INT indices, accessors 0 to 3), placed by the nodes given,
/// with `roots` the scene's nodes. No light and no camera (the importer adds defaults).
fn document(nodes: Value, roots: Value) -> Value {
    document_with_normals(nodes, roots, [[0.0, 1.0, 0.0]; 4])
}

/// [`document`] with the quad's vertex normals `normals` (accessor 1) instead of +y.
fn document_with_normals(nodes: Value, roots: Value, normals: [[f32; 3]; 4]) -> Value {
    let positions: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
    ];
    let uvs: [[f32; 2]; 4] = [[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]];
    let indices: [u32; 6] = [0, 2, 1, 0, 3, 2];
    let mut bin: Vec<u8> = Vec::new();
    for v in positions.iter().chain(&normals).flatten() {
        bin.extend(v.to_le_bytes());
    }
    for v in uvs.iter().flatten() {
        bin.extend(v.to_le_bytes());
    }
    for i in indices {
        bin.extend(i.to_le_bytes());
    }
    json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"name": "quad", "primitives": [{
            "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
            "indices": 3
        }]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
             "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5126, "count": 4, "type": "VEC2"},
            {"bufferView": 3, "componentType": 5125, "count": 6, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 32},
            {"buffer": 0, "byteOffset": 128, "byteLength": 24}
        ],
        "buffers": [{
            "byteLength": bin.len(),
            "uri": format!("data:application/octet-stream;base64,{}", base64(&bin))
        }]
    })
}

/// A fresh temporary folder for this test.
fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!(
        "caustica-gltf-hostile-{}-{name}",
        std::process::id()
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// `doc` written as `<name>.gltf` in a fresh temporary folder and read back.
fn load(name: &str, doc: &Value) -> Result<GltfImport, SceneFileError> {
    let dir = temp_dir(name);
    let path = dir.join(format!("{name}.gltf"));
    std::fs::write(&path, doc.to_string()).unwrap();
    let result = load_gltf(&path);
    let _ = std::fs::remove_dir_all(&dir);
    result
}

/// The one-line message of the error `doc` must give, which must hold every part of
/// `expected`.
fn refused(name: &str, doc: &Value, expected: &[&str]) -> String {
    let e = match load(name, doc) {
        Ok(_) => panic!("{name}: imported, expected an error with {expected:?}"),
        Err(e) => e.to_string(),
    };
    assert!(!e.contains('\n'), "{name}: not one line: {e}");
    for part in expected {
        assert!(e.contains(part), "{name}: '{part}' missing in: {e}");
    }
    e
}

/// Triangles of all the imported objects.
fn triangles(im: &GltfImport) -> usize {
    im.scene
        .objects
        .iter()
        .map(|o| match &o.shape {
            Shape::Mesh { indices, .. } => indices.len(),
            other => panic!("{}: not a mesh: {other:?}", o.name),
        })
        .sum()
}

#[test]
fn a_legal_small_file_still_imports() {
    // the quad at the root and, translated, under a parent: two objects, 4 triangles
    let doc = document(
        json!([
            {"name": "floor", "mesh": 0},
            {"name": "group", "translation": [0.0, 1.0, 0.0], "children": [2]},
            {"name": "raised", "mesh": 0}
        ]),
        json!([0, 1]),
    );
    let im = load("legal", &doc).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(im.scene.objects.len(), 2);
    assert_eq!(triangles(&im), 4);
    let raised = &im.scene.objects[1];
    assert!(raised.name.contains("'raised'"), "{}", raised.name);
    let t = raised
        .transform
        .expect("an instance under its parent's translation");
    assert_eq!(t.translation, glam::Vec3::Y);
}

#[test]
fn a_cycle_is_refused() {
    // the sweep's case: a node that is its own child
    let doc = document(json!([{"mesh": 0, "children": [0]}]), json!([0]));
    refused("self", &doc, &["nodes[0]", "its own ancestor", "trees"]);
    // a cycle of two nodes, under nothing the scene lists: refused all the same
    let doc = document(
        json!([{"mesh": 0}, {"name": "a", "children": [2]}, {"name": "b", "children": [1]}]),
        json!([0]),
    );
    refused("pair", &doc, &["its own ancestor", "trees"]);
}

#[test]
fn a_node_with_two_parents_is_refused() {
    let doc = document(
        json!([{"children": [2]}, {"children": [2]}, {"name": "shared", "mesh": 0}]),
        json!([0, 1]),
    );
    refused(
        "two_parents",
        &doc,
        &[
            "nodes[2] 'shared' is a child of both nodes[0] and nodes[1]",
            "trees",
        ],
    );
    // one parent listing it twice
    let doc = document(json!([{"children": [1, 1]}, {"mesh": 0}]), json!([0]));
    refused("twice", &doc, &["nodes[0] lists nodes[1] twice"]);
    // a scene root that is also a child
    let doc = document(json!([{"children": [1]}, {"mesh": 0}]), json!([0, 1]));
    refused(
        "root_child",
        &doc,
        &["nodes[1] is a root of scenes[0] and a child of nodes[0]"],
    );
    // a root the scene lists twice
    let doc = document(json!([{"mesh": 0}]), json!([0, 0]));
    refused("root_twice", &doc, &["scenes[0] lists nodes[0] twice"]);
}

#[test]
fn a_diamond_of_shared_children_is_refused_at_once() {
    // the sweep's case: 40 levels of two nodes, each the parent of both nodes of the next
    // level, the last level placing the mesh: 2^40 paths, which filled memory
    let levels = 40;
    let mut nodes = Vec::new();
    for l in 0..levels {
        for _ in 0..2 {
            if l + 1 < levels {
                nodes.push(json!({"children": [2 * (l + 1), 2 * (l + 1) + 1]}));
            } else {
                nodes.push(json!({"mesh": 0}));
            }
        }
    }
    let doc = document(Value::Array(nodes), json!([0, 1]));
    refused(
        "diamond",
        &doc,
        &["nodes[2] is a child of both nodes[0] and nodes[1]"],
    );
}

#[test]
fn a_legal_chain_100000_nodes_deep_imports() {
    // each node a little above its parent; the last one places the quad, which lands
    // 100000 * 1e-5 = 1 above the origin (f32 sums: to 1e-2). A recursive walk overflows
    // the test thread's 2 MiB stack well before this depth.
    let depth = 100_000;
    let nodes: Vec<Value> = (0..depth)
        .map(|k| {
            if k + 1 < depth {
                json!({"translation": [0.0, 1e-5, 0.0], "children": [k + 1]})
            } else {
                json!({"name": "leaf", "translation": [0.0, 1e-5, 0.0], "mesh": 0})
            }
        })
        .collect();
    let doc = document(Value::Array(nodes), json!([0]));
    let im = load("deep", &doc).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(im.scene.objects.len(), 1);
    assert_eq!(triangles(&im), 2);
    let o = &im.scene.objects[0];
    assert!(o.name.contains("'leaf'"), "{}", o.name);
    let t = o.transform.expect("an instance at the chain's translation");
    assert!((t.translation.y - 1.0).abs() < 1e-2, "{}", t.translation);
}

#[test]
fn accessors_of_unexpected_types_are_refused_naming_the_primitive() {
    let quad = || document(json!([{"mesh": 0}]), json!([0]));
    // the sweep's case: FLOAT indices (the gltf crate hits unreachable!())
    let mut doc = quad();
    doc["accessors"][3]["componentType"] = json!(5126);
    refused(
        "idx_float",
        &doc,
        &[
            "meshes[0] 'quad' primitive 0",
            "indices accessors[3]",
            "SCALAR of FLOAT",
        ],
    );
    // signed and VEC2 indices
    let mut doc = quad();
    doc["accessors"][3]["componentType"] = json!(5122);
    doc["accessors"][3]["count"] = json!(12);
    refused(
        "idx_short",
        &doc,
        &["primitive 0", "indices", "SCALAR of SHORT"],
    );
    let mut doc = quad();
    doc["accessors"][3]["type"] = json!("VEC2");
    doc["accessors"][3]["count"] = json!(3);
    refused("idx_vec2", &doc, &["indices", "VEC2 of UNSIGNED_INT"]);
    // VEC2 positions (the min and max kept at three values: the gltf crate checks those)
    let mut doc = quad();
    doc["accessors"][0]["type"] = json!("VEC2");
    refused(
        "pos_vec2",
        &doc,
        &["POSITION accessors[0]", "VEC2 of FLOAT", "VEC3 of FLOAT"],
    );
    // UNSIGNED_SHORT normals
    let mut doc = quad();
    doc["accessors"][1]["componentType"] = json!(5123);
    refused(
        "nor_u16",
        &doc,
        &["NORMAL accessors[1]", "VEC3 of UNSIGNED_SHORT"],
    );
    // UNSIGNED_INT texture coordinates (unreachable!() in the gltf crate too)
    let mut doc = quad();
    doc["accessors"][2]["componentType"] = json!(5125);
    refused(
        "uv_u32",
        &doc,
        &["TEXCOORD_0 accessors[2]", "VEC2 of UNSIGNED_INT"],
    );
    // no elements (the gltf crate computes count - 1)
    let mut doc = quad();
    doc["accessors"][3]["count"] = json!(0);
    refused("idx_empty", &doc, &["indices accessors[3]", "no elements"]);
    // a stride smaller than an element (the gltf crate would split one across strides)
    let mut doc = quad();
    doc["bufferViews"][0]["byteStride"] = json!(4);
    refused(
        "stride",
        &doc,
        &["accessors[0]", "byteStride 4", "bufferViews[0]"],
    );
    // a count far past the data, near 2^64: refused, not wrapped around
    let mut doc = quad();
    doc["accessors"][3]["count"] = json!(u64::MAX / 2);
    refused("idx_count_huge", &doc, &["accessors[3]", "bufferViews[3]"]);
}

#[test]
fn one_mesh_placed_by_many_nodes_is_refused_before_it_is_read() {
    // a strip of 2^20 + 2 UNSIGNED_BYTE indices (2^20 triangles, about 1 MiB) placed by
    // 65 nodes: 65 * 2^20 triangles, over the limit of 2^26, counted from the accessors
    let strip = (1usize << 20) + 2;
    let mut doc = document(json!([]), json!([]));
    let mut bin: Vec<u8> = Vec::new();
    for v in [[0.0f32, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, 1.0]] {
        for x in v {
            bin.extend(x.to_le_bytes());
        }
    }
    bin.resize(36 + strip, 0);
    doc["accessors"] = json!([
        {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
         "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
        {"bufferView": 1, "componentType": 5121, "count": strip, "type": "SCALAR"}
    ]);
    doc["bufferViews"] = json!([
        {"buffer": 0, "byteOffset": 0, "byteLength": 36},
        {"buffer": 0, "byteOffset": 36, "byteLength": strip}
    ]);
    doc["buffers"] = json!([{
        "byteLength": bin.len(),
        "uri": format!("data:application/octet-stream;base64,{}", base64(&bin))
    }]);
    doc["meshes"] =
        json!([{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 5}]}]);
    let copies = (MAX_IMPORT_TRIANGLES >> 20) + 1;
    doc["nodes"] = Value::Array((0..copies).map(|_| json!({"mesh": 0})).collect());
    doc["scenes"][0]["nodes"] = json!((0..copies).collect::<Vec<u64>>());
    refused(
        "many_placements",
        &doc,
        &[
            &format!("nodes[{}] places meshes[0]", copies - 1),
            &format!("{} triangles", copies << 20),
            &format!("limit of {MAX_IMPORT_TRIANGLES} triangles"),
        ],
    );
}

#[test]
fn a_base_colour_outside_zero_one_is_clamped_with_a_warning() {
    let mut doc = document(json!([{"name": "floor", "mesh": 0}]), json!([0]));
    doc["materials"] =
        json!([{"pbrMetallicRoughness": {"baseColorFactor": [5.0, -1.0, 0.5, 1.0]}}]);
    doc["meshes"][0]["primitives"][0]["material"] = json!(0);
    let im = load("colour", &doc).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        im.warnings
            .iter()
            .any(|w| w.contains("baseColorFactor") && w.contains("outside [0, 1]")),
        "{:?}",
        im.warnings
    );
}

/// [`document`] with the quad at the root, a perspective camera 'eye' (`cameras[0]`,
/// named 'lens', `perspective` and `extras` as given) on a node above it looking at it.
fn camera_document(perspective: Value, extras: Option<Value>) -> Value {
    let mut doc = document(
        json!([
            {"name": "floor", "mesh": 0},
            {"name": "eye", "camera": 0, "translation": [0.5, 2.0, 0.5],
             "rotation": [-FRAC_1_SQRT_2, 0.0, 0.0, FRAC_1_SQRT_2]}
        ]),
        json!([0, 1]),
    );
    let mut camera = json!({"name": "lens", "type": "perspective", "perspective": perspective});
    if let Some(e) = extras {
        camera["extras"] = e;
    }
    doc["cameras"] = json!([camera]);
    doc
}

#[test]
fn a_camera_size_in_extras_that_is_no_pixel_count_is_refused_naming_the_field() {
    let lens = || json!({"yfov": 0.8, "znear": 0.01, "aspectRatio": 1.7});
    // the audit's case: 2^32 + 64 wrapped to 64 through `as u32`
    let doc = camera_document(
        lens(),
        Some(json!({"caustica": {"width": 4_294_967_360u64, "height": 36}})),
    );
    refused(
        "ext_width_wrap",
        &doc,
        &[
            "nodes[1] 'eye'",
            "cameras[0] 'lens'",
            "extras.caustica.width 4294967360",
            "1..=16384",
        ],
    );
    // zero, negative, fractional, over the limit, not a number: the field named each time
    for (name, width, height, field) in [
        (
            "ext_height_0",
            json!(64),
            json!(0),
            "extras.caustica.height 0",
        ),
        (
            "ext_width_neg",
            json!(-64),
            json!(36),
            "extras.caustica.width -64",
        ),
        (
            "ext_width_frac",
            json!(64.5),
            json!(36),
            "extras.caustica.width 64.5",
        ),
        (
            "ext_height_big",
            json!(64),
            json!(16385),
            "extras.caustica.height 16385",
        ),
        (
            "ext_width_text",
            json!("64"),
            json!(36),
            "extras.caustica.width \"64\"",
        ),
    ] {
        let doc = camera_document(
            lens(),
            Some(json!({"caustica": {"width": width, "height": height}})),
        );
        refused(name, &doc, &["cameras[0] 'lens'", field]);
    }
    // in range (a whole number written as a float too): the size given
    for (w, h) in [(json!(64), json!(36)), (json!(16384.0), json!(1))] {
        let doc = camera_document(lens(), Some(json!({"caustica": {"width": w, "height": h}})));
        let im = load("ext_ok", &doc).unwrap_or_else(|e| panic!("{e}"));
        let c = &im.scene.camera;
        assert_eq!(
            (c.width as u64, c.height as u64),
            (w.as_f64().unwrap() as u64, h.as_f64().unwrap() as u64)
        );
    }
}

#[test]
fn an_aspect_ratio_that_is_not_positive_is_refused_and_an_extreme_one_clamped() {
    let lens = |aspect: Value| json!({"yfov": 0.8, "znear": 0.01, "aspectRatio": aspect});
    // glTF requires aspectRatio > 0; -2 gave a 960 x 1 image without a word
    for (name, aspect, shown) in [
        ("aspect_neg", json!(-2.0), "aspectRatio -2"),
        ("aspect_zero", json!(0.0), "aspectRatio 0"),
        // past f32: infinite
        ("aspect_inf", json!(1e39), "aspectRatio inf"),
    ] {
        let doc = camera_document(lens(aspect), None);
        refused(name, &doc, &["nodes[1] 'eye'", "cameras[0] 'lens'", shown]);
    }
    // the importer's own size: 960 wide at the aspect ratio
    let size = |aspect: f64| {
        let im = load("aspect", &camera_document(lens(json!(aspect)), None))
            .unwrap_or_else(|e| panic!("aspectRatio {aspect}: {e}"));
        let clamped = im
            .warnings
            .iter()
            .any(|w| w.contains("cameras[0] 'lens'") && w.contains("aspectRatio"));
        (im.scene.camera.width, im.scene.camera.height, clamped)
    };
    assert_eq!(size(1.7), (960, 565, false));
    assert_eq!(size(960.0 / 16384.0), (960, 16384, false));
    // legal but extreme: within 1..=16384 on both sides, as near the aspect as that
    // allows, with a warning (0.05 asked for 960 x 19200; 1e-30 for 960 x 9.6e32 pixels,
    // which the scene's validator refused as a camera height the file does not have)
    assert_eq!(size(0.05), (819, 16384, true));
    assert_eq!(size(1e-30), (1, 16384, true));
    // wide: 960 / 3000 rounds to 0 rows (was silently 960 x 1)
    assert_eq!(size(3000.0), (3000, 1, true));
    assert_eq!(size(1e30), (16384, 1, true));
}

#[test]
fn normals_under_a_singular_or_near_singular_scale_stay_unit_and_finite() {
    // the audit's cases: a flat quad squashed further along its normal (scale y 0 gave
    // NaN normals, 1e-30 normals of 1e30, and the file was refused for its normals); a
    // mirrored flat one (its winding and normals must agree)
    for (name, scale) in [
        ("scale_y0", [1.0f32, 0.0, 1.0]),
        ("scale_y_tiny", [1.0, 1e-30, 1.0]),
        ("scale_mirror_y0", [-1.0, 0.0, 1.0]),
        ("scale_small", [1e-3, 1e-30, 2.0]),
    ] {
        let doc = document(
            json!([{"name": "flat", "mesh": 0, "scale": scale}]),
            json!([0]),
        );
        let im = load(name, &doc).unwrap_or_else(|e| panic!("{name}: {e}"));
        assert_eq!(im.scene.objects.len(), 1, "{name}");
        let o = &im.scene.objects[0];
        let Shape::Mesh {
            normals,
            positions,
            indices,
            ..
        } = &o.shape
        else {
            panic!("{name}: not a mesh")
        };
        assert_eq!(normals.len(), 4, "{name}: the file's normals kept");
        // the +y normals transformed by the cofactor matrix: still +y, or -y when mirrored
        let expected = if scale[0] < 0.0 { -Vec3::Y } else { Vec3::Y };
        for n in normals.iter() {
            assert!(
                n.is_finite() && (*n - expected).length() < 1e-6,
                "{name}: normal {n}"
            );
        }
        // every triangle faces the way its normals point
        for t in indices.iter() {
            let [a, b, c] = t.map(|i| positions[i as usize]);
            let face = (b - a).cross(c - a);
            assert!(
                face.dot(normals[t[0] as usize]) > 0.0,
                "{name}: face {face}"
            );
        }
    }
    // a normal the scale collapses (+x, on the quad squashed along y): the primitive's
    // normals are dropped with a warning and generated from its faces
    let doc = document_with_normals(
        json!([{"name": "flat", "mesh": 0, "scale": [1.0, 0.0, 1.0]}]),
        json!([0]),
        [
            [0.0, 1.0, 0.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 1.0, 0.0],
        ],
    );
    let im = load("collapsed", &doc).unwrap_or_else(|e| panic!("collapsed: {e}"));
    assert!(
        im.warnings.iter().any(|w| w.contains("nodes[0] 'flat'")
            && w.contains("primitive 0")
            && w.contains("NORMAL")),
        "{:?}",
        im.warnings
    );
    let o = &im.scene.objects[0];
    let Shape::Mesh { normals, .. } = &o.shape else {
        panic!("not a mesh")
    };
    assert!(normals.is_empty(), "{normals:?}");
    for n in &tessellate(&o.shape).normals {
        assert!((*n - Vec3::Y).length() < 1e-6, "generated normal {n}");
    }
    // a zero normal in the file is the file's own: refused naming it, as without a scale
    for (name, scale) in [
        ("zero_normal_scaled", [1.0f32, 0.0, 1.0]),
        ("zero_normal", [1.0; 3]),
    ] {
        let doc = document_with_normals(
            json!([{"name": "flat", "mesh": 0, "scale": scale}]),
            json!([0]),
            [[0.0, 1.0, 0.0], [0.0; 3], [0.0, 1.0, 0.0], [0.0, 1.0, 0.0]],
        );
        refused(name, &doc, &["normals[1]", "zero-length direction"]);
    }
}
