//! Frames larger than lavapipe's storage binding (128 MiB) before the G-buffer and the
//! screen photon map were split into planes: sspm at 2560x1440 and
//! 3840x2160 on every backend found. With planes the largest per-pixel buffer is 16 bytes
//! a pixel (3840x2160: 132.7 MB < 128 MiB = 134.2 MB), so every backend renders both.
//!
//! Each backend's frame is compared with the CPU's by the whole-frame comparison of
//! `caustica_conformance::techniques::sspm::compare_frames` (G-buffer agreement, photon
//! statistics, raw and filtered caustics, direct light, with its argued tolerances); the
//! composite is then checked bitwise against the CPU `composite` of the backend's own
//! direct and filtered images (one IEEE addition a channel: `check_composite`'s argument),
//! so that it is within the frame tolerance of the CPU's. Every image must be finite.
//! Prints the wall time of each frame.

use caustica_conformance::backends;
use caustica_conformance::harness::Report;
use caustica_conformance::harness::Verdict;
use caustica_conformance::small_settings;
use caustica_conformance::stiff::cheap_scene;
use caustica_conformance::techniques::sspm::{compare_frames, render_frame, Frame};
use caustica_core::ScreenSettings;
use caustica_core::SspmSettings;
use std::time::Instant;

/// The composite is `composite(direct, filtered)` of the frame's own images, bit for bit
/// (subnormal flushing aside, as in `check_composite`), and every image is finite.
fn composite_and_finite(f: &Frame) -> Verdict {
    let mut v = Verdict::new("composite");
    let want = caustica_cpu::kernels::composite::composite(&f.direct.pixels, &f.filtered.pixels);
    let subnormal = |x: f32| x != 0.0 && x.abs() < f32::MIN_POSITIVE;
    let mut differ = 0u64;
    for (i, (x, y)) in want.iter().zip(&f.composite.pixels).enumerate() {
        for ch in 0..4 {
            let (x, y) = (x[ch], y[ch]);
            let flushed = ch < 3
                && (subnormal(f.direct.pixels[i][ch])
                    || subnormal(f.filtered.pixels[i][ch])
                    || subnormal(x))
                && y.abs() < f32::MIN_POSITIVE;
            if x.to_bits() != y.to_bits() && !flushed {
                differ += 1;
            }
        }
    }
    v.check(differ == 0, || {
        format!("composite: {differ} channels differ from direct + filtered")
    });
    for (name, img) in [
        ("composite", &f.composite),
        ("raw caustics", &f.raw),
        ("filtered caustics", &f.filtered),
        ("direct", &f.direct),
    ] {
        v.check(img.all_finite(), || format!("{name} has NaN/Inf"));
    }
    v
}

#[test]
fn sspm_renders_2560x1440_and_3840x2160_on_every_backend() {
    let mut report = Report::new("large frames");
    let mut all = backends();
    // 64 x 64 photons and a gather radius of at most 4 pixels: the frame's cost is then
    // its pixels (the gather, 2 r + 1 taps a pixel and pass, dominates: 33 taps at the
    // default 16 take PoCL ~19 s at 3840x2160 on two cores)
    let settings = SspmSettings {
        screen: ScreenSettings {
            max_radius_px: 4,
            ..small_settings(64).screen
        },
        ..small_settings(64)
    };
    let start = Instant::now();
    for (w, h) in [(2560u32, 1440u32), (3840, 2160)] {
        let scene = cheap_scene((w, h));
        let case = format!("mirror quad {w}x{h}");
        let mut reference: Option<Frame> = None;
        for (name, b) in all.iter_mut() {
            let t0 = Instant::now();
            let frame = match render_frame(b.as_mut(), &scene, &settings) {
                Ok(f) => f,
                Err(e) => {
                    report.error(name, &case, e);
                    continue;
                }
            };
            eprintln!(
                "large frames: {name} {w}x{h}: {:.2} s wall ({:.1} ms frame)",
                t0.elapsed().as_secs_f64(),
                frame.stats.frame_ms
            );

            let mut v = composite_and_finite(&frame);
            match &reference {
                None if *name == "cpu" => {
                    report.add(name, &case, v);
                    reference = Some(frame);
                }
                None => report.error(name, &case, "no cpu reference frame".into()),
                Some(r) => {
                    v.absorb(compare_frames(&scene, r, &frame));
                    report.add(name, &case, v);
                }
            }
        }
    }
    eprintln!(
        "large frames: {:.1} s wall in all",
        start.elapsed().as_secs_f64()
    );
    report.finish();
}
