//! `trace_indirect` on the reference's RSM photons: the stored photons as counts and
//! flux sums within the path-divergence allowance ([`divergence_allowance`] of the
//! stored photons, each diverged path changing at most `bounces` of them), as
//! multisets (each photon matched by one of the other backend's within
//! `trace_photons`' position tolerance, with the same tile and power within one rgb9e5
//! step, but for [`PHOTON_MATCH`]'s share), every path end accounted for, and tile
//! counts that add up to the stored photons. The `WAVES` variant ([`run_trace_waves`]),
//! plain and sorted (each queue keyed by the wave that fills it and taken in
//! `sort_indirect_paths`' order), is compared the same way with the reference's single
//! launch, and on every backend with that backend's single launch exactly
//! ([`compare_schedules`]).
//!
//! One link of PhotonGi's chain, [`super::shading_normal_correction::check_photon_gi`].

use super::sample_rsm::*;
use crate::harness::fixture::{run_and_free, Fixture};
use crate::harness::tolerance::{
    divergence_allowance, PHOTON_FLUX_REL, PHOTON_MATCH, PHOTON_POSITION_REL, SPECTRAL_FLUX_REL,
};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::launch::DISPATCH_RECORD_WORDS;
use caustica_core::device::layout::{
    counter, GBufferTexel, GiPhoton, IndirectPath, IndirectTraceParams, PathSortParams,
    RsmPhoton,
};
use caustica_core::kernels::{
    DispatchArgs, DispatchRecord, IndirectWave, SortIndirectPaths, TraceIndirect, WaveKeys,
};
use caustica_core::math::path_sort::{
    path_sort_key, path_sort_phase, PathKey, PATH_SORT_BITS, PATH_SORT_BUCKETS,
};
use glam::Vec3;
use caustica_core::math::fixed_point::join_u64;
use caustica_core::math::gi_photon::{gi_store, screen_tiles};
use caustica_core::math::packing::unpack_unit_vector;
use caustica_core::recording::Recording;

/// Diffuse bounces of the checked paths.
pub(crate) const BOUNCES: u32 = 3;
pub(crate) const TILE: u32 = 8;

/// (stored photons, tile counts, counters) of `trace_indirect`.
pub(crate) type Traced = (Vec<GiPhoton>, Vec<u32>, Vec<u32>);

pub(crate) fn run_trace(
    fx: &Fixture,
    b: &mut dyn Backend,
    rsm: &[RsmPhoton],
    gbuffer: &[GBufferTexel],
    power_scale: f32,
    quantum: f32,
) -> Result<Traced, String> {
    run_trace_waves(fx, b, rsm, gbuffer, (power_scale, quantum), 1, false).map(|(t, _)| t)
}

/// The last queue a sorted run keyed, as its sort left it (read back after the run: the
/// last wave neither keys nor sorts).
pub(crate) struct KeyedQueue {
    /// The queue's paths (its capacity).
    paths: Vec<IndirectPath>,
    /// Per slot (key, rank).
    keys: Vec<PathKey>,
    /// The queue's length word.
    length: u32,
    /// The buckets after the sort's scan: each key's first slot.
    first: Vec<u32>,
    /// The sort's order.
    order: Vec<u32>,
}

/// The queuing wave's keys and the sort's order of `q` on one backend, against their
/// definition: each live slot's key [`path_sort_key`] of its path (bitwise: one
/// subtraction and one product per axis, no contraction), each key's ranks a permutation
/// of its count, the first slots the counts' exclusive sums, the order a permutation of
/// the live slots in key order.
pub(crate) fn check_keyed_queue(v: &mut Verdict, backend: &str, l: u32, q: &KeyedQueue) {
    let n = (q.length as usize).min(q.paths.len()).min(q.keys.len());
    let (lo, scale) = sort_box();
    let mut counts = vec![0u32; PATH_SORT_BUCKETS as usize];
    let mut keyed = true;
    for (path, &[k, _]) in q.paths[..n].iter().zip(&q.keys) {
        let want = path_sort_key(Vec3::from(path.origin), Vec3::from(path.direction), lo, scale);
        keyed &= k == want;
        if let Some(c) = counts.get_mut(k as usize) {
            *c += 1;
        }
    }
    v.check(keyed, || {
        format!("light {l}, {backend}: a queued path's key is not its path's sort key")
    });
    let mut ranks: Vec<(u32, u32)> = q.keys[..n].iter().map(|&[k, r]| (k, r)).collect();
    ranks.sort_unstable();
    let dense = ranks.iter().enumerate().all(|(j, &(k, r))| {
        j == 0 || ranks[j - 1].0 != k || ranks[j - 1].1 + 1 == r
    }) && ranks.iter().all(|&(k, r)| counts.get(k as usize).is_some_and(|&c| r < c));
    v.check(dense, || {
        format!("light {l}, {backend}: a key's ranks are not a permutation of its count")
    });
    let mut sum = 0u32;
    let first: Vec<u32> = counts
        .iter()
        .map(|&c| {
            let f = sum;
            sum += c;
            f
        })
        .collect();
    v.check(q.first.get(..first.len()) == Some(&first[..]), || {
        format!("light {l}, {backend}: the sort's first slots are not the keys' counts' sums")
    });
    let order = &q.order[..n.min(q.order.len())];
    let mut seen = vec![false; n];
    let permutation = order.iter().all(|&i| {
        (i as usize) < n && !std::mem::replace(&mut seen[i as usize], true)
    });
    v.check(
        permutation
            && order.windows(2).all(|w| q.keys[w[0] as usize][0] <= q.keys[w[1] as usize][0]),
        || format!("light {l}, {backend}: the order is not the live slots in key order"),
    );
    v.note(format!("light {l}, {backend}: {n} sorted paths checked"));
}

/// The sorted waves' key box: origin cells of `2 SORT_BOX / 2^PATH_SORT_BITS` from
/// `-SORT_BOX` on each axis.
fn sort_box() -> (Vec3, Vec3) {
    (
        Vec3::splat(-SORT_BOX),
        Vec3::splat((1u32 << PATH_SORT_BITS) as f32 / (2.0 * SORT_BOX)),
    )
}

/// Segments per path of the checked launches.
const MAX_SEGMENTS: u32 = 12;

/// Waves of the `WAVES` variant's check: segments 0, 1 and 2 one a wave, the last wave
/// the rest.
pub(crate) const WAVES: u32 = 4;

/// Half the side of the sorted waves' key box, centred on the origin (scene units): the
/// fixtures' scenes lie within it, and a path outside lands in an edge cell.
const SORT_BOX: f32 = 10.0;

/// [`run_trace`] in `waves` waves (1: the single launch): wave `k` traces segment `k`
/// (the last the rest of each path), the later waves launched from the queue's length
/// through `dispatch_args`, as PhotonGi records them; `sorted`: each queue keyed by the
/// wave that fills it (a box of 8 cells a side over `SORT_BOX`) and taken by the next in
/// `sort_indirect_paths`' order (the `sorted_waves` schedule).
pub(crate) fn run_trace_waves(
    fx: &Fixture,
    b: &mut dyn Backend,
    rsm: &[RsmPhoton],
    gbuffer: &[GBufferTexel],
    (power_scale, quantum): (f32, f32),
    waves: u32,
    sorted: bool,
) -> Result<(Traced, Option<KeyedQueue>), String> {
    let cam = fx.camera;
    let mut rec = Recording::new();
    let g = rec.upload_gbuffer(gbuffer);
    let r = rec.upload(rsm, "RSM photons");
    let photons = rec.create::<[u32; 8]>(rsm.len() as u32 * BOUNCES, "indirect photons");
    let count = rec.create(1, "count");
    let tiles = rec.create(screen_tiles(cam.width, cam.height, TILE), "tile counts");
    let counters = rec.create(counter::WORDS as u32, "counters");
    rec.clear(count);
    rec.clear(tiles);
    rec.clear(counters);
    let n = rsm.len() as u32;
    let params = IndirectTraceParams {
        camera: cam,
        first: 0,
        count: n,
        seed: 77,
        max_bounces: BOUNCES,
        max_segments: MAX_SEGMENTS,
        tile_size: TILE,
        store: gi_store::PACKED,
        fresnel_model: 0,
        power_scale,
        flux_quantum: quantum,
        dispersion_mode: caustica_core::math::spectrum::dispersion_mode::SPECTRAL,
        segment_first: 0,
        segment_end: MAX_SEGMENTS,
        chunk_first: 0,
        chunk_size: u32::MAX,
        queue_keys: 0,
        key_origin_min: sort_box().0.to_array(),
        queue_order: 0,
        key_origin_scale: sort_box().1.to_array(),
        _pad: 0,
    };
    let single = TraceIndirect {
        scene: fx.args,
        params,
        rsm_photons: r,
        photons,
        photon_count: count,
        tile_counts: tiles,
        counters,
        gbuffer: g,
        dispatch: None,
        waves: None,
    };
    // sorted: the last keyed queue (the one the last wave continues), its keys and lengths
    let mut keyed = None;
    if waves <= 1 {
        rec.kernel(single);
    } else {
        let paths = [
            rec.create::<IndirectPath>(n.max(1), "path queue a"),
            rec.create::<IndirectPath>(n.max(1), "path queue b"),
        ];
        let path_counts = rec.create::<u32>(waves + 1, "paths per wave");
        let rows = rec.upload(
            &(1..waves).map(|k| [0, n, 1, k]).collect::<Vec<_>>(),
            "wave rows",
        );
        let args = rec.create::<u32>((waves - 1) * DISPATCH_RECORD_WORDS as u32, "wave records");
        let keys = sorted.then(|| WaveKeys {
            path_keys: rec.create::<PathKey>(n.max(1), "path keys"),
            buckets: rec.create::<u32>(PATH_SORT_BUCKETS, "path sort buckets"),
            order: rec.create::<u32>(n.max(1), "path order"),
        });
        keyed = keys.map(|k| (paths[(waves as usize - 1) % 2], k, path_counts));
        rec.clear(path_counts);
        for k in 0..waves {
            let dispatch = (k > 0).then(|| {
                rec.kernel(DispatchArgs {
                    table: rows,
                    counts: path_counts,
                    args,
                });
                DispatchRecord {
                    args,
                    record: k - 1,
                }
            });
            if let (Some(w), Some(d)) = (keys, dispatch) {
                for phase in [path_sort_phase::SCAN, path_sort_phase::SCATTER] {
                    rec.kernel(SortIndirectPaths {
                        params: PathSortParams {
                            phase,
                            count_word: k,
                            _pad: [0; 2],
                        },
                        path_keys: w.path_keys,
                        path_counts,
                        order: w.order,
                        buckets: w.buckets,
                        dispatch: Some(d),
                    });
                }
            }
            let end = if k + 1 == waves { MAX_SEGMENTS } else { k + 1 };
            // the buckets count the keys of the paths this wave queues (none for the last)
            if let Some(w) = keys.filter(|_| end < MAX_SEGMENTS) {
                rec.clear(w.buckets);
            }
            rec.kernel(TraceIndirect {
                params: IndirectTraceParams {
                    segment_first: k,
                    segment_end: end,
                    queue_keys: (sorted && end < MAX_SEGMENTS) as u32,
                    queue_order: (sorted && k > 0) as u32,
                    ..params
                },
                dispatch,
                waves: Some(IndirectWave {
                    paths_in: paths[k as usize % 2],
                    paths_out: paths[(k as usize + 1) % 2],
                    path_counts,
                    keys,
                }),
                ..single
            });
        }
    }
    run_and_free(b, "trace_indirect", &rec, |b| {
        let n = read_buf(b, count)?[0] as usize;
        let words = read_buf(b, photons)?;
        let ph = words[..n.min(words.len())]
            .iter()
            .map(|w| bytemuck::cast::<[u32; 8], GiPhoton>(*w))
            .collect();
        let queue = match keyed {
            Some((paths, k, counts)) => Some(KeyedQueue {
                paths: read_buf(b, paths)?,
                keys: read_buf(b, k.path_keys)?,
                length: read_buf(b, counts)?[waves as usize - 1],
                first: read_buf(b, k.buckets)?,
                order: read_buf(b, k.order)?,
            }),
            None => None,
        };
        Ok(((ph, read_buf(b, tiles)?, read_buf(b, counters)?), queue))
    })
}

/// The waves against the single launch on the same backend: the same photons (as a
/// multiset of their exact words: a path's random numbers are keyed by its photon and
/// segment and its state crosses the queue in full precision, so nothing may differ but
/// the order), the same tile counts and the same counters, word for word.
pub(crate) fn compare_schedules(
    v: &mut Verdict,
    backend: &str,
    l: u32,
    (pha, tia, ca): (&[GiPhoton], &[u32], &[u32]),
    (phw, tiw, cw): (&[GiPhoton], &[u32], &[u32]),
) {
    let sorted = |p: &[GiPhoton]| {
        let mut w: Vec<[u32; 8]> = p.iter().map(|x| bytemuck::cast(*x)).collect();
        w.sort_unstable();
        w
    };
    v.check(sorted(pha) == sorted(phw), || {
        format!(
            "light {l}, {backend}: {WAVES} waves store other photons than the single launch \
             ({} vs {})",
            phw.len(),
            pha.len()
        )
    });
    v.check(tia == tiw, || {
        format!("light {l}, {backend}: the waves' tile counts differ from the single launch's")
    });
    v.check(ca == cw, || {
        format!("light {l}, {backend}: the waves' counters {cw:?} differ from the single launch's {ca:?}")
    });
}

/// Point 3 of the module doc: light `l`'s stored photons, tile counts and counters
/// (reference, candidate), traced with `power_scale` and `quantum`.
pub(crate) fn compare_indirect(
    v: &mut Verdict,
    fx: &Fixture,
    l: u32,
    (pha, tia, ca): (&[GiPhoton], &[u32], &[u32]),
    (phb, tib, cb): (&[GiPhoton], &[u32], &[u32]),
    power_scale: f32,
    quantum: f32,
) {
    // diverged paths: a share of the paths, each moving one path end and at most
    // BOUNCES stored photons
    let stored = ca[counter::STORED].max(cb[counter::STORED]) as u64;
    let paths_allow = divergence_allowance(SAMPLES as u64);
    let allow = divergence_allowance(stored) * BOUNCES as u64;
    let diff = |k: usize| (ca[k] as i64 - cb[k] as i64).unsigned_abs();
    v.check(diff(counter::STORED) <= allow, || {
        format!(
            "light {l}: stored {} vs {} (allowance {allow})",
            ca[counter::STORED],
            cb[counter::STORED]
        )
    });
    for k in [
        counter::ESCAPED,
        counter::NEGLIGIBLE,
        counter::BOUNCE_LIMIT,
        counter::OFF_SCREEN,
        counter::DEPTH_MISMATCH,
    ] {
        v.check(diff(k) <= paths_allow.max(allow), || {
            format!("light {l}: counter {k}: {} vs {}", ca[k], cb[k])
        });
    }
    v.check(
        pha.len() as u32 == ca[counter::STORED] && phb.len() as u32 == cb[counter::STORED],
        || "stored photons and STORED disagree".into(),
    );
    v.check(
        tia.iter().sum::<u32>() as usize == pha.len()
            && tib.iter().sum::<u32>() as usize == phb.len(),
        || format!("light {l}: tile counts do not add up to the stored photons"),
    );
    let ends = |c: &[u32]| c[counter::ESCAPED] + c[counter::NEGLIGIBLE] + c[counter::BOUNCE_LIMIT];
    v.check(ends(ca) == SAMPLES && ends(cb) == SAMPLES, || {
        format!(
            "light {l}: path ends {} / {} of {SAMPLES}",
            ends(ca),
            ends(cb)
        )
    });
    // photons of a spectral colour (dispersive glass) differ by up to SPECTRAL_FLUX_REL of
    // their largest channel in every channel: of all channels' sum at most
    let flux_units = |c: &[u32], ch: usize| {
        join_u64([
            c[counter::STORED_FLUX + 2 * ch],
            c[counter::STORED_FLUX + 2 * ch + 1],
        ]) as f64
    };
    let all = |c: &[u32]| (0..3).map(|ch| flux_units(c, ch)).sum::<f64>();
    let spectral = if fx.scene.materials.values().any(|m| m.is_dispersive()) {
        SPECTRAL_FLUX_REL * all(ca).max(all(cb))
    } else {
        0.0
    };
    for ch in 0..3 {
        let fa = join_u64([
            ca[counter::STORED_FLUX + 2 * ch],
            ca[counter::STORED_FLUX + 2 * ch + 1],
        ]) as f64;
        let fb = join_u64([
            cb[counter::STORED_FLUX + 2 * ch],
            cb[counter::STORED_FLUX + 2 * ch + 1],
        ]) as f64;
        // each diverged path moves at most BOUNCES photons of up to the largest
        // photon's flux; the rest agree within PHOTON_FLUX_REL
        let biggest = pha
            .iter()
            .chain(phb)
            .map(|p| caustica_core::math::packing::unpack_rgb9e5(p.power).max_element())
            .fold(0.0f32, f32::max) as f64
            * power_scale as f64
            / quantum as f64;
        let tol = PHOTON_FLUX_REL * fa.max(fb) + spectral + allow as f64 * biggest + 3.0;
        v.check((fa - fb).abs() <= tol, || {
            format!("light {l}: stored flux channel {ch}: {fa} vs {fb} units")
        });
    }
    let diagonal = (fx.ds.bounds.max - fx.ds.bounds.min).length();
    let unmatched_ab = unmatched(pha, phb, diagonal);
    let unmatched_ba = unmatched(phb, pha, diagonal);
    let allow_match = ((1.0 - PHOTON_MATCH) * stored as f64).ceil() as u64 + 2;
    v.check(
        unmatched_ab <= allow_match && unmatched_ba <= allow_match,
        || {
            format!(
                "light {l}: {unmatched_ab} / {unmatched_ba} stored photons without a match \
             (allowance {allow_match})"
            )
        },
    );
}

/// Photons of `a` without a photon of `b` at the same place (within
/// `PHOTON_POSITION_REL` of the scene diagonal: `trace_photons`' argument) with the same
/// tile, normal and direction within a packing quantum or two, and power within one rgb9e5
/// step (2^-9 of the largest channel: the same float flux may round to neighbouring
/// mantissas when it differs by an ulp).
pub(crate) fn unmatched(a: &[GiPhoton], b: &[GiPhoton], diagonal: f32) -> u64 {
    use caustica_core::math::packing::unpack_rgb9e5;
    let tol = PHOTON_POSITION_REL * diagonal;
    let close = |x: &GiPhoton, y: &GiPhoton| {
        let d = glam::Vec3::from(x.position) - glam::Vec3::from(y.position);
        let (px, py) = (unpack_rgb9e5(x.power), unpack_rgb9e5(y.power));
        let step = px.max_element().max(py.max_element()) * (2.0 / 512.0);
        d.length() <= tol
            && x.tile == y.tile
            && (px - py).abs().max_element() <= step
            && unpack_unit_vector(x.normal).dot(unpack_unit_vector(y.normal)) >= 1.0 - 1e-4
    };
    a.iter().filter(|x| !b.iter().any(|y| close(x, y))).count() as u64
}
