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
