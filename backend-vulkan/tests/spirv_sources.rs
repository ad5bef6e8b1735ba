//! The SPIR-V kept in `spirv/` was compiled from the GLSL in `shaders/` as it is now:
//! `scripts/compile-shaders.sh` records, per stage, the sha256 of the stage file followed
//! by every file under `shaders/common/` in lexical order; this test recomputes it. A
//! source edited without running the script fails here.

use sha2::{Digest, Sha256};
use std::path::Path;

#[test]
fn spirv_matches_its_glsl_sources() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let manifest =
        std::fs::read_to_string(root.join("spirv/SOURCES.sha256")).expect("spirv/SOURCES.sha256");
    let mut common: Vec<_> = std::fs::read_dir(root.join("shaders/common"))
        .unwrap()
        .map(|e| e.unwrap().path())
        .collect();
    common.sort();
    let mut stages = 0;
    for line in manifest.lines() {
        let (hash, stage) = line.split_once("  ").expect("`hash  stage` lines");
        let mut h = Sha256::new();
        h.update(std::fs::read(root.join("shaders").join(stage)).unwrap());
        for c in &common {
            h.update(std::fs::read(c).unwrap());
        }
        let got: String = h.finalize().iter().map(|b| format!("{b:02x}")).collect();
        assert_eq!(
            got, hash,
            "{stage}: source changed since its SPIR-V was built; run scripts/compile-shaders.sh"
        );
        let spv = std::fs::read(root.join("spirv").join(format!("{stage}.spv"))).unwrap();
        assert!(
            spv.len() > 20 && spv[..4] == [0x03, 0x02, 0x23, 0x07],
            "{stage}.spv is not SPIR-V"
        );
        stages += 1;
    }
    // every stage under shaders/ is listed
    let on_disk = std::fs::read_dir(root.join("shaders"))
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().is_file())
        .count();
    assert_eq!(
        stages, on_disk,
        "a stage is missing from spirv/SOURCES.sha256"
    );
}
