//! Loading any scene file caustica reads: [`load_scene_file`] picks the reader by the
//! file's extension: `.gltf` and `.glb` through [`crate::gltf_scene`] (the `gltf`
//! feature), anything else as caustica's JSON scene format, whose `obj_file` shapes
//! (`{"type": "obj_file", "path": "mesh.obj"}`, relative to the scene file) are read with
//! `tobj` (the `obj` feature).
//!
//! An OBJ file is a bare mesh: its vertex positions are taken as world space, its faces
//! triangulated (fans), its normals and UVs kept where every vertex has them (else
//! normals are generated as the area-weighted face average, and UVs as box-projected
//! charts, `caustica_core::scene::uv_charts`, as for any mesh of a scene file without
//! them, with a warning naming the object), all its objects and groups merged into the one shape, its `.mtl` materials not
//! read: the scene's object names the caustica material. Bad OBJ files are errors at the
//! shape's `path` in the scene file.

use caustica_core::scene::format::SceneFileError;
use caustica_core::scene::Scene;
use std::path::Path;

/// A scene read from a file, with what its reader could not represent (glTF).
#[derive(Clone, Debug)]
pub struct LoadedScene {
    /// The validated scene.
    pub scene: Scene,
    /// One line per dropped, approximated or generated element (for caustica's own format:
    /// the meshes given generated UV charts).
    pub warnings: Vec<String>,
}

/// Reads, parses and validates the scene file at `path` (see the module doc).
pub fn load_scene_file(path: &Path) -> Result<LoadedScene, SceneFileError> {
    let ext = path
        .extension()
        .map(|e| e.to_string_lossy().to_ascii_lowercase());
    if matches!(ext.as_deref(), Some("gltf" | "glb")) {
        #[cfg(feature = "gltf")]
        {
            let im = crate::gltf_scene::load_gltf(path)?;
            return Ok(LoadedScene {
                scene: im.scene,
                warnings: im.warnings,
            });
        }
        #[cfg(not(feature = "gltf"))]
        return Err(SceneFileError {
            file: path.display().to_string(),
            line: 0,
            column: 0,
            reason: "glTF needs caustica's `gltf` feature".into(),
        });
    }
    if ext.as_deref() == Some("obj") {
        // an OBJ file is a mesh without camera or lights: a scene file places it
        return Err(SceneFileError {
            file: path.display().to_string(),
            line: 0,
            column: 0,
            reason: "an OBJ file is a mesh, not a scene: place it in a scene file's \
                     object as `\"shape\": {\"type\": \"obj_file\", \"path\": ...}` \
                     (docs/scene-format.md)"
                .into(),
        });
    }
    let text = caustica_core::scene::format::read_scene_text(path)?;
    let file = path.display().to_string();
    #[cfg(feature = "obj")]
    let scene = {
        let dir = path.parent().unwrap_or(Path::new(".")).to_path_buf();
        caustica_core::scene::format::parse_scene_resolving(&text, &file, &mut |p| {
            load_obj(&dir.join(p))
        })?
    };
    #[cfg(not(feature = "obj"))]
    let scene = caustica_core::scene::format::parse_scene(&text, &file)?;
    let mut scene = scene;
    // after validation: every index is in range
    let warnings = caustica_core::scene::uv_charts::generate_missing_uvs(&mut scene)
        .into_iter()
        .map(|w| format!("{file}: {w}"))
        .collect();
    Ok(LoadedScene { scene, warnings })
}

/// The mesh of an OBJ file as a [`caustica_core::scene::Shape::Mesh`] (see the module
/// doc), or why not.
#[cfg(feature = "obj")]
pub fn load_obj(path: &Path) -> Result<caustica_core::scene::Shape, String> {
    use glam::{Vec2, Vec3};
    let bytes = caustica_core::scene::format::read_scene_bytes(path).map_err(|e| e.to_string())?;
    let options = tobj::LoadOptions {
        single_index: true,
        triangulate: true,
        ignore_points: true,
        ignore_lines: true,
    };
    let (models, _materials) = tobj::load_obj_buf(
        &mut std::io::Cursor::new(bytes),
        &options,
        // .mtl files are not read: the scene file assigns the material
        |_| Err(tobj::LoadError::OpenFileFailed),
    )
    .map_err(|e| format!("{}: not a usable OBJ file: {e}", path.display()))?;
    let (mut positions, mut normals, mut uvs, mut indices) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut all_normals, mut all_uvs) = (true, true);
    for m in &models {
        let mesh = &m.mesh;
        let base = positions.len() as u32;
        let n = mesh.positions.len() / 3;
        positions.extend(
            mesh.positions
                .chunks_exact(3)
                .map(|p| Vec3::new(p[0], p[1], p[2])),
        );
        if mesh.normals.len() == 3 * n {
            normals.extend(
                mesh.normals
                    .chunks_exact(3)
                    .map(|p| Vec3::new(p[0], p[1], p[2])),
            );
        } else {
            all_normals = false;
        }
        if mesh.texcoords.len() == 2 * n {
            uvs.extend(
                mesh.texcoords
                    .chunks_exact(2)
                    .map(|t| Vec2::new(t[0], t[1])),
            );
        } else {
            all_uvs = false;
        }
        for t in mesh.indices.chunks_exact(3) {
            indices.push([base + t[0], base + t[1], base + t[2]]);
        }
    }
    if indices.is_empty() {
        return Err(format!("{} has no face", path.display()));
    }
    Ok(caustica_core::scene::Shape::Mesh {
        positions: positions.into(),
        normals: (if all_normals { normals } else { Vec::new() }).into(),
        uvs: (if all_uvs { uvs } else { Vec::new() }).into(),
        indices: indices.into(),
    })
}
