//! Submissions ([`Backend::submit`], [`Backend::poll`]): what a submission is and gives
//! back, and [`Submissions`], the book-keeping every asynchronous backend shares (the
//! submissions on its device by number, the results of those it finished before they were
//! polled, and the start of its `poll`); pass times from device timestamps.

#[cfg(doc)]
use super::{Backend, Capabilities};
use super::{BackendError, PassTime};

/// A recording submitted with [`Backend::submit`], not yet collected.
#[derive(Debug)]
pub struct Submission {
    /// The backend's number for it (increasing in submission order).
    pub id: u64,
    state: SubmissionState,
}

#[derive(Debug)]
enum SubmissionState {
    /// On the device; the backend holds what it will give back.
    Pending,
    /// Done when submitted (the default [`Backend::submit`]).
    Finished(Finished),
    /// Its result was handed out.
    Collected,
}

impl Submission {
    /// A submission still on the device, numbered `id` by its backend.
    pub fn pending(id: u64) -> Submission {
        Submission {
            id,
            state: SubmissionState::Pending,
        }
    }

    /// A submission that finished when it was made.
    pub fn finished(result: Finished) -> Submission {
        Submission {
            id: 0,
            state: SubmissionState::Finished(result),
        }
    }

    /// Whether the backend still owes its result.
    pub fn is_pending(&self) -> bool {
        matches!(self.state, SubmissionState::Pending)
    }

    /// Marks the result handed out (a backend's `poll` calls this when it gives it).
    pub fn mark_collected(&mut self) {
        self.state = SubmissionState::Collected;
    }

    /// The result of a submission that finished when it was made; an error if it was
    /// collected already or is still pending (a backend's own `poll` handles those).
    pub fn take_finished(&mut self) -> Result<Finished, BackendError> {
        match std::mem::replace(&mut self.state, SubmissionState::Collected) {
            SubmissionState::Finished(f) => Ok(f),
            SubmissionState::Collected => Err(BackendError::BadArgument(format!(
                "submission {} was collected already",
                self.id
            ))),
            SubmissionState::Pending => {
                self.state = SubmissionState::Pending;
                Err(BackendError::BadArgument(format!(
                    "submission {} belongs to another backend",
                    self.id
                )))
            }
        }
    }
}

/// Most submissions a backend keeps uncollected: beyond it, the oldest is waited for and
/// its result discarded (polling it later is an error), so a host that never asks for
/// its frames' statistics does not grow the backend's memory.
pub const MAX_UNCOLLECTED: usize = 64;

/// What an asynchronous backend keeps of the submissions it finished before they were
/// polled (waited for to free a slot, or to bound its uncollected work), oldest dropped
/// first beyond [`MAX_UNCOLLECTED`]; and the start of every such backend's `poll`.
#[derive(Debug, Default)]
pub struct UncollectedResults {
    results: std::collections::BTreeMap<u64, Result<Finished, BackendError>>,
}

impl UncollectedResults {
    /// Keeps the result of submission `id` until it is polled.
    pub fn keep(&mut self, id: u64, result: Result<Finished, BackendError>) {
        if self.results.len() >= MAX_UNCOLLECTED {
            self.results.pop_first();
        }
        self.results.insert(id, result);
    }

    /// A poll's answer that needs no device: a submission that finished when it was made,
    /// one collected already (an error), or one kept here. `None`: the backend looks at
    /// its work in flight.
    pub fn settle(
        &mut self,
        submission: &mut Submission,
    ) -> Option<Result<Option<Finished>, BackendError>> {
        if !submission.is_pending() {
            return Some(submission.take_finished().map(Some));
        }
        let r = self.results.remove(&submission.id)?;
        submission.mark_collected();
        Some(r.map(Some))
    }

    /// Forgets every kept result.
    pub fn clear(&mut self) {
        self.results.clear();
    }
}

/// Submissions a backend with kept frame slots (OpenCL's staging, Vulkan's command
/// buffers and pools) has on its device at once; the next waits for the oldest (a host
/// running more frames ahead than this is paced by the device).
pub const MAX_FRAMES_IN_FLIGHT: usize = 3;

/// What an asynchronous backend keeps of its submissions: those on its device (`T`, the
/// backend's own record of one), by number, oldest first; the results of those it
/// finished before they were polled ([`UncollectedResults`]); and the numbering. Its
/// [`Submissions::settle`] is the start of every such backend's `poll`.
#[derive(Debug)]
pub struct Submissions<T> {
    on_device: std::collections::BTreeMap<u64, T>,
    finished: UncollectedResults,
    last: u64,
}

impl<T> Default for Submissions<T> {
    fn default() -> Self {
        Submissions {
            on_device: Default::default(),
            finished: Default::default(),
            last: 0,
        }
    }
}

impl<T> Submissions<T> {
    /// The number the next submission will get.
    pub fn next_id(&self) -> u64 {
        self.last + 1
    }

    /// The number of the last submission made (0 before the first).
    pub fn last_id(&self) -> u64 {
        self.last
    }

    /// Adds a submission now on the device, numbered [`Submissions::next_id`].
    pub fn push(&mut self, on_device: T) -> Submission {
        self.last += 1;
        self.on_device.insert(self.last, on_device);
        Submission::pending(self.last)
    }

    /// How many are on the device.
    pub fn len(&self) -> usize {
        self.on_device.len()
    }

    /// Whether none is on the device.
    pub fn is_empty(&self) -> bool {
        self.on_device.is_empty()
    }

    /// Submission `id`, while it is on the device.
    pub fn get(&self, id: u64) -> Option<&T> {
        self.on_device.get(&id)
    }

    /// Submission `id`, while it is on the device.
    pub fn get_mut(&mut self, id: u64) -> Option<&mut T> {
        self.on_device.get_mut(&id)
    }

    /// The number of the oldest submission on the device.
    pub fn oldest(&self) -> Option<u64> {
        self.on_device.keys().next().copied()
    }

    /// Takes the oldest submission off the device list (to wait for it, and
    /// [`Submissions::keep`] its result for its poll).
    pub fn take_oldest(&mut self) -> Option<(u64, T)> {
        self.on_device.pop_first()
    }

    /// Keeps the result of submission `id`, finished before it was polled, until it is
    /// polled.
    pub fn keep(&mut self, id: u64, result: Result<Finished, BackendError>) {
        self.finished.keep(id, result);
    }

    /// The start of `poll`: the answer when it needs no device (a submission that
    /// finished when it was made, one collected already, one whose result is kept, or
    /// one this backend does not have: [`unknown_submission`]). `None`: `submission` is on
    /// the device ([`Submissions::get`] has it).
    pub fn settle(
        &mut self,
        submission: &mut Submission,
    ) -> Option<Result<Option<Finished>, BackendError>> {
        if let Some(answer) = self.finished.settle(submission) {
            return Some(answer);
        }
        if !self.on_device.contains_key(&submission.id) {
            return Some(Err(unknown_submission(submission.id)));
        }
        None
    }

    /// Takes `submission` off the device list and marks it collected (its result is being
    /// handed out).
    pub fn collect(&mut self, submission: &mut Submission) -> Option<T> {
        let on_device = self.on_device.remove(&submission.id)?;
        submission.mark_collected();
        Some(on_device)
    }

    /// Forgets every submission and kept result (the backend is going away; the device
    /// has finished).
    pub fn clear(&mut self) {
        self.on_device.clear();
        self.finished.clear();
    }
}

/// Pass times from device timestamps: `ticks` holds a (start, end) pair per pass in
/// `passes`' order, `period_ns` nanoseconds per tick.
pub fn pass_times_from_ticks(
    passes: &[&'static str],
    ticks: &[u64],
    period_ns: f64,
) -> Vec<PassTime> {
    passes
        .iter()
        .enumerate()
        .map(|(i, k)| PassTime {
            kernel: k,
            seconds: ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period_ns * 1e-9,
        })
        .collect()
}

/// The error of polling a submission a backend neither has in flight nor kept.
pub fn unknown_submission(id: u64) -> BackendError {
    BackendError::BadArgument(format!(
        "submission {id} is not one of this backend's, or its result was discarded \
         ({MAX_UNCOLLECTED} newer submissions were left uncollected)"
    ))
}

/// What a finished submission gives back.
#[derive(Clone, Debug, Default)]
pub struct Finished {
    /// Time of each kernel step, in order (see [`Capabilities::timestamps`]).
    pub times: Vec<PassTime>,
    /// The bytes of each buffer asked for in [`Backend::submit`]'s `readbacks`, in that
    /// order, as they were after the submission's last step.
    pub readbacks: Vec<Vec<u8>>,
}

#[cfg(test)]
mod tests {
    use super::*;

    fn done(n: usize) -> Result<Finished, BackendError> {
        Ok(Finished {
            times: Vec::new(),
            readbacks: vec![vec![0u8; n]],
        })
    }

    #[test]
    fn submissions_are_numbered_and_settled_once() {
        let mut s: Submissions<&str> = Submissions::default();
        assert_eq!(s.next_id(), 1);
        let mut a = s.push("a");
        let mut b = s.push("b");
        assert_eq!((a.id, b.id, s.last_id(), s.len()), (1, 2, 2, 2));
        // on the device: the backend looks
        assert!(s.settle(&mut a).is_none());
        assert_eq!(s.collect(&mut a), Some("a"));
        assert!(!a.is_pending());
        // collected already: an error, not the backend's business
        assert!(matches!(s.settle(&mut a), Some(Err(_))));
        // retired before its poll: the kept result, once
        assert_eq!(s.take_oldest(), Some((2, "b")));
        s.keep(2, done(3));
        let kept = s
            .settle(&mut b)
            .expect("kept")
            .expect("ok")
            .expect("finished");
        assert_eq!(kept.readbacks, vec![vec![0u8; 3]]);
        assert!(matches!(s.settle(&mut b), Some(Err(_))));
        // not this backend's
        let mut other = Submission::pending(99);
        let e = s.settle(&mut other).expect("answered").unwrap_err();
        assert!(e.to_string().contains("not one of this backend's"), "{e}");
    }

    #[test]
    fn pass_times_are_tick_differences() {
        let t = pass_times_from_ticks(&["a", "b"], &[10, 30, 40, 35], 2.0);
        assert_eq!(t[0].kernel, "a");
        assert_eq!(t[0].seconds, 20.0 * 2.0 * 1e-9);
        assert_eq!(t[1].seconds, 0.0, "a clock that went back counts as 0");
    }
}
