//! The checked-in shader layout files (`caustica_core::device::shader_layouts::FILES`:
//! WGSL, OpenCL C, GLSL) are what the generator writes from core's layouts and shared
//! constants. A stale file fails here with the command that regenerates it; with
//! `CAUSTICA_BLESS=1` the test writes the files instead (then rebuild the SPIR-V with
//! `scripts/compile-shaders.sh`, since the GLSL file is a source of every stage).

use caustica_core::device::shader_layouts::{generate, FILES, REGENERATE};
use std::path::Path;

#[test]
fn generated_shader_layouts_are_up_to_date() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    let bless = std::env::var_os("CAUSTICA_BLESS").is_some_and(|v| v == "1");
    let mut stale = Vec::new();
    for f in FILES {
        let want = generate(f.language).unwrap_or_else(|e| panic!("{}: {e}", f.path));
        let path = root.join(f.path);
        let have = std::fs::read_to_string(&path).unwrap_or_default();
        if have == want {
            continue;
        }
        if bless {
            std::fs::write(&path, &want).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            eprintln!("wrote {}", f.path);
        } else {
            let line = have
                .lines()
                .zip(want.lines())
                .position(|(a, b)| a != b)
                .unwrap_or(have.lines().count().min(want.lines().count()));
            stale.push(format!(
                "{} (first difference at line {})",
                f.path,
                line + 1
            ));
        }
    }
    assert!(
        stale.is_empty(),
        "generated shader layout files are stale: {}\nregenerate with: {REGENERATE}\n\
         (and then scripts/compile-shaders.sh for the SPIR-V)",
        stale.join(", ")
    );
}
