//! AdaptiveCaustics' kernels (`trace_photons`' `ADAPTIVE` variant and `refine_clusters`),
//! checked on the fixture's scene with a caustic atlas laid out as for CausticMap's check
//! ([`super::gather_caustic_map`]): nothing to check where the scene has no receiver tile or no
//! light sees a caster.
//!
//! - The adaptive trace: the first light view plane of the first light that has one, on a
//!   32x32 grid, every one of its 256 clusters (in a shuffled list behind four unused
//!   entries, so `first` and the list are really read): slot `i` is one photon on both
//!   backends, so the slots are compared one by one: stored or not, met a caster or not,
//!   its triangle and the atlas texel under its uv, its flux within
//!   [`FluxMatch`]. A path that diverges (the argument of
//!   [`crate::harness::tolerance::PATH_DIVERGENCE`]) or lands within a rounding of a texel
//!   edge changes one slot, so at most [`divergence_allowance`] slots may differ. The
//!   counters (stored, path ends) are the same photons' and get the same allowance.
//! - `refine_clusters` on the CPU's slots (so only the kernel under test differs), at an
//!   inner level under the error metric (discards, converged outputs and refinements all
//!   occur on a lit scene; with Wyman 2009's photon test and with the casters' projected bounds)
//!   with a tolerance of 4 texels, at the finest level under the level metric (everything
//!   relevant is output), and outputting converged entries whose footprints (1 to 4
//!   texels) splat over several texels: integer decisions and integer atomics, so the cluster counts,
//!   the child list as a multiset (its order is the atomics' arrival order), the atlas
//!   sums and the counters must be **bitwise** equal.
//! - The fused finest level ([`TraversalSettings::fused_finest`](caustica_core::techniques::adaptive_caustics::TraversalSettings::fused_finest): the adaptive trace with
//!   `fused_deposit`), on the whole list and launched from its record over half of it:
//!   the atlas sums, centroid sums, reach mask and counters bitwise those of the CPU's
//!   atlas deposit of the stored slots that the same backend's adaptive trace wrote.
//! - The screen target ([`check_screen_target`]): the trace in world space (slots
//!   compared as above, positions within [`PHOTON_POSITION_REL`] of the scene), and
//!   `refine_clusters` on the CPU's world slots with the fixture's camera. At the finest
//!   level nothing is projected: counts, lists, counters and the output photons (as a
//!   multiset) must be bitwise equal. At an inner level under the error metric a
//!   photon's pixel is a projection (two dots and a division, as `deposit_screen`'s), so
//!   a photon within a few ulps of a pixel edge may flip a cluster between converged and
//!   refined: at most [`DEPOSIT_PHOTON_CHANGES`] of the slots (plus 2) may change a fate.

use super::gather_caustic_map::{cpu_deposit, layout};
use super::trace_photons::run_fused_trace_as;
use crate::harness::fixture::{run_and_free, Fixture, ReferenceInputs};
use crate::harness::tolerance::{
    divergence_allowance, FluxMatch, DEPOSIT_PHOTON_CHANGES, PHOTON_POSITION_REL,
};
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, read_photon_map, Backend};
use caustica_core::device::layout::*;
use caustica_core::frame::emission::light_view_plane::{light_view_planes, LightViewPlane};
use caustica_core::frame::host::caster_boxes;
use caustica_core::frame::receivers::atlas::layout::AtlasLayout;
use caustica_core::kernels::{
    ClusterBatch, DispatchArgs, DispatchRecord, RefineClusters, TracePhotons,
};
use caustica_core::math::map_gather::atlas_texel_index;
use caustica_core::math::photon_clusters::{
    cluster_entry, cluster_metric, cluster_relevance, cluster_target, entry_cluster, slot_stored,
    MAX_ERROR_TEXELS, NO_TRIANGLE,
};
use caustica_core::math::rng::pcg_hash;
use caustica_core::recording::Recording;
use caustica_core::techniques::adaptive_caustics::caster_rects;

/// Side of the checked plane's grid.
const GRID: u32 = 32;
/// Unused list entries before the clusters.
const FIRST: u32 = 4;

fn plane(fx: &Fixture) -> Option<(u32, LightViewPlane)> {
    fx.scene.lights.iter().enumerate().find_map(|(i, l)| {
        let p = light_view_planes(
            l,
            fx.ds.caster_bounds,
            fx.ds.bounds,
            GRID,
            caustica_core::frame::emission::PointEmission::CasterCone,
        )
        .ok()?;
        let mut p = p[0];
        p.resolution = (GRID, GRID);
        Some((i as u32, p))
    })
}

/// The cluster list: `FIRST` unused entries, then every cluster of the grid, shuffled.
fn cluster_list() -> Vec<u32> {
    let n = (GRID / 2) * (GRID / 2);
    let mut ids: Vec<u32> = (0..n).collect();
    ids.sort_by_key(|&c| pcg_hash(c ^ 0x5eed));
    let mut list = vec![n + 7; FIRST as usize];
    list.extend(ids);
    list
}

fn quanta() -> (f32, f32) {
    (2f32.powi(-24), 2f32.powi(-20))
}

/// How a check launches a kernel over a list: the list length the device holds (the
/// kernel takes entries `FIRST .. length`, at most the recorded bound) and whether the
/// launch's shape comes from `dispatch_args` (an indirect launch) or is the bound.
#[derive(Clone, Copy, Debug)]
pub struct ListLaunch {
    /// The list's length word.
    pub length: u32,
    /// Launched from a `dispatch_args` record.
    pub indirect: bool,
}

impl ListLaunch {
    /// Every entry of `list`, the bound launched.
    pub fn whole(list: &[u32]) -> ListLaunch {
        ListLaunch {
            length: list.len() as u32,
            indirect: false,
        }
    }
}

/// Records `dispatch_args` over one row `[FIRST, bound, per_item, 0]` reading `length`,
/// when `l` is indirect: the record the launch reads.
fn dispatch(
    rec: &mut Recording,
    l: ListLaunch,
    length: caustica_core::device::handle::Buf<u32>,
    (bound, per_item): (u32, u32),
) -> Option<DispatchRecord> {
    l.indirect.then(|| {
        let table = rec.upload(&[[FIRST, bound, per_item, 0]], "dispatch rows");
        let args = rec.create(8, "dispatch records");
        rec.kernel(DispatchArgs {
            table,
            counts: length,
            args,
        });
        DispatchRecord { args, record: 0 }
    })
}

/// Runs the adaptive trace of every listed cluster on `b`: the slots and the counters.
fn run_trace(
    fx: &Fixture,
    b: &mut dyn Backend,
    (light, p, surface): (u32, &LightViewPlane, bool),
    list: &[u32],
) -> Result<(Vec<Photon>, Vec<u32>), String> {
    run_trace_as(fx, b, (light, p, surface), list, ListLaunch::whole(list))
}

/// [`run_trace`] with the list's length and launch of `l` (slots past the live clusters
/// stay zero).
fn run_trace_as(
    fx: &Fixture,
    b: &mut dyn Backend,
    (light, p, surface): (u32, &LightViewPlane, bool),
    list: &[u32],
    l: ListLaunch,
) -> Result<(Vec<Photon>, Vec<u32>), String> {
    let count = 4 * (list.len() as u32 - FIRST);
    let mut variant = caustica_core::frame::plan::SceneFeatures::of(&fx.scene).trace_variant();
    variant.surface_store = surface;
    variant.adaptive = true;
    let mut rec = Recording::new();
    let clusters = rec.upload(list, "clusters");
    let photons = rec.create(count, "photon slots");
    let photon_count = rec.upload(&[l.length], "cluster list length");
    let counters = rec.upload(&[0u32; counter::WORDS], "counters");
    let shape = dispatch(&mut rec, l, photon_count, (count / 4, 4));
    rec.kernel(TracePhotons {
        scene: fx.args,
        variant,
        params: p.trace_params(light, (FIRST, count), 0xada9, 12, 1e-4, quanta().0),
        photons,
        photon_count,
        counters,
        clusters: Some(ClusterBatch {
            list: clusters,
            dispatch: shape,
        }),
        deposit: None,
    });
    run_and_free(b, "trace_photons (adaptive)", &rec, |b| {
        let n = read_buf(b, photon_count)?;
        if n[0] != l.length {
            return Err(caustica_core::backend::BackendError::BadArgument(
                "the adaptive trace wrote its list length".into(),
            ));
        }
        Ok((read_buf(b, photons)?, read_buf(b, counters)?))
    })
}

/// What `refine_clusters` left on a backend.
#[derive(PartialEq, Debug)]
struct Refined {
    counts: Vec<u32>,
    children: Vec<u32>,
    converged: Vec<u32>,
    counters: Vec<u32>,
    atlas: Vec<DepositTexel>,
    /// The atlas's centroid sums.
    centroids: Vec<u32>,
    /// The screen target's output photons, sorted by their bits.
    outputs: Vec<Photon>,
}

/// The deposit target of a `refine_clusters` run: the atlas, or the screen of `camera`.
enum Target<'a> {
    Atlas(&'a AtlasLayout),
    Screen(GpuCamera),
}

/// Children already in the list before the step (the kernel appends after them).
const BEFORE: u32 = 7;

fn run_refine(
    b: &mut dyn Backend,
    target: &Target,
    (list, rects): (&[u32], &[[f32; 4]]),
    slots: &[Photon],
    step: (u32, u32, u32, u32, u32),
) -> Result<Refined, String> {
    let count = list.len() as u32 - FIRST;
    let launch = ListLaunch::whole(list);
    run_refine_as(
        b,
        target,
        (list, rects),
        slots,
        step,
        (launch, BEFORE + 4 * count),
    )
}

/// [`run_refine`] with the list's length and launch of `l` and a child list of
/// `capacity` entries (refined clusters past it overflow into the converged list).
fn run_refine_as(
    b: &mut dyn Backend,
    target: &Target,
    (list, rects): (&[u32], &[[f32; 4]]),
    slots: &[Photon],
    (level, finest, metric, relevance, error_texels): (u32, u32, u32, u32, u32),
    (l, capacity): (ListLaunch, u32),
) -> Result<Refined, String> {
    let count = list.len() as u32 - FIRST;
    let (fq, hq) = quanta();
    let mut rec = Recording::new();
    let clusters = rec.upload(list, "clusters");
    let caster_rects = rec.upload(rects, "caster rectangles");
    let photons = rec.upload(slots, "photon slots");
    let (no_tiles, no_tile_rects) = (vec![NO_TILE], vec![[0u32; 4]]);
    let (tt, tl, atlas_texels, atlas_width, camera, kind) = match target {
        Target::Atlas(l) => (
            &l.triangle_tiles,
            &l.tiles,
            l.texels.len() as u32,
            l.plan.size.0,
            GpuCamera::default(),
            cluster_target::ATLAS,
        ),
        Target::Screen(cam) => (
            &no_tiles,
            &no_tile_rects,
            1,
            1,
            *cam,
            cluster_target::SCREEN,
        ),
    };
    let triangle_tiles = rec.upload(tt, "triangle tiles");
    let tiles = rec.upload(tl, "tiles");
    let children = rec.upload(&vec![u32::MAX; capacity as usize], "children");
    let converged = rec.upload(&vec![u32::MAX; count as usize], "converged");
    let converged_count = rec.upload(&[0u32], "converged count");
    let list_length = rec.upload(&[l.length], "cluster list length");
    let shape = dispatch(&mut rec, l, list_length, (count, 1));
    let mut start = [0u32; cluster_count::WORDS];
    start[cluster_count::CHILDREN] = BEFORE;
    let counts = rec.upload(&start, "cluster counts");
    let counters = rec.upload(&[0u32; counter::WORDS], "counters");
    let atlas = rec.create_photon_map(atlas_texels);
    rec.clear_photon_map(&atlas);
    let centroids = rec.create(
        atlas_texels * caustica_core::math::map_gather::CENTROID_WORDS,
        "centroid sums",
    );
    rec.clear(centroids);
    let output_photons = rec.upload(&vec![Photon::default(); 4 * count as usize], "outputs");
    let output_count = rec.upload(&[0u32], "output count");
    rec.kernel(RefineClusters {
        params: RefineParams {
            atlas_width,
            flux_quantum: fq,
            hit_distance_quantum: hq,
            level,
            finest,
            metric,
            error_from_level: 0,
            grid_w: GRID,
            first: FIRST,
            count,
            children_capacity: capacity,
            relevance,
            rect_count: rects.len() as u32,
            deposit_target: kind,
            error_texels,
            _pad: 0,
            camera,
        },
        clusters,
        list_length,
        caster_rects,
        photons,
        triangle_tiles,
        tiles,
        children,
        converged,
        converged_count,
        cluster_counts: counts,
        counters,
        atlas,
        output_photons,
        output_count,
        dispatch: shape,
        centroids,
    });
    run_and_free(b, "refine_clusters", &rec, |b| {
        let counts = read_buf(b, counts)?;
        let mut kids = read_buf(b, children)?;
        kids.truncate(counts[cluster_count::CHILDREN].min(capacity) as usize);
        kids[BEFORE as usize..].sort_unstable();
        let mut conv = read_buf(b, converged)?;
        let listed = read_buf(b, converged_count)?[0];
        if listed != counts[cluster_count::CONVERGED] + counts[cluster_count::OVERFLOW] {
            return Err(caustica_core::backend::BackendError::BadArgument(format!(
                "refine_clusters listed {listed} converged entries, counted {:?}",
                counts
            )));
        }
        conv.truncate(listed.min(count) as usize);
        conv.sort_unstable();
        let n = read_buf(b, output_count)?[0].min(4 * count) as usize;
        let mut outputs = read_buf(b, output_photons)?;
        outputs.truncate(n);
        outputs.sort_by_key(|ph| {
            let f = |x: &[f32]| x.iter().map(|v| v.to_bits()).collect::<Vec<u32>>();
            (
                f(&ph.position),
                ph.hit_distance.to_bits(),
                f(&ph.flux),
                ph.direction,
            )
        });
        Ok(Refined {
            outputs,
            counts,
            children: kids,
            converged: conv,
            counters: read_buf(b, counters)?,
            atlas: read_photon_map(b, &atlas)?,
            centroids: read_buf(b, centroids)?,
        })
    })
}

/// The atlas texel of a stored slot, `NO_TILE` without a tile.
fn texel(l: &AtlasLayout, ph: &Photon) -> u32 {
    match l.triangle_tiles.get(ph.direction as usize) {
        Some(&t) if t != NO_TILE => atlas_texel_index(
            l.tiles[t as usize],
            glam::Vec2::new(ph.position[0], ph.position[1]),
            l.plan.size.0,
        ),
        _ => NO_TILE,
    }
}

/// `refine_clusters` of `list` on the reference `r` and the candidate `c` with launch and
/// child-list capacity `shape`: the reference's fates add up to the live clusters, and the
/// candidate's results are the reference's, bitwise (with a child list too short for
/// every refinement, which clusters find room is the atomics' arrival order: the lists
/// are then compared as the clusters they hold). Returns the reference's counts.
fn check_refinement(
    v: &mut Verdict,
    what: &str,
    (r, c): (&mut dyn Backend, &mut dyn Backend),
    (target, list, rects, slots): (&Target, &[u32], &[[f32; 4]], &[Photon]),
    step: (u32, u32, u32, u32, u32),
    shape: (ListLaunch, u32),
) -> Result<Vec<u32>, String> {
    let a = run_refine_as(r, target, (list, rects), slots, step, shape)?;
    let b = run_refine_as(c, target, (list, rects), slots, step, shape)?;
    let (launch, capacity) = shape;
    let count = list.len() as u32 - FIRST;
    let live = launch.length.saturating_sub(FIRST).min(count);
    let w = |i: usize| a.counts[i];
    let refined = (w(cluster_count::CHILDREN) - BEFORE) / 4 - w(cluster_count::OVERFLOW);
    let fates = refined
        + w(cluster_count::OUTPUT)
        + w(cluster_count::DISCARDED)
        + w(cluster_count::CONVERGED)
        + w(cluster_count::OVERFLOW);
    v.check(fates == live, || {
        format!("{what}: cpu fates {:?} do not add up to {live}", a.counts)
    });
    let same = if capacity < BEFORE + 4 * count {
        a.counts == b.counts
            && a.counters == b.counters
            && a.atlas == b.atlas
            && a.centroids == b.centroids
            && a.outputs == b.outputs
            && held_clusters(&a) == held_clusters(&b)
    } else {
        a == b
    };
    v.check(same, || {
        format!(
            "{what}: cpu and candidate differ (counts {:?} vs {:?})",
            a.counts, b.counts
        )
    });
    Ok(a.counts)
}

/// The clusters a refinement's lists hold, sorted: each child's parent (once per four
/// children) and each converged or overflowed entry's cluster.
fn held_clusters(r: &Refined) -> Vec<u32> {
    let half = GRID / 2;
    let mut held: Vec<u32> = r.children[BEFORE as usize..]
        .iter()
        .map(|&c| (c / GRID / 2) * half + (c % GRID) / 2)
        .collect();
    held.sort_unstable();
    held.dedup();
    held.extend(r.converged.iter().map(|&e| entry_cluster(e)));
    held.sort_unstable();
    held
}

/// Both kernels on the fixture's scene (see the module doc).
pub fn check_adaptive_caustics(
    fx: &Fixture,
    _inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("trace_photons (adaptive) + refine_clusters");
    let (Some(l), Some((light, p))) = (layout(fx), plane(fx)) else {
        return Ok(v);
    };
    let list = cluster_list();
    let (sa, ca) = run_trace(fx, r, (light, &p, true), &list)?;
    let (sb, cb) = run_trace(fx, c, (light, &p, true), &list)?;
    let n = sa.len() as u64;
    let k = divergence_allowance(n);
    let tol = FluxMatch::of(
        &fx.scene,
        fx.settings.frame.dispersion,
        PHOTON_POSITION_REL * fx.ds.bounds.diagonal(),
    );
    let same = |a: &Photon, b: &Photon| {
        let stored = a.direction != NO_TRIANGLE;
        stored == (b.direction != NO_TRIANGLE)
            && a.position[2] == b.position[2]
            && (!stored
                || (a.direction == b.direction
                    && texel(&l, a) == texel(&l, b)
                    && tol.close(a.flux, b.flux)))
    };
    let differ = sa.iter().zip(&sb).filter(|(a, b)| !same(a, b)).count() as u64;
    v.check(differ <= k, || {
        format!("{differ} of {n} photon slots differ (allowance {k})")
    });
    for (word, what) in [
        (counter::STORED, "stored"),
        (counter::NO_SPECULAR, "no specular"),
        (counter::ESCAPED, "escaped"),
        (counter::NEGLIGIBLE, "negligible"),
        (counter::BOUNCE_LIMIT, "bounce limit"),
    ] {
        v.check((ca[word] as u64).abs_diff(cb[word] as u64) <= k, || {
            format!("{what}: cpu {} vs {} (allowance {k})", ca[word], cb[word])
        });
    }
    let stored = sa.iter().filter(|s| s.direction != NO_TRIANGLE).count() as u64;
    v.check(stored == ca[counter::STORED] as u64, || {
        format!(
            "cpu: {stored} stored slots, stored counter {}",
            ca[counter::STORED]
        )
    });
    v.note(format!("{stored} of {n} slots stored"));
    let rects = caster_rects(&p, &boxes_of(&fx.ds));
    // converged entries as the resample step reads them: footprints of 1 to 4 texels
    let spread_list: Vec<u32> = list
        .iter()
        .enumerate()
        .map(|(i, &e)| {
            if i < FIRST as usize {
                e
            } else {
                cluster_entry(e, 1 + pcg_hash(e) % MAX_ERROR_TEXELS)
            }
        })
        .collect();
    for (what, step, list) in [
        (
            "inner level, error metric, photon relevance",
            (1, 3, cluster_metric::ERROR, cluster_relevance::PHOTONS, 1),
            &list,
        ),
        (
            "inner level, error metric, bounds relevance",
            (1, 3, cluster_metric::ERROR, cluster_relevance::BOUNDS, 1),
            &list,
        ),
        (
            "inner level, error metric, 4-texel tolerance",
            (1, 3, cluster_metric::ERROR, cluster_relevance::BOUNDS, 4),
            &list,
        ),
        (
            "finest level, level metric, bounds relevance",
            (2, 2, cluster_metric::LEVEL, cluster_relevance::BOUNDS, 1),
            &list,
        ),
        (
            "converged clusters output over their footprints",
            (2, 2, cluster_metric::LEVEL, cluster_relevance::BOUNDS, 1),
            &spread_list,
        ),
    ] {
        let a = run_refine(r, &Target::Atlas(&l), (list, &rects), &sa, step)?;
        let b = run_refine(c, &Target::Atlas(&l), (list, &rects), &sa, step)?;
        let clusters = list.len() as u32 - FIRST;
        let refined = (a.counts[cluster_count::CHILDREN] - BEFORE) / 4;
        v.check(
            refined
                + a.counts[cluster_count::OUTPUT]
                + a.counts[cluster_count::DISCARDED]
                + a.counts[cluster_count::CONVERGED]
                == clusters,
            || {
                format!(
                    "{what}: cpu fates {:?} do not add up to {clusters}",
                    a.counts
                )
            },
        );
        v.check(a.counts == b.counts, || {
            format!(
                "{what}: cluster counts cpu {:?} vs {:?}",
                a.counts, b.counts
            )
        });
        v.check(a.children == b.children, || {
            format!("{what}: the child lists differ as multisets")
        });
        v.check(a.converged == b.converged, || {
            format!("{what}: the converged lists differ as multisets")
        });
        v.check(a.counters == b.counters, || {
            format!("{what}: counters cpu {:?} vs {:?}", a.counters, b.counters)
        });
        let equal = a.atlas.iter().zip(&b.atlas).filter(|(x, y)| x == y).count();
        v.check(equal == a.atlas.len(), || {
            format!(
                "{what}: {} of {} atlas texels differ (integer atomics must agree bitwise)",
                a.atlas.len() - equal,
                a.atlas.len()
            )
        });
    }
    // the device-driven shapes: a list shorter than the bound launched from its
    // dispatch record, and a child list too small for every refined cluster (they
    // overflow into the converged list, counted)
    let count = list.len() as u32 - FIRST;
    let step = (1, 3, cluster_metric::ERROR, cluster_relevance::BOUNDS, 1);
    for (what, launch, capacity) in [
        (
            "indirect launch of half the list",
            ListLaunch {
                length: FIRST + count / 2,
                indirect: true,
            },
            BEFORE + 4 * count,
        ),
        (
            "a child list of a quarter of the refinements",
            ListLaunch::whole(&list),
            BEFORE + count,
        ),
        (
            "an empty list launched indirectly",
            ListLaunch {
                length: FIRST / 2,
                indirect: true,
            },
            BEFORE + 4 * count,
        ),
    ] {
        let counts = check_refinement(
            &mut v,
            what,
            (r, c),
            (&Target::Atlas(&l), &list, &rects, &sa),
            step,
            (launch, capacity),
        )?;
        v.note(format!("{what}: counts {counts:?}"));
    }
    // the trace launched from its record over half the list: those slots as the whole
    // list's, the rest untouched
    let half = ListLaunch {
        length: FIRST + count / 2,
        indirect: true,
    };
    let (ha, _) = run_trace_as(fx, r, (light, &p, true), &list, half)?;
    let (hb, _) = run_trace_as(fx, c, (light, &p, true), &list, half)?;
    let live = 4 * (count / 2) as usize;
    let untouched = |s: &[Photon]| s[live..].iter().all(|ph| *ph == Photon::default());
    v.check(untouched(&ha) && untouched(&hb), || {
        "an indirect adaptive trace wrote slots past its live clusters".into()
    });
    v.check(ha[..live] == sa[..live], || {
        "the cpu's indirect trace of half the list differs from its whole trace".into()
    });
    let differ = ha[..live]
        .iter()
        .zip(&hb[..live])
        .filter(|(a, b)| !same(a, b))
        .count() as u64;
    v.check(differ <= k, || {
        format!("indirect trace: {differ} of {live} slots differ (allowance {k})")
    });
    for (what, launch) in [("whole list", ListLaunch::whole(&list)), ("indirect half", half)] {
        check_fused_clusters(&mut v, what, fx, c, (light, &p, &l), &list, launch)?;
    }
    Ok(v)
}

/// The fused finest level on `c`: the adaptive trace with `fused_deposit` over `list`
/// (launched as `launch`) deposits its stored photons itself. Checked against the CPU's
/// atlas deposit of the stored slots that `c`'s own adaptive trace wrote (the same code
/// up to where a stored photon goes): integer atomics of power-of-two quanta, so the
/// sums, the centroid sums, the reach mask and the counters (the trace's plus the
/// deposit's) must be **bitwise** equal.
fn check_fused_clusters(
    v: &mut Verdict,
    what: &str,
    fx: &Fixture,
    c: &mut dyn Backend,
    (light, p, l): (u32, &LightViewPlane, &AtlasLayout),
    list: &[u32],
    launch: ListLaunch,
) -> Result<(), String> {
    let (slots, trace_counters) = run_trace_as(fx, c, (light, p, true), list, launch)?;
    // a stored slot (of a live cluster: the others stay zero) is the stored photon with
    // its mark in position.z
    let live = launch.length.saturating_sub(FIRST).min(list.len() as u32 - FIRST);
    let stored: Vec<Photon> = slots[..4 * live as usize]
        .iter()
        .filter(|s| s.direction != NO_TRIANGLE)
        .map(|s| Photon {
            position: [s.position[0], s.position[1], 0.0],
            ..*s
        })
        .collect();
    let (es, deposit_counters, er, ecentroids) = cpu_deposit(l, &stored);
    let ec: Vec<u32> = trace_counters
        .iter()
        .zip(&deposit_counters)
        .map(|(t, d)| t.wrapping_add(*d))
        .collect();
    let count = 4 * (list.len() as u32 - FIRST);
    let mut variant = caustica_core::frame::plan::SceneFeatures::of(&fx.scene).trace_variant();
    variant.surface_store = true;
    variant.adaptive = true;
    variant.fused_deposit = true;
    let (sums, counters, reach, centroids) = run_fused_trace_as(fx, c, l, variant, |rec| {
        let clusters = rec.upload(list, "clusters");
        let length = rec.upload(&[launch.length], "cluster list length");
        let shape = dispatch(rec, launch, length, (count / 4, 4));
        let params = p.trace_params(light, (FIRST, count), 0xada9, 12, 1e-4, quanta().0);
        let batch = ClusterBatch {
            list: clusters,
            dispatch: shape,
        };
        (params, length, Some(batch))
    })?;
    v.check(counters == ec, || {
        format!("fused trace, {what}: counters differ: expected {ec:?}, fused {counters:?}")
    });
    v.check(reach == er && centroids == ecentroids, || {
        format!("fused trace, {what}: the reach mask or the centroid sums differ")
    });
    let equal = es.iter().zip(&sums).filter(|(a, b)| a == b).count();
    v.check(equal == es.len() && sums.len() == es.len(), || {
        format!(
            "fused trace, {what}: {} of {} atlas texels differ from the deposit of the \
             trace's {} stored slots (integer atomics must agree bitwise)",
            es.len() - equal,
            es.len(),
            stored.len()
        )
    });
    v.note(format!(
        "fused trace, {what}: {} stored photons deposited",
        stored.len()
    ));
    Ok(())
}

/// The screen target's trace and refinement (see the module doc).
pub fn check_screen_target(
    fx: &Fixture,
    _inputs: &ReferenceInputs,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
) -> Result<Verdict, String> {
    let mut v = Verdict::new("trace_photons (adaptive, world) + refine_clusters (screen)");
    let Some((light, p)) = plane(fx) else {
        return Ok(v);
    };
    let list = cluster_list();
    let (sa, _) = run_trace(fx, r, (light, &p, false), &list)?;
    let (sb, _) = run_trace(fx, c, (light, &p, false), &list)?;
    let n = sa.len() as u64;
    let k = divergence_allowance(n);
    let reach = PHOTON_POSITION_REL * fx.ds.bounds.diagonal();
    let tol = FluxMatch::of(&fx.scene, fx.settings.frame.dispersion, reach);
    let stored = |ph: &Photon| slot_stored(ph.flux);
    let same = |a: &Photon, b: &Photon| {
        stored(a) == stored(b)
            && if stored(a) {
                glam::Vec3::from(a.position).distance(glam::Vec3::from(b.position)) <= reach
                    && tol.close(a.flux, b.flux)
            } else {
                a.position[2] == b.position[2]
            }
    };
    let differ = sa.iter().zip(&sb).filter(|(a, b)| !same(a, b)).count() as u64;
    v.check(differ <= k, || {
        format!("{differ} of {n} world-space photon slots differ (allowance {k})")
    });
    let kept = sa.iter().filter(|s| stored(s)).count();
    v.note(format!("{kept} of {n} world-space slots stored"));
    let rects = caster_rects(&p, &boxes_of(&fx.ds));
    let screen = Target::Screen(fx.camera);
    let clusters = list.len() as u64 - FIRST as u64;
    for (what, step, exact) in [
        (
            "finest level, level metric",
            (2, 2, cluster_metric::LEVEL, cluster_relevance::BOUNDS, 1),
            true,
        ),
        (
            "inner level, error metric",
            (1, 3, cluster_metric::ERROR, cluster_relevance::BOUNDS, 1),
            false,
        ),
    ] {
        let a = run_refine(r, &screen, (&list, &rects), &sa, step)?;
        let b = run_refine(c, &screen, (&list, &rects), &sa, step)?;
        let listed = a.outputs.len() as u32;
        v.check(listed == a.counts[cluster_count::OUTPUT_PHOTONS], || {
            format!(
                "{what}: cpu listed {listed} photons, counted {:?}",
                a.counts
            )
        });
        if exact {
            v.check(a == b, || {
                format!(
                    "{what}: cpu and candidate differ (counts {:?} vs {:?}, {} vs {} outputs)",
                    a.counts,
                    b.counts,
                    a.outputs.len(),
                    b.outputs.len()
                )
            });
        } else {
            // a flipped pixel moves one cluster between converged and refined
            let allow = (DEPOSIT_PHOTON_CHANGES * n as f64).ceil() as u64 + 2;
            let moved = (a.counts[cluster_count::CONVERGED] as u64)
                .abs_diff(b.counts[cluster_count::CONVERGED] as u64);
            v.check(moved <= allow.min(clusters), || {
                format!(
                    "{what}: converged clusters cpu {:?} vs {:?} (allowance {allow})",
                    a.counts, b.counts
                )
            });
            v.check(
                a.counts[cluster_count::DISCARDED] == b.counts[cluster_count::DISCARDED],
                || format!("{what}: discards differ: {:?} vs {:?}", a.counts, b.counts),
            );
        }
    }
    Ok(v)
}

/// The casters' bounding boxes of `ds`, in object order.
fn boxes_of(
    ds: &caustica_core::device::device_scene::DeviceScene,
) -> Vec<caustica_core::math::geometry::Aabb> {
    caster_boxes(ds).into_iter().map(|(_, b)| b).collect()
}

/// `refine_clusters` launched from its dispatch record over lists of each of `lengths`
/// (the device's list length: 0 to past the bound), on the CPU's slots of the fixture's
/// plane: bitwise the CPU's, and the fates add up to the live clusters.
pub fn check_indirect_refinement(
    fx: &Fixture,
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    lengths: &[u32],
) -> Result<Verdict, String> {
    let mut v = Verdict::new("refine_clusters (indirect, any list length)");
    let (Some(l), Some((light, p))) = (layout(fx), plane(fx)) else {
        return Ok(v);
    };
    let list = cluster_list();
    let (slots, _) = run_trace(fx, r, (light, &p, true), &list)?;
    let rects = caster_rects(&p, &boxes_of(&fx.ds));
    let count = list.len() as u32 - FIRST;
    let step = (1, 3, cluster_metric::ERROR, cluster_relevance::BOUNDS, 1);
    for &length in lengths {
        let launch = ListLaunch {
            length,
            indirect: true,
        };
        check_refinement(
            &mut v,
            &format!("length {length}"),
            (r, c),
            (&Target::Atlas(&l), &list, &rects, &slots),
            step,
            (launch, BEFORE + 4 * count),
        )?;
    }
    v.note(format!("{} list lengths, bound {count}", lengths.len()));
    Ok(v)
}
