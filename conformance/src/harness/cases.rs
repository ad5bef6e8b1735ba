//! The scenes the suite runs: the built-in scenes at [`BUILTIN_SIZE`], and the fixed
//! inputs of the per-kernel checks ([`kernel_cases`]).

use caustica_core::scene::Scene;
use caustica_core::SspmSettings;

/// Resolution of the built-in scenes in the cross-backend tests (about their 16:9).
///
/// `width - height` is odd on purpose. The `cornell` camera is centred on the box, so the
/// box's four wall-ceiling and wall-floor edges project exactly onto the image diagonals
/// through the centre, `px - py = (width - height) / 2` in pixel units; with an even
/// difference (96x54) some 100 pixel centres lie exactly on an edge shared by two faces,
/// where the closest hit is a tie that any rounding difference breaks either way (this was
/// seen before the triangle test became watertight, when such rays could also slip
/// between the faces, with the `UlpNoise` mutant of `tests/suite_sensitivity.rs`: 15 such
/// pixels changed material). No pixel centre is on those diagonals when the difference is odd.
pub const BUILTIN_SIZE: (u32, u32) = (96, 55);

/// Built-in scene `name` at `BUILTIN_SIZE`.
pub fn builtin_small(name: &str) -> Scene {
    let mut s = caustica_core::scene::builtin::builtin(name).expect("a built-in scene");
    (s.camera.width, s.camera.height) = BUILTIN_SIZE;
    s
}

/// The fixed inputs of the per-kernel checks: every built-in scene with a 96x96 photon grid
/// (default settings otherwise), and four generated scenes with generated settings, drawn
/// from [`crate::strategies`] with proptest's deterministic RNG (the same every run).
pub fn kernel_cases() -> Vec<(String, Scene, SspmSettings)> {
    use proptest::strategy::{Strategy, ValueTree};
    let mut cases: Vec<(String, Scene, SspmSettings)> =
        caustica_core::scene::builtin::BUILTIN_SCENES
            .iter()
            .map(|n| (n.to_string(), builtin_small(n), crate::small_settings(96)))
            .collect();
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let strategy = (
        crate::strategies::scene(),
        crate::strategies::sspm_settings(),
    );
    for i in 0..4 {
        let (scene, settings) = strategy
            .new_tree(&mut runner)
            .expect("a generated case")
            .current();
        cases.push((format!("generated#{i}"), scene, settings));
    }
    cases
}
