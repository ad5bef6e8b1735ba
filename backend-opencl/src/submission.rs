//! The non-blocking submission (docs/embedding.md, "A host's frame loop"):
//! [`Backend::submit`] only enqueues (writes and readbacks non-blocking, a marker event
//! last, a flush) into a staging slot kept across submissions, and [`Backend::poll`] hands
//! the kernel times (profiling events) and readbacks out once the marker has completed.
//! With `MAX_FRAMES_IN_FLIGHT` submissions on the queue the next waits for the oldest.
//!
//! [`Backend::submit`]: caustica_core::backend::Backend::submit
//! [`Backend::poll`]: caustica_core::backend::Backend::poll

use crate::device::cl_error;
use crate::memory::StagingSlot;
use crate::OpenClBackend;
use caustica_core::backend::{BackendError, Finished, PassTime, Submission, MAX_FRAMES_IN_FLIGHT};
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::Recording;
use opencl3::event::{Event, CL_COMPLETE};
use opencl3::memory::Buffer;

/// A submission on the queue (`Backend::submit`): what it must keep alive until it has
/// run, and what it gives back.
pub(crate) struct InFlight {
    /// Kernel names and their profiling events.
    kernels: Vec<(&'static str, Event)>,
    /// The launches' parameter sub-buffers (released once done).
    _params: Vec<Buffer<u8>>,
    /// The staging slot (parameters, write data, readback landing).
    slot: StagingSlot,
    /// Offset and size of each readback in the slot's pinned readback memory.
    readbacks: Vec<(usize, usize)>,
    /// A marker after everything else: complete when the submission is.
    done: Event,
}

/// Kernel times from profiling events (the commands have completed).
fn pass_times(kernels: &[(&'static str, Event)]) -> Result<Vec<PassTime>, BackendError> {
    kernels
        .iter()
        .map(|(kernel, e)| {
            let start = e
                .profiling_command_start()
                .map_err(cl_error("reading a kernel timestamp"))?;
            let end = e
                .profiling_command_end()
                .map_err(cl_error("reading a kernel timestamp"))?;
            Ok(PassTime {
                kernel,
                seconds: end.saturating_sub(start) as f64 * 1e-9,
            })
        })
        .collect()
}

impl OpenClBackend {
    /// The OpenCL event that completes with `submission` (its marker), while it is on
    /// the queue: a host with its own OpenCL work on this context waits on it (retain it
    /// with `clRetainEvent` to keep it past the submission's collection). `None` once the
    /// submission was collected.
    pub fn submission_event(&self, submission: &Submission) -> Option<opencl3::types::cl_event> {
        self.submissions.get(submission.id).map(|f| f.done.get())
    }

    /// [`caustica_core::backend::Backend::execute`]'s body (core runs it inside
    /// [`caustica_core::backend::driver_entry`]): a submission, waited for.
    pub(crate) fn execute_recording(
        &mut self,
        recording: &Recording,
    ) -> Result<Vec<PassTime>, BackendError> {
        let mut s = self.submit_recording(recording, &[])?;
        let f = self.poll_submission(&mut s, true)?;
        Ok(f.map(|f| f.times).unwrap_or_default())
    }

    /// A staging slot: a free one, a new one, or (with [`MAX_FRAMES_IN_FLIGHT`] on the
    /// queue) the oldest submission's once it has finished, its result kept for its poll.
    fn take_slot(&mut self) -> Result<StagingSlot, BackendError> {
        if let Some(s) = self.free_slots.pop() {
            return Ok(s);
        }
        if self.submissions.len() >= MAX_FRAMES_IN_FLIGHT {
            let (oldest, f) = self.submissions.take_oldest().expect("not empty");
            let result = self.retire(f, true);
            self.submissions.keep(oldest, result);
            if let Some(s) = self.free_slots.pop() {
                return Ok(s);
            }
        }
        Ok(StagingSlot::default())
    }

    /// A finished (or, with `wait`, waited-for) submission's result; its slot back in the
    /// free list.
    fn retire(&mut self, f: InFlight, wait: bool) -> Result<Finished, BackendError> {
        let waited = if wait {
            f.done.wait().map_err(cl_error("waiting for a submission"))
        } else {
            Ok(())
        };
        let result = waited.and_then(|_| {
            let times = pass_times(&f.kernels)?;
            let mut readbacks = Vec::with_capacity(f.readbacks.len());
            for (at, bytes) in &f.readbacks {
                let mut out =
                    caustica_core::device::host_bytes(*bytes as u64, "a submission's readback")?;
                if let Some(p) = &f.slot.readback {
                    out.copy_from_slice(p.bytes(*at, *bytes));
                }
                readbacks.push(out);
            }
            Ok(Finished { times, readbacks })
        });
        self.free_slots.push(f.slot);
        result
    }

    /// [`caustica_core::backend::Backend::submit`]'s body: the recording's parameters and
    /// write data staged in a slot's pinned memory and uploaded by non-blocking copies,
    /// every step enqueued, the readbacks copied into pinned memory, a marker, a flush; no
    /// wait (see [`crate::memory`]). Creations upload blocking (set-up work, not a frame's).
    pub(crate) fn submit_recording(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        let layout = self.layout(recording, readbacks)?;
        let mut slot = self.take_slot()?;
        let staged = self.enqueue(recording, readbacks, &layout, &mut slot);
        let (kernels, params) = match staged {
            Ok(x) => x,
            Err(e) => {
                // what was enqueued may still read the slot: let it finish first
                let _ = self.queue.finish();
                self.free_slots.push(slot);
                return Err(e);
            }
        };
        let done = match unsafe { self.queue.enqueue_marker_with_wait_list(&[]) }
            .map_err(cl_error("enqueueing a submission's marker"))
            .and_then(|d| {
                self.queue
                    .flush()
                    .map_err(cl_error("flushing the queue"))
                    .map(|_| d)
            }) {
            Ok(d) => d,
            Err(e) => {
                let _ = self.queue.finish();
                self.free_slots.push(slot);
                return Err(e);
            }
        };
        Ok(self.submissions.push(InFlight {
            kernels,
            _params: params,
            slot,
            readbacks: layout.readbacks,
            done,
        }))
    }

    /// [`caustica_core::backend::Backend::poll`]'s body.
    pub(crate) fn poll_submission(
        &mut self,
        s: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        if let Some(answer) = self.submissions.settle(s) {
            return answer;
        }
        if !wait {
            let f = self.submissions.get(s.id).expect("settle: on the device");
            let status = f
                .done
                .command_execution_status()
                .map_err(cl_error("querying a submission"))?;
            if status.0 < 0 {
                return Err(BackendError::Driver(format!(
                    "a submission failed on the device (status {})",
                    status.0
                )));
            }
            if status.0 != CL_COMPLETE {
                return Ok(None);
            }
        }
        let f = self.submissions.collect(s).expect("looked up above");
        self.retire(f, wait).map(Some)
    }
}
