//! The scene file format: JSON, exactly the serde form of [`Scene`]: materials, shapes and
//! lights are objects tagged by `"type"` (snake_case variant names), unknown fields are
//! rejected and fields with defaults may be left out. `caustica scenes --export NAME`
//! prints a built-in scene in it.
//!
//! Every malformed or physically invalid input is rejected with a [`SceneFileError`] that
//! names the file, the line and column, and the reason.

use super::Scene;
use std::fmt;
use std::path::Path;

/// A scene file that could not be read, parsed or validated.
#[derive(Clone, Debug, PartialEq)]
pub struct SceneFileError {
    /// The file (or `<builtin>` / `<string>`).
    pub file: String,
    /// 1-based line of the offending value; 0 when unknown.
    pub line: usize,
    /// 1-based column of the offending value; 0 when unknown.
    pub column: usize,
    /// What is wrong, including the field path for validation problems.
    pub reason: String,
}

impl fmt::Display for SceneFileError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if self.line > 0 {
            write!(
                f,
                "{}:{}:{}: {}",
                self.file, self.line, self.column, self.reason
            )
        } else {
            write!(f, "{}: {}", self.file, self.reason)
        }
    }
}

impl std::error::Error for SceneFileError {}

/// Reads, parses and validates a scene file.
pub fn load_scene_file(path: &Path) -> Result<Scene, SceneFileError> {
    let text = read_scene_text(path)?;
    parse_scene(&text, &path.display().to_string())
}

/// A scene file's bytes (JSON, glTF, GLB, OBJ), read with a limit: at most
/// [`super::limits::MAX_SCENE_FILE_BYTES`], so a huge file, a pipe or /dev/zero is refused
/// after that many bytes, not after filling memory.
pub fn read_scene_bytes(path: &Path) -> Result<Vec<u8>, SceneFileError> {
    let fail = |reason: String| SceneFileError {
        file: path.display().to_string(),
        line: 0,
        column: 0,
        reason,
    };
    let limit = super::limits::MAX_SCENE_FILE_BYTES;
    let f = std::fs::File::open(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    let mut bytes = Vec::new();
    std::io::Read::read_to_end(&mut std::io::Read::take(f, limit + 1), &mut bytes)
        .map_err(|e| fail(format!("cannot read: {e}")))?;
    if bytes.len() as u64 > limit {
        return Err(fail(format!(
            "larger than the {} MiB a scene file may have",
            limit >> 20
        )));
    }
    Ok(bytes)
}

/// A scene file's text: [`read_scene_bytes`], UTF-8.
pub fn read_scene_text(path: &Path) -> Result<String, SceneFileError> {
    let bytes = read_scene_bytes(path)?;
    let fail = |reason: String| SceneFileError {
        file: path.display().to_string(),
        line: 0,
        column: 0,
        reason,
    };
    String::from_utf8(bytes).map_err(|e| {
        fail(format!(
            "not UTF-8 text (byte {})",
            e.utf8_error().valid_up_to()
        ))
    })
}

/// Parses and validates scene JSON; `file` names the source in errors. On a validation
/// failure the first problem is reported (with its line), and the others by path.
pub fn parse_scene(text: &str, file: &str) -> Result<Scene, SceneFileError> {
    parse_scene_resolving(text, file, &mut |_| {
        Err("OBJ files need caustica's `obj` feature (its scene loader reads them)".into())
    })
}

/// [`parse_scene`], with every [`super::Shape::ObjFile`] replaced by `load(path)` before
/// validation; a failed load is reported at the shape's `path` in `text`.
pub fn parse_scene_resolving(
    text: &str,
    file: &str,
    load: &mut dyn FnMut(&str) -> Result<super::Shape, String>,
) -> Result<Scene, SceneFileError> {
    // (serde would read a list as the scene's fields in order)
    let lead = text.len() - text.trim_start().len();
    if text[lead..].starts_with('[') {
        let before = &text[..lead];
        return Err(SceneFileError {
            file: file.into(),
            line: before.matches('\n').count() + 1,
            column: before.len() - before.rfind('\n').map_or(0, |i| i + 1) + 1,
            reason: "a scene file is a JSON object (`camera`, `materials`, `objects`, \
                     `lights`), not a list"
                .into(),
        });
    }
    let mut scene: Scene = serde_json::from_str(text).map_err(|e| SceneFileError {
        file: file.into(),
        line: e.line(),
        column: e.column(),
        reason: e
            .to_string()
            .split(" at line ")
            .next()
            .unwrap_or_default()
            .to_string(),
    })?;
    for (i, o) in scene.objects.iter_mut().enumerate() {
        if let super::Shape::ObjFile { path } = &o.shape {
            let at = format!("objects[{i}].shape.path");
            o.shape = load(path).map_err(|reason| {
                let (line, column) = locate(text, &at).unwrap_or((0, 0));
                SceneFileError {
                    file: file.into(),
                    line,
                    column,
                    reason: format!("{at}: {reason}"),
                }
            })?;
        }
    }
    if let Err(problems) = scene.validate() {
        let first = &problems[0];
        let (line, column) = locate(text, &first.path).unwrap_or((0, 0));
        let rest: Vec<&str> = problems[1..].iter().map(|p| p.path.as_str()).collect();
        let more = super::more_problems(&rest);
        return Err(SceneFileError {
            file: file.into(),
            line,
            column,
            reason: format!("{}: {}{more}", first.path, first.reason),
        });
    }
    Ok(scene)
}

/// The scene as pretty-printed JSON in the file format.
pub fn to_json(scene: &Scene) -> String {
    serde_json::to_string_pretty(scene).expect("scene serialisation cannot fail")
}

enum Seg<'a> {
    Key(&'a str),
    Index(usize),
}

fn split_path(path: &str) -> Vec<Seg<'_>> {
    let mut segs = Vec::new();
    for part in path.split('.') {
        let (key, rest) = part.split_at(part.find('[').unwrap_or(part.len()));
        if !key.is_empty() {
            segs.push(Seg::Key(key));
        }
        for idx in rest.split('[').filter(|s| !s.is_empty()) {
            if let Ok(i) = idx.trim_end_matches(']').parse() {
                segs.push(Seg::Index(i));
            }
        }
    }
    segs
}

/// 1-based (line, column) of the value at `path` in JSON `text`: a minimal scanner that
/// walks objects and arrays without building values. Returns the deepest position found.
fn locate(text: &str, path: &str) -> Option<(usize, usize)> {
    let b = text.as_bytes();
    let segs = split_path(path);
    let mut pos = skip_ws(b, 0);
    for seg in &segs {
        pos = match (seg, b.get(pos)?) {
            (Seg::Key(k), b'{') => find_member(b, pos, |key, _| key == *k)?,
            (Seg::Index(i), b'[') => find_member(b, pos, |_, n| n == *i)?,
            _ => break,
        };
    }
    let before = &text[..pos.min(text.len())];
    let line = before.matches('\n').count() + 1;
    let column = before.len() - before.rfind('\n').map_or(0, |p| p + 1) + 1;
    Some((line, column))
}

fn skip_ws(b: &[u8], mut p: usize) -> usize {
    while p < b.len() && b[p].is_ascii_whitespace() {
        p += 1;
    }
    p
}

/// Scans the object or array starting at `p` and returns the start of the member value
/// for which `pick(key, index)` holds (keys are "" in arrays).
fn find_member(b: &[u8], p: usize, pick: impl Fn(&str, usize) -> bool) -> Option<usize> {
    let is_obj = b[p] == b'{';
    let mut p = skip_ws(b, p + 1);
    let mut n = 0;
    while p < b.len() && b[p] != b'}' && b[p] != b']' {
        let mut key = "";
        if is_obj {
            let end = skip_string(b, p)?;
            key = std::str::from_utf8(&b[p + 1..end - 1]).ok()?;
            p = skip_ws(b, end);
            if b.get(p) != Some(&b':') {
                return None;
            }
            p = skip_ws(b, p + 1);
        }
        if pick(key, n) {
            return Some(p);
        }
        p = skip_ws(b, skip_value(b, p)?);
        if b.get(p) == Some(&b',') {
            p = skip_ws(b, p + 1);
        }
        n += 1;
    }
    None
}

fn skip_string(b: &[u8], mut p: usize) -> Option<usize> {
    p += 1;
    while p < b.len() {
        match b[p] {
            b'\\' => p += 2,
            b'"' => return Some(p + 1),
            _ => p += 1,
        }
    }
    None
}

fn skip_value(b: &[u8], p: usize) -> Option<usize> {
    match *b.get(p)? {
        b'"' => skip_string(b, p),
        b'{' | b'[' => {
            let mut depth = 0usize;
            let mut q = p;
            while q < b.len() {
                match b[q] {
                    b'"' => {
                        q = skip_string(b, q)?;
                        continue;
                    }
                    b'{' | b'[' => depth += 1,
                    b'}' | b']' => {
                        depth -= 1;
                        if depth == 0 {
                            return Some(q + 1);
                        }
                    }
                    _ => {}
                }
                q += 1;
            }
            None
        }
        _ => {
            let mut q = p;
            while q < b.len() && !matches!(b[q], b',' | b'}' | b']') && !b[q].is_ascii_whitespace()
            {
                q += 1;
            }
            Some(q)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::builtin::{builtin, BUILTIN_SCENES};

    #[test]
    fn every_builtin_round_trips_and_validates() {
        for name in BUILTIN_SCENES {
            let s = builtin(name).unwrap();
            s.validate().unwrap_or_else(|p| panic!("{name}: {p:?}"));
            let back = parse_scene(&to_json(&s), name).unwrap();
            assert_eq!(back, s, "{name}");
        }
    }

    #[test]
    fn a_list_is_no_scene() {
        let e = parse_scene("\n  [1, 2]", "s.json").unwrap_err();
        assert!(e.reason.contains("a scene file is a JSON object"), "{e}");
        assert_eq!((e.line, e.column), (2, 3));
    }

    #[test]
    fn duplicate_materials_and_unknown_box_fields_are_errors() {
        let text = to_json(&builtin("sphere").unwrap());
        // the same material name twice in the materials object
        let first = text.find("\"materials\": {").expect("materials") + "\"materials\": {".len();
        let dup = format!(
            "{}\"glass\": {{\"type\": \"diffuse\", \"albedo\": [0.5, 0.5, 0.5]}},{}",
            &text[..first],
            &text[first..]
        );
        assert!(dup.matches("\"glass\"").count() >= 2, "{dup}");
        let e = parse_scene(&dup, "s.json").unwrap_err();
        assert!(
            e.reason.contains("material 'glass' is defined twice"),
            "{e}"
        );
        assert!(e.line > 0);
        let mut s = builtin("sphere-sun").unwrap();
        if let crate::scene::Light::Directional {
            projection_volume, ..
        } = &mut s.lights[0]
        {
            *projection_volume = Some(crate::math::geometry::Aabb {
                min: glam::Vec3::splat(-1.0),
                max: glam::Vec3::splat(1.0),
            });
        }
        let text = to_json(&s).replacen("\"min\":", "\"mni\": [0, 0, 0], \"min\":", 1);
        let e = parse_scene(&text, "s.json").unwrap_err();
        assert!(e.reason.contains("unknown field `mni`"), "{e}");
    }

    #[test]
    fn dielectrics_without_ior_model_are_cauchy_and_abbe_reads() {
        use crate::scene::{IorModel, Material};
        let mut text = to_json(&builtin("prism").unwrap());
        assert!(
            !text.contains("ior_model"),
            "Cauchy, the default, is not written"
        );
        let s = parse_scene(&text, "p.json").unwrap();
        let flint = |s: &crate::scene::Scene| s.materials["flint"].clone();
        assert!(matches!(
            flint(&s),
            Material::Dielectric {
                ior_model: IorModel::Cauchy,
                ..
            }
        ));
        text = text.replace(
            "\"cauchy_b\": 0.04",
            "\"ior_model\": {\"type\": \"abbe\", \"abbe_number\": 30.0}",
        );
        let s = parse_scene(&text, "p.json").unwrap();
        assert_eq!(
            flint(&s),
            Material::Dielectric {
                ior: 1.5,
                cauchy_b: 0.0,
                absorption: glam::Vec3::ZERO,
                ior_model: IorModel::Abbe { abbe_number: 30.0 },
            }
        );
        assert!(s.materials["flint"].is_dispersive());
        assert_eq!(parse_scene(&to_json(&s), "p.json").unwrap(), s);
        // an unknown field of the model, and a bad Abbe number, are located errors
        let bad = text.replace("\"abbe_number\": 30.0", "\"abbe_numbr\": 30.0");
        let e = parse_scene(&bad, "p.json").unwrap_err();
        assert!(e.reason.contains("abbe_numbr"), "{e}");
        let bad = text.replace("\"abbe_number\": 30.0", "\"abbe_number\": -2.0");
        let e = parse_scene(&bad, "p.json").unwrap_err();
        assert!(
            e.reason.contains("materials.flint.ior_model.abbe_number"),
            "{e}"
        );
    }

    #[test]
    fn negative_ior_names_its_line() {
        let mut text = to_json(&builtin("sphere").unwrap());
        text = text.replace("\"ior\": 1.5", "\"ior\": -1.5");
        let e = parse_scene(&text, "s.json").unwrap_err();
        let line = text.lines().position(|l| l.contains("-1.5")).unwrap() + 1;
        assert_eq!(e.line, line, "{e}");
        assert!(e.reason.contains("materials.glass.ior"), "{e}");
        assert!(e.to_string().starts_with(&format!("s.json:{line}:")), "{e}");
    }

    #[test]
    fn syntax_errors_and_nan_have_lines() {
        let text = to_json(&builtin("sphere").unwrap()).replace("\"ior\": 1.5", "\"ior\": NaN");
        let e = parse_scene(&text, "s.json").unwrap_err();
        assert!(e.line > 1, "{e}");
        let e = parse_scene("{\n \"name\": 3 }", "x").unwrap_err();
        assert_eq!(e.line, 2, "{e}");
    }

    #[test]
    fn zero_direction_and_empty_mesh_are_rejected() {
        let mut s = builtin("sphere-sun").unwrap();
        if let crate::scene::Light::Directional { direction, .. } = &mut s.lights[0] {
            *direction = glam::Vec3::ZERO;
        }
        let e = parse_scene(&to_json(&s), "f").unwrap_err();
        assert!(
            e.reason.contains("lights[0].direction") && e.line > 0,
            "{e}"
        );
        let mut s = builtin("sphere").unwrap();
        s.objects[0].shape = crate::scene::Shape::Mesh {
            positions: vec![].into(),
            normals: vec![].into(),
            uvs: vec![].into(),
            indices: vec![].into(),
        };
        let e = parse_scene(&to_json(&s), "f").unwrap_err();
        assert!(e.reason.contains("empty mesh"), "{e}");
    }
}
