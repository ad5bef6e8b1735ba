//! Traversal statistics (developer aid, cargo feature `traversal-stats`, off by default):
//! how many BVH8 node visits, triangle tests and stack pushes and pops each photon ray of
//! `trace_photons` and `trace_indirect` costs, and how much of a GPU warp that work would
//! keep busy.
//!
//! The CPU traversal is the GPU ports' algorithm step for step (same node test, child
//! order and stack), so its counts are theirs. A *step* is one node visit or one triangle
//! test. The warp estimate takes the GPU's thread order (a pass's `thread -> photon` map),
//! forms warps of 32 threads and assumes a warp runs each path segment for as long as its
//! longest lane needs: efficiency = steps taken / (32 x sum over segments of the longest
//! lane's steps). For `trace_indirect` it also prints the warp-steps of a persistent
//! launch whose lanes take the next ray as theirs ends (`persistent_warp_steps`). Both
//! leave out everything but traversal (shading, stores, memory), so they bound what
//! regrouping rays could buy, not a time.
//!
//! A `sorted_waves` wave that keys its queue also prints how the queued paths spread
//! over the sort's buckets, where the GPU's atomics land ([`sort_keys`]).
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
    /// Node visits, triangle tests and traversal-stack pushes and pops of the pass, in
    /// that order.
    static TOTALS: [AtomicU64; 3] = [AtomicU64::new(0), AtomicU64::new(0), AtomicU64::new(0)];

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

    pub fn stack_accessed() {
        let counted = CURRENT.with(|c| c.borrow().as_ref().is_some_and(|(_, r)| !r.is_empty()));
        if counted {
            TOTALS[2].fetch_add(1, Ordering::Relaxed);
        }
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

    /// The next ray of `path` at or after `ray` that takes a step, with its steps (a ray
    /// of no steps, ended before its traversal began, holds no lane).
    fn next_ray(path: &[u32], ray: usize) -> Option<(usize, u32)> {
        (ray..path.len())
            .find(|&r| path[r] > 0)
            .map(|r| (r, path[r]))
    }

    /// Warp-steps of a persistent launch, an idealised form of Aila and Laine 2009's
    /// persistent threads with dynamic fetch: `lanes` threads in warps of 32, all warps
    /// in lockstep, each lane one step of its ray an iteration; a lane whose ray ends
    /// takes, for the next iteration and at no cost, its path's next ray or else the next
    /// path of one queue in thread order (lanes in index order). Returns, summed over
    /// the warps, the iterations in which at least one of a warp's lanes holds a ray.
    /// Refilling at every ray rather than below a threshold, and free of the shading,
    /// fetches and stores between rays, it bounds what refilled lanes could save.
    fn persistent_warp_steps(paths: &[&[u32]], lanes: usize) -> u64 {
        let mut next = 0usize;
        let take = |next: &mut usize| {
            while *next < paths.len() {
                let p = *next;
                *next += 1;
                if let Some((r, s)) = next_ray(paths[p], 0) {
                    return Some((p, r, s));
                }
            }
            None
        };
        // each lane's (path, ray, steps left); a lane without a path is done
        let mut state: Vec<Option<(usize, usize, u32)>> =
            (0..lanes).map(|_| take(&mut next)).collect();
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
                    } else if let Some((r, s)) = next_ray(paths[p], r + 1) {
                        Some((p, r, s))
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

    pub fn sort_keys(count_word: u32, keys: &[u32], buckets: usize) {
        if keys.is_empty() {
            return;
        }
        let mut counts = vec![0u64; buckets];
        keys.iter().for_each(|&k| counts[k as usize] += 1);
        let used = counts.iter().filter(|&&c| c > 0).count();
        let fullest = counts.iter().max().copied().unwrap_or(0);
        // distinct keys among each warp's 32 queued paths, in queue order
        let mut per_warp = 0usize;
        for warp in keys.chunks(32) {
            let mut w = warp.to_vec();
            w.sort_unstable();
            w.dedup();
            per_warp += w.len();
        }
        eprintln!(
            "sort stats, queue of wave {count_word}: {} paths in {used} of {buckets} buckets, the \
             fullest {:.2}% of them; a warp's 32 paths (queue order) in {:.1} buckets",
            keys.len(),
            100.0 * fullest as f64 / keys.len() as f64,
            per_warp as f64 / keys.len().div_ceil(32) as f64,
        );
    }

    pub fn report(
        pass: &str,
        threads: u32,
        persistent_lanes: Option<u32>,
        key_of_thread: impl Fn(u32) -> u32,
    ) {
        let photons = PHOTONS
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .take()
            .unwrap_or_default();
        let nodes = TOTALS[0].swap(0, Ordering::Relaxed);
        let triangles = TOTALS[1].swap(0, Ordering::Relaxed);
        let stack = TOTALS[2].swap(0, Ordering::Relaxed);
        let mut steps: Vec<u32> = photons.values().flatten().copied().collect();
        let rays = steps.len().max(1) as f64;
        steps.sort_unstable();
        let pct = |q: f64| {
            steps
                .get(((steps.len() as f64 - 1.0) * q) as usize)
                .map_or(0, |&s| s)
        };
        let taken: u64 = steps.iter().map(|&x| x as u64).sum();
        // each GPU thread's photon's per-ray steps, in thread order
        let paths: Vec<&[u32]> = (0..threads)
            .map(|t| photons.get(&key_of_thread(t)).map_or(&[][..], |l| &l[..]))
            .collect();
        let mut warp_slots = 0u64;
        for lanes in paths.chunks(32) {
            let segments = lanes.iter().map(|l| l.len()).max().unwrap_or(0);
            for s in 0..segments {
                let longest = lanes.iter().filter_map(|l| l.get(s)).max().unwrap_or(&0);
                warp_slots += 32 * *longest as u64;
            }
        }
        let persistent = persistent_lanes.map_or(String::new(), |lanes| {
            let w = persistent_warp_steps(&paths, lanes as usize);
            format!("; {w} warp-steps as {lanes} persistent lanes refilled ray by ray")
        });
        eprintln!(
            "traversal stats, {pass}: {} rays; per ray {:.2} node visits, {:.2} triangle \
             tests, {:.2} stack pushes and pops; steps per ray p50 {} p90 {} p99 {} max {}; \
             warps of 32 in the GPU's thread order keep {:.1}% of their lanes' slots busy \
             ({taken} steps, {} warp-steps{persistent})",
            steps.len(),
            nodes as f64 / rays,
            triangles as f64 / rays,
            stack as f64 / rays,
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

/// One push or pop of the traversal stack (on a GPU, an access to the thread's private
/// stack frame in device memory, through the caches).
#[inline(always)]
pub fn stack_accessed() {
    #[cfg(feature = "traversal-stats")]
    enabled::stack_accessed();
}

/// Prints the pass's statistics: `threads` GPU threads, thread `t` tracing the photon
/// filed under `key_of_thread(t)`; with `persistent_lanes`, also the warp-steps of a
/// persistent launch of that many lanes over the same paths.
#[inline(always)]
pub fn report(
    pass: &str,
    threads: u32,
    persistent_lanes: Option<u32>,
    key_of_thread: impl Fn(u32) -> u32,
) {
    #[cfg(feature = "traversal-stats")]
    enabled::report(pass, threads, persistent_lanes, key_of_thread);
    #[cfg(not(feature = "traversal-stats"))]
    let _ = (pass, threads, persistent_lanes, key_of_thread);
}

/// Prints how one queue's paths spread over the sort's buckets (`keys` in queue order,
/// each below `buckets`; `count_word`, the wave the queue feeds, names it; the lines of
/// several lights and chunks come in recording order): buckets used, the fullest one's
/// share, and the buckets a warp's 32 consecutive paths fall in, which is how many
/// distinct words the GPU's per-path atomics of one warp hit.
#[inline(always)]
pub fn sort_keys(count_word: u32, keys: &[u32], buckets: usize) {
    #[cfg(feature = "traversal-stats")]
    enabled::sort_keys(count_word, keys, buckets);
    #[cfg(not(feature = "traversal-stats"))]
    let _ = (count_word, keys, buckets);
}
