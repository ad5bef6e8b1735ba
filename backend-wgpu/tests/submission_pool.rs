//! Pooled submission resources on wgpu: a frame loop in its steady state creates no timestamp query
//! set and no staging buffer; each submission takes them from the backend's pool and
//! gives them back when it is collected. Fails loudly when no wgpu adapter exists (CI
//! installs lavapipe with scripts/install-drivers.sh).

use caustica_core::scene::builtin::builtin;
use caustica_core::TechniqueSettings;
use caustica_core::{Sspm, SspmSettings, Technique};
use caustica_wgpu::WgpuBackend;

#[test]
fn a_steady_frame_loop_creates_no_queries_or_staging() {
    let mut b = WgpuBackend::new().unwrap_or_else(|e| panic!("wgpu backend unavailable: {e}"));
    let mut scene = builtin("sphere").unwrap();
    scene.camera.width = 64;
    scene.camera.height = 36;
    let settings = SspmSettings::default().with_photons(32, 32);
    let mut s = Sspm::new(&mut b, &scene, settings).expect("scene uploads");
    // two frames in flight, each collected two frames later (a host's loop)
    let mut in_flight = std::collections::VecDeque::new();
    let mut created_after_warm_up = None;
    for frame in 0..12 {
        in_flight.push_back(s.submit_frame(&mut b).expect("submit_frame"));
        if in_flight.len() > 2 {
            let mut t = in_flight.pop_front().unwrap();
            let stats = t.stats(&mut b, true).expect("stats").expect("waited for");
            assert!(stats.photons_stored > 0);
        }
        if frame == 3 {
            created_after_warm_up = Some(b.pooled_resources_created());
        }
    }
    for mut t in in_flight {
        t.stats(&mut b, true).expect("stats");
    }
    let warm = created_after_warm_up.unwrap();
    assert!(
        warm > 0,
        "the first frames create their queries and staging"
    );
    assert_eq!(
        b.pooled_resources_created(),
        warm,
        "frames 4 to 11 created query sets or staging buffers"
    );
    s.free(&mut b).unwrap();
}
