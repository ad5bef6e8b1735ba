//! Core is built in layers and a lower layer never imports a higher one (see lib.rs):
//! math < scene < device < kernels < recording < backend < frame < techniques. This test
//! reads every source file of the crate and fails on any `crate::<module>` path in code
//! (comments and doc links aside) that points to a higher layer.

use std::path::{Path, PathBuf};

const LAYERS: [&str; 8] = [
    "math",
    "scene",
    "device",
    "kernels",
    "recording",
    "backend",
    "frame",
    "techniques",
];

fn layer_of(module: &str) -> Option<usize> {
    LAYERS.iter().position(|l| *l == module)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for e in std::fs::read_dir(dir).expect("readable source folder") {
        let p = e.expect("entry").path();
        if p.is_dir() {
            rust_files(&p, out);
        } else if p.extension().is_some_and(|x| x == "rs") {
            out.push(p);
        }
    }
}

#[test]
fn no_layer_imports_a_higher_one() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    let mut violations = Vec::new();
    for f in &files {
        let rel = f.strip_prefix(&src).expect("under src");
        let first = rel
            .components()
            .next()
            .and_then(|c| c.as_os_str().to_str())
            .unwrap_or("")
            .trim_end_matches(".rs");
        let Some(own) = layer_of(first) else {
            continue; // lib.rs: the root re-exports every layer
        };
        let text = std::fs::read_to_string(f).expect("readable file");
        for (n, line) in text.lines().enumerate() {
            let code = line.split("//").next().unwrap_or("");
            for (i, _) in code.match_indices("crate::") {
                let module: String = code[i + 7..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_')
                    .collect();
                if let Some(target) = layer_of(&module) {
                    if target > own {
                        violations.push(format!(
                            "{}:{}: layer {} imports {}",
                            rel.display(),
                            n + 1,
                            LAYERS[own],
                            module
                        ));
                    }
                }
            }
        }
    }
    assert!(files.len() > 20, "found only {} files", files.len());
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

/// No technique imports another: each is its photon pipeline, filter and temporal state
/// over the frame host, and what two share lives in `frame/` (emission, receivers). This
/// fails on any `techniques::<other>` path in code (comments aside) of a technique's
/// folder; the registry (`techniques/mod.rs`) names them all.
#[test]
fn no_technique_imports_another() {
    let techniques = Path::new(env!("CARGO_MANIFEST_DIR")).join("src/techniques");
    let names: Vec<String> = std::fs::read_dir(&techniques)
        .expect("techniques folder")
        .filter_map(|e| e.ok())
        .filter(|e| e.path().is_dir())
        .map(|e| e.file_name().to_string_lossy().into_owned())
        .collect();
    assert!(names.len() >= 4, "found only {names:?}");
    let mut violations = Vec::new();
    for own in &names {
        let mut files = Vec::new();
        rust_files(&techniques.join(own), &mut files);
        for f in &files {
            let text = std::fs::read_to_string(f).expect("readable file");
            for (n, line) in text.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                for other in names.iter().filter(|o| *o != own) {
                    let imports = [
                        format!("techniques::{other}"),
                        format!("super::super::{other}"),
                    ];
                    if imports.iter().any(|p| code.contains(p.as_str())) {
                        violations.push(format!(
                            "{}:{}: {own} imports {other}",
                            f.strip_prefix(&techniques).unwrap_or(f).display(),
                            n + 1
                        ));
                    }
                }
            }
        }
    }
    assert!(violations.is_empty(), "{}", violations.join("\n"));
}

/// The module path (`frame::receivers::atlas`) of a source file under `src`.
fn module_of(src: &Path, file: &Path) -> String {
    let rel = file
        .strip_prefix(src)
        .expect("under src")
        .with_extension("");
    let mut parts: Vec<String> = rel
        .components()
        .map(|c| c.as_os_str().to_string_lossy().into_owned())
        .collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts.join("::")
}

/// frame/ knows no technique and has no import cycle: every path to a frame module in a
/// frame file's code (comments aside) is an edge from its module to the longest module
/// the path names (`crate::frame::...`, `super::...` from the file's parent, and in a
/// `mod.rs` a child's name, `plan::...`), and the graph of frame's modules has no cycle
/// (so each module can be read from the ones it imports). The layer test above already
/// keeps `crate::techniques` out of frame/.
#[test]
fn frame_modules_import_each_other_without_cycles() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src.join("frame"), &mut files);
    let modules: Vec<String> = files.iter().map(|f| module_of(&src, f)).collect();
    let mut edges: Vec<Vec<usize>> = vec![Vec::new(); modules.len()];
    for (i, f) in files.iter().enumerate() {
        let text = std::fs::read_to_string(f).expect("readable file");
        let own = &modules[i];
        let parent = own.rsplit_once("::").map_or("", |(p, _)| p).to_string();
        let is_mod_rs = f.file_name().is_some_and(|n| n == "mod.rs");
        // the children a mod.rs declares (`pub mod plan;`)
        let children: Vec<String> = text
            .lines()
            .filter_map(|l| {
                let l = l.trim().trim_start_matches("pub ");
                l.strip_prefix("mod ")?
                    .strip_suffix(';')
                    .map(str::to_string)
            })
            .filter(|_| is_mod_rs)
            .collect();
        // a file's own tests (`#[cfg(test)] mod tests`, at its end) import nothing of it
        for line in text.lines().take_while(|l| l.trim() != "#[cfg(test)]") {
            let code = line.split("//").next().unwrap_or("");
            let word = |at: usize, len: usize| -> String {
                code[at + len..]
                    .chars()
                    .take_while(|c| c.is_ascii_alphanumeric() || *c == '_' || *c == ':')
                    .collect()
            };
            let starts_a_path = |at: usize| {
                at == 0 || {
                    let before = code.as_bytes()[at - 1];
                    !(before.is_ascii_alphanumeric() || before == b'_' || before == b':')
                }
            };
            let mut paths: Vec<String> = code
                .match_indices("crate::frame::")
                .map(|(at, _)| format!("frame::{}", word(at, 14)))
                .collect();
            paths.extend(
                code.match_indices("super::")
                    .filter(|(at, _)| starts_a_path(*at))
                    .map(|(at, _)| format!("{parent}::{}", word(at, 7))),
            );
            for child in &children {
                let needle = format!("{child}::");
                paths.extend(
                    code.match_indices(needle.as_str())
                        .filter(|(at, _)| starts_a_path(*at))
                        .map(|(at, _)| format!("{own}::{}", word(at, 0))),
                );
            }
            for path in paths {
                // the longest module the path names
                let target = modules
                    .iter()
                    .enumerate()
                    .filter(|(_, m)| path == **m || path.starts_with(&format!("{m}::")))
                    .max_by_key(|(_, m)| m.len())
                    .map(|(j, _)| j);
                if let Some(j) = target.filter(|&j| j != i && !edges[i].contains(&j)) {
                    edges[i].push(j);
                }
            }
        }
    }
    assert!(
        modules.len() > 15,
        "found only {} frame modules",
        modules.len()
    );
    // depth-first search with colours: a grey module met again closes a cycle
    fn visit(
        i: usize,
        edges: &[Vec<usize>],
        colour: &mut [u8],
        stack: &mut Vec<usize>,
    ) -> Option<Vec<usize>> {
        colour[i] = 1;
        stack.push(i);
        for &j in &edges[i] {
            if colour[j] == 1 {
                let from = stack.iter().position(|&k| k == j).expect("on the stack");
                let mut cycle = stack[from..].to_vec();
                cycle.push(j);
                return Some(cycle);
            }
            if colour[j] == 0 {
                if let Some(c) = visit(j, edges, colour, stack) {
                    return Some(c);
                }
            }
        }
        stack.pop();
        colour[i] = 2;
        None
    }
    let mut colour = vec![0u8; modules.len()];
    for i in 0..modules.len() {
        if colour[i] == 0 {
            if let Some(cycle) = visit(i, &edges, &mut colour, &mut Vec::new()) {
                let names: Vec<&str> = cycle.iter().map(|&k| modules[k].as_str()).collect();
                panic!("an import cycle inside frame/: {}", names.join(" -> "));
            }
        }
    }
}
