//! CausticMap's kernels (`gather_caustic_map`, `caustic_map_lookup`), checked together on
//! the same inputs ([`check_caustic_map`]): the fixture's scene gets a 64x64 caustic atlas
//! over its diffuse receivers (no atlas, nothing to check, where it has none or their UVs
//! cannot address one); each kernel runs on the CPU's output uploaded to both backends, so
//! only the kernel under test differs. The gather's input is the CPU's atlas deposit of
//! 4096 generated texture-space photons (uv anywhere in `[0, 1]^2`, triangles of
//! receivers and of casters, fluxes over 12 binary orders), whose reach mask must be
//! exactly the photons' triangles.
//! - `gather_caustic_map` (N = 3, and N = 1: the raw map; N = 3 once more with every
//!   tile's `TILE_FULLY_COVERED` flag cleared on the backend under test, so that its
//!   counting of each source's covered texels is checked against the flag's shortcut on
//!   the CPU) on the CPU's sums: per texel a
//!   sum of at most `N^2` sources, each converted exactly (a power-of-two quantum times a
//!   u64 split in two exact f32 parts and one rounding) and divided by a count and by the
//!   area, i.e. at most `N^2 + 3` roundings of `2^-24` each, plus WGSL/SPIR-V's division
//!   (2.5 ulp): relative `GATHER_REL` (1e-5 >> 14 ulp) of the texel's value, absolute
//!   `1e-30` for zero texels.
//! - the density gather on the atlas (`gather: density`): `photon_count_table` bitwise,
//!   `gather_footprint` and both `density_gather` passes as on the screen
//!   ([`check_atlas_density_gather`]).
//! - `caustic_map_lookup` on the CPU's gathered map: `direct_light`'s specular tree
//!   (the same walk, its tolerance argued there: `DIRECT_REL` per pixel on
//!   `DIRECT_AGREEMENT` of the pixels, where a ray that grazes an edge may take the other
//!   triangle) ending in a bilinear lookup of four texels (7 roundings); under both
//!   reflectance models (exact and Schlick).
//!
//! [`check_fused_trace`] checks CausticMap's fused pass, `trace_photons`' `fused_deposit`
//! variant, on the backend under test against the CPU's atlas deposit of the photons
//! that the same backend's texture-space trace stores (the variant without
//! `fused_deposit`: the same code up to where a stored photon goes, and that trace is
//! `check_trace`'s). The deposit is integer atomics of quanta that are powers of two
//! (`x / 2^k` is exact under any division bound), so the atlas sums, the reach mask and
//! the counters (the trace's plus the deposit's) must be **bitwise** equal; under the
//! stochastic and, on scenes with dielectrics, the deterministic Fresnel split.

use super::density_gather::{compare, flush_allowance, tap_sum};
use crate::harness::fixture::{run_and_free, Fixture, ReferenceInputs};
use crate::harness::tolerance::DENSITY_GATHER_REL;
use crate::harness::tolerance::{DIRECT_AGREEMENT, DIRECT_FLOOR, DIRECT_REL, GATHER_REL};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, read_photon_map, Backend};
use caustica_core::device::layout::*;
use caustica_core::frame::receivers::atlas::layout::{atlas_layout, atlas_receivers, AtlasLayout};
use caustica_core::kernels::{
    AtlasDeposit, CausticMapLookup, DensityGather, FusedDeposit, GatherCausticMap, GatherFootprint,
    PhotonCountTable, TracePhotons, TraceVariant,
};
use caustica_core::math::density_gather::{
    accumulate_source_index, atlas_edge_texel, source_index_len,
};
use caustica_core::math::map_gather::{tile_receiver, triangle_reach_bit, triangle_reach_words};
use caustica_core::math::optics::fresnel_model;
use caustica_core::math::rng::random_f32;
use caustica_core::recording::Recording;
use caustica_core::techniques::caustic_map::{atlas_gather_params, CausticMapSettings};
use caustica_cpu::kernels::caustic_map::{deposit_atlas_fresh, AtlasDepositResult};

/// Side of the checked atlas (texels).
pub const CHECK_ATLAS: u32 = 64;

pub(crate) fn layout(fx: &Fixture) -> Option<AtlasLayout> {
    let receiver = atlas_receivers(&fx.scene);
    if !receiver.iter().any(|r| *r) {
        return None;
    }
    atlas_layout(&fx.ds, &receiver, (CHECK_ATLAS, CHECK_ATLAS)).ok()
}

/// Texture-space photons: three in four on a receiver's triangle, the others on any
/// triangle (casters have no tile).
fn photons(l: &AtlasLayout, n: u32) -> Vec<Photon> {
    let tris = l.triangle_tiles.len() as u32;
    let receivers: Vec<u32> = (0..tris)
        .filter(|&t| l.triangle_tiles[t as usize] != NO_TILE)
        .collect();
    (0..n)
        .map(|i| {
            let r = |d| random_f32(0xa71a5, i, 0, d);
            let pick = |pool: u32| ((r(6) * pool as f32) as u32).min(pool - 1);
            Photon {
                position: [r(0), r(1), 0.0],
                hit_distance: r(2) * 3.0,
                flux: [r(3), r(4), r(5)].map(|x| x * 2f32.powi(-((i % 12) as i32))),
                direction: if i % 4 != 0 && !receivers.is_empty() {
                    receivers[pick(receivers.len() as u32) as usize]
                } else {
                    pick(tris)
                },
            }
        })
        .collect()
}

fn params(l: &AtlasLayout, n: u32, capacity: u32) -> AtlasParams {
    AtlasParams {
        width: l.plan.size.0,
        height: l.plan.size.1,
        flux_quantum: 2f32.powi(-24),
        hit_distance_quantum: 2f32.powi(-20),
        photon_capacity: capacity,
        gather_width: n,
        _pad: [0; 2],
    }
}

/// What the atlas deposit writes: the atlas sums, the counters, the triangle reach mask.
type Deposit = AtlasDepositResult;

/// The CPU's atlas deposit of `ph` into a fresh atlas of layout `l` (the function behind
/// the CPU's fused trace: the reference both checks compare with).
fn cpu_deposit(l: &AtlasLayout, ph: &[Photon]) -> Deposit {
    deposit_atlas_fresh(
        &params(l, 1, ph.len() as u32),
        (&l.triangle_tiles, &l.tiles),
        ph,
        l.texels.len(),
        triangle_reach_words(l.triangle_tiles.len() as u32) as usize,
    )
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
    let mut rec = Recording::new();
    // the fused pass stores no photon: one slot, as CausticMap has
    let photons = rec.create(1, "photons");
    let photon_count = rec.create(1, "photon count");
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
    rec.kernel(TracePhotons {
        scene: fx.args,
        variant,
        params: TraceParams {
            split_budget,
            ..fx.trace_batch(k)
        },
        photons,
        photon_count,
        counters,
        clusters: None,
        deposit: Some(FusedDeposit::Atlas(AtlasDeposit {
            params: params(l, 1, 1),
            triangle_tiles,
            tiles,
            triangle_reach,
            sums,
        })),
    });
    run_and_free(b, "trace_photons (atlas deposit)", &rec, |b| {
        Ok((
            read_photon_map(b, &sums)?,
            read_buf(b, counters)?,
            read_buf(b, triangle_reach)?,
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
            let (sums, counters, reach) = run_fused_trace(fx, c, &l, k, fused, budget)?;
            let (es, deposit_counters, er) = cpu_deposit(&l, &photons);
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

/// Runs `gather_caustic_map` of width `n` on `b` over `sums`; `counted`: with every
/// tile's `TILE_FULLY_COVERED` flag cleared, so that the kernel counts each source's
/// covered texels where the flag would give it their number.
fn run_gather(
    b: &mut dyn Backend,
    l: &AtlasLayout,
    sums: &[DepositTexel],
    n: u32,
    counted: bool,
) -> Result<Vec<[f32; 4]>, String> {
    let mut rec = Recording::new();
    let out = rec.create(l.texels.len() as u32, "caustic map");
    let texels = rec.upload(&l.texels, "texels");
    let tile_words: Vec<AtlasTileTexel> = l
        .tiles
        .iter()
        .map(|t| {
            if counted {
                [t[0], t[1], t[2], tile_receiver(t[3])]
            } else {
                *t
            }
        })
        .collect();
    let tiles = rec.upload(&tile_words, "tiles");
    let atlas = rec.upload_photon_map(sums);
    rec.kernel(GatherCausticMap {
        params: params(l, n, 1),
        texels,
        tiles,
        atlas,
        out,
    });
    run_and_free(b, "gather_caustic_map", &rec, |b| read_buf(b, out))
}

/// Runs `caustic_map_lookup` on `b` over `map`, dielectrics under `fresnel_model`.
fn run_lookup(
    fx: &Fixture,
    b: &mut dyn Backend,
    l: &AtlasLayout,
    map: &[[f32; 4]],
    fresnel_model: u32,
) -> Result<Vec<[f32; 4]>, String> {
    let mut rec = Recording::new();
    let out = rec.create(fx.pixels(), "caustics");
    let triangle_tiles = rec.upload(&l.triangle_tiles, "triangle tiles");
    let tiles = rec.upload(&l.tiles, "tiles");
    let texels = rec.upload(&l.texels, "texels");
    let map = rec.upload(map, "map");
    rec.kernel(CausticMapLookup {
        scene: fx.args,
        params: MapLookupParams {
            camera: fx.camera,
            atlas_width: l.plan.size.0,
            max_specular_depth: fx.settings.max_specular_depth,
            min_weight: 1e-3,
            fresnel_model,
        },
        triangle_tiles,
        tiles,
        texels,
        map,
        out,
    });
    run_and_free(b, "caustic_map_lookup", &rec, |b| read_buf(b, out))
}

/// Gather settings of the density check on the atlas: radii from 1/2 (where 8 photons
/// share a 3x3 window) to the cap of 8 texels (the sparse texels).
fn density_settings(l: &AtlasLayout) -> CausticMapSettings {
    CausticMapSettings {
        atlas_size: l.plan.size.0,
        knn_photons: 8,
        max_radius_texels: 8,
        ..Default::default()
    }
}

/// The density gather on the atlas (`GatherParams::surface` ATLAS): both axes of
/// `photon_count_table` from the CPU's sums (integer sums: bitwise), `gather_footprint`
/// on the CPU's table and both `density_gather` passes on the CPU's intermediate images,
/// each within `DENSITY_GATHER_REL` of the magnitudes it gathers (the screen check's
/// argument: the same sums of products, in the same order; the column pass divides by the
/// texel's area once more, one rounding, inside the margin).
fn check_atlas_density_gather(
    v: &mut Verdict,
    l: &AtlasLayout,
    sums: &[DepositTexel],
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<(), String> {
    let s = density_settings(l);
    let params = |axis| atlas_gather_params(&s, 2f32.powi(-24), 2f32.powi(-20), axis);
    let edge: Vec<[f32; 4]> = l
        .texels
        .iter()
        .map(|t| atlas_edge_texel(t[1], f32::from_bits(t[0])))
        .collect();
    let n = edge.len() as u32;
    let cam = params(0).camera;
    // photon_count_table, both axes
    let table = |b: &mut dyn Backend| {
        let mut rec = Recording::new();
        let m = rec.upload_photon_map(sums);
        let table = rec.create(n, "photon count table");
        let e = rec.upload(&edge, "atlas edge texels");
        let g = rec.create_gbuffer(1);
        for axis in 0..2 {
            rec.kernel(PhotonCountTable {
                params: params(axis),
                photon_map: m,
                table,
                gbuffer: g,
                edge: e,
            });
        }
        run_and_free(b, "photon_count_table (atlas)", &rec, |b| {
            Ok((read_buf(b, table)?, read_buf(b, e)?))
        })
    };
    let (ta, ea) = table(r)?;
    let (tb, eb) = table(c)?;
    v.check(ta == tb, || "atlas photon_count_table differs".into());
    v.check(
        ea.iter()
            .zip(&edge)
            .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits))
            && eb
                .iter()
                .zip(&edge)
                .all(|(a, b)| a.map(f32::to_bits) == b.map(f32::to_bits)),
        || "photon_count_table wrote the atlas's edge texels".into(),
    );
    // gather_footprint
    let footprint = |b: &mut dyn Backend| {
        let mut rec = Recording::new();
        let m = rec.upload_photon_map(sums);
        let t = rec.upload(&ta, "photon count table");
        let e = rec.upload(&edge, "atlas edge texels");
        let out = rec.create(n, "footprints");
        let source_index = rec.create(source_index_len(cam.width, cam.height), "source index");
        rec.kernel(GatherFootprint {
            params: params(0),
            photon_map: m,
            table: t,
            edge: e,
            out,
            source_index,
        });
        run_and_free(b, "gather_footprint (atlas)", &rec, |b| read_buf(b, out))
    };
    let (fa, fb) = (footprint(r)?, footprint(c)?);
    let radius = |f: &[[f32; 4]]| f.iter().map(|p| [p[3], 0.0, 0.0, 0.0]).collect::<Vec<_>>();
    compare(
        v,
        "atlas gather_footprint radius",
        &cam,
        (&radius(&fa), &radius(&fb)),
        &|_, _| (DENSITY_GATHER_REL, 0.0, 0.0),
        false,
    );
    compare(
        v,
        "atlas gather_footprint flux",
        &cam,
        (&fa, &fb),
        &|_, _| (DENSITY_GATHER_REL, 0.0, 0.0),
        false,
    );
    // density_gather, rows on the CPU's footprints, columns on the CPU's rows
    let pass = |b: &mut dyn Backend, axis: u32, input: &[[f32; 4]]| {
        let mut rec = Recording::new();
        let e = rec.upload(&edge, "atlas edge texels");
        let i = rec.upload(input, "gather input");
        let g = rec.create_gbuffer(1);
        let out = rec.create(n, "gather output");
        // the source index the pass before would have written for this input
        let mut grid = vec![0; source_index_len(cam.width, cam.height) as usize];
        let cap = params(axis).max_radius_px as i32;
        accumulate_source_index(&mut grid, input, cam.width, cam.height, axis, cap);
        let source_index = rec.upload(&grid, "source index");
        rec.kernel(DensityGather {
            params: params(axis),
            gbuffer: g,
            edge: e,
            input: i,
            out,
            source_index,
        });
        run_and_free(b, "density_gather (atlas)", &rec, |b| read_buf(b, out))
    };
    let rows = pass(r, 0, &fa)?;
    let mut lit = 0;
    for (axis, input) in [(0u32, &fa), (1, &rows)] {
        let (a, b) = (pass(r, axis, input)?, pass(c, axis, input)?);
        if axis == 1 {
            lit = a.iter().filter(|t| t[0] > 0.0).count();
        }
        let reach = s.max_radius_texels as i32;
        // flux -> output: 1 for the rows, 1 / area for the columns' irradiance
        let to_output = |i: usize| if axis == 0 { 1.0 } else { 1.0 / edge[i][1] };
        compare(
            v,
            &format!("atlas density_gather axis {axis}"),
            &cam,
            (&a, &b),
            &|i, ch| {
                (
                    DENSITY_GATHER_REL,
                    tap_sum(&cam, reach, axis, input, i, ch) * to_output(i),
                    flush_allowance(reach, axis, input, i) * to_output(i),
                )
            },
            true,
        );
    }
    v.check(lit > 0, || "the density-gathered atlas is dark".into());
    Ok(())
}

/// The three kernels on the fixture's scene (see the module doc).
pub fn check_caustic_map(
    fx: &Fixture,
    _inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("gather_caustic_map + caustic_map_lookup");
    let Some(l) = layout(fx) else {
        return Ok(v);
    };
    let ph = photons(&l, 4096);
    // the gather's input: the CPU's deposit of the generated photons (the deposit itself
    // is check_fused_trace's), its reach mask exactly the photons' triangles
    let (sa, ca, ra) = cpu_deposit(&l, &ph);
    let mut expected = vec![0u32; ra.len()];
    for p in &ph {
        let (word, bit) = triangle_reach_bit(p.direction);
        expected[word as usize] |= bit;
    }
    v.check(ra == expected, || {
        "cpu: the triangle reach mask is not the photons' triangles".into()
    });
    let deposited = ca[counter::DEPOSITED] as u64;
    v.check(
        deposited + ca[counter::OFF_SCREEN] as u64 == ph.len() as u64,
        || {
            format!(
                "cpu: deposited + no tile = {} + {}, {} photons",
                deposited,
                ca[counter::OFF_SCREEN],
                ph.len()
            )
        },
    );
    v.check(deposited > 0, || {
        "no photon landed on a receiver tile".into()
    });
    let mut gathered = Vec::new();
    // N = 3 twice: flagged tiles as laid out, then counted on the backend under test
    for (n, counted) in [(3u32, false), (3, true), (1, false)] {
        let ga = run_gather(r, &l, &sa, n, false)?;
        let gb = run_gather(c, &l, &sa, n, counted)?;
        let n_label = if counted {
            "3 (counted)".to_string()
        } else {
            n.to_string()
        };
        let bad = ga
            .iter()
            .zip(&gb)
            .filter(|(a, b)| {
                (0..4).any(|k| {
                    (a[k] - b[k]).abs() > GATHER_REL * a[k].abs() + 1e-30 || !b[k].is_finite()
                })
            })
            .count();
        let lit = ga.iter().filter(|t| t[0] > 0.0).count();
        v.check(lit > 0, || {
            format!("N = {n_label}: the gathered map is dark")
        });
        v.check(bad == 0, || {
            format!(
                "N = {n_label}: {bad} of {} texels differ by more than {GATHER_REL} relative",
                ga.len()
            )
        });
        if !counted {
            gathered.push(ga);
        }
    }
    check_atlas_density_gather(&mut v, &l, &sa, r, c)?;
    // both reflectance models of the specular chain (the exact default, seed 001's Schlick)
    for model in [fresnel_model::EXACT, fresnel_model::SCHLICK] {
        let la = run_lookup(fx, r, &l, &gathered[0], model)?;
        let lb = run_lookup(fx, c, &l, &gathered[0], model)?;
        let agree = la
            .iter()
            .zip(&lb)
            .filter(|(a, b)| {
                (0..3).all(|k| (a[k] - b[k]).abs() <= DIRECT_REL * a[k].abs() + DIRECT_FLOOR)
            })
            .count();
        let frac = agree as f64 / la.len().max(1) as f64;
        v.check(frac >= DIRECT_AGREEMENT, || {
            format!(
                "caustic_map_lookup (fresnel_model {model}): {frac:.4} of pixels agree, need \
                 {DIRECT_AGREEMENT}"
            )
        });
        v.check(lb.iter().all(|p| p.iter().all(|x| x.is_finite())), || {
            format!("lookup (fresnel_model {model}): a non-finite pixel")
        });
    }
    Ok(v)
}
