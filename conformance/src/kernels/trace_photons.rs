//! `trace_photons`: the stored photons of every emitting light, compared as multisets. Counts
//! and every path-end counter within the path-divergence allowance, flux sums and the
//! fixed-point stored-flux counter within the diverged photons' flux, and
//! [`PHOTON_MATCH`] of each backend's photons matched by one of the other's within
//! [`PHOTON_POSITION_REL`] of the scene diagonal, in both directions.
//!
//! [`check_fused_trace`] checks CausticMap's fused pass, `trace_photons`' `fused_deposit`
//! variant, on the backend under test against the CPU's atlas deposit of the photons
//! that the same backend's texture-space trace stores (the variant without
//! `fused_deposit`: the same code up to where a stored photon goes, and that trace is
//! `check_trace`'s). The deposit is integer atomics of quanta that are powers of two
//! (`x / 2^k` is exact under any division bound), so the atlas sums, the reach mask and
//! the counters (the trace's plus the deposit's) must be **bitwise** equal; under the
//! stochastic and, on scenes with dielectrics, the deterministic Fresnel split.

use super::gather_caustic_map::{cpu_deposit, params, Deposit, CHECK_ATLAS};
use crate::harness::fixture::Fixture;
use crate::harness::fixture::{run_and_free, ReferenceInputs};
use crate::harness::measure::v3;
use crate::harness::tolerance::{
    divergence_allowance, FluxMatch, PHOTON_FLUX_REL, PHOTON_MATCH, PHOTON_POSITION_REL,
};
use crate::harness::verdict::Verdict;
use caustica_core::backend::Backend;
use caustica_core::backend::{read_buf, read_photon_map};
use caustica_core::device::layout::*;
use caustica_core::device::layout::{counter, Photon};
use caustica_core::frame::receivers::atlas::layout::{atlas_layout, atlas_receivers, AtlasLayout};
use caustica_core::device::handle::Buf;
use caustica_core::kernels::{AtlasDeposit, ClusterBatch, FusedDeposit, TracePhotons, TraceVariant};
use caustica_core::math::fixed_point::join_u64;
use caustica_core::math::map_gather::triangle_reach_words;
use caustica_core::recording::Recording;
use glam::Vec3;
use std::collections::HashMap;

/// Spatial hash of photons for "is there a matching photon nearby" queries.
struct PhotonGrid<'a> {
    cell: f32,
    cells: HashMap<[i32; 3], Vec<&'a Photon>>,
}

impl<'a> PhotonGrid<'a> {
    fn new(photons: &'a [Photon], tol: f32) -> PhotonGrid<'a> {
        let cell = tol.max(f32::MIN_POSITIVE);
        let mut cells: HashMap<[i32; 3], Vec<&Photon>> = HashMap::new();
        for p in photons {
            cells
                .entry(Self::key(v3(p.position), cell))
                .or_default()
                .push(p);
        }
        PhotonGrid { cell, cells }
    }

    fn key(p: Vec3, cell: f32) -> [i32; 3] {
        let k = (p / cell).floor();
        [k.x as i32, k.y as i32, k.z as i32]
    }

    /// True when a photon lies within `tol` of `p` with a flux that `flux` says is close
    /// to `p`'s.
    fn has_match(&self, p: &Photon, tol: f32, flux: FluxMatch) -> bool {
        let pos = v3(p.position);
        let k = Self::key(pos, self.cell);
        let flux_ok = |q: &Photon| flux.close(p.flux, q.flux);
        for dx in -1..=1 {
            for dy in -1..=1 {
                for dz in -1..=1 {
                    if let Some(v) = self.cells.get(&[k[0] + dx, k[1] + dy, k[2] + dz]) {
                        if v.iter()
                            .any(|q| v3(q.position).distance(pos) <= tol && flux_ok(q))
                        {
                            return true;
                        }
                    }
                }
            }
        }
        false
    }
}

/// Number of photons of `a` with no match in `b` (see [`PhotonGrid::has_match`]).
fn unmatched(a: &[Photon], b: &[Photon], tol: f32, flux_rel: FluxMatch) -> u64 {
    let grid = PhotonGrid::new(b, tol);
    a.iter()
        .filter(|p| !grid.has_match(p, tol, flux_rel))
        .count() as u64
}

fn flux_sum(photons: &[Photon]) -> [f64; 3] {
    let mut s = [0.0f64; 3];
    for p in photons {
        for (c, v) in s.iter_mut().enumerate() {
            *v += p.flux[c] as f64;
        }
    }
    s
}

/// Checks the accounting of one backend's trace counters for `emitted` photons.
fn trace_accounting(v: &mut Verdict, who: &str, counters: &[u32], stored: usize, emitted: u64) {
    let ends = [
        counter::STORED,
        counter::NO_SPECULAR,
        counter::ESCAPED,
        counter::NEGLIGIBLE,
        counter::BOUNCE_LIMIT,
    ];
    let sum: u64 = ends.iter().map(|&i| counters[i] as u64).sum();
    v.check(sum == emitted, || {
        format!("{who}: path ends add up to {sum}, {emitted} photons were emitted")
    });
    v.check(counters[counter::STORED] as usize == stored, || {
        format!(
            "{who}: STORED counter {} but {stored} photons in the buffer",
            counters[counter::STORED]
        )
    });
    for w in [
        counter::OFF_SCREEN,
        counter::DEPTH_MISMATCH,
        counter::DEPOSITED,
        counter::UNDERFLOW,
        counter::SATURATED,
    ] {
        v.check(counters[w] == 0, || {
            format!("{who}: trace_photons wrote deposit counter word {w}")
        });
    }
}

/// One backend's `trace_photons` result: the stored photons and the counters.
type TraceRun<'a> = (&'a [Photon], &'a [u32]);

/// Checks that the first-segment caster-ball test changed no stored photon on one
/// backend: `with` and `without` it, the stored photons are the same multiset bitwise
/// (each photon's path depends on its index alone, and a photon the test ends could
/// meet no caster first, so it could not be stored), the path ends differ only by
/// first-segment escapes counted as `no_specular`, and no more rays are traced.
fn caster_test_keeps_every_photon(v: &mut Verdict, who: &str, with: TraceRun, without: TraceRun) {
    let key = |p: &Photon| bytemuck::bytes_of(p).to_vec();
    let mut a: Vec<Vec<u8>> = with.0.iter().map(key).collect();
    let mut b: Vec<Vec<u8>> = without.0.iter().map(key).collect();
    a.sort_unstable();
    b.sort_unstable();
    v.check(a == b, || {
        format!(
            "{who}: the caster-ball test changed the stored photons ({} with it, {} without)",
            a.len(),
            b.len()
        )
    });
    let (cw, co) = (with.1, without.1);
    for w in [
        counter::STORED,
        counter::NEGLIGIBLE,
        counter::BOUNCE_LIMIT,
        counter::STORED_FLUX,
        counter::STORED_FLUX + 1,
        counter::STORED_FLUX + 2,
        counter::STORED_FLUX + 3,
        counter::STORED_FLUX + 4,
        counter::STORED_FLUX + 5,
    ] {
        v.check(cw[w] == co[w], || {
            format!(
                "{who}: caster-ball test changed counter word {w}: {} vs {}",
                cw[w], co[w]
            )
        });
    }
    let ends = |c: &[u32]| c[counter::NO_SPECULAR] as u64 + c[counter::ESCAPED] as u64;
    v.check(
        ends(cw) == ends(co) && cw[counter::ESCAPED] <= co[counter::ESCAPED],
        || {
            format!(
                "{who}: with the caster-ball test no_specular {} escaped {}, without {} and {}",
                cw[counter::NO_SPECULAR],
                cw[counter::ESCAPED],
                co[counter::NO_SPECULAR],
                co[counter::ESCAPED]
            )
        },
    );
    let rays = |c: &[u32]| join_u64([c[counter::RAYS], c[counter::RAYS + 1]]);
    // every photon the test ends would have ended after its first ray
    v.note(format!(
        "{who}: the caster-ball test ended {} photons before their first ray ({} of {} rays \
         left)",
        rays(co).saturating_sub(rays(cw)),
        rays(cw),
        rays(co)
    ));
    v.check(rays(cw) <= rays(co), || {
        format!(
            "{who}: {} rays with the caster-ball test, {} without",
            rays(cw),
            rays(co)
        )
    });
}

/// `trace_photons` for every emitting light of the fixture, compared as multisets.
pub fn check_trace(
    fx: &Fixture,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut all = Verdict::new("trace_photons");
    if fx.constants.domains.is_empty() {
        all.note("no light emits photons (no caster): nothing to trace");
        return Ok(all);
    }
    let emitted = fx.settings.frame.photons_w as u64 * fx.settings.frame.photons_h as u64;
    let tol = PHOTON_POSITION_REL * fx.ds.bounds.diagonal();
    let flux_rel = FluxMatch::of(&fx.scene, fx.settings.frame.dispersion, tol);
    for k in 0..fx.constants.domains.len() {
        let light = fx.constants.domains[k].0;
        let (pa, ca) = fx.run_trace(r, k)?;
        let (pb, cb) = fx.run_trace(c, k)?;
        let mut v = Verdict::new(format!("light {light}"));
        trace_accounting(&mut v, "cpu", &ca, pa.len(), emitted);
        trace_accounting(&mut v, "candidate", &cb, pb.len(), emitted);
        let n = pa.len().max(pb.len()) as u64;
        let allow = divergence_allowance(n);
        let d = (pa.len() as i64 - pb.len() as i64).unsigned_abs();
        v.check(d <= allow, || {
            format!(
                "stored {} photons, cpu {} (allowed difference {allow})",
                pb.len(),
                pa.len()
            )
        });
        // Every path ends in one category: a diverged path moves one count between two.
        let allow_paths = divergence_allowance(emitted);
        for (w, name) in [
            (counter::NO_SPECULAR, "no_specular"),
            (counter::ESCAPED, "escaped"),
            (counter::NEGLIGIBLE, "negligible"),
            (counter::BOUNCE_LIMIT, "bounce_limit"),
        ] {
            let d = (ca[w] as i64 - cb[w] as i64).unsigned_abs();
            v.check(d <= allow_paths, || {
                format!(
                    "{name}: {} vs cpu {} (allowed difference {allow_paths})",
                    cb[w], ca[w]
                )
            });
        }
        // Ray segments: a diverged path may trace up to max_bounces more or fewer.
        let rays = |c: &[u32]| join_u64([c[counter::RAYS], c[counter::RAYS + 1]]);
        let d = (rays(&ca) as i64 - rays(&cb) as i64).unsigned_abs();
        let allow_rays = allow_paths * fx.settings.trace.max_bounces as u64;
        v.check(d <= allow_rays, || {
            format!(
                "rays traced {} vs cpu {} (allowed {allow_rays})",
                rays(&cb),
                rays(&ca)
            )
        });
        // Flux: the diverged photons' whole flux plus rounding of the others.
        let max_photon_flux = fx.constants.max_photon_flux as f64;
        let (fa, fb) = (flux_sum(&pa), flux_sum(&pb));
        for ch in 0..3 {
            let all = |f: [f64; 3]| f[0] + f[1] + f[2];
            let bound = allow as f64 * max_photon_flux
                + flux_rel.sum_bound(fa[ch].max(fb[ch]), all(fa).max(all(fb)));
            v.check((fa[ch] - fb[ch]).abs() <= bound, || {
                format!(
                    "flux[{ch}] {:.6e} vs cpu {:.6e} (allowed {bound:.3e})",
                    fb[ch], fa[ch]
                )
            });
            // The fixed-point stored-flux counter (units of the quantum, <= 2^24 per
            // photon) follows the same argument, plus one rounding unit per photon.
            let q = |c: &[u32]| {
                join_u64([
                    c[counter::STORED_FLUX + 2 * ch],
                    c[counter::STORED_FLUX + 2 * ch + 1],
                ])
            };
            let dq = (q(&ca) as i64 - q(&cb) as i64).unsigned_abs() as f64;
            let max_q = max_photon_flux / fx.constants.flux_quantum as f64;
            let bound_q = allow as f64 * max_q
                + n as f64 * (1.0 + (PHOTON_FLUX_REL + 3.0 * flux_rel.spectral as f64) * max_q);
            v.check(dq <= bound_q, || {
                format!(
                    "stored-flux counter[{ch}] {} vs cpu {} (allowed {bound_q:.3e})",
                    q(&cb),
                    q(&ca)
                )
            });
        }
        // Multiset match in both directions, on position and flux.
        let (ua, ub) = (
            unmatched(&pb, &pa, tol, flux_rel),
            unmatched(&pa, &pb, tol, flux_rel),
        );
        for (u, len, who) in [(ua, pb.len(), "candidate"), (ub, pa.len(), "cpu")] {
            let allowed = ((1.0 - PHOTON_MATCH) * len as f64).ceil() as u64 + 2;
            v.check(u <= allowed, || {
                format!(
                    "{u} of {len} {who} photons have no counterpart within {tol:.2e} (allowed {allowed})"
                )
            });
        }
        // A batch that is part of the grid, starting inside a band of tiles: the photons
        // it covers (core's math::sampling::tiled_photon_index) are the CPU's; a backend
        // that handed its threads photons in row order would store another set.
        let count = fx.settings.frame.photons_w * fx.settings.frame.photons_h;
        if count >= 3 {
            let (first, part) = (count / 3 + 1, count / 3);
            let partial = |p: &mut caustica_core::device::layout::TraceParams| {
                p.first = first;
                p.count = part;
            };
            let (qa, _) = fx.run_trace_with(r, k, partial)?;
            let (qb, _) = fx.run_trace_with(c, k, partial)?;
            for (u, len, who) in [
                (unmatched(&qb, &qa, tol, flux_rel), qb.len(), "candidate"),
                (unmatched(&qa, &qb, tol, flux_rel), qa.len(), "cpu"),
            ] {
                let allowed = ((1.0 - PHOTON_MATCH) * len as f64).ceil() as u64 + 2;
                v.check(u <= allowed, || {
                    format!(
                        "batch {first} .. {}: {u} of {len} {who} photons have no counterpart \
                         within {tol:.2e} (allowed {allowed})",
                        first + part
                    )
                });
            }
        }
        // The first-segment caster-ball test (core's device::caster_spheres) on each
        // backend against the same backend without it.
        let runs: [(&str, &mut dyn Backend, TraceRun); 2] = [
            ("cpu", &mut *r, (&pa, &ca)),
            ("candidate", &mut *c, (&pb, &cb)),
        ];
        for (who, b, with) in runs {
            let without = fx.run_trace_with(b, k, |p| p.caster_sphere_count = 0)?;
            caster_test_keeps_every_photon(&mut v, who, with, (&without.0, &without.1));
        }
        v.note(format!(
            "stored {} vs cpu {}; unmatched {ua} / {ub} within {tol:.2e}; flux {:.4e} vs {:.4e}",
            pb.len(),
            pa.len(),
            fb.iter().sum::<f64>(),
            fa.iter().sum::<f64>()
        ));
        all.absorb(v);
    }
    Ok(all)
}

/// Runs the fused trace (`variant` with `fused_deposit`) of light `domains[k]` on `b`
/// into a cleared atlas of layout `l`.
fn run_fused_trace(
    fx: &Fixture,
    b: &mut dyn Backend,
    l: &AtlasLayout,
    k: usize,
    variant: TraceVariant,
    split_budget: u32,
) -> Result<Deposit, String> {
    run_fused_trace_as(fx, b, l, variant, |rec| {
        let params = TraceParams {
            split_budget,
            ..fx.trace_batch(k)
        };
        (params, rec.create(1, "photon count"), None)
    })
}

/// Runs a fused trace (`variant` with `fused_deposit`) on `b` into a cleared atlas of
/// layout `l`: `batch` records its inputs and gives its parameters, its `photon_count`
/// (the adaptive variant's list length) and its cluster list.
pub(crate) fn run_fused_trace_as(
    fx: &Fixture,
    b: &mut dyn Backend,
    l: &AtlasLayout,
    variant: TraceVariant,
    batch: impl FnOnce(&mut Recording) -> (TraceParams, Buf<u32>, Option<ClusterBatch>),
) -> Result<Deposit, String> {
    let mut rec = Recording::new();
    let (trace, photon_count, clusters) = batch(&mut rec);
    // the fused pass stores no photon: one slot, as CausticMap has
    let photons = rec.create(1, "photons");
    let counters = rec.create(counter::WORDS as u32, "counters");
    let sums = rec.create_photon_map(l.texels.len() as u32);
    rec.clear_photon_map(&sums);
    let triangle_tiles = rec.upload(&l.triangle_tiles, "triangle tiles");
    let tiles = rec.upload(&l.tiles, "tiles");
    let triangle_reach = rec.create(
        triangle_reach_words(l.triangle_tiles.len() as u32),
        "triangle reach",
    );
    rec.clear(triangle_reach);
    let centroids = rec.create(
        l.texels.len() as u32 * caustica_core::math::map_gather::CENTROID_WORDS,
        "centroid sums",
    );
    rec.clear(centroids);
    rec.kernel(TracePhotons {
        scene: fx.args,
        variant,
        params: trace,
        photons,
        photon_count,
        counters,
        clusters,
        deposit: Some(FusedDeposit::Atlas(AtlasDeposit {
            params: params(l, 1, 1),
            triangle_tiles,
            tiles,
            triangle_reach,
            sums,
            centroids,
        })),
    });
    run_and_free(b, "trace_photons (atlas deposit)", &rec, |b| {
        Ok((
            read_photon_map(b, &sums)?,
            read_buf(b, counters)?,
            read_buf(b, triangle_reach)?,
            read_buf(b, centroids)?,
        ))
    })
}

/// Branches per emitted photon of the checked deterministic split.
const CHECK_SPLIT_BUDGET: u32 = 4;

/// The fused trace on every light of the fixture's scene (see the module doc).
pub fn check_fused_trace(
    fx: &Fixture,
    _inputs: &ReferenceInputs,
    _r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("trace_photons (atlas deposit)");
    // every other receiver left out, so that photons also land where no tile is
    let mut receivers = atlas_receivers(&fx.scene);
    let tiled: Vec<usize> = (0..receivers.len()).filter(|&i| receivers[i]).collect();
    if tiled.len() > 1 {
        for i in tiled.into_iter().skip(1).step_by(2) {
            receivers[i] = false;
        }
    }
    let Some(l) = receivers
        .iter()
        .any(|r| *r)
        .then(|| atlas_layout(&fx.ds, &receivers, (CHECK_ATLAS, CHECK_ATLAS)).ok())
        .flatten()
    else {
        return Ok(v);
    };
    let stochastic = TraceVariant {
        surface_store: true,
        ..fx.trace_variant()
    };
    let mut variants = vec![(stochastic, 1)];
    if stochastic.dielectric {
        let split = TraceVariant {
            fresnel_split: true,
            ..stochastic
        };
        variants.push((split, CHECK_SPLIT_BUDGET));
    }
    for (variant, budget) in variants {
        for k in 0..fx.constants.domains.len() {
            let label = format!(
                "light domain {k}{}",
                if variant.fresnel_split { ", split" } else { "" }
            );
            let (photons, trace_counters) =
                fx.run_trace_as(c, k, variant, |p| p.split_budget = budget)?;
            let fused = TraceVariant {
                fused_deposit: true,
                ..variant
            };
            let (sums, counters, reach, centroids) =
                run_fused_trace(fx, c, &l, k, fused, budget)?;
            let (es, deposit_counters, er, ecentroids) = cpu_deposit(&l, &photons);
            // the trace and the deposit count disjoint words (their sum is the fused one's)
            let ec: Vec<u32> = trace_counters
                .iter()
                .zip(&deposit_counters)
                .map(|(t, d)| t.wrapping_add(*d))
                .collect();
            v.check(reach == er, || {
                let differ = er.iter().zip(&reach).filter(|(a, b)| a != b).count();
                format!("{label}: {differ} words of the triangle reach mask differ")
            });
            v.check(counters == ec, || {
                format!("{label}: counters differ: expected {ec:?}, fused {counters:?}")
            });
            v.check(centroids == ecentroids, || {
                let differ = ecentroids
                    .iter()
                    .zip(&centroids)
                    .filter(|(a, b)| a != b)
                    .count();
                format!(
                    "{label}: {differ} words of the atlas's centroid sums differ (integer \
                     atomics of offsets computed by products by powers of two and floors \
                     must agree bitwise)"
                )
            });
            let equal = es.iter().zip(&sums).filter(|(a, b)| a == b).count();
            v.check(equal == es.len(), || {
                format!(
                    "{label}: {} of {} atlas texels differ from the deposit of the trace's \
                     {} photons (integer atomics must agree bitwise)",
                    es.len() - equal,
                    es.len(),
                    photons.len()
                )
            });
        }
    }
    Ok(v)
}
