//! Core's layout table (`caustica_core::device::layout_table`) and the shaders' shared
//! type files name the same structs: every struct that `shaders/wgsl/common/types.wgsl`
//! or `backend-vulkan/shaders/common/types.glsl` declares is in the table (the layout
//! tests of those crates then compare it field by field), and every table struct is
//! mirrored by at least one of them. Here because it reads two crates' files.

use caustica_core::device::layout_table::structs;
use std::collections::BTreeSet;
use std::path::Path;

/// The names of the structs declared in a shared shader types file (`struct Name`).
fn declared_structs(file: &str) -> BTreeSet<String> {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("..").join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .map(|l| l.split("//").next().unwrap_or("").trim_start())
        .filter_map(|l| l.strip_prefix("struct "))
        .map(|rest| {
            rest.split(|c: char| !c.is_alphanumeric() && c != '_')
                .next()
                .unwrap()
                .to_owned()
        })
        .collect()
}

/// The table names every struct that the shaders' shared types files mirror, and each
/// of its structs is mirrored by at least one of them.
#[test]
fn table_names_every_struct_the_shaders_use() {
    // shader-only structs: never in a buffer, so no core layout
    const SHADER_ONLY: &[&str] = &["HitPayload"];
    let wgsl = declared_structs("shaders/wgsl/common/types.wgsl");
    let glsl = declared_structs("backend-vulkan/shaders/common/types.glsl");
    let table: BTreeSet<String> = structs().iter().map(|s| s.name.to_owned()).collect();
    for name in wgsl.iter().chain(&glsl) {
        assert!(
            table.contains(name) || SHADER_ONLY.contains(&name.as_str()),
            "{name}: a shader struct missing from the layout table"
        );
    }
    for name in &table {
        assert!(
            wgsl.contains(name) || glsl.contains(name),
            "{name}: in the table but mirrored by no shader"
        );
    }
}
