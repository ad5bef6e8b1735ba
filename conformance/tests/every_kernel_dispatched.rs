//! Every declared kernel is really dispatched by every backend: a frame of `prism` (glass
//! with dispersion) with pruning off runs every pass of the kernel list, and each
//! backend's own pass timings must name every kernel that launches work, at least once.
//! `prepare_scene` launches nothing on the GPU-style backends; that it did its job shows
//! in the traced kernels having run on the prepared scene (they fail without it).
//! A backend that silently skipped a kernel (or reported the CPU's answer without running
//! its own) would miss its name here; conformance's per-kernel checks then judge the
//! values.

use caustica_conformance::{backends, small_settings};
use caustica_core::kernels::KERNELS;
use caustica_core::scene::builtin::builtin;
use caustica_core::{Sspm, SspmSettings};

#[test]
fn every_backend_dispatches_every_declared_kernel() {
    let mut scene = builtin("prism").expect("built-in scene");
    scene.camera.width = 64;
    scene.camera.height = 36;
    for (name, mut b) in backends() {
        let settings = SspmSettings {
            prune: false,
            ..small_settings(64)
        };
        let mut s = Sspm::new(b.as_mut(), &scene, settings).expect("valid scene");
        let stats = s.frame(b.as_mut(), &mut |_| {}).expect("frame");
        s.free(b.as_mut()).expect("free");
        for k in KERNELS.iter().filter(|k| k.name != "prepare_scene") {
            let pass = stats.passes.iter().find(|p| p.name == k.name);
            assert!(
                pass.is_some_and(|p| p.dispatches >= 1),
                "backend {name} did not dispatch kernel {} (passes: {:?})",
                k.name,
                stats.passes.iter().map(|p| &p.name).collect::<Vec<_>>()
            );
        }
        assert!(
            stats.photons_stored > 0,
            "{name}: traced kernels saw no scene"
        );
    }
}
