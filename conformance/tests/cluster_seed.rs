//! AdaptiveCaustics' bounds seed: `seed_clusters` on every backend against core's test
//! and the CPU, with proptest-drawn grids, windows, caster rectangles and capacities
//! (from 0 past the clusters kept); and the host's window ([`seed_window`]) never leaves
//! out a cluster the test keeps.

use caustica_conformance::harness;
use caustica_conformance::kernels::seed_clusters::{check_seed_clusters, seeded_clusters};
use caustica_conformance::strategies;
use caustica_core::device::layout::SeedParams;
use caustica_core::techniques::adaptive_caustics::{seed_window, EMPTY_RECT};
use proptest::prelude::*;
use proptest::test_runner::TestRunner;

/// A rectangle coordinate: anywhere, on a cluster edge of a 2^k grid (the exact
/// boundary case), or far outside the plane.
fn coordinate() -> impl Strategy<Value = f32> {
    prop_oneof![
        -1.2f32..1.2,
        (0u32..=64, 2u32..8).prop_map(|(i, k)| i as f32 / (1u32 << k) as f32 * 2.0 - 1.0),
        Just(-1e30f32),
        Just(1e30f32),
    ]
}

/// Up to four rectangles (some empty: `EMPTY_RECT`, or corners swapped).
fn rects() -> impl Strategy<Value = Vec<[f32; 4]>> {
    let rect = prop_oneof![
        4 => (coordinate(), coordinate(), coordinate(), coordinate())
            .prop_map(|(a, b, c, d)| [a.min(c), b.min(d), a.max(c), b.max(d)]),
        1 => Just(EMPTY_RECT),
        1 => (coordinate(), coordinate(), coordinate(), coordinate())
            .prop_map(|(a, b, c, d)| [a, b, c, d]),
    ];
    proptest::collection::vec(rect, 0..5)
}

/// A grid of 2^1 to 2^9 texels a side, a window inside it and a capacity drawn from 0
/// to past the window's clusters.
fn params() -> impl Strategy<Value = SeedParams> {
    (1u32..10).prop_flat_map(|k| {
        let cw = (1u32 << k) / 2;
        (0..cw, 0..cw).prop_flat_map(move |(x, y)| {
            (1..=cw - x, 1..=cw - y).prop_flat_map(move |(w, h)| {
                prop_oneof![Just(0u32), 0..=w * h, Just(w * h + 5)].prop_map(move |capacity| {
                    SeedParams {
                        grid_w: 1 << k,
                        first_x: x,
                        first_y: y,
                        window_w: w,
                        window_h: h,
                        capacity,
                        ..Default::default()
                    }
                })
            })
        })
    })
}

#[test]
fn seed_clusters_lists_what_core_keeps() {
    harness::check_generated(
        "seed_clusters on generated grids and rectangles",
        (params(), rects()),
        |r, c, (params, rects)| check_seed_clusters(r, c, params, rects),
    );
}

/// The host's window holds every cluster of the whole grid that the test keeps.
#[test]
fn the_seed_window_misses_no_kept_cluster() {
    let mut runner = TestRunner::new(ProptestConfig {
        cases: 512,
        ..strategies::config()
    });
    runner
        .run(&((1u32..10), rects()), |(k, rects)| {
            let grid_w = 1u32 << k;
            let cw = grid_w / 2;
            let whole = SeedParams {
                grid_w,
                window_w: cw,
                window_h: cw,
                ..Default::default()
            };
            let kept = seeded_clusters(&whole, &rects);
            let [x, y, w, h] = seed_window(&rects, grid_w);
            prop_assert!(
                x + w <= cw && y + h <= cw,
                "window {:?} past {cw}",
                [x, y, w, h]
            );
            for c in kept {
                let (cx, cy) = (c % cw, c / cw);
                prop_assert!(
                    (x..x + w).contains(&cx) && (y..y + h).contains(&cy),
                    "cluster ({cx}, {cy}) of {cw} outside the window {:?}",
                    [x, y, w, h]
                );
            }
            Ok(())
        })
        .unwrap();
}
