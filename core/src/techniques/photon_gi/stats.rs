//! PhotonGi's own frame statistics: the time of `trace_indirect`'s per-bounce waves. A
//! frame carries them in [`FrameStats::own`] under [`PhotonGiStats::KEY`].

use crate::backend::PassTime;
use crate::frame::stats::FrameStats;
use crate::math::path_sort::path_sort_phase;
use serde::{Deserialize, Serialize};

/// Where the per-bounce waves' time goes: present where a frame runs waves (`waves` or
/// `sorted_waves` with more than one wave; `auto` where it resolves to them and some
/// light has more photons than `auto_waves_above_photons` or a count not yet known),
/// absent for the single kernel (also where `auto` traced every light in one launch) and
/// where the frame timed no kernel. Only `trace_indirect`'s and
/// `sort_indirect_paths`' launches are in it: each later wave's `dispatch_args` and the
/// sort's bucket clear are not.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
pub struct PhotonGiStats {
    /// Waves per chunk of a light's photons traced in waves: `indirect_waves`, at most
    /// `max_segments`.
    pub waves: u32,
    /// `trace_indirect`'s time per wave (index k: segment k of every path still going,
    /// the last wave the rest of each path), summed over the lights and their chunks, in
    /// ms of the frame's `timing` (device timestamps or host wall clock).
    pub trace_ms_per_wave: Vec<f64>,
    /// `trace_indirect`'s time in the lights that `auto` traced in one launch each
    /// (photons up to `auto_waves_above_photons`), in ms; 0 without them.
    #[serde(default)]
    pub single_ms: f64,
    /// `sort_indirect_paths`' time before each wave (its two launches), in ms; index 0
    /// is 0 (the RSM photons are not sorted); empty without sorting.
    pub sort_ms_per_wave: Vec<f64>,
    /// `sort_indirect_paths`' time by launch, summed over the waves, lights and chunks,
    /// in ms: `[scan, scatter]` (`math::path_sort::path_sort_phase`'s order);
    /// empty without sorting.
    pub sort_ms_per_phase: Vec<f64>,
}

/// The launches of one sort (`math::path_sort::path_sort_phase`).
const SORT_PHASES: usize = path_sort_phase::SCATTER as usize + 1;

impl PhotonGiStats {
    /// The name of these statistics in [`FrameStats::own`] (and the frame's JSON form).
    pub const KEY: &'static str = "photon_gi";

    /// The waves' statistics of a frame: `None` for the other techniques and for the
    /// single kernel.
    pub fn of(stats: &FrameStats) -> Option<PhotonGiStats> {
        stats.own_stats(Self::KEY)
    }

    /// Puts these statistics into the frame's.
    pub fn put(&self, stats: &mut FrameStats) {
        stats.put_own(Self::KEY, self);
    }

    /// The waves' times from a frame's kernel times in recorded order. `chunks` lists
    /// the frame's chunks of a light's photons in recorded order, each by its launches
    /// of `trace_indirect` (1: the light's single launch; more: its waves, in order), and
    /// nothing else launches it, so the j-th `trace_indirect` of the frame is known; a
    /// sort belongs to the wave after it, and its launches come as scan, scatter. `None`
    /// without waves, where the `trace_indirect` times are not one a recorded launch (a
    /// device that gives no timestamps), or where the sort's launches are not a whole
    /// number of pairs, each before a wave (times of another shape than the
    /// recording's).
    pub fn from_times(chunks: &[u32], sorted: bool, times: &[PassTime]) -> Option<PhotonGiStats> {
        let waves = chunks.iter().copied().filter(|&w| w > 1).max()?;
        let n = waves as usize;
        // each launch's wave, `None` for a single launch
        let launches: Vec<Option<usize>> = chunks
            .iter()
            .flat_map(|&w| (0..w as usize).map(move |k| (w > 1).then_some(k)))
            .collect();
        let mut s = PhotonGiStats {
            waves,
            trace_ms_per_wave: vec![0.0; n],
            single_ms: 0.0,
            sort_ms_per_wave: if sorted { vec![0.0; n] } else { Vec::new() },
            sort_ms_per_phase: if sorted {
                vec![0.0; SORT_PHASES]
            } else {
                Vec::new()
            },
        };
        let (mut traced, mut sorts) = (0usize, 0usize);
        for t in times {
            let ms = t.seconds * 1e3;
            match t.kernel {
                "trace_indirect" => {
                    match *launches.get(traced)? {
                        Some(k) => s.trace_ms_per_wave[k] += ms,
                        None => s.single_ms += ms,
                    }
                    traced += 1;
                }
                "sort_indirect_paths" if sorted => {
                    s.sort_ms_per_wave[(*launches.get(traced)?)?] += ms;
                    s.sort_ms_per_phase[sorts % SORT_PHASES] += ms;
                    sorts += 1;
                }
                _ => {}
            }
        }
        (traced == launches.len() && sorts.is_multiple_of(SORT_PHASES)).then_some(s)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn at(kernel: &'static str, ms: f64) -> PassTime {
        PassTime {
            kernel,
            seconds: ms * 1e-3,
        }
    }

    #[test]
    fn the_waves_of_every_chunk_add_up_by_wave() {
        // two chunks of three sorted waves, a light's single launch between them, other
        // kernels between them
        let mut times = vec![at("sample_rsm", 5.0)];
        for chunk in 0..2 {
            let c = chunk as f64;
            if chunk == 1 {
                times.push(at("trace_indirect", 100.0));
            }
            times.push(at("trace_indirect", 1.0 + c));
            for k in 1..3 {
                times.push(at("dispatch_args", 7.0));
                for phase in 0..SORT_PHASES {
                    times.push(at(
                        "sort_indirect_paths",
                        0.25 * k as f64 * (phase + 1) as f64,
                    ));
                }
                times.push(at("trace_indirect", 10.0 * k as f64 + c));
            }
        }
        times.push(at("splat_photons", 3.0));
        let chunks = [3, 1, 3];
        let s = PhotonGiStats::from_times(&chunks, true, &times).expect("whole chunks");
        assert_eq!(s.waves, 3);
        assert_eq!(s.trace_ms_per_wave, vec![3.0, 21.0, 41.0]);
        assert_eq!(s.single_ms, 100.0);
        assert_eq!(s.sort_ms_per_wave, vec![0.0, 1.5, 3.0]);
        // each phase over both chunks' two sorts: 2 x (0.25 + 0.5) x (phase + 1)
        assert_eq!(s.sort_ms_per_phase, vec![1.5, 3.0]);
        let unsorted = PhotonGiStats::from_times(&chunks, false, &times).expect("whole chunks");
        assert!(unsorted.sort_ms_per_wave.is_empty() && unsorted.sort_ms_per_phase.is_empty());
        // a partial chunk, a launch more than recorded, a sort before a single launch or
        // without its scatter: not the recording's shape
        assert_eq!(PhotonGiStats::from_times(&chunks, false, &times[..3]), None);
        assert_eq!(PhotonGiStats::from_times(&[3, 3], false, &times), None);
        assert_eq!(PhotonGiStats::from_times(&[3, 3, 1], true, &times), None);
        let mut short = times.clone();
        let last_sort = short
            .iter()
            .rposition(|t| t.kernel == "sort_indirect_paths")
            .expect("a sort");
        short.remove(last_sort);
        assert_eq!(PhotonGiStats::from_times(&chunks, true, &short), None);
        // no waves, or no kernel timed
        assert_eq!(PhotonGiStats::from_times(&[1, 1], false, &times), None);
        assert_eq!(PhotonGiStats::from_times(&[], false, &times), None);
        assert_eq!(PhotonGiStats::from_times(&chunks, true, &[]), None);
    }
}
