//! The non-blocking frame: a technique records a whole frame as one
//! [`Recording`] ([`RecordedFrame`]), the host submits it ([`RecordedFrame::submit`], or
//! its own command encoder for an embedding backend) and goes on; the frame's statistics
//! (pass times, photon counters) come back later through [`FrameTicket::stats`], without
//! stalling, from copies the device made at the end of that frame.

use crate::backend::{Backend, Finished, PassTime, Submission};
use crate::device::handle::ResourceId;
use crate::frame::error::Error;
use crate::frame::stats::FrameStats;
use crate::frame::stats::Progress;
use crate::recording::Recording;

/// A frame recorded but not yet submitted.
#[derive(Debug)]
pub struct RecordedFrame {
    /// Every step of the frame, in order (the technique's pending updates first).
    pub recording: Recording,
    /// Buffers to copy to the host after the last step ([`Backend::submit`]'s
    /// `readbacks`): the frame's photon counters, when it has photon passes.
    pub readbacks: Vec<ResourceId>,
    /// The statistics known when recording (plan, skipped passes, emitted photons and
    /// flux, batches); `frame_ms` is the host time spent recording.
    pub stats: FrameStats,
    /// What goes into the statistics from `readbacks` when the frame completes, in order.
    pub ends: Vec<EndRead>,
    /// Its place among its technique's frames (set when the technique records it).
    pub(crate) order: Option<(std::sync::Arc<FrameOrder>, u64)>,
}

/// The order of a technique's frames: a recorded frame carries the technique's pending
/// updates (and work a technique does once, such as laying out an atlas), so every frame
/// must run, in the order recorded. A frame dropped unsubmitted or submitted out of order
/// is noted here, and the technique's next frame is refused (its device state no longer
/// follows its updates) instead of rendering a stale scene.
#[derive(Debug, Default)]
pub(crate) struct FrameOrder {
    /// The number of the next frame to be submitted.
    next: std::sync::atomic::AtomicU64,
    /// What broke the order, if anything did.
    broken: std::sync::Mutex<Option<String>>,
}

/// A technique's frames: how many it has recorded or run, and their order.
#[derive(Debug, Default)]
pub(crate) struct FrameSequence {
    /// Which of them were submitted, and whether the order broke.
    pub(crate) order: std::sync::Arc<FrameOrder>,
    /// How many frames were recorded or run (the next frame's number).
    pub(crate) count: u64,
}

impl FrameSequence {
    /// An error when a recorded frame is not yet submitted: `what` would run on the device
    /// now, before that frame's work (its updates, or the buffers it uses freed), so the
    /// frame must be submitted first.
    pub(crate) fn check_all_submitted(&self, what: &str) -> Result<(), Error> {
        use std::sync::atomic::Ordering;
        // a broken order says so first (its frames can never be submitted)
        self.order.check()?;
        let next = self.order.next.load(Ordering::SeqCst);
        if next < self.count {
            return Err(Error::InvalidParameter(format!(
                "{what} runs on the device at once, but frame {next} is recorded and not yet \
                 submitted: submit the recorded frames first"
            )));
        }
        Ok(())
    }
}

impl FrameSequence {
    /// Whether every frame before the last one recorded or run was submitted: work that a
    /// frame being recorded submits of its own (a readback of an earlier frame's results)
    /// then runs after those frames.
    pub(crate) fn earlier_frames_submitted(&self) -> bool {
        self.order.next.load(std::sync::atomic::Ordering::SeqCst) + 1 >= self.count
    }
}

impl FrameOrder {
    /// Notes that frame `seq` is submitted now.
    fn submit(&self, seq: u64) {
        use std::sync::atomic::Ordering;
        let next = self.next.swap(seq + 1, Ordering::SeqCst);
        if next != seq {
            self.break_with(format!(
                "frame {seq} was submitted while frame {next} was still to be submitted"
            ));
        }
    }

    pub(crate) fn break_with(&self, why: String) {
        let mut b = self.broken.lock().unwrap_or_else(|e| e.into_inner());
        b.get_or_insert(why);
    }

    /// Frame `seq`, a blocking frame, may run now (every earlier one was submitted, in
    /// order, and none was dropped); it counts as submitted.
    pub(crate) fn run_now(&self, seq: u64) -> Result<(), Error> {
        self.check()?;
        self.submit(seq);
        self.check()
    }

    /// An error if the order was broken.
    pub(crate) fn check(&self) -> Result<(), Error> {
        let b = self.broken.lock().unwrap_or_else(|e| e.into_inner());
        match &*b {
            Some(why) => Err(Error::InvalidParameter(format!(
                "{why}: the updates and first-frame work it carried never ran, so the \
                 technique's device state no longer follows its scene; submit every \
                 recorded frame in the order recorded, and make the technique anew"
            ))),
            None => Ok(()),
        }
    }
}

impl Drop for RecordedFrame {
    fn drop(&mut self) {
        if let Some((order, seq)) = self.order.take() {
            order.break_with(format!(
                "frame {seq} was recorded and dropped without being submitted"
            ));
        }
    }
}

/// Device data a frame reads back at its end, and how it goes into the statistics.
#[derive(Clone, Debug)]
pub enum EndRead {
    /// Photon counters (fixed point with `quantum`) at `readbacks[at]`
    /// ([`FrameStats::read_counters`]).
    Counters {
        /// Index into the frame's readbacks.
        at: usize,
        /// Flux per fixed-point unit (W).
        quantum: f32,
    },
    /// A technique's own read (AdaptiveCaustics' traversal counts).
    Own(std::sync::Arc<dyn FrameEnd>),
}

/// A technique's own end-of-frame read: what it makes of the frame's readbacks and kernel
/// times, put into the frame's statistics (usually [`FrameStats::own`]).
pub trait FrameEnd: std::fmt::Debug + Send + Sync {
    /// Puts what the device gave back (`readbacks` of the frame, `times` of its kernel
    /// steps in order) into `stats`.
    fn apply(&self, readbacks: &[Vec<u8>], times: &[PassTime], stats: &mut FrameStats);
}

impl EndRead {
    /// Puts what the device gave back (`readbacks` of the frame, `times` of its kernel
    /// steps in order) into `stats`.
    pub fn apply(&self, readbacks: &[Vec<u8>], times: &[PassTime], stats: &mut FrameStats) {
        match self {
            EndRead::Counters { at, quantum } => {
                if let Some(c) = readbacks.get(*at) {
                    let words: Vec<u32> = bytemuck::pod_collect_to_vec(c);
                    stats.read_counters(&words, *quantum);
                }
            }
            EndRead::Own(end) => end.apply(readbacks, times, stats),
        }
    }
}

impl RecordedFrame {
    /// Submits the frame on `backend` without waiting for it.
    pub fn submit(mut self, backend: &mut dyn Backend) -> Result<FrameTicket, Error> {
        let t0 = std::time::Instant::now();
        let submission = match backend.submit(&self.recording, &self.readbacks) {
            Ok(s) => s,
            Err(e) => {
                if let Some((order, seq)) = self.order.take() {
                    order.break_with(format!("frame {seq} failed to submit ({e})"));
                }
                return Err(e.into());
            }
        };
        let mut ticket = self.submitted(submission);
        ticket.stats.frame_ms += t0.elapsed().as_secs_f64() * 1e3;
        Ok(ticket)
    }

    /// The ticket of a frame the host submitted itself (an embedding backend's own
    /// encoding of [`RecordedFrame::recording`], which returned `submission`).
    pub fn submitted(mut self, submission: Submission) -> FrameTicket {
        if let Some((order, seq)) = self.order.take() {
            order.submit(seq);
        }
        FrameTicket {
            submission,
            stats: std::mem::take(&mut self.stats),
            ends: std::mem::take(&mut self.ends),
        }
    }
}

/// A submitted frame whose statistics are still to be collected.
#[derive(Debug)]
pub struct FrameTicket {
    submission: Submission,
    stats: FrameStats,
    ends: Vec<EndRead>,
}

impl FrameTicket {
    /// The backend's number of the frame's submission.
    pub fn submission_id(&self) -> u64 {
        self.submission.id
    }

    /// The frame's statistics once the device has finished it: `Ok(None)` while it runs
    /// and `wait` is false (never blocks then). `frame_ms` is the host time the frame cost
    /// to record and submit. Collected once; asking again is an error.
    pub fn stats(
        &mut self,
        backend: &mut dyn Backend,
        wait: bool,
    ) -> Result<Option<FrameStats>, Error> {
        let Some(finished) = backend.poll(&mut self.submission, wait)? else {
            return Ok(None);
        };
        Ok(Some(self.complete(finished)))
    }

    /// The recorded statistics completed with what the device gave back.
    fn complete(&self, finished: Finished) -> FrameStats {
        let mut stats = self.stats.clone();
        for t in &finished.times {
            stats.add_pass_time(t.kernel, t.seconds);
        }
        for end in &self.ends {
            end.apply(&finished.readbacks, &finished.times, &mut stats);
        }
        stats
    }
}

/// A blocking frame's recordings, each with the photons it traces, run as one pipeline:
/// all submitted without waiting (the device never idles between them, and the host pays
/// one wait, not one per recording), then waited for in order, `progress` called as each
/// photon batch completes. After each submission the host also looks, without waiting,
/// whether the oldest ones have finished, so that a backend whose submissions run at once
/// (the CPU's) or a device that keeps up reports its batches as they end, not all at the
/// last wait. The pass times go into `stats`; returns the bytes of `readbacks` as they
/// were after the last recording and every kernel step's time in order. On an error every
/// submitted recording is still waited for before it is returned.
pub fn run_pipelined(
    backend: &mut dyn Backend,
    recordings: Vec<(Recording, u64)>,
    readbacks: &[ResourceId],
    stats: &mut FrameStats,
    progress: &mut dyn FnMut(Progress),
) -> Result<(Vec<Vec<u8>>, Vec<PassTime>), Error> {
    let total: u64 = recordings.iter().map(|r| r.1).sum();
    let last = recordings.len().saturating_sub(1);
    let mut pipeline = InFlight {
        pending: std::collections::VecDeque::with_capacity(recordings.len()),
        failure: None,
        done: 0,
        total,
        out: Vec::new(),
        times: Vec::new(),
    };
    for (k, (rec, photons)) in recordings.iter().enumerate() {
        let wanted = if k == last { readbacks } else { &[] };
        match backend.submit(rec, wanted) {
            Ok(s) => pipeline.pending.push_back((s, *photons)),
            Err(e) => {
                pipeline.failure = Some(Error::from(e));
                break;
            }
        }
        pipeline.settle(backend, false, stats, progress);
        if pipeline.failure.is_some() {
            break;
        }
    }
    pipeline.settle(backend, true, stats, progress);
    match pipeline.failure {
        Some(e) => Err(e),
        None => Ok((pipeline.out, pipeline.times)),
    }
}

/// [`run_pipelined`]'s submissions not yet finished, oldest first, and what the finished
/// ones gave.
struct InFlight {
    pending: std::collections::VecDeque<(Submission, u64)>,
    failure: Option<Error>,
    /// Photons of the finished submissions, and of all.
    done: u64,
    total: u64,
    /// The readbacks of the last finished submission (the last recording's are the
    /// frame's) and every kernel step's time in order.
    out: Vec<Vec<u8>>,
    times: Vec<PassTime>,
}

impl InFlight {
    /// Takes the finished submissions from the front, in order: all of them, waiting for
    /// each (`wait`), or those already finished.
    fn settle(
        &mut self,
        backend: &mut dyn Backend,
        wait: bool,
        stats: &mut FrameStats,
        progress: &mut dyn FnMut(Progress),
    ) {
        while let Some((s, photons)) = self.pending.front_mut() {
            let photons = *photons;
            match backend.poll(s, wait) {
                Ok(Some(f)) => {
                    self.pending.pop_front();
                    if self.failure.is_some() {
                        continue;
                    }
                    for t in &f.times {
                        stats.add_pass_time(t.kernel, t.seconds);
                    }
                    self.times.extend(f.times);
                    if photons > 0 {
                        self.done += photons;
                        progress(Progress {
                            photons_done: self.done,
                            photons_total: self.total,
                        });
                    }
                    self.out = f.readbacks;
                }
                Ok(None) if !wait => return,
                Ok(None) => {
                    self.pending.pop_front();
                }
                Err(e) if !wait => {
                    // the submission may still be on the device: the waiting pass polls
                    // it again
                    self.failure.get_or_insert(Error::from(e));
                    return;
                }
                Err(e) => {
                    self.pending.pop_front();
                    self.failure.get_or_insert(Error::from(e));
                }
            }
        }
    }
}
