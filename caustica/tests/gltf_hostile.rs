//! Hostile glTF files: node hierarchies that are not trees (a cycle, a node with two
//! parents, a diamond of shared children 40 levels deep) are refused before anything
//! walks them; a legal chain 100 000 nodes deep imports without recursion; accessors of
//! a type the reader does not expect (FLOAT indices, VEC2 positions, ...) are refused
//! with an error naming the mesh and primitive instead of panicking in the `gltf`
//! crate; a file that places one mesh by many nodes is refused from the accessors'
//! sizes before it is read. Each file is written to a temporary folder and read with
//! `load_gltf`, as the CLI reads it.
#![cfg(feature = "gltf")]

use caustica::gltf_scene::{load_gltf, GltfImport, MAX_IMPORT_TRIANGLES};
use caustica::scene::format::SceneFileError;
use caustica::scene::Shape;
use serde_json::{json, Value};
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
    let positions: [[f32; 3]; 4] = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0],
    ];
    let normals = [[0.0f32, 1.0, 0.0]; 4];
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
