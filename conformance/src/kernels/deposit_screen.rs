//! `deposit_screen`, checked together with `resolve_caustics` ([`check_deposit`]): both run
//! in one recording on the reference's G-buffer and photon list, and the resolved radiance
//! is compared on each backend's own photon map ([`compare_resolve`]). Per backend the
//! counters must account for every photon and agree with the map; across backends
//! [`DEPOSIT_TEXEL_AGREEMENT`] of the texels must be bitwise equal and the per-texel counts
//! may move by [`DEPOSIT_PHOTON_CHANGES`] of the photons.

use super::resolve_caustics::compare_resolve;
use crate::harness::fixture::run_and_free;
use crate::harness::fixture::{Fixture, ReferenceInputs};
use crate::harness::tolerance::{DEPOSIT_PHOTON_CHANGES, DEPOSIT_TEXEL_AGREEMENT};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, read_photon_map, Backend};
use caustica_core::device::layout::{counter, DepositTexel, GBufferTexel, TraceParams};
use caustica_core::kernels::{FusedDeposit, ScreenDeposit, TracePhotons};
use caustica_core::math::fixed_point::join_u64;
use caustica_core::recording::Recording;

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
    let (equal, moved) = map_agreement(&ma, &mb);
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

/// Two photon maps' agreement: the texels bitwise equal, and the photons moved (the sum
/// over texels of their counts' differences).
fn map_agreement(a: &[DepositTexel], b: &[DepositTexel]) -> (u64, u64) {
    let equal = a.iter().zip(b).filter(|(a, b)| a == b).count() as u64;
    let moved = a
        .iter()
        .zip(b)
        .map(|(a, b)| (join_u64(a.photons) as i64 - join_u64(b.photons) as i64).unsigned_abs())
        .sum();
    (equal, moved)
}

/// Runs the fused trace (the scene's world-space variant with `fused_deposit`) of light
/// `domains[k]` on `b` into a cleared screen photon map over G-buffer `gbuffer`; returns
/// the map and the counters.
fn run_fused_screen(
    fx: &Fixture,
    b: &mut dyn Backend,
    k: usize,
    gbuffer: &[GBufferTexel],
) -> Result<(Vec<DepositTexel>, Vec<u32>), String> {
    let mut rec = Recording::new();
    let g = rec.upload_gbuffer(gbuffer);
    // the fused pass stores no photon: one slot, as Sspm has
    let photons = rec.create(1, "photons");
    let photon_count = rec.create(1, "photon count");
    let counters = rec.create(counter::WORDS as u32, "counters");
    let map = rec.create_photon_map(fx.pixels());
    rec.clear_photon_map(&map);
    let mut variant = fx.trace_variant();
    variant.fused_deposit = true;
    rec.kernel(TracePhotons {
        scene: fx.args,
        variant,
        params: TraceParams {
            ..fx.trace_batch(k)
        },
        photons,
        photon_count,
        counters,
        clusters: None,
        deposit: Some(FusedDeposit::Screen(ScreenDeposit {
            params: fx.constants.deposit_params(fx.camera, &fx.settings, 1),
            gbuffer: g,
            photon_map: map,
        })),
    });
    run_and_free(b, "trace_photons (screen deposit)", &rec, |b| {
        Ok((read_photon_map(b, &map)?, read_buf(b, counters)?))
    })
}

/// Sspm's fused pass, `trace_photons`' `fused_deposit` variant in world space, on the
/// backend under test against that backend's own `deposit_screen` of the photons its
/// world-space trace (the variant without `fused_deposit`, the same code up to where a
/// stored photon goes; `check_trace`'s) stores, both on the reference's G-buffer. The
/// deposit is the same projection, depth test and integer sums, but OpenCL builds the
/// trace with its default division bounds (`RELAXED_DIVISION_VARIANTS`) and
/// `deposit_screen` with correctly rounded division, and the shader backends compile the
/// two as separate pipelines: a photon within ulps of a pixel edge or of the depth
/// threshold may fall the other way, as between backends ([`DEPOSIT_TEXEL_AGREEMENT`] of
/// the texels bitwise, [`DEPOSIT_PHOTON_CHANGES`] of the photons moved). The trace's
/// counters must be bitwise the stored trace's; the deposit's outcomes may move by the
/// moved photons only.
pub fn check_fused_screen_trace(
    fx: &Fixture,
    inputs: &ReferenceInputs,
    _r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("trace_photons (screen deposit)");
    for k in 0..fx.constants.domains.len() {
        let (photons, trace_counters) = fx.run_trace_as(c, k, fx.trace_variant(), |_| {})?;
        let two = fx.run_deposit(c, &inputs.gbuffer, &photons)?;
        let (map, counters) = run_fused_screen(fx, c, k, &inputs.gbuffer)?;
        let deposit_words = [
            counter::DEPOSITED,
            counter::OFF_SCREEN,
            counter::DEPTH_MISMATCH,
            counter::UNDERFLOW,
            counter::SATURATED,
        ];
        for w in (0..counter::WORDS).filter(|w| !deposit_words.contains(w)) {
            v.check(counters[w] == trace_counters[w], || {
                format!(
                    "light domain {k}: trace counter word {w} is {} fused, {} stored",
                    counters[w], trace_counters[w]
                )
            });
        }
        let n = photons.len() as u64;
        let outcomes: u64 = deposit_words[..3].iter().map(|&w| counters[w] as u64).sum();
        v.check(outcomes == n, || {
            format!("light domain {k}: fused outcomes {outcomes}, {n} stored photons")
        });
        let texels = map.len() as u64;
        let (equal, moved) = map_agreement(&map, &two.photon_map);
        v.check(
            equal as f64 >= DEPOSIT_TEXEL_AGREEMENT * texels as f64,
            || {
                format!(
                    "light domain {k}: fused map bitwise equal to deposit_screen's on only \
                     {equal}/{texels} texels (need {}%)",
                    100.0 * DEPOSIT_TEXEL_AGREEMENT
                )
            },
        );
        let allowed = (DEPOSIT_PHOTON_CHANGES * n as f64).ceil() as u64 + 2;
        v.check(moved <= allowed, || {
            format!("light domain {k}: per-texel counts moved by {moved} (allowed {allowed})")
        });
        for &w in &deposit_words {
            let d = (counters[w] as i64 - two.counters[w] as i64).unsigned_abs();
            let bound = if w == counter::UNDERFLOW || w == counter::SATURATED {
                3 * moved
            } else {
                moved
            };
            v.check(d <= bound, || {
                format!(
                    "light domain {k}: deposit counter word {w} is {} fused, {} by \
                     deposit_screen (moved photons {moved})",
                    counters[w], two.counters[w]
                )
            });
        }
        v.note(format!(
            "light domain {k}: {n} photons, map equal on {equal}/{texels} texels, moved {moved}"
        ));
    }
    Ok(v)
}
