//! The non-blocking frame on OpenCL: a submission only enqueues, and its marker event is the
//! host's to wait on (here with `clWaitForEvents`); once it has completed, the frame's
//! statistics come back without blocking. Fails loudly when no OpenCL platform exists (CI
//! installs PoCL with scripts/install-drivers.sh).

use caustica_core::scene::builtin::builtin;
use caustica_core::TechniqueSettings;
use caustica_core::{Sspm, SspmSettings, Technique};
use caustica_opencl::OpenClBackend;

#[test]
fn a_submitted_frame_hands_the_host_its_event() {
    let mut b = OpenClBackend::new().unwrap_or_else(|e| panic!("OpenCL backend unavailable: {e}"));
    let mut scene = builtin("sphere").unwrap();
    scene.camera.width = 64;
    scene.camera.height = 36;
    let settings = SspmSettings::default().with_photons(32, 32);
    let mut s = Sspm::new(&mut b, &scene, settings).expect("scene uploads");
    let mut ticket = s.submit_frame(&mut b).expect("submit_frame");
    let event = b
        .submission_event(&caustica_core::backend::Submission::pending(
            ticket.submission_id(),
        ))
        .expect("the submission is on the queue");
    opencl3::event::wait_for_events(&[event]).expect("the host waits on the event");
    let stats = ticket
        .stats(&mut b, false)
        .expect("stats")
        .expect("finished once its event completed");
    assert!(stats.photons_stored > 0);
    assert!(
        b.submission_event(&caustica_core::backend::Submission::pending(
            ticket.submission_id()
        ))
        .is_none(),
        "a collected submission has no event"
    );
    s.free(&mut b).unwrap();
}
