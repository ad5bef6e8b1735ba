//! The non-blocking submission (docs/embedding.md, "A host's frame loop"): a recording
//! encoded into a command encoder (the backend's own, submitted at once, or the embedding
//! host's, submitted by the host), with copies of its timestamps and of the asked-for
//! buffers into mappable staging at its end. Nothing waits: the staging is mapped
//! asynchronously once the work is on the queue, and [`Backend::poll`] hands the result out
//! when every mapping is done.

use crate::{dispatch, kernel_count, WgpuBackend};
use caustica_core::backend::{BackendError, Finished, Submission};
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::Recording;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};

/// A submission not yet collected.
pub struct InFlight {
    /// The queue's index, once submitted (`None` until the host has submitted its
    /// encoder: [`WgpuBackend::submitted`]).
    index: Option<wgpu::SubmissionIndex>,
    /// Mappable copies: the timestamps (if timed on the device) then the readbacks
    /// (from the pool, given back when collected).
    staging: Vec<(wgpu::Buffer, u64)>,
    /// The timestamp queries (from the pool, given back when collected).
    queries: Option<crate::pool::TimestampQueries>,
    /// Kernels timed, their timestamp period, and whether `staging[0]` holds the ticks.
    passes: Vec<&'static str>,
    period_ns: f32,
    timed: bool,
    /// Whether the mappings were requested (the encoder is on the queue).
    requested: bool,
    /// Mappings completed (plus one for the queue's work-done callback), and the first
    /// mapping error.
    mapped: Arc<AtomicUsize>,
    failed: Arc<Mutex<Option<String>>>,
}

/// A mappable copy of `bytes` of `src` in a staging buffer from `pool`, recorded into
/// `enc`.
fn staged_copy(
    pool: &mut crate::pool::SubmissionPool,
    device: &wgpu::Device,
    enc: &mut wgpu::CommandEncoder,
    src: &wgpu::Buffer,
    bytes: u64,
) -> (wgpu::Buffer, u64) {
    let size = bytes.max(4).next_multiple_of(wgpu::COPY_BUFFER_ALIGNMENT);
    let staging = pool.staging(device, size);
    if bytes > 0 {
        enc.copy_buffer_to_buffer(src, 0, &staging, 0, size.min(src.size()));
    }
    (staging, bytes)
}

impl WgpuBackend {
    /// Records `recording` into the caller's `enc` without submitting or waiting: the
    /// host submits `enc` on this backend's queue (the one given to
    /// [`WgpuBackend::from_device`]), then calls [`WgpuBackend::submitted`], and collects
    /// the result later with [`caustica_core::backend::Backend::poll`]. After the last step
    /// the buffers in `readbacks` are copied into mappable staging (their values at that
    /// point). Buffers the recording creates exist at once; steps run in `enc`'s order,
    /// after whatever the host recorded before and before what it records after.
    pub fn encode(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
        enc: &mut wgpu::CommandEncoder,
    ) -> Result<Submission, BackendError> {
        self.check_uncaptured()?;
        if self.in_flight.len() >= caustica_core::backend::MAX_UNCOLLECTED {
            // a host this far ahead is paced by the device: wait for the oldest and keep
            // its result for its poll
            if let Some(oldest) = self.in_flight.keys().min().copied() {
                let mut s = Submission::pending(oldest);
                let result = self.poll_submission(&mut s, true);
                self.finished
                    .keep(oldest, result.map(|r| r.unwrap_or_default()));
            }
        }
        let mut timer = dispatch::Timer::new(self, kernel_count(recording));
        self.encode_steps(recording, enc, &mut timer, false)?;
        timer.resolve(enc);
        let mut staging = Vec::new();
        let timed = if let Some((buf, bytes)) = timer.resolved() {
            staging.push(staged_copy(&mut self.pool, &self.device, enc, buf, bytes));
            true
        } else {
            false
        };
        for id in readbacks {
            let b = self
                .buffers
                .get(id)
                .ok_or(BackendError::MissingResource(*id))?;
            staging.push(staged_copy(
                &mut self.pool,
                &self.device,
                enc,
                &b.buffer,
                b.bytes,
            ));
        }
        let queries = timer.take_queries();
        self.next_submission += 1;
        let id = self.next_submission;
        self.in_flight.insert(
            id,
            InFlight {
                index: None,
                staging,
                queries,
                passes: timer.passes().to_vec(),
                period_ns: timer.period_ns(),
                timed,
                requested: false,
                mapped: Arc::new(AtomicUsize::new(0)),
                failed: Arc::new(Mutex::new(None)),
            },
        );
        Ok(Submission::pending(id))
    }

    /// Timestamp query sets and staging buffers created so far: they are kept and reused,
    /// so in a frame loop's steady state this stops growing.
    pub fn pooled_resources_created(&self) -> u64 {
        self.pool.created
    }

    /// Tells the backend that the encoder holding `submission` was submitted (its queue
    /// index, if the host has it): the staging copies are mapped asynchronously from now.
    /// [`caustica_core::backend::Backend::poll`] calls it itself if the host did not, so
    /// poll only after submitting the encoder.
    pub fn submitted(
        &mut self,
        submission: &Submission,
        index: Option<wgpu::SubmissionIndex>,
    ) -> Result<(), BackendError> {
        let Some(f) = self.in_flight.get_mut(&submission.id) else {
            return Ok(());
        };
        if f.requested {
            return Ok(());
        }
        f.requested = true;
        f.index = index;
        for (buf, _) in &f.staging {
            let (mapped, failed) = (Arc::clone(&f.mapped), Arc::clone(&f.failed));
            buf.slice(..).map_async(wgpu::MapMode::Read, move |r| {
                if let Err(e) = r {
                    if let Ok(mut g) = failed.lock() {
                        g.get_or_insert(e.to_string());
                    }
                }
                mapped.fetch_add(1, Ordering::AcqRel);
            });
        }
        // and the queue's own word that the work submitted so far is done
        let mapped = Arc::clone(&f.mapped);
        self.queue.on_submitted_work_done(move || {
            mapped.fetch_add(1, Ordering::AcqRel);
        });
        Ok(())
    }

    /// [`caustica_core::backend::Backend::poll`]'s body.
    pub(crate) fn poll_submission(
        &mut self,
        s: &mut Submission,
        wait: bool,
    ) -> Result<Option<Finished>, BackendError> {
        if let Some(answer) = self.finished.settle(s) {
            return answer;
        }
        let Some(f) = self.in_flight.get(&s.id) else {
            return Err(caustica_core::backend::unknown_submission(s.id));
        };
        let index = f.index.clone();
        if !f.requested {
            self.submitted(s, None)?;
        }
        let poll = if wait {
            wgpu::PollType::Wait {
                submission_index: index,
                timeout: None,
            }
        } else {
            wgpu::PollType::Poll
        };
        self.device
            .poll(poll)
            .map_err(|e| BackendError::DeviceLost(e.to_string()))?;
        self.check_uncaptured()?;
        // every mapping and the work-done callback
        let complete = |f: &InFlight| f.mapped.load(Ordering::Acquire) > f.staging.len();
        if !complete(&self.in_flight[&s.id]) {
            if wait {
                // a host-submitted encoder has no index here: wait for everything
                self.wait()?;
            }
            if !complete(&self.in_flight[&s.id]) {
                if wait {
                    return Err(BackendError::Driver(
                        "a submission's readback did not complete (was its encoder \
                         submitted on this backend's queue?)"
                            .into(),
                    ));
                }
                return Ok(None);
            }
        }
        let f = self.in_flight.remove(&s.id).expect("looked up above");
        s.mark_collected();
        if let Some(e) = f.failed.lock().ok().and_then(|mut g| g.take()) {
            return Err(BackendError::Driver(format!(
                "mapping a submission's readback: {e}"
            )));
        }
        let mut data = Vec::with_capacity(f.staging.len());
        let mut read = Ok(());
        for (buf, bytes) in &f.staging {
            if read.is_ok() {
                read = buf
                    .slice(..)
                    .get_mapped_range()
                    .map_err(|e| BackendError::Driver(format!("reading back: {e}")))
                    .and_then(|view| {
                        let mut out =
                            caustica_core::device::host_bytes(*bytes, "a submission's readback")?;
                        out.copy_from_slice(&view[..*bytes as usize]);
                        data.push(out);
                        Ok(())
                    });
            }
        }
        // the staging and the queries back to the pool (unmapped: the views are gone)
        let InFlight {
            staging,
            queries,
            passes,
            period_ns,
            timed,
            ..
        } = f;
        for (buf, _) in staging {
            buf.unmap();
            self.pool.give_staging(buf);
        }
        if let Some(q) = queries {
            self.pool.give_queries(q);
        }
        read?;
        let times = if timed {
            dispatch::Timer::times_from_ticks(&passes, &data.remove(0), period_ns)
        } else {
            // without timestamp queries a submitted frame's kernels are not timed (timing
            // them on the host would mean waiting for each)
            Vec::new()
        };
        Ok(Some(Finished {
            times,
            readbacks: data,
        }))
    }
}
