//! `deposit_screen`, checked together with `resolve_caustics` ([`check_deposit`]): both run
//! in one recording on the reference's G-buffer and photon list, and the resolved radiance
//! is compared on each backend's own photon map ([`compare_resolve`]). Per backend the
//! counters must account for every photon and agree with the map; across backends
//! [`DEPOSIT_TEXEL_AGREEMENT`] of the texels must be bitwise equal and the per-texel counts
//! may move by [`DEPOSIT_PHOTON_CHANGES`] of the photons.

use super::resolve_caustics::compare_resolve;
use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::tolerance::{DEPOSIT_PHOTON_CHANGES, DEPOSIT_TEXEL_AGREEMENT};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;
use caustica_core::device::layout::counter;
use caustica_core::math::fixed_point::join_u64;

/// `deposit_screen` + `resolve_caustics` on the reference's G-buffer and photon list.
pub fn check_deposit(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("deposit_screen + resolve_caustics");
    let a = fx.run_deposit(r, &inputs.gbuffer, &inputs.photons)?;
    let b = fx.run_deposit(c, &inputs.gbuffer, &inputs.photons)?;
    let (ma, ca, ia) = (a.photon_map, a.counters, a.raw);
    let (mb, cb, ib) = (b.photon_map, b.counters, b.raw);
    let n = inputs.photons.len() as u64;
    for (who, m, cn) in [("cpu", &ma, &ca), ("candidate", &mb, &cb)] {
        let outcomes = cn[counter::DEPOSITED] as u64
            + cn[counter::OFF_SCREEN] as u64
            + cn[counter::DEPTH_MISMATCH] as u64;
        v.check(outcomes == n, || {
            format!("{who}: deposited + off_screen + depth_mismatch = {outcomes}, {n} photons")
        });
        let in_map: u64 = m.iter().map(|t| join_u64(t.photons)).sum();
        v.check(in_map == cn[counter::DEPOSITED] as u64, || {
            format!(
                "{who}: the map holds {in_map} photons, DEPOSITED says {}",
                cn[counter::DEPOSITED]
            )
        });
        for w in [
            counter::STORED,
            counter::NO_SPECULAR,
            counter::ESCAPED,
            counter::NEGLIGIBLE,
            counter::BOUNCE_LIMIT,
            counter::RAYS,
            counter::STORED_FLUX,
        ] {
            v.check(cn[w] == 0, || {
                format!("{who}: deposit_screen wrote trace counter word {w}")
            });
        }
    }
    let texels = ma.len() as u64;
    let equal = ma.iter().zip(&mb).filter(|(a, b)| a == b).count() as u64;
    let moved: u64 = ma
        .iter()
        .zip(&mb)
        .map(|(a, b)| (join_u64(a.photons) as i64 - join_u64(b.photons) as i64).unsigned_abs())
        .sum();
    v.check(
        equal as f64 >= DEPOSIT_TEXEL_AGREEMENT * texels as f64,
        || {
            format!(
                "photon map bitwise equal on only {equal}/{texels} texels (need {}%)",
                100.0 * DEPOSIT_TEXEL_AGREEMENT
            )
        },
    );
    let allowed = (DEPOSIT_PHOTON_CHANGES * n as f64).ceil() as u64 + 2;
    v.check(moved <= allowed, || {
        format!(
            "per-texel photon counts differ by {moved} in all (allowed {allowed} of {n} photons)"
        )
    });
    // A photon counted by one backend and not the other (or elsewhere) shows in `moved`;
    // each has at most 3 channels that may underflow or saturate.
    for (w, name) in [
        (counter::UNDERFLOW, "underflow"),
        (counter::SATURATED, "saturated"),
    ] {
        let d = (ca[w] as i64 - cb[w] as i64).unsigned_abs();
        v.check(d <= 3 * moved, || {
            format!("{name} {} vs cpu {}", cb[w], ca[w])
        });
    }
    // Resolve, on texels whose sums are bitwise equal.
    let worst = compare_resolve(&fx.camera, &inputs.gbuffer, (&ma, &ia), (&mb, &ib), &mut v);
    v.note(format!(
        "{n} photons, deposited {} vs cpu {}; map equal on {equal}/{texels} texels, counts \
         moved {moved}; resolve worst {worst:.3} of tolerance",
        cb[counter::DEPOSITED],
        ca[counter::DEPOSITED]
    ));
    Ok(v)
}
