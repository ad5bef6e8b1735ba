//! glTF 2.0 in and out: every built-in scene survives `scene_to_gltf` ->
//! `parse_gltf`; the glTF twins render as their JSON scenes on the CPU backend; node
//! transforms (rotation, scale, a mirroring instance) land where the matrices say, with
//! outward normals; GLB containers read as the same document; bad files get one-line,
//! located errors; what caustica cannot represent comes back as warnings.
#![cfg(feature = "gltf")]

mod common;

use caustica::gltf_scene::{parse_gltf, scene_to_gltf, LUMINOUS_EFFICACY_LM_PER_W};
use caustica::scene::builtin::{builtin, BUILTIN_SCENES};
use caustica::scene::shapes::tessellate;
use caustica::scene::{Light, Material, Shape};
use glam::Vec3;

fn rel(a: f32, b: f32) -> f32 {
    (a - b).abs() / a.abs().max(b.abs()).max(1e-30)
}

fn import(text: &str) -> caustica::gltf_scene::GltfImport {
    parse_gltf(text.as_bytes(), "test.gltf", "test", None).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn every_built_in_scene_survives_a_gltf_round_trip() {
    for name in BUILTIN_SCENES {
        let s = builtin(name).unwrap();
        let im = import(&scene_to_gltf(&s));
        assert!(im.warnings.is_empty(), "{name}: {:?}", im.warnings);
        let t = im.scene;
        assert_eq!(t.objects.len(), s.objects.len(), "{name}");
        for (a, b) in s.objects.iter().zip(&t.objects) {
            let (ma, mb) = (tessellate(&a.shape), tessellate(&b.shape));
            // identity transforms: positions and indices exactly, normals to rounding
            assert_eq!(ma.positions, mb.positions, "{name}: {}", a.name);
            assert_eq!(ma.indices, mb.indices, "{name}: {}", a.name);
            assert_eq!(ma.uvs, mb.uvs, "{name}: {}", a.name);
            assert_eq!(ma.normals, mb.normals, "{name}: {}", a.name);
            // the same material
            match (&s.materials[&a.material], &t.materials[&b.material]) {
                (Material::Diffuse { albedo: x }, Material::Diffuse { albedo: y }) => {
                    assert_eq!(x, y)
                }
                (Material::Mirror { reflectance: x }, Material::Mirror { reflectance: y }) => {
                    assert_eq!(x, y)
                }
                (
                    Material::Dielectric {
                        ior: i0,
                        cauchy_b: b0,
                        absorption: a0,
                        ior_model: m0,
                    },
                    Material::Dielectric {
                        ior: i1,
                        cauchy_b: b1,
                        absorption: a1,
                        ior_model: m1,
                    },
                ) => {
                    // ior through n_d and back; B through the Abbe number; sigma through
                    // exp and ln: a few ulp each
                    assert_eq!(m0, m1, "{name}: the index model");
                    assert!(rel(*i0, *i1) < 1e-6, "{name}: ior {i0} vs {i1}");
                    assert!((b0 - b1).abs() <= 1e-5 * b0.abs(), "{name}: B {b0} vs {b1}");
                    for k in 0..3 {
                        assert!(
                            (a0[k] - a1[k]).abs() <= 1e-5 * a0.max_element(),
                            "{name}: {a0} vs {a1}"
                        );
                    }
                }
                (x, y) => panic!("{name}: {} became {x:?} -> {y:?}", a.name),
            }
        }
        // lights and camera exactly: caustica keeps its own values in extras.caustica
        // (used where the standard fields agree with them)
        assert_eq!(s.lights, t.lights, "{name}");
        assert_eq!(s.camera, t.camera, "{name}");
        let _ = light_power;
    }
}

fn light_power(l: &Light) -> Vec3 {
    match l {
        Light::Point { intensity, .. } | Light::Spot { intensity, .. } => *intensity,
        Light::Directional { irradiance, .. } => *irradiance,
    }
}

/// Relative L2 difference of two images over every channel.
fn image_difference(a: &[[f32; 4]], b: &[[f32; 4]]) -> f64 {
    let (mut d, mut n) = (0.0f64, 0.0f64);
    for (p, q) in a.iter().zip(b) {
        for k in 0..3 {
            d += (p[k] as f64 - q[k] as f64).powi(2);
            n += (p[k] as f64).powi(2);
        }
    }
    (d / n.max(1e-300)).sqrt()
}

/// KHR_materials_dispersion reads as the extension's own index model: the Abbe number
/// `V_d = 20 / dispersion` with the `KHR_materials_ior` index as `n_d`; caustica's Abbe
/// glass writes and reads back as itself, exactly through `extras.caustica` and, without
/// the extras, through the standard fields to f32 rounding (`20 / (20 / V)`: 2 ulp).
#[test]
fn khr_dispersion_is_the_abbe_model() {
    use caustica::scene::IorModel;
    let mut s = builtin("prism").unwrap();
    let abbe = Material::Dielectric {
        ior: 1.62,
        cauchy_b: 0.0,
        absorption: Vec3::ZERO,
        ior_model: IorModel::Abbe { abbe_number: 36.4 },
    };
    s.materials.insert("flint".into(), abbe.clone());
    let text = scene_to_gltf(&s);
    assert_eq!(import(&text).scene.materials["flint"], abbe);
    // the standard fields alone (another exporter's file)
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    for m in doc["materials"].as_array_mut().unwrap() {
        m.as_object_mut().unwrap().remove("extras");
    }
    let plain = import(&doc.to_string()).scene;
    let Material::Dielectric {
        ior,
        cauchy_b,
        ior_model: IorModel::Abbe { abbe_number },
        ..
    } = plain.materials["flint"]
    else {
        panic!("the Abbe model: {:?}", plain.materials["flint"]);
    };
    assert_eq!((ior, cauchy_b), (1.62, 0.0));
    assert!(
        (abbe_number - 36.4).abs() <= 4.0 * f32::EPSILON * 36.4,
        "{abbe_number}"
    );
}

#[test]
fn gltf_twins_render_as_their_json_scenes() {
    // sphere: transmission + ior + volume (no absorption); jelly: volume attenuation;
    // prism: dispersion; cornell: mirror and glass
    for name in ["sphere", "jelly", "prism", "cornell"] {
        let s = builtin(name).unwrap();
        let twin = import(&scene_to_gltf(&s)).scene;
        let (a, b) = (common::render_small(&s), common::render_small(&twin));
        // the same triangles, materials, lights and camera (caustica's exact values in
        // extras.caustica, which agree with the standard fields): bitwise the same frame
        let d = image_difference(&a, &b);
        assert!(a == b, "{name}: the twin differs, relative L2 {d}");
    }
}

/// A hand-written glTF: one quad mesh (two triangles in the xz plane at y = 0, normal +y)
/// used by two nodes, one rotated, scaled and translated, one mirrored by a negative
/// scale; a point light and a spot light under a rotated parent; a camera.
fn instanced_document() -> String {
    // positions (4 x vec3), normals (4 x vec3), indices (6 x u32)
    let pos: [f32; 12] = [
        -1.0, 0.0, -1.0, 1.0, 0.0, -1.0, 1.0, 0.0, 1.0, -1.0, 0.0, 1.0,
    ];
    let nor: [f32; 12] = [0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    let idx: [u32; 6] = [0, 2, 1, 0, 3, 2];
    let mut bin: Vec<u8> = Vec::new();
    bin.extend(pos.iter().flat_map(|x| x.to_le_bytes()));
    bin.extend(nor.iter().flat_map(|x| x.to_le_bytes()));
    bin.extend(idx.iter().flat_map(|x| x.to_le_bytes()));
    let b64 = {
        // the exporter's encoder is private: a tiny one here
        const T: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
        let mut s = String::new();
        for c in bin.chunks(3) {
            let n = (c[0] as u32) << 16
                | (*c.get(1).unwrap_or(&0) as u32) << 8
                | *c.get(2).unwrap_or(&0) as u32;
            for k in 0..4 {
                s.push(if k <= c.len() {
                    T[(n >> (18 - 6 * k) & 63) as usize] as char
                } else {
                    '='
                });
            }
        }
        s
    };
    let half = std::f32::consts::FRAC_1_SQRT_2;
    serde_json::json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_lights_punctual"],
        "extensions": {"KHR_lights_punctual": {"lights": [
            {"type": "point", "intensity": 683.0 * 5.0, "color": [1.0, 0.5, 0.25]},
            {"type": "spot", "intensity": 683.0, "spot": {"innerConeAngle": 0.2, "outerConeAngle": 0.4}}
        ]}},
        "scene": 0,
        "scenes": [{"nodes": [0, 1, 2, 4]}],
        "nodes": [
            {"name": "floor", "mesh": 0, "scale": [3.0, 1.0, 2.0]},
            {"name": "tilted", "mesh": 0, "translation": [0.0, 1.0, 0.0],
             "rotation": [half, 0.0, 0.0, half], "scale": [0.5, 0.5, 0.5]},
            {"name": "lights", "rotation": [0.0, half, 0.0, half], "children": [3, 5]},
            {"name": "bulb", "translation": [0.0, 4.0, 0.0], "extensions": {"KHR_lights_punctual": {"light": 0}}},
            {"name": "mirrored", "mesh": 0, "translation": [0.0, 2.0, 0.0], "scale": [-1.0, 1.0, 1.0]},
            {"name": "spot", "translation": [1.0, 3.0, 0.0], "rotation": [-half, 0.0, 0.0, half],
             "extensions": {"KHR_lights_punctual": {"light": 1}}},
            {"name": "eye", "camera": 0, "translation": [0.0, 2.0, 6.0]}
        ],
        "cameras": [{"type": "perspective", "perspective": {"yfov": 0.8, "aspectRatio": 2.0, "znear": 0.01}}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1}, "indices": 2, "material": 0}]}],
        "materials": [{"name": "white", "pbrMetallicRoughness": {"baseColorFactor": [0.8, 0.8, 0.8, 1.0], "metallicFactor": 0.0}}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3", "min": [-1.0, 0.0, -1.0], "max": [1.0, 0.0, 1.0]},
            {"bufferView": 1, "componentType": 5126, "count": 4, "type": "VEC3"},
            {"bufferView": 2, "componentType": 5125, "count": 6, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteOffset": 0, "byteLength": 48},
            {"buffer": 0, "byteOffset": 48, "byteLength": 48},
            {"buffer": 0, "byteOffset": 96, "byteLength": 24}
        ],
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{b64}")}]
    })
    .to_string()
}

#[test]
fn node_transforms_and_instances_land_where_the_matrices_say() {
    let im = import(&instanced_document());
    let s = &im.scene;
    // the camera node is not in the scene's roots: a default camera, with a warning
    assert!(
        im.warnings.iter().any(|w| w.contains("default")),
        "{:?}",
        im.warnings
    );
    assert_eq!(s.objects.len(), 3);
    // every mesh node has a translation, rotation and scale: each is an instance, its
    // vertices in object space, its placement the node's own values exactly
    assert!(s.objects.iter().all(|o| o.transform.is_some()));
    assert_eq!(
        s.objects[0].transform.unwrap().scale,
        Vec3::new(3.0, 1.0, 2.0)
    );
    assert_eq!(
        s.objects[2].transform.unwrap().scale,
        Vec3::new(-1.0, 1.0, 1.0)
    );
    let positions = |k: usize| match &s.objects[k].shape {
        Shape::Mesh { positions, .. } => {
            let t = s.objects[k].transform.unwrap();
            positions
                .iter()
                .map(|p| t.transform_point(*p))
                .collect::<Vec<_>>()
        }
        _ => unreachable!(),
    };
    // floor: scaled by (3, 1, 2)
    assert_eq!(positions(0)[2], Vec3::new(3.0, 0.0, 2.0));
    // tilted: 90 degrees about x, half size, up 1: (1, 0, 1) -> (0.5, 1 - 0.5, 0)
    let p = positions(1)[2];
    assert!((p - Vec3::new(0.5, 0.5, 0.0)).length() < 1e-6, "{p}");
    // in object space every triangle faces the way its normals point (core reverses a
    // mirroring instance's winding with its normals)
    for o in &s.objects {
        let m = tessellate(&o.shape);
        for t in &m.indices {
            let [a, b, c] = t.map(|i| m.positions[i as usize]);
            let face = (b - a).cross(c - a);
            let n = m.normals[t[0] as usize];
            assert!(face.dot(n) > 0.0, "{}: face {face} vs normal {n}", o.name);
        }
    }
    // lights: point at the parent-rotated (0, 4, 0) with cd / 683 per channel
    match s.lights[0] {
        Light::Point {
            position,
            intensity,
        } => {
            assert!((position - Vec3::new(0.0, 4.0, 0.0)).length() < 1e-6);
            assert!((intensity - Vec3::new(5.0, 2.5, 1.25)).length() < 1e-5);
        }
        ref l => panic!("{l:?}"),
    }
    // spot: local -z rotated -90 degrees about x points down (-y), then the parent's 90
    // degrees about y keeps it down; position (1, 3, 0) rotated about y -> (0, 3, -1)
    match s.lights[1] {
        Light::Spot {
            position,
            direction,
            inner_angle_deg,
            outer_angle_deg,
            intensity,
        } => {
            assert!(
                (position - Vec3::new(0.0, 3.0, -1.0)).length() < 1e-5,
                "{position}"
            );
            assert!((direction - Vec3::NEG_Y).length() < 1e-5, "{direction}");
            assert!((inner_angle_deg - 0.2f32.to_degrees()).abs() < 1e-4);
            assert!((outer_angle_deg - 0.4f32.to_degrees()).abs() < 1e-4);
            assert!((intensity - Vec3::ONE).length() < 1e-6);
        }
        ref l => panic!("{l:?}"),
    }
    let _ = LUMINOUS_EFFICACY_LM_PER_W;
}

/// The same document with every mesh node's placement applied to its vertices (static
/// objects, as the importer made them before instances existed).
fn flattened(scene: &caustica::Scene) -> caustica::Scene {
    let mut flat = scene.clone();
    for o in &mut flat.objects {
        let Some(t) = o.transform.take() else {
            continue;
        };
        if let Shape::Mesh {
            positions,
            normals,
            indices,
            ..
        } = &mut o.shape
        {
            for p in std::sync::Arc::make_mut(positions).iter_mut() {
                *p = t.transform_point(*p);
            }
            let nm = glam::Mat3::from(t.normal_matrix());
            for n in std::sync::Arc::make_mut(normals).iter_mut() {
                *n = nm * *n;
            }
            if t.scale.x * t.scale.y * t.scale.z < 0.0 {
                for tri in std::sync::Arc::make_mut(indices).iter_mut() {
                    tri.swap(1, 2);
                }
            }
        }
    }
    flat
}

#[test]
fn imported_instances_render_as_the_flattened_objects() {
    let s = import(&instanced_document()).scene;
    let flat = flattened(&s);
    assert!(flat.objects.iter().all(|o| o.transform.is_none()));
    let (a, b) = (common::render_small(&s), common::render_small(&flat));
    // an instance's world vertices are its object-space ones under the placement, as the
    // flattened ones are, but traced in object space (ray moved by the inverse placement):
    // hit points differ by a few ulps of the scene's size, so shading by a few ulps of the
    // peak; the bound is conformance's for an identity instance (2^-13 of the peak, room
    // for a shadow-ray edge case), measured 7e-8 here
    let peak = b
        .iter()
        .flatten()
        .fold(0.0f32, |m, x| m.max(x.abs()))
        .max(1e-30);
    let worst = a
        .iter()
        .zip(&b)
        .flat_map(|(p, q)| p.iter().zip(q).map(|(x, y)| (x - y).abs()))
        .fold(0.0f32, f32::max);
    eprintln!("instances against flattened objects: worst {worst:e} of peak {peak:e}");
    assert!(
        worst <= peak / 8192.0,
        "instances and flattened objects differ by {worst} (peak {peak})"
    );
    // and the export keeps them instances: exported and read back, the same placements
    let again = import(&caustica::gltf_scene::scene_to_gltf(&s)).scene;
    for (o, p) in s.objects.iter().zip(&again.objects) {
        assert_eq!(o.transform, p.transform, "{}", o.name);
    }
}

#[test]
fn the_instanced_scene_renders_as_its_json_twin() {
    let im = import(&instanced_document());
    let s = im.scene;
    // the JSON twin: the same meshes, built from the transformed corners by hand
    let json = caustica::scene::format::to_json(&s);
    let twin = caustica::scene::format::parse_scene(&json, "twin.json").unwrap();
    let (a, b) = (common::render_small(&s), common::render_small(&twin));
    assert!(
        a == b,
        "the JSON round trip of an imported scene renders bitwise the same"
    );
}

/// A GLB container around a .gltf document whose one buffer is moved into the BIN chunk.
fn to_glb(gltf_text: &str) -> Vec<u8> {
    let mut doc: serde_json::Value = serde_json::from_str(gltf_text).unwrap();
    let uri = doc["buffers"][0]["uri"].as_str().unwrap().to_string();
    let data = parse_data_uri(&uri);
    doc["buffers"][0].as_object_mut().unwrap().remove("uri");
    let mut json = serde_json::to_vec(&doc).unwrap();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let mut bin = data;
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::new();
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((json.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(&json);
    out.extend((bin.len() as u32).to_le_bytes());
    out.extend(b"BIN\0");
    out.extend(&bin);
    out
}

fn parse_data_uri(uri: &str) -> Vec<u8> {
    let b64 = uri.split_once(";base64,").unwrap().1;
    let mut out = Vec::new();
    let (mut acc, mut bits) = (0u32, 0u32);
    for ch in b64.bytes() {
        let v = match ch {
            b'A'..=b'Z' => ch - b'A',
            b'a'..=b'z' => ch - b'a' + 26,
            b'0'..=b'9' => ch - b'0' + 52,
            b'+' => 62,
            b'/' => 63,
            _ => break,
        } as u32;
        acc = acc << 6 | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    out
}

#[test]
fn a_glb_reads_as_its_gltf() {
    let text = scene_to_gltf(&builtin("prism").unwrap());
    let a = import(&text).scene;
    let mut b = parse_gltf(&to_glb(&text), "prism.glb", "test", None)
        .unwrap()
        .scene;
    b.description = a.description.clone();
    assert_eq!(a, b);
}

#[test]
fn bad_files_get_one_line_located_errors() {
    // broken JSON: file, line and column
    let e = parse_gltf(
        b"{\n  \"asset\": {\"version\": \"2.0\"},\n  oops\n}",
        "bad.gltf",
        "t",
        None,
    )
    .unwrap_err();
    assert_eq!((e.file.as_str(), e.line), ("bad.gltf", 3), "{e}");
    assert!(!e.to_string().contains('\n'));
    // no light: a default sun, with a warning
    let mut doc: serde_json::Value = serde_json::from_str(&instanced_document()).unwrap();
    doc["scenes"][0]["nodes"] = serde_json::json!([0, 1]);
    let im = parse_gltf(doc.to_string().as_bytes(), "dark.gltf", "t", None).unwrap();
    assert!(im
        .warnings
        .iter()
        .any(|w| w.contains("no KHR_lights_punctual light")));
    assert!(matches!(im.scene.lights[..], [Light::Directional { .. }]));
    // no mesh at all
    doc["scenes"][0]["nodes"] = serde_json::json!([2]);
    let e = parse_gltf(doc.to_string().as_bytes(), "empty.gltf", "t", None).unwrap_err();
    assert!(e.to_string().contains("no triangle mesh"), "{e}");
    // an index beyond the vertices
    let mut doc: serde_json::Value = serde_json::from_str(&instanced_document()).unwrap();
    doc["accessors"][2]["count"] = serde_json::json!(7);
    doc["bufferViews"][2]["byteLength"] = serde_json::json!(28);
    let e = parse_gltf(doc.to_string().as_bytes(), "short.gltf", "t", None).unwrap_err();
    assert!(e.to_string().starts_with("short.gltf: "), "{e}");
    // an external buffer without a directory
    let mut doc: serde_json::Value = serde_json::from_str(&instanced_document()).unwrap();
    doc["buffers"][0]["uri"] = serde_json::json!("missing.bin");
    let e = parse_gltf(doc.to_string().as_bytes(), "ext.gltf", "t", None).unwrap_err();
    assert!(e.to_string().contains("missing.bin"), "{e}");
    // not glTF at all
    assert!(parse_gltf(b"\x00\x01binary", "x.glb", "t", None).is_err());
}

#[test]
fn what_caustica_cannot_represent_is_warned_per_element() {
    let mut doc: serde_json::Value = serde_json::from_str(&instanced_document()).unwrap();
    doc["materials"] = serde_json::json!([{
        "name": "frosted",
        "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 0.5], "roughnessFactor": 0.5},
        "emissiveFactor": [1.0, 0.0, 0.0],
        "extensions": {"KHR_materials_transmission": {"transmissionFactor": 0.7}}
    }]);
    doc["extensionsUsed"] =
        serde_json::json!(["KHR_lights_punctual", "KHR_materials_transmission"]);
    doc["extensions"]["KHR_lights_punctual"]["lights"][0]["range"] = serde_json::json!(10.0);
    let im = parse_gltf(doc.to_string().as_bytes(), "w.gltf", "t", None).unwrap();
    let all = im.warnings.join("\n");
    for what in [
        "partial transmission 0.7",
        "roughness 0.5",
        "emission",
        "alpha",
        "thin-walled",
        "range",
    ] {
        assert!(all.contains(what), "missing '{what}' in:\n{all}");
    }
    assert!(im.warnings.iter().all(|w| w.starts_with("w.gltf: ")));
    assert!(matches!(
        im.scene.materials["frosted"],
        Material::Dielectric { .. }
    ));
}

#[test]
fn edits_in_other_tools_win_over_causticas_extras() {
    // a light made twice as bright and a glass given another ior in another tool: the
    // standard fields disagree with extras.caustica, and are read
    let text = scene_to_gltf(&builtin("sphere").unwrap());
    let mut doc: serde_json::Value = serde_json::from_str(&text).unwrap();
    let light = &mut doc["extensions"]["KHR_lights_punctual"]["lights"][0];
    let i = light["intensity"].as_f64().unwrap();
    light["intensity"] = serde_json::json!(2.0 * i);
    for m in doc["materials"].as_array_mut().unwrap() {
        if let Some(ior) = m.pointer_mut("/extensions/KHR_materials_ior/ior") {
            *ior = serde_json::json!(1.33);
        }
    }
    let s = import(&doc.to_string()).scene;
    match s.lights[0] {
        Light::Point { intensity, .. } => assert!((intensity.x - 20.0).abs() < 1e-4, "{intensity}"),
        ref l => panic!("{l:?}"),
    }
    assert!(s
        .materials
        .values()
        .any(|m| matches!(m, Material::Dielectric { ior, .. } if (*ior - 1.33).abs() < 1e-6)));
}

/// The Khronos glTF sample assets with transmission, volume and dispersion, rendered when
/// a checkout of <https://github.com/KhronosGroup/glTF-Sample-Assets> is named by
/// `CAUSTICA_GLTF_SAMPLES`; skipped, loudly, when it is not (it is not vendored here: the
/// repository is about 1 GB).
#[test]
fn khronos_sample_assets_load_and_render_when_present() {
    let Ok(root) = std::env::var("CAUSTICA_GLTF_SAMPLES") else {
        eprintln!(
            "*** SKIPPED: set CAUSTICA_GLTF_SAMPLES to a glTF-Sample-Assets checkout to render \
             DispersionTest, DragonAttenuation, TransmissionTest, AttenuationTest, IORTestGrid ***"
        );
        return;
    };
    for name in [
        "DispersionTest",
        "DragonAttenuation",
        "TransmissionTest",
        "AttenuationTest",
        "IORTestGrid",
    ] {
        let path = std::path::Path::new(&root).join(format!("Models/{name}/glTF/{name}.gltf"));
        let im = caustica::gltf_scene::load_gltf(&path).unwrap_or_else(|e| panic!("{e}"));
        for w in &im.warnings {
            eprintln!("warning: {w}");
        }
        let img = common::render_small(&im.scene);
        assert!(
            img.iter().flatten().all(|v| v.is_finite()),
            "{name}: non-finite pixel"
        );
        assert!(
            img.iter().any(|p| p[0] + p[1] + p[2] > 0.0),
            "{name}: black"
        );
    }
}

#[test]
fn meshes_without_uvs_get_charts_a_caustic_map_can_address() {
    // the instanced document's quad has positions and normals only
    let im = import(&instanced_document());
    let charted: Vec<&String> = im
        .warnings
        .iter()
        .filter(|w| w.contains("no UVs; generated 1 UV chart"))
        .collect();
    assert_eq!(charted.len(), 3, "{:?}", im.warnings);
    for o in &im.scene.objects {
        let Shape::Mesh { uvs, positions, .. } = &o.shape else {
            unreachable!()
        };
        assert_eq!(uvs.len(), positions.len(), "{}", o.name);
    }
    let ds = caustica_core::device::device_scene::DeviceScene::build(&im.scene, Default::default())
        .unwrap();
    let receiver = caustica_core::frame::receivers::atlas::layout::atlas_receivers(&im.scene);
    let layout =
        caustica_core::frame::receivers::atlas::layout::atlas_layout(&ds, &receiver, (256, 256))
            .unwrap();
    assert_eq!(layout.tiles.len(), 3);
    assert!(layout.covered_texels > 0);
}
