//! `seed_clusters`: a cluster's footprint and the rectangle test are exact in f32 on
//! every port (powers of two and small integers: `cluster_overlaps_rect`), so every
//! backend must list **exactly** the clusters core's test keeps, and count them bitwise;
//! only the list's order is free (a GPU's atomics), so it is compared as a set. When the
//! appends run past the capacity, the length still counts every one, and the entries
//! written are as many distinct kept clusters as fit. The proptest in
//! `conformance/tests/cluster_seed.rs` draws grids, windows, rectangles (empty, inside,
//! straddling, on cluster edges, the whole plane) and capacities from 0 past the count.

use crate::harness::fixture::run_and_free;
use crate::harness::verdict::Verdict;
use caustica_core::backend::{read_buf, Backend};
use caustica_core::device::layout::SeedParams;
use caustica_core::kernels::SeedClusters;
use caustica_core::math::photon_clusters::{cluster_overlaps_rects, seed_cluster};
use caustica_core::recording::Recording;

/// Entries of the list ahead of the seed (another writer's), kept by every backend.
const BEFORE: u32 = 3;
/// What an entry no one wrote holds.
const UNWRITTEN: u32 = u32::MAX;

/// The list (`BEFORE` entries already there, then `capacity` more) and its length that
/// `seed_clusters` leaves on `b`.
pub fn run_seed_clusters(
    b: &mut dyn Backend,
    params: &SeedParams,
    rects: &[[f32; 4]],
) -> Result<(Vec<u32>, u32), String> {
    let mut rec = Recording::new();
    let caster_rects = if rects.is_empty() {
        rec.create(1, "caster rectangles")
    } else {
        rec.upload(rects, "caster rectangles")
    };
    let capacity = BEFORE + params.capacity;
    let list = rec.upload(&vec![UNWRITTEN; capacity as usize], "cluster list");
    let list_length = rec.upload(&[BEFORE], "list length");
    rec.kernel(SeedClusters {
        params: SeedParams {
            capacity,
            rect_count: rects.len() as u32,
            ..*params
        },
        caster_rects,
        list,
        list_length,
    });
    run_and_free(b, "seed_clusters", &rec, |b| {
        Ok((read_buf(b, list)?, read_buf(b, list_length)?[0]))
    })
}

/// The clusters core's test keeps, in window order.
pub fn seeded_clusters(params: &SeedParams, rects: &[[f32; 4]]) -> Vec<u32> {
    let p = params;
    (0..p.window_w * p.window_h)
        .map(|t| seed_cluster(t, p.grid_w, (p.first_x, p.first_y), (p.window_w, p.window_h)))
        .filter(|&c| cluster_overlaps_rects(c, p.grid_w, rects))
        .collect()
}

/// `seed_clusters` on the reference `r` and the candidate `c`, each against core's
/// [`seeded_clusters`] (see the module doc).
pub fn check_seed_clusters(
    r: &mut dyn Backend,
    c: &mut dyn Backend,
    params: &SeedParams,
    rects: &[[f32; 4]],
) -> Result<Verdict, String> {
    let mut v = Verdict::new("seed_clusters");
    let expected = seeded_clusters(params, rects);
    let mut sorted = expected.clone();
    sorted.sort_unstable();
    let runs = [
        ("reference", run_seed_clusters(r, params, rects)?),
        ("candidate", run_seed_clusters(c, params, rects)?),
    ];
    for (who, (list, length)) in runs {
        v.check(length == BEFORE + expected.len() as u32, || {
            format!(
                "{who}: length {length}, core keeps {} after {BEFORE}",
                expected.len()
            )
        });
        v.check(list[..BEFORE as usize].iter().all(|&e| e == UNWRITTEN), || {
            format!("{who}: wrote below the list's length")
        });
        let mut written: Vec<u32> = list[BEFORE as usize..]
            .iter()
            .copied()
            .filter(|&e| e != UNWRITTEN)
            .collect();
        written.sort_unstable();
        let fits = expected.len().min(params.capacity as usize);
        let distinct = written.windows(2).all(|w| w[0] < w[1]);
        let kept = written.iter().all(|e| sorted.binary_search(e).is_ok());
        v.check(written.len() == fits && distinct && kept, || {
            format!(
                "{who}: wrote {} entries ({}distinct), {} fit of the {} core keeps",
                written.len(),
                if distinct { "" } else { "not " },
                fits,
                expected.len()
            )
        });
        if fits == expected.len() {
            v.check(written == sorted, || format!("{who}: a different set"));
        }
    }
    v.note(format!(
        "{} of {} clusters kept, capacity {}",
        expected.len(),
        params.window_w * params.window_h,
        params.capacity
    ));
    Ok(v)
}
