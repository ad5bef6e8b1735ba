//! Traversal statistics (developer aid, cargo feature `traversal-stats`, off by default):
//! how many BVH8 node visits and triangle tests each photon ray of `trace_photons` and
//! `trace_indirect` costs, and how much of a GPU warp that work would keep busy.
//!
//! The CPU traversal is the GPU ports' algorithm step for step (same node test, child
//! order and stack), so its counts are theirs. A *step* is one node visit or one triangle
//! test. The warp estimate takes the GPU's thread order (a pass's `thread -> photon` map),
//! forms warps of 32 threads and assumes a warp runs each path segment for as long as its
//! longest lane needs: efficiency = steps taken / (32 x sum over segments of the longest
//! lane's steps). Beside it, the warp-steps of a persistent launch whose lanes take the
//! next ray as theirs ends (`persistent_warp_steps`). Both leave out everything but
//! traversal (shading, stores, memory), so they bound what regrouping rays could buy, not
//! a time.
//!
//! Printed to stderr after each pass, e.g. `cargo run --release -p caustica --features
//! caustica-cpu/traversal-stats -- render --scene rooms --technique photon-gi`. Without
//! the feature every function here is an empty inline.

#[cfg(feature = "traversal-stats")]
mod enabled {
    use std::cell::RefCell;
    use std::collections::HashMap;
    use std::sync::atomic::{AtomicU64, Ordering};
    use std::sync::Mutex;

    thread_local! {
        /// The photon this thread traces (its key) and the steps of each of its rays.
        static CURRENT: RefCell<Option<(u32, Vec<u32>)>> = const { RefCell::new(None) };
    }

    /// Every finished photon's per-ray steps, by key, until the pass reports.
    static PHOTONS: Mutex<Option<HashMap<u32, Vec<u32>>>> = Mutex::new(None);
    /// Node visits and triangle tests of the pass, in that order.
    static TOTALS: [AtomicU64; 2] = [AtomicU64::new(0), AtomicU64::new(0)];

    pub fn photon_begins(key: u32) {
        CURRENT.with(|c| *c.borrow_mut() = Some((key, Vec::new())));
    }

    pub fn photon_ends() {
        if let Some((key, rays)) = CURRENT.with(|c| c.borrow_mut().take()) {
            let mut map = PHOTONS.lock().unwrap_or_else(|e| e.into_inner());
            map.get_or_insert_with(HashMap::new).insert(key, rays);
        }
    }

    pub fn ray_begins() {
        CURRENT.with(|c| {
            if let Some((_, rays)) = c.borrow_mut().as_mut() {
                rays.push(0);
            }
        });
    }

    fn step(kind: usize) {
        let counted = CURRENT.with(|c| match c.borrow_mut().as_mut() {
            Some((_, rays)) => match rays.last_mut() {
                Some(s) => {
                    *s += 1;
                    true
                }
                None => false,
            },
            None => false,
        });
        if counted {
            TOTALS[kind].fetch_add(1, Ordering::Relaxed);
        }
    }

    pub fn node_visited() {
        step(0);
    }

    pub fn triangle_tested() {
        step(1);
    }

    /// The lanes a persistent launch would keep resident: an H200's 132 multiprocessors
    /// with 21 warps each, as many as `trace_indirect`'s 96 registers a thread allow.
    const PERSISTENT_LANES: usize = 132 * 21 * 32;

    /// Warp-steps of a persistent launch (Aila and Laine 2009's persistent threads with
    /// their dynamic fetch at every ray): `lanes` threads in warps of 32 step their rays
    /// together, one step a lane an iteration; a lane whose ray ends takes its path's next
    /// ray, or the next path of one queue in thread order, for the next iteration. Counts
    /// traversal steps alone (no shading, fetch or stores): a bound on what refilling
    /// lanes could save, as the warp-steps of the other schedules are.
    fn persistent_warp_steps(paths: &[&[u32]], lanes: usize) -> u64 {
        let mut next = 0usize;
        // each lane's (path, ray, steps left); a lane without a path is done
        let mut state: Vec<Option<(usize, usize, u32)>> = vec![None; lanes];
        let take = |next: &mut usize| {
            while *next < paths.len() {
                let p = *next;
                *next += 1;
                if let Some(&s) = paths[p].first() {
                    return Some((p, 0, s.max(1)));
                }
            }
            None
        };
        for lane in state.iter_mut() {
            *lane = take(&mut next);
        }
        let mut warp_steps = 0u64;
        loop {
            let mut any = false;
            for warp in state.chunks_mut(32) {
                if !warp.iter().any(Option::is_some) {
                    continue;
                }
                any = true;
                warp_steps += 1;
                for lane in warp.iter_mut() {
                    let Some((p, r, left)) = *lane else { continue };
                    *lane = if left > 1 {
                        Some((p, r, left - 1))
                    } else if let Some(&s) = paths[p].get(r + 1) {
                        Some((p, r + 1, s.max(1)))
                    } else {
                        take(&mut next)
                    };
                }
            }
            if !any {
                return warp_steps;
            }
        }
    }

    pub fn report(pass: &str, threads: u32, key_of_thread: impl Fn(u32) -> u32) {
        let photons = PHOTONS
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
            .unwrap_or_default();
        let nodes = TOTALS[0].swap(0, Ordering::Relaxed);
        let triangles = TOTALS[1].swap(0, Ordering::Relaxed);
        let mut steps: Vec<u32> = photons.values().flatten().copied().collect();
        let rays = steps.len().max(1) as f64;
        steps.sort_unstable();
        let pct = |q: f64| {
            steps
                .get(((steps.len() as f64 - 1.0) * q) as usize)
                .map_or(0, |&s| s)
        };
        let taken: u64 = steps.iter().map(|&x| x as u64).sum();
        let mut warp_slots = 0u64;
        let empty = Vec::new();
        for first in (0..threads).step_by(32) {
            let lanes: Vec<&Vec<u32>> = (first..(first + 32).min(threads))
                .map(|t| photons.get(&key_of_thread(t)).unwrap_or(&empty))
                .collect();
            let segments = lanes.iter().map(|l| l.len()).max().unwrap_or(0);
            for s in 0..segments {
                let longest = lanes.iter().filter_map(|l| l.get(s)).max().unwrap_or(&0);
                warp_slots += 32 * *longest as u64;
            }
        }
        let paths: Vec<&[u32]> = (0..threads)
            .map(|t| photons.get(&key_of_thread(t)).map_or(&[][..], |l| &l[..]))
            .collect();
        let persistent = persistent_warp_steps(&paths, PERSISTENT_LANES);
        eprintln!(
            "traversal stats, {pass}: {} rays; per ray {:.2} node visits, {:.2} triangle \
             tests; steps per ray p50 {} p90 {} p99 {} max {}; warps of 32 in the \
             GPU's thread order keep {:.1}% of their lanes' slots busy ({taken} steps, {} \
             warp-steps; {persistent} warp-steps as {PERSISTENT_LANES} persistent lanes \
             that take the next ray as theirs ends)",
            steps.len(),
            nodes as f64 / rays,
            triangles as f64 / rays,
            pct(0.5),
            pct(0.9),
            pct(0.99),
            steps.last().map_or(0, |&s| s),
            100.0 * taken as f64 / warp_slots.max(1) as f64,
            warp_slots / 32,
        );
    }
}

/// Starts counting the rays of the photon filed under `key` on this thread.
#[inline(always)]
pub fn photon_begins(key: u32) {
    #[cfg(feature = "traversal-stats")]
    enabled::photon_begins(key);
    #[cfg(not(feature = "traversal-stats"))]
    let _ = key;
}

/// Files this thread's photon's counts.
#[inline(always)]
pub fn photon_ends() {
    #[cfg(feature = "traversal-stats")]
    enabled::photon_ends();
}

/// A traversal starts (a new ray of the current photon).
#[inline(always)]
pub fn ray_begins() {
    #[cfg(feature = "traversal-stats")]
    enabled::ray_begins();
}

/// One BVH8 node's children were tested.
#[inline(always)]
pub fn node_visited() {
    #[cfg(feature = "traversal-stats")]
    enabled::node_visited();
}

/// One ray-triangle test ran.
#[inline(always)]
pub fn triangle_tested() {
    #[cfg(feature = "traversal-stats")]
    enabled::triangle_tested();
}

/// Prints the pass's statistics: `threads` GPU threads, thread `t` tracing the photon
/// filed under `key_of_thread(t)`.
#[inline(always)]
pub fn report(pass: &str, threads: u32, key_of_thread: impl Fn(u32) -> u32) {
    #[cfg(feature = "traversal-stats")]
    enabled::report(pass, threads, key_of_thread);
    #[cfg(not(feature = "traversal-stats"))]
    let _ = (pass, threads, key_of_thread);
}
