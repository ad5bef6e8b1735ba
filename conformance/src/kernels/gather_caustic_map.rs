//! `gather_caustic_map` and the density gather on a caustic atlas, the first part of
//! CausticMap's check ([`super::caustic_map_lookup::check_caustic_map`], which has the
//! setup):
//! - `gather_caustic_map` (N = 3, and N = 1: the raw map; N = 3 once more with every
//!   tile's `TILE_FULLY_COVERED` flag cleared on the backend under test, so that its
//!   counting of each source's covered texels is checked against the flag's shortcut on
//!   the CPU) on the CPU's sums: per texel a sum of at most `N^2` sources, each converted
//!   exactly (a power-of-two quantum times a u64 split in two exact f32 parts and one
//!   rounding) and divided by a count and by the area, i.e. at most `N^2 + 3` roundings
//!   of `2^-24` each, plus WGSL/SPIR-V's division (2.5 ulp): relative `GATHER_REL` (1e-5
//!   >> 14 ulp) of the texel's value, absolute `1e-30` for zero texels.
//! - the density gather on the atlas (`gather: density`): `photon_count_table` bitwise,
//!   `gather_footprint` and both `density_gather` passes as on the screen
//!   (`check_atlas_density_gather`).
use caustica_core::AtlasSettings;
use super::density_gather::{compare, flush_allowance, tap_sum, Alpha};
use crate::harness::fixture::{run_and_free, Fixture};
use crate::harness::tolerance::DENSITY_GATHER_REL;
use crate::harness::tolerance::GATHER_REL;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::*;
use caustica_core::frame::receivers::atlas::layout::{atlas_layout, atlas_receivers, AtlasLayout};
use caustica_core::kernels::{DensityGather, GatherCausticMap, GatherFootprint, PhotonCountTable};
use caustica_core::math::density_gather::{
    accumulate_source_index, atlas_edge_texel, source_index_len,
};
use caustica_core::math::map_gather::{tile_receiver, triangle_reach_bit, triangle_reach_words};
use caustica_core::math::rng::random_f32;
use caustica_core::recording::Recording;
use caustica_core::techniques::caustic_map::{atlas_gather_params, CausticMapSettings};
use caustica_cpu::atlas_deposit::{deposit_atlas_fresh, AtlasDepositResult};

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
pub(crate) fn photons(l: &AtlasLayout, n: u32) -> Vec<Photon> {
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

pub(crate) fn params(l: &AtlasLayout, n: u32, capacity: u32) -> AtlasParams {
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
pub(crate) type Deposit = AtlasDepositResult;

/// The CPU's atlas deposit of `ph` into a fresh atlas of layout `l` (the function behind
/// the CPU's fused trace: the reference both checks compare with).
pub(crate) fn cpu_deposit(l: &AtlasLayout, ph: &[Photon]) -> Deposit {
    deposit_atlas_fresh(
        &params(l, 1, ph.len() as u32),
        (&l.triangle_tiles, &l.tiles),
        ph,
        l.texels.len(),
        triangle_reach_words(l.triangle_tiles.len() as u32) as usize,
    )
}

/// Runs `gather_caustic_map` of width `n` on `b` over `sums`; `counted`: with every
/// tile's `TILE_FULLY_COVERED` flag cleared, so that the kernel counts each source's
/// covered texels where the flag would give it their number.
pub(crate) fn run_gather(
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

/// An image of RGBA texels.
pub(crate) type Image = Vec<[f32; 4]>;

/// The gather's part of the check: the CPU's deposit of generated photons into atlas
/// `l` (its reach mask exactly the photons' triangles) gathered on both backends at
/// N = 3 (as laid out, then counted on the candidate) and N = 1. Returns the CPU's sums
/// and the reference's gathered maps (N = 3, then N = 1).
pub(crate) fn compare_gather(
    v: &mut Verdict,
    l: &AtlasLayout,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<(Vec<DepositTexel>, Vec<Image>), String> {
    let ph = photons(l, 4096);
    // the gather's input: the CPU's deposit of the generated photons (the deposit itself
    // is check_fused_trace's), its reach mask exactly the photons' triangles
    let (sa, ca, ra, _) = cpu_deposit(l, &ph);
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
        let ga = run_gather(r, l, &sa, n, false)?;
        let gb = run_gather(c, l, &sa, n, counted)?;
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
    Ok((sa, gathered))
}

/// Gather settings of the density check on the atlas: radii from 1/2 (where 8 photons
/// share a 3x3 window) to the cap of 8 texels (the sparse texels).
pub(crate) fn density_settings(l: &AtlasLayout) -> CausticMapSettings {
    CausticMapSettings {
        atlas: AtlasSettings {
            atlas_size: l.plan.size.0,
            knn_photons: 8,
            max_radius_texels: 8,
            ..CausticMapSettings::default().atlas
        },
        ..CausticMapSettings::default()
    }
}

/// The density gather on the atlas (`GatherParams::surface` ATLAS): both axes of
/// `photon_count_table` from the CPU's sums (integer sums: bitwise), `gather_footprint`
/// on the CPU's table and both `density_gather` passes on the CPU's intermediate images,
/// each within `DENSITY_GATHER_REL` of the magnitudes it gathers (the screen check's
/// argument: the same sums of products, in the same order; the column pass divides by the
/// texel's area once more, one rounding, inside the margin).
pub(crate) fn check_atlas_density_gather(
    v: &mut Verdict,
    l: &AtlasLayout,
    sums: &[DepositTexel],
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<(), String> {
    let s = density_settings(l);
    let params = |axis| atlas_gather_params(&s.atlas_config(), 2f32.powi(-24), 2f32.powi(-20), axis);
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
        Alpha::Free,
    );
    compare(
        v,
        "atlas gather_footprint flux",
        &cam,
        (&fa, &fb),
        &|_, _| (DENSITY_GATHER_REL, 0.0, 0.0),
        Alpha::Free,
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
        let reach = s.atlas.max_radius_texels as i32;
        // flux -> output: 1 for the rows, 1 / area for the columns' irradiance
        let to_output = |i: usize| if axis == 0 { 1.0 } else { 1.0 / edge[i][1] };
        // the radius a lit pixel of the column pass passes through
        let lit_radius = |i: usize| input[i][3];
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
            if axis == 0 {
                Alpha::Exact
            } else {
                Alpha::ExactOrDark(&lit_radius)
            },
        );
    }
    v.check(lit > 0, || "the density-gathered atlas is dark".into());
    Ok(())
}
