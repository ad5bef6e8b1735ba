//! glTF 2.0 scenes in and out (the `gltf` feature): [`load_gltf`] reads `.gltf` (buffers
//! embedded as data URIs or in files beside or below it: a URI that is an absolute path
//! or climbs out of its folder is refused) and `.glb` into a [`Scene`] with the
//! warnings of what caustica cannot represent; [`scene_to_gltf`] writes any scene as a
//! self-contained `.gltf` (one embedded buffer), so caustica's scenes open in other tools.
//!
//! **What is read.** The default scene's node hierarchy (which must be what glTF 2.0
//! requires, a set of trees: a node with two parents, or one that is its own ancestor,
//! is an error; walked without recursion, so any depth reads), with each node's world
//! transform applied to its meshes (positions by the matrix, normals by its cofactor matrix,
//! the inverse transpose's direction, which a singular scale also has, renormalised; the
//! winding reversed where the determinant is negative so that normals stay outward; a
//! primitive whose normal the transform collapses to no direction gets generated normals,
//! with a warning).
//! A mesh node whose world transform is a translation, rotation and scale (any glTF
//! node's own, and any chain of them without shear) becomes an *instance* per primitive:
//! its vertices stay in object space under that placement (`Object::transform`), so a
//! host moves it with `set_object_transforms` without a rebuild; a node under an
//! identity parent keeps the file's exact values. Identity nodes join the static level,
//! and a world transform with shear (a non-uniform scale above a rotation) is applied to
//! the vertices instead (a static object). Triangle
//! primitives (lists, strips and fans); points and lines are skipped with a warning.
//! Missing normals are generated as the area-weighted average of the faces around each
//! vertex (`scene::shapes`); missing UVs are generated as box-projected charts
//! (`scene::uv_charts`: charts grown over shared edges, split where they would overlap,
//! packed at one texel density), with a warning naming the mesh. Every accessor read is
//! checked first (POSITION and NORMAL VEC3 of FLOAT, TEXCOORD_0 VEC2 of FLOAT or of
//! unsigned byte or short, read as normalized, indices SCALAR of unsigned byte, short
//! or int, each inside its buffer), and the import's size is counted before anything is
//! read: at most [`MAX_IMPORT_TRIANGLES`] triangles and [`MAX_IMPORT_VERTICES`]
//! vertices, summed over every node that places a mesh. The first perspective camera met in the hierarchy
//! (its image size from `extras.caustica`, whose width and height must be whole numbers
//! in 1..=16384, else [`DEFAULT_IMAGE_WIDTH`] pixels wide at its `aspectRatio`, which
//! must be positive, the height clamped into 1..=16384 with a warning), or
//! a default camera framing the scene, with a warning; a scene without lights (assets lit
//! by an environment map) gets a default directional light, with a warning.
//!
//! **Lights** (KHR_lights_punctual): photometric to radiometric with the luminous
//! efficacy [`LUMINOUS_EFFICACY_LM_PER_W`] = 683 lm/W, the constant that defines the
//! candela (monochromatic light at 540 THz, 555 nm): point and spot intensity in cd
//! (lm/sr) becomes W/sr, directional illuminance in lux (lm/m^2) becomes W/m^2, per
//! channel `color * intensity / 683`. 683 is the largest efficacy any light can have, so
//! a broadband light carries more watts than this says; it is what glTF exporters use
//! (Blender writes W as `W * 683 / (4 pi)` cd for point lights), so caustica reads their
//! files back at the power they were made with. Spot cone angles are half-angles in
//! radians in glTF, degrees here; a light's `range` has no counterpart (warned).
//!
//! **Materials.** `KHR_materials_transmission` with factor 1 becomes a dielectric with
//! the `KHR_materials_ior` index (default 1.5) and Beer-Lambert absorption
//! `sigma = -ln(attenuationColor) / attenuationDistance` per channel from
//! `KHR_materials_volume` (0 for an infinite distance); `KHR_materials_dispersion`'s
//! `dispersion = 20 / V_d` gives the dielectric the extension's own index model,
//! [`IorModel::Abbe`] with `V_d` and the `KHR_materials_ior` index as `n_d` (the index at
//! each wavelength as the extension's formula defines it, `math::optics::abbe_ior`). A
//! file caustica wrote from a Cauchy glass reads back as that glass (its `B` in
//! `extras.caustica`, where it agrees with the Abbe number).
//! Metallic 1 with roughness at most [`MIRROR_MAX_ROUGHNESS`] becomes a mirror of
//! reflectance `baseColorFactor`; everything else is diffuse with albedo
//! `baseColorFactor`. What cannot be represented is listed in the warnings, per file:
//! textures, partial transmission (below 1: a dielectric from 0.5 up, else diffuse), thin
//! walls (transmission without a volume: traced as a solid), rough glass or metal,
//! metallic factors between 0 and 1, emission, alpha blending and masking.

use caustica_core::math::optics::REFERENCE_WAVELENGTH_UM;
use caustica_core::scene::format::SceneFileError;
use caustica_core::scene::limits::MAX_COORDINATE;
use caustica_core::scene::shapes::tessellate;
use caustica_core::scene::{
    more_problems, Aabb, Camera, IorModel, Light, Material, Object, Scene, Shape, Transform,
};
use glam::{DMat3, Mat3, Mat4, Quat, Vec2, Vec3};
use serde_json::{json, Value};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// Luminous efficacy (lm/W) assumed to turn glTF's photometric light units into watts:
/// 683, the definition of the candela (see the module doc).
pub const LUMINOUS_EFFICACY_LM_PER_W: f32 = 683.0;

/// Largest glTF roughness still read as a perfect mirror (metals) or smooth glass
/// (transmission): below 0.05 a GGX lobe's width is under about 3 degrees, which a
/// caustic of a perfect reflector resolves no differently at the scenes' scales.
pub const MIRROR_MAX_ROUGHNESS: f32 = 0.05;

/// The light a glTF file without `KHR_lights_punctual` lights gets (with a warning): a
/// directional light of this irradiance (W/m^2 per channel)...
pub const DEFAULT_SUN_IRRADIANCE: f32 = 3.0;
/// ... travelling along this direction (steeply down, a little sideways).
pub const DEFAULT_SUN_DIRECTION: Vec3 = Vec3::new(0.3, -1.0, 0.2);

/// Wavelengths (micrometres) of the Fraunhofer lines that define the Abbe number
/// `V_d = (n_d - 1) / (n_F - n_C)`: d (587.6 nm, where glTF's `ior` is given), F
/// (486.1 nm), C (656.3 nm).
pub const FRAUNHOFER_D_UM: f32 = 0.5876;
/// Fraunhofer F line (micrometres).
pub const FRAUNHOFER_F_UM: f32 = 0.4861;
/// Fraunhofer C line (micrometres).
pub const FRAUNHOFER_C_UM: f32 = 0.6563;

/// Most triangles one glTF import may produce (2^26 = 67 M, four times the default render
/// budget `max_triangles`, [`caustica_core::scene::limits::DEFAULT_MAX_TRIANGLES`]),
/// counted from the accessors' sizes before anything is read. A mesh is imported once
/// per node that places it, so a small file can place one mesh many times; this stops
/// such a file before it fills memory. The render budget is checked when the scene is
/// built, as for any scene.
pub const MAX_IMPORT_TRIANGLES: u64 = 1 << 26;
/// Most vertices one glTF import may produce (2^26, at most 32 bytes each: position,
/// normal, UV), counted like [`MAX_IMPORT_TRIANGLES`].
pub const MAX_IMPORT_VERTICES: u64 = 1 << 26;

/// A glTF file read into a scene, with what it holds that caustica cannot represent.
#[derive(Clone, Debug)]
pub struct GltfImport {
    /// The scene (validated).
    pub scene: Scene,
    /// One line per thing dropped or approximated, naming the glTF element.
    pub warnings: Vec<String>,
}

/// Cauchy `B` (um^2) of a glass with index `n_d` at 587.6 nm and Abbe number `abbe`.
/// With `n(l) = A + B / l^2`, `n_F - n_C = B (1 / l_F^2 - 1 / l_C^2)` and
/// `V_d = (n_d - 1) / (n_F - n_C)`, so `B = (n_d - 1) / (V_d (1 / l_F^2 - 1 / l_C^2))`
/// (0.0042 um^2 for BK7: n_d 1.5168, V_d 64.17). Returns 0 for `abbe` 0 or infinite (no
/// dispersion).
pub fn cauchy_b_from_abbe(n_d: f32, abbe: f32) -> f32 {
    if !(abbe.is_finite() && abbe > 0.0) {
        return 0.0;
    }
    let k = 1.0 / (FRAUNHOFER_F_UM * FRAUNHOFER_F_UM) - 1.0 / (FRAUNHOFER_C_UM * FRAUNHOFER_C_UM);
    (n_d - 1.0) / (abbe * k)
}

/// caustica's `ior` (at [`REFERENCE_WAVELENGTH_UM`], 550 nm) of a Cauchy glass given at
/// the d line: `n(0.55) = n_d + B (1 / 0.55^2 - 1 / 0.5876^2)`.
pub fn ior_at_reference(n_d: f32, cauchy_b: f32) -> f32 {
    n_d + cauchy_b
        * (1.0 / (REFERENCE_WAVELENGTH_UM * REFERENCE_WAVELENGTH_UM)
            - 1.0 / (FRAUNHOFER_D_UM * FRAUNHOFER_D_UM))
}

/// Reads a `.gltf` or `.glb` file (see the module doc).
pub fn load_gltf(path: &Path) -> Result<GltfImport, SceneFileError> {
    let file = path.display().to_string();
    let bytes = caustica_core::scene::format::read_scene_bytes(path)?;
    let name = path
        .file_stem()
        .map(|s| printable(&s.to_string_lossy()))
        .unwrap_or_else(|| "gltf".into());
    parse_gltf(&bytes, &file, &name, path.parent())
}

fn located(file: &str, reason: String) -> SceneFileError {
    SceneFileError {
        file: file.into(),
        line: 0,
        column: 0,
        reason,
    }
}

/// Parses glTF (JSON or GLB bytes) into a scene named `name`; `file` names the source in
/// errors and warnings, `dir` is where relative buffer URIs are looked up, never outside
/// it (none: only embedded buffers).
pub fn parse_gltf(
    bytes: &[u8],
    file: &str,
    name: &str,
    dir: Option<&Path>,
) -> Result<GltfImport, SceneFileError> {
    let fail = |reason: String| located(file, reason);
    let doc = gltf::Gltf::from_slice(bytes).map_err(|e| match e {
        gltf::Error::Deserialize(j) => SceneFileError {
            file: file.into(),
            line: j.line(),
            column: j.column(),
            reason: format!("not glTF: {j}"),
        },
        gltf::Error::Validation(v) => {
            let (path, err) = &v[0];
            let rest: Vec<String> = v[1..].iter().map(|(p, _)| p.to_string()).collect();
            fail(format!(
                "invalid glTF at {path}: {err}{}",
                more_problems(&rest)
            ))
        }
        other => fail(format!("not glTF: {other}")),
    })?;
    let buffers = resolve_buffers(&doc, dir).map_err(&fail)?;
    check_accessors(&doc, &buffers).map_err(&fail)?;
    let mut im = Importer {
        buffers: &buffers,
        warnings: Vec::new(),
        materials: BTreeMap::new(),
        material_names: BTreeMap::new(),
        objects: Vec::new(),
        lights: Vec::new(),
        camera: None,
        bounds: Aabb::EMPTY,
    };
    for ext in doc.extensions_required() {
        if !SUPPORTED_EXTENSIONS.contains(&ext) {
            im.warnings.push(format!(
                "required extension {ext} is not supported: its data is ignored"
            ));
        }
    }
    let scene = doc
        .default_scene()
        .or_else(|| doc.scenes().next())
        .ok_or_else(|| fail("the file has no scene".into()))?;
    // before any traversal: trees only, readable accessors, a bounded import
    check_hierarchy(&doc, &scene).map_err(&fail)?;
    check_meshes(&scene).map_err(&fail)?;
    walk_trees(&scene, Mat4::IDENTITY, &mut |node, parent| {
        im.visit(node, parent)
    })
    .map_err(&fail)?;
    if im.objects.is_empty() {
        return Err(fail("the scene has no triangle mesh".into()));
    }
    if im.lights.is_empty() {
        // many assets rely on an environment map, which caustica does not have
        im.warnings.push(format!(
            "no KHR_lights_punctual light: a default directional light is added \
             ({DEFAULT_SUN_IRRADIANCE} W/m^2 per channel, from above)"
        ));
        im.lights.push(Light::Directional {
            direction: DEFAULT_SUN_DIRECTION,
            irradiance: Vec3::splat(DEFAULT_SUN_IRRADIANCE),
            projection_volume: None,
        });
    }
    let camera = match im.camera.take() {
        Some(c) => c,
        None => {
            im.warnings
                .push("no perspective camera: a default one frames the scene".into());
            default_camera(im.bounds)
        }
    };
    let mut scene = Scene {
        name: name.into(),
        description: format!("imported from {file}"),
        camera,
        materials: im.materials,
        objects: im.objects,
        lights: im.lights,
    };
    if let Err(problems) = scene.validate() {
        return Err(fail(format!(
            "the imported scene is invalid: {}: {}{}",
            problems[0].path,
            problems[0].reason,
            more_problems(
                &problems[1..]
                    .iter()
                    .map(|p| p.path.as_str())
                    .collect::<Vec<_>>()
            )
        )));
    }
    // after validation: every index is in range
    im.warnings
        .extend(caustica_core::scene::uv_charts::generate_missing_uvs(
            &mut scene,
        ));
    Ok(GltfImport {
        scene,
        warnings: im
            .warnings
            .into_iter()
            .map(|w| format!("{file}: {w}"))
            .collect(),
    })
}

/// Extensions this reader understands (others are ignored, with a warning when required).
const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_volume",
    "KHR_materials_dispersion",
];

/// Every buffer's bytes: the GLB chunk, a base64 data URI, or a file relative to `dir`.
fn resolve_buffers(doc: &gltf::Gltf, dir: Option<&Path>) -> Result<Vec<Vec<u8>>, String> {
    let mut out = Vec::new();
    for b in doc.buffers() {
        let data = match b.source() {
            gltf::buffer::Source::Bin => doc
                .blob
                .clone()
                .ok_or_else(|| format!("buffers[{}] refers to a missing GLB chunk", b.index()))?,
            gltf::buffer::Source::Uri(uri) => {
                if let Some(rest) = uri.strip_prefix("data:") {
                    let (_, payload) = rest.split_once(";base64,").ok_or_else(|| {
                        format!("buffers[{}]: a data URI that is not base64", b.index())
                    })?;
                    base64_decode(payload)
                        .ok_or_else(|| format!("buffers[{}]: bad base64", b.index()))?
                } else {
                    let dir = dir.ok_or_else(|| {
                        format!(
                            "buffers[{}]: external file '{uri}' but no directory",
                            b.index()
                        )
                    })?;
                    if uri.contains("://") {
                        return Err(format!(
                            "buffers[{}]: '{}' is a remote URI; caustica reads files \
                             beside the glTF file and data: URIs",
                            b.index(),
                            printable(uri)
                        ));
                    }
                    let p = file_in_folder(dir, uri).map_err(|why| {
                        format!(
                            "buffers[{}]: '{}' {why}; caustica reads only files beside or \
                             below the glTF file: put the .bin beside the .gltf and name it \
                             by a relative path such as 'scene.bin'",
                            b.index(),
                            printable(uri)
                        )
                    })?;
                    if b.length() as u64 > MAX_BUFFER_BYTES {
                        return Err(format!(
                            "buffers[{}] declares {} bytes, more than the {} GiB a buffer may \
                             have",
                            b.index(),
                            b.length(),
                            MAX_BUFFER_BYTES >> 30
                        ));
                    }
                    // at most the declared length: a pipe or /dev/zero stops there
                    let read = std::fs::File::open(&p).and_then(|f| {
                        let mut data = Vec::new();
                        std::io::Read::read_to_end(
                            &mut std::io::Read::take(f, b.length() as u64),
                            &mut data,
                        )
                        .map(|_| data)
                    });
                    read.map_err(|e| {
                        format!("buffers[{}]: cannot read {}: {e}", b.index(), p.display())
                    })?
                }
            }
        };
        if data.len() < b.length() {
            return Err(format!(
                "buffers[{}] holds {} bytes, {} declared",
                b.index(),
                data.len(),
                b.length()
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// The file that the relative URI `uri` of an external buffer names in the glTF file's
/// folder `dir`, or why it names none there (the caller says which buffer).
///
/// The URI is judged after percent-decoding (`%2e%2e/` is `../`), with both `/` and `\`
/// as separators, so that a file names the same file on every system: a leading
/// separator (`/etc/passwd`, `\\server\share`) or a Windows drive (`C:`, in any segment)
/// is an absolute path, a first segment with a colon (`file:`) is a URI scheme, and
/// `..` is refused where it would climb above `dir`. The segments are normalised, not
/// looked up: empty and `.` segments are skipped and `a/../b.bin`, which stays inside,
/// is `dir/b.bin`. Symbolic links under `dir` are followed as they are (made by the
/// folder's owner, not by the file).
fn file_in_folder(dir: &Path, uri: &str) -> Result<PathBuf, &'static str> {
    let decoded = percent_decode(uri);
    if decoded.starts_with(['/', '\\']) {
        return Err("is an absolute path");
    }
    let mut segments: Vec<&str> = Vec::new();
    for (k, segment) in decoded.split(['/', '\\']).enumerate() {
        let b = segment.as_bytes();
        if b.len() >= 2 && b[0].is_ascii_alphabetic() && b[1] == b':' {
            return Err("is an absolute path (a Windows drive)");
        }
        if k == 0 && segment.contains(':') {
            return Err("has a URI scheme, not a relative path");
        }
        match segment {
            "" | "." => {}
            ".." => {
                if segments.pop().is_none() {
                    return Err("leaves the folder of the glTF file");
                }
            }
            s => segments.push(s),
        }
    }
    if segments.is_empty() {
        return Err("names no file");
    }
    Ok(segments.iter().fold(dir.to_path_buf(), |p, s| p.join(s)))
}

/// Most bytes an external buffer may declare: 4 GiB, more than the largest import
/// ([`MAX_IMPORT_TRIANGLES`], [`MAX_IMPORT_VERTICES`]) reads.
const MAX_BUFFER_BYTES: u64 = 4 << 30;

/// Every buffer view inside its buffer, every accessor inside its view: a reader never
/// reads past the data (the `gltf` crate's validation does not check ranges).
fn check_accessors(doc: &gltf::Gltf, buffers: &[Vec<u8>]) -> Result<(), String> {
    for v in doc.views() {
        let end = (v.offset() as u64).saturating_add(v.length() as u64);
        let have = buffers.get(v.buffer().index()).map_or(0, |b| b.len()) as u64;
        if end > have {
            return Err(format!(
                "bufferViews[{}] ends at byte {end} of buffers[{}], which holds {have}",
                v.index(),
                v.buffer().index()
            ));
        }
    }
    for a in doc.accessors() {
        if a.sparse().is_some() {
            return Err(format!(
                "accessors[{}]: sparse accessors are not supported",
                a.index()
            ));
        }
        let Some(v) = a.view() else { continue };
        let size = a.size() as u64;
        let stride = v.stride().map_or(size, |s| s as u64);
        if stride < size {
            // the `gltf` crate's readers would split an element across strides (a panic)
            return Err(format!(
                "accessors[{}]: elements of {size} bytes do not fit the byteStride {stride} of \
                 bufferViews[{}]",
                a.index(),
                v.index()
            ));
        }
        if a.count() == 0 {
            continue;
        }
        // saturating: a count near 2^64 is past any view, not wrapped back into it
        let end = (a.offset() as u64)
            .saturating_add((a.count() as u64 - 1).saturating_mul(stride))
            .saturating_add(size);
        if end > v.length() as u64 {
            return Err(format!(
                "accessors[{}]: {} elements end at byte {end} of bufferViews[{}], which holds {}",
                a.index(),
                a.count(),
                v.index(),
                v.length()
            ));
        }
    }
    Ok(())
}

/// `nodes[k]`, with the node's name where it has one, as errors and warnings name it.
fn node_label(node: &gltf::Node) -> String {
    match node.name() {
        Some(n) => format!("nodes[{}] '{}'", node.index(), printable(n)),
        None => format!("nodes[{}]", node.index()),
    }
}

/// A name from the file as caustica's names hold it: each control character (a line
/// break, a terminal escape) as U+FFFD, so that printing it cannot reach a terminal.
fn printable(name: &str) -> String {
    name.chars()
        .map(|c| {
            if c.is_control() {
                char::REPLACEMENT_CHARACTER
            } else {
                c
            }
        })
        .collect()
}

/// `meshes[k]`, with the mesh's name where it has one.
fn mesh_label(mesh: &gltf::Mesh) -> String {
    match mesh.name() {
        Some(n) => format!("meshes[{}] '{}'", mesh.index(), printable(n)),
        None => format!("meshes[{}]", mesh.index()),
    }
}

/// The label ([`node_label`]) of node `index` of `doc`.
fn node_label_at(doc: &gltf::Document, index: usize) -> String {
    doc.nodes()
        .nth(index)
        .map_or_else(|| format!("nodes[{index}]"), |n| node_label(&n))
}

/// Refuses, before anything walks it, a node hierarchy that is not what glTF 2.0
/// requires, a disjoint union of strict trees: a node that is a child of two nodes (or
/// listed twice by one), a node that is its own ancestor (a cycle), a root of `scene`
/// that is another node's child or is listed twice by the scene. A walk of what passes
/// meets each node once; a cycle would walk forever, and a node shared by the nodes of
/// each level of a chain would be reached (and its meshes imported) exponentially often.
fn check_hierarchy(doc: &gltf::Document, scene: &gltf::Scene) -> Result<(), String> {
    let trees = "glTF node hierarchies are trees";
    let mut parent: Vec<Option<usize>> = vec![None; doc.nodes().len()];
    for node in doc.nodes() {
        for child in node.children() {
            let c = child.index();
            let Some(slot) = parent.get_mut(c) else {
                return Err(format!(
                    "{} lists a child nodes[{c}] that does not exist",
                    node_label(&node)
                ));
            };
            match *slot {
                Some(p) if p == node.index() => {
                    return Err(format!(
                        "{} lists {} twice among its children: {trees}",
                        node_label(&node),
                        node_label(&child)
                    ))
                }
                Some(p) => {
                    return Err(format!(
                        "{} is a child of both {} and {}: {trees}, a node has one parent at most",
                        node_label(&child),
                        node_label_at(doc, p),
                        node_label(&node)
                    ))
                }
                None => *slot = Some(node.index()),
            }
        }
    }
    // one parent each: from every node, follow the parents until a root or a node an
    // earlier walk met (which leads to a root); meeting this walk's own trail is a cycle
    let mut walked_from = vec![usize::MAX; parent.len()];
    for start in 0..parent.len() {
        let mut k = start;
        while walked_from[k] == usize::MAX {
            walked_from[k] = start;
            match parent[k] {
                Some(p) => k = p,
                None => break,
            }
        }
        if walked_from[k] == start && parent[k].is_some() {
            return Err(format!(
                "{} is its own ancestor (its children lead back to it): {trees}",
                node_label_at(doc, k)
            ));
        }
    }
    let mut is_root = vec![false; parent.len()];
    for root in scene.nodes() {
        let r = root.index();
        if let Some(Some(p)) = parent.get(r) {
            return Err(format!(
                "{} is a root of scenes[{}] and a child of {}: {trees}",
                node_label(&root),
                scene.index(),
                node_label_at(doc, *p)
            ));
        }
        match is_root.get_mut(r) {
            Some(true) => {
                return Err(format!(
                    "scenes[{}] lists {} twice among its nodes",
                    scene.index(),
                    node_label(&root)
                ))
            }
            Some(seen) => *seen = true,
            None => {
                return Err(format!(
                    "scenes[{}] lists a node nodes[{r}] that does not exist",
                    scene.index()
                ))
            }
        }
    }
    Ok(())
}

/// Visits `scene`'s nodes depth first, each before its children, in the file's order,
/// with an explicit stack (one entry per level, on the heap: a chain of any depth
/// cannot overflow the thread's stack). `visit(node, s)` is given what its parent's
/// visit returned (`root` for the scene's roots); its error ends the walk. The hierarchy
/// must have passed [`check_hierarchy`] (else a cycle never ends).
fn walk_trees<'a, S: Copy>(
    scene: &gltf::Scene<'a>,
    root: S,
    visit: &mut impl FnMut(&gltf::Node<'a>, S) -> Result<S, String>,
) -> Result<(), String> {
    let mut stack: Vec<(gltf::scene::iter::Children<'a>, S)> = Vec::new();
    for node in scene.nodes() {
        let s = visit(&node, root)?;
        stack.push((node.children(), s));
        while let Some((children, s)) = stack.last_mut() {
            let s = *s;
            match children.next() {
                Some(child) => {
                    let c = visit(&child, s)?;
                    stack.push((child.children(), c));
                }
                None => {
                    stack.pop();
                }
            }
        }
    }
    Ok(())
}

/// Checks, before anything is read, every primitive of the meshes that `scene`'s nodes
/// place ([`check_primitive`]) and the size of the import: the triangles and vertices
/// of every placement of a mesh (one per node that has it), summed over the nodes,
/// within [`MAX_IMPORT_TRIANGLES`] and [`MAX_IMPORT_VERTICES`]. The hierarchy must have
/// passed [`check_hierarchy`].
fn check_meshes(scene: &gltf::Scene) -> Result<(), String> {
    let mut sizes: BTreeMap<usize, (u64, u64)> = BTreeMap::new();
    let (mut triangles, mut vertices) = (0u64, 0u64);
    walk_trees(scene, (), &mut |node, ()| {
        let Some(mesh) = node.mesh() else {
            return Ok(());
        };
        let (t, v) = match sizes.get(&mesh.index()) {
            Some(size) => *size,
            None => {
                let size = mesh_size(&mesh)?;
                sizes.insert(mesh.index(), size);
                size
            }
        };
        triangles = triangles.saturating_add(t);
        vertices = vertices.saturating_add(v);
        if triangles > MAX_IMPORT_TRIANGLES || vertices > MAX_IMPORT_VERTICES {
            return Err(format!(
                "{} places {} ({t} triangles, {v} vertices), which brings the import to {triangles} \
                 triangles and {vertices} vertices, over the limit of {MAX_IMPORT_TRIANGLES} \
                 triangles and {MAX_IMPORT_VERTICES} vertices a glTF import may have (a mesh is \
                 imported once per node that places it)",
                node_label(node),
                mesh_label(&mesh)
            ));
        }
        Ok(())
    })
}

/// Triangles and vertices one placement of `mesh` imports (as [`Importer::mesh`] reads
/// it), after checking each primitive ([`check_primitive`]).
fn mesh_size(mesh: &gltf::Mesh) -> Result<(u64, u64), String> {
    let (mut triangles, mut vertices) = (0u64, 0u64);
    for prim in mesh.primitives() {
        let at = format!("{} primitive {}", mesh_label(mesh), prim.index());
        let (t, v) = check_primitive(&prim, &at)?;
        triangles = triangles.saturating_add(t);
        vertices = vertices.saturating_add(v);
    }
    Ok((triangles, vertices))
}

/// Checks the accessors [`Importer::mesh`] reads from `prim` (named `at` in errors)
/// before the `gltf` crate's readers see them: they assume glTF's types and panic
/// (`unreachable!()`) or misread on others. POSITION and NORMAL are VEC3 of FLOAT,
/// TEXCOORD_0 VEC2 of FLOAT, UNSIGNED_BYTE or UNSIGNED_SHORT, the indices SCALAR of
/// UNSIGNED_BYTE, UNSIGNED_SHORT or UNSIGNED_INT, each with at least one element.
/// Returns the triangles and vertices the primitive imports (points and lines: no
/// triangles, and the vertices read before they are skipped; nothing without POSITION).
fn check_primitive(prim: &gltf::Primitive, at: &str) -> Result<(u64, u64), String> {
    use gltf::accessor::{DataType as D, Dimensions as Dim};
    use gltf::mesh::Mode;
    use gltf::Semantic;
    let Some(positions) = prim.get(&Semantic::Positions) else {
        return Ok((0, 0));
    };
    check_read_accessor(&positions, at, "POSITION", Dim::Vec3, &[D::F32])?;
    if let Some(a) = prim.get(&Semantic::Normals) {
        check_read_accessor(&a, at, "NORMAL", Dim::Vec3, &[D::F32])?;
    }
    if let Some(a) = prim.get(&Semantic::TexCoords(0)) {
        check_read_accessor(&a, at, "TEXCOORD_0", Dim::Vec2, &[D::F32, D::U8, D::U16])?;
    }
    let count = match prim.indices() {
        Some(a) => {
            check_read_accessor(&a, at, "indices", Dim::Scalar, &[D::U8, D::U16, D::U32])?;
            a.count()
        }
        None => positions.count(),
    } as u64;
    let triangles = match prim.mode() {
        Mode::Triangles => count / 3,
        Mode::TriangleStrip | Mode::TriangleFan => count.saturating_sub(2),
        _ => 0,
    };
    Ok((triangles, positions.count() as u64))
}

/// Refuses accessor `a`, read as `what` of the primitive `at`, unless its elements are
/// `dims` of one of the component types `types` and it has at least one element (the
/// `gltf` crate's readers assume both).
fn check_read_accessor(
    a: &gltf::Accessor,
    at: &str,
    what: &str,
    dims: gltf::accessor::Dimensions,
    types: &[gltf::accessor::DataType],
) -> Result<(), String> {
    if a.dimensions() != dims || !types.contains(&a.data_type()) {
        let wanted: Vec<&str> = types.iter().map(|t| component_type_name(*t)).collect();
        let wanted = match wanted.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => wanted.join(""),
        };
        return Err(format!(
            "{at}: {what} accessors[{}] is {} of {}; caustica reads {what} as {} of {}",
            a.index(),
            dimensions_name(a.dimensions()),
            component_type_name(a.data_type()),
            dimensions_name(dims),
            wanted
        ));
    }
    if a.count() == 0 {
        return Err(format!(
            "{at}: {what} accessors[{}] has no elements (glTF requires a count of at least 1)",
            a.index()
        ));
    }
    Ok(())
}

/// glTF's name of a component type (`componentType`).
fn component_type_name(t: gltf::accessor::DataType) -> &'static str {
    use gltf::accessor::DataType as D;
    match t {
        D::I8 => "BYTE",
        D::U8 => "UNSIGNED_BYTE",
        D::I16 => "SHORT",
        D::U16 => "UNSIGNED_SHORT",
        D::U32 => "UNSIGNED_INT",
        D::F32 => "FLOAT",
    }
}

/// glTF's name of an accessor's element type (`type`).
fn dimensions_name(d: gltf::accessor::Dimensions) -> &'static str {
    use gltf::accessor::Dimensions as Dim;
    match d {
        Dim::Scalar => "SCALAR",
        Dim::Vec2 => "VEC2",
        Dim::Vec3 => "VEC3",
        Dim::Vec4 => "VEC4",
        Dim::Mat2 => "MAT2",
        Dim::Mat3 => "MAT3",
        Dim::Mat4 => "MAT4",
    }
}

struct Importer<'b> {
    buffers: &'b [Vec<u8>],
    warnings: Vec<String>,
    materials: BTreeMap<String, Material>,
    /// glTF material index (None: the default material) -> caustica name.
    material_names: BTreeMap<Option<usize>, String>,
    objects: Vec<Object>,
    lights: Vec<Light>,
    camera: Option<Camera>,
    bounds: Aabb,
}

/// A node's world transform as an instance placement: the node's own translation,
/// rotation and scale, exactly as the file has them, under an identity parent; otherwise
/// `world` decomposed, if that decomposition gives `world` back (no shear, which a
/// non-uniform scale under a rotated child makes) and its scale is one an instance may
/// have. `None` for the identity (the object stays in the static level) and where no
/// placement reproduces `world` (its vertices are transformed instead).
fn instance_placement(node: &gltf::Node, parent: Mat4, world: Mat4) -> Option<Transform> {
    let t = if parent == Mat4::IDENTITY {
        let (translation, rotation, scale) = node.transform().decomposed();
        Transform {
            translation: Vec3::from(translation),
            rotation: Quat::from_array(rotation),
            scale: Vec3::from(scale),
        }
    } else {
        let (scale, rotation, translation) = world.to_scale_rotation_translation();
        let back = Mat4::from_scale_rotation_translation(scale, rotation, translation);
        let size = world
            .to_cols_array()
            .iter()
            .fold(1.0f32, |m, x| m.max(x.abs()));
        let off = (back - world)
            .to_cols_array()
            .iter()
            .fold(0.0f32, |m, x| m.max(x.abs()));
        // f32 decomposition round-trips to a few ulps of the largest element
        if off > 1e-5 * size {
            return None;
        }
        Transform {
            translation,
            rotation,
            scale,
        }
    };
    if t.translation == Vec3::ZERO && t.rotation == Quat::IDENTITY && t.scale == Vec3::ONE {
        return None;
    }
    t.problem().is_none().then_some(t)
}

impl Importer<'_> {
    /// Imports what `node` itself holds (its meshes, light and camera; not its children)
    /// under the world transform `parent`; returns the node's own world transform, the
    /// one its children are placed under.
    fn visit(&mut self, node: &gltf::Node, parent: Mat4) -> Result<Mat4, String> {
        let local = Mat4::from_cols_array_2d(&node.transform().matrix());
        let world = parent * local;
        let label = node_label(node);
        if let Some(mesh) = node.mesh() {
            let placement = instance_placement(node, parent, world);
            self.mesh(&mesh, world, placement, &label)?;
        }
        if let Some(light) = node.light() {
            self.light(&light, world, &label);
        }
        if let Some(cam) = node.camera() {
            self.camera(&cam, world, &label)?;
        }
        Ok(world)
    }

    /// The primitives of `mesh` as objects: instances placed by `placement` (object-space
    /// vertices; a mirroring placement's winding is core's to reverse), or with `world`
    /// applied to their vertices.
    fn mesh(
        &mut self,
        mesh: &gltf::Mesh,
        world: Mat4,
        placement: Option<Transform>,
        label: &str,
    ) -> Result<(), String> {
        // an instance keeps its vertices in object space
        let vertex_matrix = if placement.is_some() {
            Mat4::IDENTITY
        } else {
            world
        };
        let normal_matrix = NormalMatrix::new(Mat3::from_mat4(vertex_matrix));
        let flip = normal_matrix.mirrors;
        for prim in mesh.primitives() {
            let at = format!("{label} mesh {} primitive {}", mesh.index(), prim.index());
            let reader = prim.reader(|b| self.buffers.get(b.index()).map(|v| v.as_slice()));
            let Some(positions) = reader.read_positions() else {
                self.warnings.push(format!("{at}: no POSITION, skipped"));
                continue;
            };
            let positions: Vec<Vec3> = positions
                .map(|p| vertex_matrix.transform_point3(Vec3::from(p)))
                .collect();
            let n = positions.len();
            let mut normals: Vec<Vec3> = match reader.read_normals() {
                Some(it) => it.map(Vec3::from).collect(),
                None => Vec::new(),
            };
            if let Some(k) = normal_matrix.apply(&mut normals) {
                // the file's normals are fine; the transform flattens this one's direction
                self.warnings.push(format!(
                    "{at}: the NORMAL {:?} of vertex {k} has no direction under the node's \
                     transform, which collapses it (a singular scale): the primitive's \
                     normals are generated from its faces instead",
                    normals[k].to_array()
                ));
                normals.clear();
            }
            let uvs: Vec<Vec2> = match reader.read_tex_coords(0) {
                Some(t) => t.into_f32().map(Vec2::from).collect(),
                None => Vec::new(),
            };
            let flat: Vec<u32> = match reader.read_indices() {
                Some(ix) => ix.into_u32().collect(),
                None => (0..n as u32).collect(),
            };
            if let Some(bad) = flat.iter().find(|&&i| i as usize >= n) {
                return Err(format!("{at}: index {bad} beyond its {n} vertices"));
            }
            use gltf::mesh::Mode;
            let mut tris: Vec<[u32; 3]> = match prim.mode() {
                Mode::Triangles => flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect(),
                Mode::TriangleStrip => (2..flat.len())
                    .map(|k| {
                        if k % 2 == 0 {
                            [flat[k - 2], flat[k - 1], flat[k]]
                        } else {
                            [flat[k - 1], flat[k - 2], flat[k]]
                        }
                    })
                    .collect(),
                Mode::TriangleFan => (2..flat.len())
                    .map(|k| [flat[0], flat[k - 1], flat[k]])
                    .collect(),
                other => {
                    self.warnings.push(format!(
                        "{at}: {other:?} primitives are not surfaces, skipped"
                    ));
                    continue;
                }
            };
            if flip {
                for t in &mut tris {
                    t.swap(1, 2);
                }
            }
            if tris.is_empty() {
                continue;
            }
            for p in &positions {
                self.bounds
                    .grow(placement.map_or(*p, |t| t.transform_point(*p)));
            }
            let material = self.material(prim.material());
            self.objects.push(Object {
                name: at,
                material,
                shape: Shape::Mesh {
                    positions: positions.into(),
                    normals: (if normals.len() == n {
                        normals
                    } else {
                        Vec::new()
                    })
                    .into(),
                    uvs: (if uvs.len() == n { uvs } else { Vec::new() }).into(),
                    indices: tris.into(),
                },
                transform: placement,
            });
        }
        Ok(())
    }

    /// The caustica material name for glTF material `m` (mapped once).
    fn material(&mut self, m: gltf::Material) -> String {
        if let Some(n) = self.material_names.get(&m.index()) {
            return n.clone();
        }
        let base = match (m.index(), m.name()) {
            (_, Some(n)) if !n.is_empty() => printable(n),
            (Some(i), _) => format!("material{i}"),
            (None, _) => "default".into(),
        };
        let mut name = base.clone();
        let mut k = 1;
        while self.materials.contains_key(&name) {
            k += 1;
            name = format!("{base}#{k}");
        }
        let at = match m.index() {
            Some(i) => format!("materials[{i}] '{name}'"),
            None => "the default material".into(),
        };
        let mat = map_material(&m, &at, &mut self.warnings);
        self.materials.insert(name.clone(), mat);
        self.material_names.insert(m.index(), name.clone());
        name
    }

    fn light(&mut self, light: &gltf::khr_lights_punctual::Light, world: Mat4, label: &str) {
        let extras = caustica_extras(light.extras());
        let power = exact_vec3(
            extras.as_ref(),
            "power",
            Vec3::from(light.color()) * light.intensity() / LUMINOUS_EFFICACY_LM_PER_W,
        );
        let position = world.transform_point3(Vec3::ZERO);
        // caustica's own direction vector (any length) where it points the same way
        let derived = world
            .transform_vector3(Vec3::NEG_Z)
            .normalize_or(Vec3::NEG_Y);
        let direction = match extras.as_ref().and_then(|e| vec3_of(e.get("direction")?)) {
            Some(d) if (d.normalize_or_zero() - derived).length() < AGREE => d,
            _ => derived,
        };
        if light.range().is_some() {
            self.warnings.push(format!(
                "{label}: light range has no counterpart (inverse-square without cut-off)"
            ));
        }
        use gltf::khr_lights_punctual::Kind;
        self.lights.push(match light.kind() {
            Kind::Point => Light::Point {
                position,
                intensity: power,
            },
            Kind::Spot {
                inner_cone_angle,
                outer_cone_angle,
            } => Light::Spot {
                position,
                direction,
                intensity: power,
                inner_angle_deg: inner_cone_angle.to_degrees(),
                outer_angle_deg: outer_cone_angle.to_degrees(),
            },
            Kind::Directional => Light::Directional {
                direction,
                irradiance: power,
                projection_volume: extras
                    .and_then(|e| serde_json::from_value(e.get("projection_volume")?.clone()).ok()),
            },
        });
    }

    /// The first perspective camera met becomes the scene's (a further one, or an
    /// orthographic one, is warned and ignored). Errors: an `aspectRatio` that is not
    /// positive (glTF requires `> 0`) and an `extras.caustica` width or height that is not
    /// a pixel count in 1..=[`MAX_IMAGE_SIDE`], each naming the camera and the field.
    fn camera(&mut self, cam: &gltf::Camera, world: Mat4, label: &str) -> Result<(), String> {
        if self.camera.is_some() {
            self.warnings.push(format!(
                "{label}: a further camera, ignored (the first one is used)"
            ));
            return Ok(());
        }
        let gltf::camera::Projection::Perspective(p) = cam.projection() else {
            self.warnings.push(format!(
                "{label}: orthographic camera not supported (caustica's camera is a pinhole)"
            ));
            return Ok(());
        };
        let at = format!("{label} {}", camera_label(cam));
        let aspect = match p.aspect_ratio() {
            Some(a) if !(a.is_finite() && a > 0.0) => {
                return Err(format!(
                    "{at}: aspectRatio {a:?} is not a positive number (glTF requires \
                     aspectRatio > 0 where a perspective camera has one)"
                ))
            }
            Some(a) => a,
            None => DEFAULT_ASPECT,
        };
        let extras = caustica_extras(cam.extras());
        let e = extras.as_ref();
        let width = e.and_then(|e| e.get("width"));
        let height = e.and_then(|e| e.get("height"));
        let (width, height) = match (width, height) {
            (Some(w), Some(h)) => (
                extras_pixels(w, &at, "width")?,
                extras_pixels(h, &at, "height")?,
            ),
            // (one without the other: the image keeps the aspect ratio's size)
            (Some(v), None) | (None, Some(v)) => {
                let which = if width.is_some() { "width" } else { "height" };
                extras_pixels(v, &at, which)?;
                self.warnings.push(format!(
                    "{at}: extras.caustica.{which} without the other side, ignored: the \
                     image is sized from the aspect ratio"
                ));
                self.size_for_aspect(aspect, &at)
            }
            (None, None) => self.size_for_aspect(aspect, &at),
        };
        let e = extras.as_ref();
        let position = world.transform_point3(Vec3::ZERO);
        let forward = world
            .transform_vector3(Vec3::NEG_Z)
            .normalize_or(Vec3::NEG_Z);
        // caustica's own target (any point along the view) where it agrees with the node
        let target = match e.and_then(|e| vec3_of(e.get("target")?)) {
            Some(t) if ((t - position).normalize_or_zero() - forward).length() < AGREE => t,
            _ => position + forward,
        };
        // caustica's own up (any vector in the plane of the view's up) where it agrees
        let derived_up = world.transform_vector3(Vec3::Y).normalize_or(Vec3::Y);
        let up = match e.and_then(|e| vec3_of(e.get("up")?)) {
            Some(u) => {
                let r = forward.cross(u).normalize_or_zero();
                if (r.cross(forward) - derived_up).length() < AGREE {
                    u
                } else {
                    derived_up
                }
            }
            None => derived_up,
        };
        let fov = p.yfov().to_degrees();
        let fov_y_deg = match e.and_then(|e| e.get("fov_y_deg")?.as_f64()) {
            Some(f) if (f as f32 - fov).abs() <= AGREE * fov => f as f32,
            _ => fov,
        };
        self.camera = Some(Camera {
            position,
            target,
            up,
            fov_y_deg,
            width,
            height,
        });
        Ok(())
    }

    /// The image size of a camera `at` without a size in `extras.caustica`:
    /// [`DEFAULT_IMAGE_WIDTH`] pixels wide at `aspect` (positive and finite). Where the
    /// height that gives is outside 1..=[`MAX_IMAGE_SIDE`], it is clamped into it, the
    /// width taken from the aspect at that height (within the same range), with a warning.
    fn size_for_aspect(&mut self, aspect: f32, at: &str) -> (u32, u32) {
        let max = MAX_IMAGE_SIDE as f64;
        let aspect64 = aspect as f64;
        let width = DEFAULT_IMAGE_WIDTH as f64;
        let exact = width / aspect64;
        let height = exact.round();
        let (w, h) = if height < 1.0 {
            // wider than 2 * 960 : 1 - one row, as wide as the aspect asks (within range)
            (aspect64.round().clamp(width, max), 1.0)
        } else if height > max {
            // taller than 960 : 16384 - the most rows, as narrow as the aspect asks
            ((max * aspect64).round().clamp(1.0, width), max)
        } else {
            return (DEFAULT_IMAGE_WIDTH, height as u32);
        };
        self.warnings.push(format!(
            "{at}: aspectRatio {aspect:?} at {DEFAULT_IMAGE_WIDTH} pixels wide needs {exact:.3e} \
             pixels high, outside 1..={MAX_IMAGE_SIDE}: the image is {w} x {h} instead \
             (aspect {:.3e})",
            w / h
        ));
        (w as u32, h as u32)
    }
}

/// Image width (pixels) of a glTF camera without a size in `extras.caustica`; the height
/// follows from its `aspectRatio` ([`DEFAULT_ASPECT`] where it has none).
pub const DEFAULT_IMAGE_WIDTH: u32 = 960;
/// The aspect ratio (width / height) of a glTF camera without `aspectRatio`: 16:9.
pub const DEFAULT_ASPECT: f32 = 16.0 / 9.0;
/// Largest image width or height (pixels) a scene's camera may have (the scene
/// validator's bound: `camera.width` and `camera.height` in 1..=16384).
pub const MAX_IMAGE_SIDE: u32 = 16384;

/// `cameras[k]`, with the camera's name where it has one.
fn camera_label(cam: &gltf::Camera) -> String {
    match cam.name() {
        Some(n) => format!("cameras[{}] '{}'", cam.index(), printable(n)),
        None => format!("cameras[{}]", cam.index()),
    }
}

/// `extras.caustica.<field>` of camera `at` as a pixel count: a whole number in
/// 1..=[`MAX_IMAGE_SIDE`] (an integer, or a float with no fraction). Anything else is an
/// error naming the camera, the field and the value as the file has it (a value past u32
/// is refused, never wrapped).
fn extras_pixels(v: &Value, at: &str, field: &str) -> Result<u32, String> {
    let pixels = v.as_u64().or_else(|| {
        v.as_f64()
            .filter(|x| x.fract() == 0.0 && *x >= 0.0 && *x <= u32::MAX as f64)
            .map(|x| x as u64)
    });
    match pixels {
        Some(n) if (1..=MAX_IMAGE_SIDE as u64).contains(&n) => Ok(n as u32),
        _ => Err(format!(
            "{at}: extras.caustica.{field} {v} is not an image size caustica can render: \
             a whole number of pixels in 1..={MAX_IMAGE_SIDE}"
        )),
    }
}

/// How a static mesh's normals follow the matrix `m` its positions are transformed by:
/// by `m`'s cofactor matrix (the transpose of its adjugate, `det(m) * m^-T` where `m` is
/// invertible), times the sign of the determinant where it is not 0, each result scaled
/// back to unit length. That is the inverse transpose's direction for an invertible
/// matrix, and it still exists for a singular one (a scale of 0 flattening a mesh into a
/// plane, or one of 1e-30), whose inverse is infinite or NaN: `cof(m) (a x b) =
/// (m a) x (m b)`, so a face's normal follows the transformed face. Computed in f64 (the
/// products of two f32 elements neither overflow nor underflow there).
struct NormalMatrix {
    /// The cofactor matrix times the determinant's sign; `None` for the identity (the
    /// file's normals are kept exactly as they are).
    cofactor: Option<DMat3>,
    /// The determinant is negative: a mirroring transform, whose triangles' winding is
    /// reversed so that their faces keep pointing the way of their normals.
    mirrors: bool,
}

impl NormalMatrix {
    fn new(m: Mat3) -> Self {
        if m == Mat3::IDENTITY {
            return Self {
                cofactor: None,
                mirrors: false,
            };
        }
        let d = m.as_dmat3();
        let (x, y, z) = (d.x_axis, d.y_axis, d.z_axis);
        // the columns of the cofactor matrix: each the cross product of the other two
        // columns of m
        let cof = DMat3::from_cols(y.cross(z), z.cross(x), x.cross(y));
        let det = d.determinant();
        let sign = if det < 0.0 { -1.0 } else { 1.0 };
        Self {
            cofactor: Some(cof * sign),
            mirrors: det < 0.0,
        }
    }

    /// Transforms `normals` in place to unit vectors. A normal the file gives that the
    /// scene validator refuses (not finite, beyond `MAX_COORDINATE`, or of length under
    /// 1e-10) is left as the file has it, for the validator to name. Returns the index of
    /// the first valid normal the transform collapses to no direction (a singular matrix
    /// along it), leaving `normals` partly transformed: its caller drops them.
    fn apply(&self, normals: &mut [Vec3]) -> Option<usize> {
        let cof = self.cofactor?;
        for (k, n) in normals.iter_mut().enumerate() {
            let valid = n.is_finite()
                && n.abs().max_element() <= MAX_COORDINATE
                && n.length_squared() >= 1e-20;
            if !valid {
                continue;
            }
            let t = cof * n.as_dvec3();
            // scaled first: a tiny or huge cofactor keeps its direction
            let m = t.abs().max_element();
            if !(m > 0.0 && m.is_finite()) {
                return Some(k);
            }
            let unit = (t / m).normalize().as_vec3();
            if !(unit.is_finite() && unit.length_squared() > 0.5) {
                return Some(k);
            }
            *n = unit;
        }
        None
    }
}

/// How closely a value in `extras.caustica` must agree with the one the standard fields
/// give (relative) to be used instead: caustica writes its exact values there (a light's
/// power through the factor 683, a direction through a quaternion, lose a few ulp), and
/// a file edited in another tool, whose standard fields then disagree, is read from the
/// standard fields.
const AGREE: f32 = 1e-4;

fn vec3_of(v: &Value) -> Option<Vec3> {
    let a = v.as_array()?;
    Some(Vec3::new(
        a.first()?.as_f64()? as f32,
        a.get(1)?.as_f64()? as f32,
        a.get(2)?.as_f64()? as f32,
    ))
}

/// `extras.caustica[key]` where it agrees with `derived` within [`AGREE`], else `derived`.
fn exact_vec3(extras: Option<&serde_json::Map<String, Value>>, key: &str, derived: Vec3) -> Vec3 {
    match extras.and_then(|e| vec3_of(e.get(key)?)) {
        Some(v) if (v - derived).length() <= AGREE * derived.length().max(v.length()) => v,
        _ => derived,
    }
}

/// `extras.caustica` of a glTF element, where caustica keeps what glTF has no field for.
fn caustica_extras(extras: &gltf::json::Extras) -> Option<serde_json::Map<String, Value>> {
    let raw = extras.as_ref()?;
    let v: Value = serde_json::from_str(raw.get()).ok()?;
    v.get("caustica")?.as_object().cloned()
}

fn map_material(m: &gltf::Material, at: &str, warn: &mut Vec<String>) -> Material {
    let pbr = m.pbr_metallic_roughness();
    let base = pbr.base_color_factor();
    let given = Vec3::new(base[0], base[1], base[2]);
    // NaN clamps to NaN: such a factor becomes 0 (black), said as well
    let color = Vec3::select(given.cmpeq(given), given, Vec3::ZERO).clamp(Vec3::ZERO, Vec3::ONE);
    if color != given {
        // glTF 2.0 bounds baseColorFactor to [0, 1]; an albedo outside it would create or
        // take energy
        warn.push(format!(
            "{at}: baseColorFactor {:?} outside [0, 1], taken as {:?}",
            given.to_array(),
            color.to_array()
        ));
    }
    let (metallic, roughness) = (pbr.metallic_factor(), pbr.roughness_factor());
    let mut textures = Vec::new();
    if pbr.base_color_texture().is_some() {
        textures.push("baseColorTexture");
    }
    if pbr.metallic_roughness_texture().is_some() {
        textures.push("metallicRoughnessTexture");
    }
    if m.normal_texture().is_some() {
        textures.push("normalTexture");
    }
    if m.occlusion_texture().is_some() {
        textures.push("occlusionTexture");
    }
    if m.emissive_texture().is_some() {
        textures.push("emissiveTexture");
    }
    if m.transmission()
        .and_then(|t| t.transmission_texture())
        .is_some()
    {
        textures.push("transmissionTexture");
    }
    if m.volume().and_then(|v| v.thickness_texture()).is_some() {
        textures.push("thicknessTexture");
    }
    if !textures.is_empty() {
        warn.push(format!(
            "{at}: textures are not supported, factors used instead: {}",
            textures.join(", ")
        ));
    }
    if m.emissive_factor() != [0.0; 3] {
        warn.push(format!("{at}: emission ignored (only lights emit here)"));
    }
    if !matches!(m.alpha_mode(), gltf::material::AlphaMode::Opaque) || base[3] < 1.0 {
        warn.push(format!(
            "{at}: alpha (blend, mask or alpha < 1) ignored: opaque"
        ));
    }
    let transmission = m.transmission().map_or(0.0, |t| t.transmission_factor());
    if transmission > 0.0 {
        if transmission < 1.0 {
            warn.push(format!(
                "{at}: partial transmission {transmission} not supported: {}",
                if transmission >= 0.5 {
                    "traced as a dielectric"
                } else {
                    "diffuse"
                }
            ));
        }
        if transmission >= 0.5 {
            if roughness > MIRROR_MAX_ROUGHNESS {
                warn.push(format!(
                    "{at}: roughness {roughness} on glass not supported: traced as smooth"
                ));
            }
            let n_d = m.ior().unwrap_or(1.5);
            let abbe = m
                .extension_value("KHR_materials_dispersion")
                .and_then(|d| d.get("dispersion")?.as_f64())
                .filter(|d| *d > 0.0)
                .map(|d| (20.0 / d) as f32);
            let absorption = match m.volume() {
                Some(v) => {
                    let d = v.attenuation_distance();
                    let c = Vec3::from(v.attenuation_color());
                    if d.is_finite() && d > 0.0 {
                        Vec3::new(
                            -c.x.max(f32::MIN_POSITIVE).ln(),
                            -c.y.max(f32::MIN_POSITIVE).ln(),
                            -c.z.max(f32::MIN_POSITIVE).ln(),
                        ) / d
                    } else {
                        Vec3::ZERO
                    }
                }
                None => {
                    warn.push(format!(
                        "{at}: transmission without KHR_materials_volume is thin-walled in \
                         glTF: traced as a solid dielectric"
                    ));
                    Vec3::ZERO
                }
            };
            // caustica's own values (extras.caustica) where the standard fields agree
            let e = caustica_extras(m.extras());
            let e = e.as_ref();
            let absorption = exact_vec3(e, "absorption", absorption);
            let extra = |key: &str| e.and_then(|e| e.get(key)?.as_f64()).map(|x| x as f32);
            let agrees = |x: f32, derived: f32| (x - derived).abs() <= AGREE * derived.abs();
            // a Cauchy glass that caustica wrote: its B agrees with the Abbe number
            let cauchy = abbe.map_or(0.0, |v| cauchy_b_from_abbe(n_d, v));
            if let Some(b) = extra("cauchy_b").filter(|b| *b != 0.0 && agrees(*b, cauchy)) {
                let ior = ior_at_reference(n_d, b);
                return Material::Dielectric {
                    ior: extra("ior").filter(|x| agrees(*x, ior)).unwrap_or(ior),
                    cauchy_b: b,
                    absorption,
                    ior_model: IorModel::Cauchy,
                };
            }
            let ior = extra("ior").filter(|x| agrees(*x, n_d)).unwrap_or(n_d);
            let ior_model = match abbe {
                Some(v) => IorModel::Abbe {
                    abbe_number: extra("abbe_number").filter(|x| agrees(*x, v)).unwrap_or(v),
                },
                None => IorModel::Cauchy,
            };
            if ior_model != IorModel::Cauchy && ior < 1.0 {
                warn.push(format!(
                    "{at}: KHR_materials_dispersion with ior {ior} < 1: no dispersion (the \
                     extension's formula holds for n_d >= 1)"
                ));
                return Material::Dielectric {
                    ior,
                    cauchy_b: 0.0,
                    absorption,
                    ior_model: IorModel::Cauchy,
                };
            }
            return Material::Dielectric {
                ior,
                cauchy_b: 0.0,
                absorption,
                ior_model,
            };
        }
    }
    if metallic >= 0.5 && roughness <= MIRROR_MAX_ROUGHNESS {
        if metallic < 1.0 {
            warn.push(format!("{at}: metallic {metallic} read as a mirror"));
        }
        return Material::Mirror { reflectance: color };
    }
    if metallic > 0.0 {
        warn.push(format!(
            "{at}: metallic {metallic} with roughness {roughness} read as diffuse"
        ));
    }
    Material::Diffuse { albedo: color }
}

fn default_camera(bounds: Aabb) -> Camera {
    let c = bounds.center();
    let r = (0.5 * bounds.diagonal()).max(1e-3);
    Camera {
        position: c + Vec3::new(0.0, 0.6, 1.6) * r * 1.8,
        target: c,
        up: Vec3::Y,
        fov_y_deg: 45.0,
        width: 960,
        height: 540,
    }
}

// ---- export ----

/// The scene as a self-contained glTF 2.0 document (`.gltf` JSON with one embedded
/// buffer): every object tessellated into a mesh (one node each; an instance's mesh in
/// object space under a node with its translation, rotation and scale), the
/// materials by the inverse of the import mapping (absorption as attenuation colour
/// `exp(-sigma / max sigma)` at distance `1 / max sigma`; dispersion as
/// `KHR_materials_dispersion`), the lights with `KHR_lights_punctual` (times 683), the
/// camera as a perspective camera; image size and a directional light's projection
/// volume in `extras.caustica`.
pub fn scene_to_gltf(scene: &Scene) -> String {
    let mut bin: Vec<u8> = Vec::new();
    let mut views = Vec::new();
    let mut accessors = Vec::new();
    let mut push = |bytes: &[u8], target: u32, acc: Value| -> usize {
        while !bin.len().is_multiple_of(4) {
            bin.push(0);
        }
        views.push(json!({"buffer": 0, "byteOffset": bin.len(), "byteLength": bytes.len(), "target": target}));
        bin.extend_from_slice(bytes);
        let mut a = acc;
        a["bufferView"] = json!(views.len() - 1);
        accessors.push(a);
        accessors.len() - 1
    };
    let names: Vec<&String> = scene.materials.keys().collect();
    let mut meshes = Vec::new();
    let mut nodes = Vec::new();
    let mut root = Vec::new();
    for o in &scene.objects {
        let m = tessellate(&o.shape);
        let n = m.positions.len();
        let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
        for p in &m.positions {
            lo = lo.min(*p);
            hi = hi.max(*p);
        }
        let f32s = |v: &[f32]| -> Vec<u8> { v.iter().flat_map(|x| x.to_le_bytes()).collect() };
        let pos: Vec<f32> = m.positions.iter().flat_map(|p| p.to_array()).collect();
        let nor: Vec<f32> = m.normals.iter().flat_map(|p| p.to_array()).collect();
        let uv: Vec<f32> = m.uvs.iter().flat_map(|p| p.to_array()).collect();
        let idx: Vec<u8> = m
            .indices
            .iter()
            .flatten()
            .flat_map(|i| i.to_le_bytes())
            .collect();
        let a_pos = push(
            &f32s(&pos),
            34962,
            json!({"componentType": 5126, "count": n, "type": "VEC3", "min": lo.to_array(), "max": hi.to_array()}),
        );
        let mut attributes = json!({"POSITION": a_pos});
        if m.normals.len() == n {
            attributes["NORMAL"] = json!(push(
                &f32s(&nor),
                34962,
                json!({"componentType": 5126, "count": n, "type": "VEC3"})
            ));
        }
        if m.uvs.len() == n {
            attributes["TEXCOORD_0"] = json!(push(
                &f32s(&uv),
                34962,
                json!({"componentType": 5126, "count": n, "type": "VEC2"})
            ));
        }
        let a_idx = push(
            &idx,
            34963,
            json!({"componentType": 5125, "count": m.indices.len() * 3, "type": "SCALAR"}),
        );
        let mat = names.iter().position(|k| **k == o.material).unwrap_or(0);
        meshes.push(json!({"name": o.name, "primitives": [{"attributes": attributes, "indices": a_idx, "material": mat, "mode": 4}]}));
        root.push(nodes.len());
        let mut node = json!({"name": o.name, "mesh": meshes.len() - 1});
        if let Some(t) = &o.transform {
            // an instance: its object-space mesh under its placement
            node["translation"] = json!(t.translation.to_array());
            node["rotation"] = json!(t.rotation.to_array());
            node["scale"] = json!(t.scale.to_array());
        }
        nodes.push(node);
    }
    let mut ext_used = std::collections::BTreeSet::new();
    let materials: Vec<Value> = scene
        .materials
        .iter()
        .map(|(name, m)| material_json(name, m, &mut ext_used))
        .collect();
    // lights
    let mut lights = Vec::new();
    for (k, l) in scene.lights.iter().enumerate() {
        let (kind, power, pos, dir) = match l {
            Light::Point {
                position,
                intensity,
            } => ("point", *intensity, *position, Vec3::NEG_Y),
            Light::Spot {
                position,
                direction,
                intensity,
                ..
            } => ("spot", *intensity, *position, direction.normalize()),
            Light::Directional {
                direction,
                irradiance,
                ..
            } => (
                "directional",
                *irradiance,
                Vec3::ZERO,
                direction.normalize(),
            ),
        };
        let peak = power.max_element();
        let color = if peak > 0.0 { power / peak } else { Vec3::ONE };
        let mut lj = json!({"name": format!("light{k}"), "type": kind, "color": color.to_array(), "intensity": peak * LUMINOUS_EFFICACY_LM_PER_W});
        if let Light::Spot {
            inner_angle_deg,
            outer_angle_deg,
            ..
        } = l
        {
            lj["spot"] = json!({"innerConeAngle": inner_angle_deg.to_radians(), "outerConeAngle": outer_angle_deg.to_radians()});
        }
        let own_dir = match l {
            Light::Spot { direction, .. } | Light::Directional { direction, .. } => *direction,
            Light::Point { .. } => dir,
        };
        let mut exact = json!({"power": power.to_array(), "direction": own_dir.to_array()});
        if let Light::Directional {
            projection_volume: Some(v),
            ..
        } = l
        {
            exact["projection_volume"] = json!(v);
        }
        lj["extras"] = json!({"caustica": exact});
        lights.push(lj);
        let rot = Quat::from_rotation_arc(Vec3::NEG_Z, dir);
        root.push(nodes.len());
        nodes.push(json!({"name": format!("light{k}"), "translation": pos.to_array(), "rotation": rot.to_array(), "extensions": {"KHR_lights_punctual": {"light": k}}}));
    }
    ext_used.insert("KHR_lights_punctual");
    // camera: -z forward, +y up
    let c = &scene.camera;
    let f = (c.target - c.position).normalize();
    let r = f.cross(c.up).normalize();
    let u = r.cross(f);
    let rot = Quat::from_mat3(&Mat3::from_cols(r, u, -f)).normalize();
    root.push(nodes.len());
    nodes.push(json!({"name": "camera", "camera": 0, "translation": c.position.to_array(), "rotation": rot.to_array()}));
    let camera = json!({"type": "perspective", "perspective": {"yfov": c.fov_y_deg.to_radians(), "aspectRatio": c.width as f32 / c.height as f32, "znear": 1e-3},
        "extras": {"caustica": {"width": c.width, "height": c.height, "target": c.target.to_array(), "up": c.up.to_array(), "fov_y_deg": c.fov_y_deg}}});
    let doc = json!({
        "asset": {"version": "2.0", "generator": concat!("caustica ", env!("CARGO_PKG_VERSION"))},
        "extensionsUsed": ext_used.iter().collect::<Vec<_>>(),
        "extensions": {"KHR_lights_punctual": {"lights": lights}},
        "scene": 0,
        "scenes": [{"name": scene.name, "nodes": root}],
        "nodes": nodes,
        "meshes": meshes,
        "materials": materials,
        "cameras": [camera],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len(), "uri": format!("data:application/octet-stream;base64,{}", base64_encode(&bin))}],
    });
    serde_json::to_string_pretty(&doc).expect("glTF serialisation cannot fail")
}

fn material_json(
    name: &str,
    m: &Material,
    ext: &mut std::collections::BTreeSet<&'static str>,
) -> Value {
    match m {
        Material::Diffuse { albedo } => {
            json!({"name": name, "pbrMetallicRoughness": {"baseColorFactor": [albedo.x, albedo.y, albedo.z, 1.0], "metallicFactor": 0.0, "roughnessFactor": 1.0}})
        }
        Material::Mirror { reflectance } => {
            json!({"name": name, "pbrMetallicRoughness": {"baseColorFactor": [reflectance.x, reflectance.y, reflectance.z, 1.0], "metallicFactor": 1.0, "roughnessFactor": 0.0}})
        }
        Material::Dielectric {
            ior,
            cauchy_b,
            absorption,
            ior_model,
        } => {
            ext.insert("KHR_materials_transmission");
            ext.insert("KHR_materials_ior");
            ext.insert("KHR_materials_volume");
            // the Abbe model's index is n_d already; a Cauchy one's goes back from 550 nm
            // to the d line
            let n_d = match ior_model {
                IorModel::Abbe { .. } => *ior,
                IorModel::Cauchy => {
                    ior - cauchy_b
                        * (1.0 / (REFERENCE_WAVELENGTH_UM * REFERENCE_WAVELENGTH_UM)
                            - 1.0 / (FRAUNHOFER_D_UM * FRAUNHOFER_D_UM))
                }
            };
            let mut e = json!({
                "KHR_materials_transmission": {"transmissionFactor": 1.0},
                "KHR_materials_ior": {"ior": n_d},
            });
            let s = absorption.max_element();
            if s > 0.0 {
                let c = (-*absorption / s).exp();
                e["KHR_materials_volume"] = json!({"thicknessFactor": 1.0, "attenuationDistance": 1.0 / s, "attenuationColor": c.to_array()});
            } else {
                e["KHR_materials_volume"] = json!({"thicknessFactor": 1.0});
            }
            let mut extras = json!({"ior": ior, "absorption": absorption.to_array()});
            match ior_model {
                IorModel::Abbe { abbe_number } => {
                    ext.insert("KHR_materials_dispersion");
                    e["KHR_materials_dispersion"] = json!({"dispersion": 20.0 / abbe_number});
                    extras["abbe_number"] = json!(abbe_number);
                }
                IorModel::Cauchy if *cauchy_b > 0.0 => {
                    ext.insert("KHR_materials_dispersion");
                    let k = 1.0 / (FRAUNHOFER_F_UM * FRAUNHOFER_F_UM)
                        - 1.0 / (FRAUNHOFER_C_UM * FRAUNHOFER_C_UM);
                    let abbe = (n_d - 1.0) / (cauchy_b * k);
                    e["KHR_materials_dispersion"] = json!({"dispersion": 20.0 / abbe});
                    extras["cauchy_b"] = json!(cauchy_b);
                }
                IorModel::Cauchy => {
                    extras["cauchy_b"] = json!(cauchy_b);
                }
            }
            json!({"name": name, "pbrMetallicRoughness": {"baseColorFactor": [1.0, 1.0, 1.0, 1.0], "metallicFactor": 0.0, "roughnessFactor": 0.0}, "extensions": e,
                "extras": {"caustica": extras}})
        }
    }
}

// ---- base64 and URIs ----

const B64: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";

fn base64_encode(data: &[u8]) -> String {
    let mut s = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let n = (c[0] as u32) << 16
            | (*c.get(1).unwrap_or(&0) as u32) << 8
            | *c.get(2).unwrap_or(&0) as u32;
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

fn base64_decode(s: &str) -> Option<Vec<u8>> {
    let mut out = Vec::with_capacity(s.len() / 4 * 3);
    let (mut acc, mut bits) = (0u32, 0u32);
    for ch in s.bytes() {
        let v = match ch {
            b'A'..=b'Z' => ch - b'A',
            b'a'..=b'z' => ch - b'a' + 26,
            b'0'..=b'9' => ch - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => break,
            b' ' | b'\n' | b'\r' | b'\t' => continue,
            _ => return None,
        } as u32;
        acc = acc << 6 | v;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Some(out)
}

/// `s` with each `%XX` (two hex digits) replaced by its byte, read as UTF-8 (a byte
/// that is not, as U+FFFD); a `%` without two hex digits after it is kept.
fn percent_decode(s: &str) -> String {
    let hex = |c: u8| (c as char).to_digit(16).map(|d| d as u8);
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            if let (Some(hi), Some(lo)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push(hi << 4 | lo);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips() {
        for len in 0..20 {
            let v: Vec<u8> = (0..len).map(|i| (i * 37 + 11) as u8).collect();
            assert_eq!(base64_decode(&base64_encode(&v)).unwrap(), v);
        }
        assert_eq!(base64_encode(b"Man"), "TWFu");
        assert_eq!(base64_encode(b"Ma"), "TWE=");
    }

    #[test]
    fn bk7_abbe_number_gives_its_cauchy_b() {
        // BK7: n_d 1.5168, V_d 64.17; Cauchy fit B ~ 0.0042 um^2
        let b = cauchy_b_from_abbe(1.5168, 64.17);
        assert!((b - 0.00420).abs() < 0.0001, "{b}");
        // and back: n_F - n_C from B gives the Abbe number
        let nf_nc = b
            * (1.0 / (FRAUNHOFER_F_UM * FRAUNHOFER_F_UM)
                - 1.0 / (FRAUNHOFER_C_UM * FRAUNHOFER_C_UM));
        assert!(((1.5168 - 1.0) / nf_nc - 64.17).abs() < 1e-3);
        assert_eq!(cauchy_b_from_abbe(1.5, 0.0), 0.0);
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("plain.bin"), "plain.bin");
        assert_eq!(percent_decode("bad%2"), "bad%2");
        assert_eq!(percent_decode("%2e%2E%2f"), "../");
        // a `%` before a character of several bytes is kept, not sliced through
        assert_eq!(percent_decode("%a\u{e9}.bin"), "%a\u{e9}.bin");
        assert_eq!(percent_decode("%\u{e9}"), "%\u{e9}");
        assert_eq!(percent_decode("%+1x"), "%+1x");
    }

    /// A glTF document whose one buffer is the file `uri` (a triangle in y = 0: positions,
    /// normals and UVs, UNSIGNED_SHORT indices), and that buffer's bytes.
    fn external_buffer_gltf(uri: &str) -> (String, Vec<u8>) {
        let mut bin = Vec::new();
        let floats: [f32; 24] = [
            0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, // positions
            0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, // normals
            0.0, 0.0, 1.0, 0.0, 0.0, 1.0, // uvs
        ];
        for f in floats {
            bin.extend(f.to_le_bytes());
        }
        for i in [0u16, 2, 1, 0] {
            bin.extend(i.to_le_bytes()); // the last one pads to 4 bytes
        }
        let doc = json!({
            "asset": {"version": "2.0"},
            "scene": 0,
            "scenes": [{"nodes": [0]}],
            "nodes": [{"mesh": 0}],
            "meshes": [{"primitives": [{
                "attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                "indices": 3
            }]}],
            "accessors": [
                {"bufferView": 0, "componentType": 5126, "count": 3, "type": "VEC3",
                 "min": [0.0, 0.0, 0.0], "max": [1.0, 0.0, 1.0]},
                {"bufferView": 1, "componentType": 5126, "count": 3, "type": "VEC3"},
                {"bufferView": 2, "componentType": 5126, "count": 3, "type": "VEC2"},
                {"bufferView": 3, "componentType": 5123, "count": 3, "type": "SCALAR"}
            ],
            "bufferViews": [
                {"buffer": 0, "byteOffset": 0, "byteLength": 36},
                {"buffer": 0, "byteOffset": 36, "byteLength": 36},
                {"buffer": 0, "byteOffset": 72, "byteLength": 24},
                {"buffer": 0, "byteOffset": 96, "byteLength": 6}
            ],
            "buffers": [{"byteLength": bin.len(), "uri": uri}]
        });
        (doc.to_string(), bin)
    }

    /// A fresh folder `<temp>/caustica-gltf-uri-<pid>-<name>` with a `gltf` folder in it.
    fn uri_test_folder(name: &str) -> std::path::PathBuf {
        let root =
            std::env::temp_dir().join(format!("caustica-gltf-uri-{}-{name}", std::process::id()));
        let _ = std::fs::remove_dir_all(&root);
        std::fs::create_dir_all(root.join("gltf")).unwrap();
        root
    }

    /// A buffer URI that is an absolute path or that climbs out of the glTF file's folder
    /// is refused with the buffer named, even where the file it names is there and holds
    /// a good buffer (`secret.bin`, beside the glTF file's folder).
    #[test]
    fn buffer_uris_outside_the_folder_are_refused() {
        let root = uri_test_folder("outside");
        let secret = root.join("secret.bin");
        let (_, bin) = external_buffer_gltf("");
        std::fs::write(&secret, &bin).unwrap();
        let absolute = secret.to_string_lossy().replace('%', "%25");
        let cases: &[(&str, &str)] = &[
            (&absolute, "absolute path"),
            ("/etc/passwd", "absolute path"),
            ("\\\\server\\share\\secret.bin", "absolute path"),
            ("%2Fetc%2Fpasswd", "absolute path"),
            ("C:\\secret.bin", "Windows drive"),
            ("c:/secret.bin", "Windows drive"),
            ("C:secret.bin", "Windows drive"),
            ("sub/D:/secret.bin", "Windows drive"),
            ("file:secret.bin", "URI scheme"),
            ("../secret.bin", "leaves the folder"),
            ("..\\secret.bin", "leaves the folder"),
            ("%2e%2e/secret.bin", "leaves the folder"),
            ("%2E%2E%2Fsecret.bin", "leaves the folder"),
            ("sub/../../secret.bin", "leaves the folder"),
            ("./sub/..\\..\\gltf/../secret.bin", "leaves the folder"),
            ("", "names no file"),
            ("sub/..", "names no file"),
        ];
        for (uri, why) in cases {
            let (doc, _) = external_buffer_gltf(uri);
            let path = root.join("gltf").join("scene.gltf");
            std::fs::write(&path, doc).unwrap();
            let e = match load_gltf(&path) {
                Ok(_) => panic!("{uri:?}: read, expected '{why}'"),
                Err(e) => e.to_string(),
            };
            assert!(e.contains("buffers[0]: '"), "{uri:?}: {e}");
            assert!(e.contains(why), "{uri:?}: '{why}' missing in: {e}");
            assert!(
                e.contains("put the .bin beside the .gltf"),
                "{uri:?}: no remedy in: {e}"
            );
            assert!(!e.contains('\n'), "{uri:?}: not one line: {e}");
        }
        let _ = std::fs::remove_dir_all(&root);
    }

    /// Relative URIs beside or below the glTF file still load, percent-encoded or not,
    /// and with `..` that stays inside.
    #[test]
    fn buffer_uris_beside_and_below_the_file_load() {
        let root = uri_test_folder("inside");
        let dir = root.join("gltf");
        std::fs::create_dir_all(dir.join("sub")).unwrap();
        for (uri, file) in [
            ("scene.bin", "scene.bin"),
            ("./scene.bin", "scene.bin"),
            ("sub/scene.bin", "sub/scene.bin"),
            ("sub\\scene.bin", "sub/scene.bin"),
            ("sub%2Fscene.bin", "sub/scene.bin"),
            ("a/../scene.bin", "scene.bin"),
            ("sub//x/..//scene.bin", "sub/scene.bin"),
            ("my%20scene.bin", "my scene.bin"),
        ] {
            let (doc, bin) = external_buffer_gltf(uri);
            std::fs::write(dir.join(file), &bin).unwrap();
            let path = dir.join("scene.gltf");
            std::fs::write(&path, doc).unwrap();
            let im = load_gltf(&path).unwrap_or_else(|e| panic!("{uri:?}: {e}"));
            assert_eq!(im.scene.objects.len(), 1, "{uri:?}");
            std::fs::remove_file(dir.join(file)).unwrap();
        }
        let _ = std::fs::remove_dir_all(&root);
    }

    #[test]
    fn uri_segments_are_normalised_inside_the_folder() {
        let dir = Path::new("base");
        assert_eq!(
            file_in_folder(dir, "a/./b//c.bin"),
            Ok(dir.join("a").join("b").join("c.bin"))
        );
        assert_eq!(
            file_in_folder(dir, "a/b/../../c.bin"),
            Ok(dir.join("c.bin"))
        );
        assert_eq!(
            file_in_folder(dir, "a/b/../../../c.bin"),
            Err("leaves the folder of the glTF file")
        );
    }
}
