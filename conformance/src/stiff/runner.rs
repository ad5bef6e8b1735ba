//! How a stiff case runs: the checks every case makes on every backend ([`universal`]), the
//! comparison with the reference's frame on every other backend ([`run_checked`]), and the
//! case's [`Outcome`].

use super::Outcome;
use crate::harness::candidates::{reference, REFERENCE_BACKEND};
use crate::harness::verdict::Verdict;
use crate::techniques::sspm::{self, Frame};
use caustica_core::backend::Backend;
use caustica_core::scene::{Material, Scene};
use caustica_core::SspmSettings;

/// Universal checks of one frame (listed in the [`stiff`](super) module docs).
pub fn universal(scene: &Scene, f: &Frame) -> Verdict {
    let mut v = Verdict::new("universal");
    for (name, img) in [
        ("composite", &f.composite),
        ("raw caustics", &f.raw),
        ("filtered caustics", &f.filtered),
        ("direct", &f.direct),
    ] {
        v.check(img.all_finite(), || format!("{name} has NaN/Inf"));
    }
    let s = &f.stats;
    let d = &s.discarded;
    let ends = s.photons_stored + d.no_specular + d.escaped + d.negligible_power + d.bounce_limit;
    v.check(ends == s.photons_emitted, || {
        format!("path ends add up to {ends}, {} emitted", s.photons_emitted)
    });
    let dep = s.photons_deposited + d.off_screen + d.depth_mismatch;
    v.check(dep == s.photons_stored, || {
        format!(
            "deposit outcomes add up to {dep}, {} stored",
            s.photons_stored
        )
    });
    // Each stored photon's units are its flux rounded to the nearest quantum: <= half a
    // quantum of excess per photon and channel.
    let rounding = 0.5 * s.flux_quantum * s.photons_stored as f64;
    let dispersive = scene.materials.values().any(Material::is_dispersive);
    if dispersive {
        // a spectral photon's channel sum changes with its wavelength (kept per channel in
        // expectation only): bounded by the largest gain a wavelength gives
        let gain = crate::harness::tolerance::spectral_sum_gain();
        let (st, em): (f64, f64) = (s.stored_flux.iter().sum(), s.emitted_flux.iter().sum());
        v.check(st <= gain * em + 3.0 * rounding, || {
            format!("stored flux (channel sum) {st:.6e} exceeds emitted {em:.6e} x {gain:.3}")
        });
    } else {
        for c in 0..3 {
            let (st, em) = (s.stored_flux[c], s.emitted_flux[c]);
            v.check(st <= em + rounding, || {
                format!("stored flux[{c}] {st:.6e} exceeds emitted {em:.6e}")
            });
        }
    }
    v.check(s.fixed_point_saturated == 0, || {
        format!("fixed-point saturation {}", s.fixed_point_saturated)
    });
    v
}

/// Renders `scene` on `b`, runs the universal checks and, on a backend other than cpu,
/// compares with the CPU reference's frame.
pub(super) fn run_checked(
    b: &mut dyn Backend,
    scene: &Scene,
    settings: &SspmSettings,
    v: &mut Verdict,
) -> Result<Frame, String> {
    let f = sspm::render_frame(b, scene, settings)?;
    let s = &f.stats;
    v.note(format!(
        "emitted {} stored {} deposited {}; {:?}",
        s.photons_emitted, s.photons_stored, s.photons_deposited, s.discarded
    ));
    v.absorb(universal(scene, &f));
    if b.name() != REFERENCE_BACKEND {
        let mut r = reference();
        let a = sspm::render_frame(&mut r, scene, settings)?;
        let mut c = sspm::compare_frames(scene, &a, &f);
        c.what = "vs cpu".into();
        // Keep the comparison's verdict, not its long list of notes.
        c.notes.retain(|n| n.contains("relative L2"));
        v.absorb(c);
    }
    Ok(f)
}

pub(super) fn outcome(key: String, v: Verdict) -> Result<Outcome, String> {
    Ok(Outcome { key, verdict: v })
}

pub(super) fn stored_fraction(f: &Frame) -> f64 {
    let s = &f.stats;
    let em: f64 = s.emitted_flux.iter().sum();
    if em == 0.0 {
        0.0
    } else {
        s.stored_flux.iter().sum::<f64>() / em
    }
}
