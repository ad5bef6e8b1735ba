//! The non-blocking submission (docs/embedding.md, "A host's frame loop"): a recording
//! encoded into a command encoder (the backend's own, submitted at once, or the embedding
//! host's, submitted by the host), with copies of its timestamps and of the asked-for
//! buffers into mappable staging at its end. Nothing waits: the staging is mapped
//! asynchronously once the work is on the queue, and [`Backend::poll`] hands the result out
//! when every mapping is done. Kernel times come from timestamp queries ([`Timer`]); the
//! query sets and staging buffers are kept and reused ([`SubmissionPool`]).

use crate::WgpuBackend;
use caustica_core::backend::{BackendError, Finished, PassTime, Submission};
use caustica_core::device::handle::ResourceId;
use caustica_core::recording::Recording;
use std::collections::HashMap;
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
    queries: Option<TimestampQueries>,
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
    pool: &mut SubmissionPool,
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
        if self.submissions.len() >= caustica_core::backend::MAX_UNCOLLECTED {
            // a host this far ahead is paced by the device: wait for the oldest and keep
            // its result for its poll
            if let Some(oldest) = self.submissions.oldest() {
                let mut s = Submission::pending(oldest);
                let result = self.poll_submission(&mut s, true);
                self.submissions
                    .keep(oldest, result.map(|r| r.unwrap_or_default()));
            }
        }
        let mut timer = Timer::new(self, recording.kernel_count());
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
            let b = self.buffers.get(*id)?;
            staging.push(staged_copy(
                &mut self.pool,
                &self.device,
                enc,
                &b.buffer,
                b.bytes,
            ));
        }
        let queries = timer.take_queries();
        Ok(self.submissions.push(InFlight {
            index: None,
            staging,
            queries,
            passes: timer.passes().to_vec(),
            period_ns: timer.period_ns(),
            timed,
            requested: false,
            mapped: Arc::new(AtomicUsize::new(0)),
            failed: Arc::new(Mutex::new(None)),
        }))
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
        let Some(f) = self.submissions.get_mut(submission.id) else {
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

    /// [`caustica_core::backend::Backend::submit`]'s body: the recording encoded into the
    /// backend's own encoder, submitted at once.
    pub(crate) fn submit_recording(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
    ) -> Result<Submission, BackendError> {
        let mut enc = self.device.create_command_encoder(&Default::default());
        let s = self.encode(recording, readbacks, &mut enc)?;
        let index = self.queue.submit([enc.finish()]);
        self.submitted(&s, Some(index))?;
        Ok(s)
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
        let f = self.submissions.get(s.id).expect("settle: on the device");
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
        if !complete(self.submissions.get(s.id).expect("on the device")) {
            if wait {
                // a host-submitted encoder has no index here: wait for everything
                self.wait()?;
            }
            if !complete(self.submissions.get(s.id).expect("on the device")) {
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
        let f = self.submissions.collect(s).expect("looked up above");
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
            Timer::times_from_ticks(&passes, &data.remove(0), period_ns)
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

/// Per-pass timing: a timestamp pair per kernel where the device has timestamp queries,
/// else host times of kernels submitted alone.
pub struct Timer {
    queries: Option<TimestampQueries>,
    /// The kernels recorded, in order.
    pub(crate) passes: Vec<&'static str>,
    host: Vec<f64>,
    period_ns: f32,
}

impl Timer {
    /// A timer for `kernels` kernels, its query set from the backend's pool (give it back
    /// with [`Timer::give_back`] once its ticks are read).
    pub fn new(b: &mut WgpuBackend, kernels: u32) -> Timer {
        let queries = (b.timestamps && kernels > 0).then(|| b.pool.queries(&b.device, kernels));
        Timer {
            queries,
            passes: Vec::new(),
            host: Vec::new(),
            period_ns: b.queue.get_timestamp_period(),
        }
    }

    /// The query set, taken out (to be kept until the GPU has resolved it).
    pub fn take_queries(&mut self) -> Option<TimestampQueries> {
        self.queries.take()
    }

    /// Returns the query set to the backend's pool.
    pub fn give_back(&mut self, b: &mut WgpuBackend) {
        if let Some(q) = self.queries.take() {
            b.pool.give_queries(q);
        }
    }

    pub(crate) fn writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let i = self.passes.len() as u32;
        self.queries
            .as_ref()
            .map(|q| wgpu::ComputePassTimestampWrites {
                query_set: &q.set,
                beginning_of_pass_write_index: Some(2 * i),
                end_of_pass_write_index: Some(2 * i + 1),
            })
    }

    pub fn host_time(&mut self, seconds: f64) {
        self.host.push(seconds);
    }

    pub fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        if let Some(q) = &self.queries {
            if !self.passes.is_empty() {
                enc.resolve_query_set(&q.set, 0..2 * self.passes.len() as u32, &q.resolve, 0);
            }
        }
    }

    /// The resolved timestamps' buffer and its length in bytes (after [`Timer::resolve`]),
    /// if the passes were timed on the device.
    pub fn resolved(&self) -> Option<(&wgpu::Buffer, u64)> {
        match &self.queries {
            Some(q) if !self.passes.is_empty() => Some((&q.resolve, 16 * self.passes.len() as u64)),
            _ => None,
        }
    }

    /// The kernels recorded, in order.
    pub fn passes(&self) -> &[&'static str] {
        &self.passes
    }

    /// Pass times from resolved timestamp pairs (`raw`: the bytes of [`Timer::resolved`]).
    pub fn times_from_ticks(passes: &[&'static str], raw: &[u8], period_ns: f32) -> Vec<PassTime> {
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(raw);
        caustica_core::backend::pass_times_from_ticks(passes, &ticks, period_ns as f64)
    }

    /// The timestamp period (ns per tick).
    pub fn period_ns(&self) -> f32 {
        self.period_ns
    }

    pub fn finish(mut self, b: &mut WgpuBackend) -> Result<Vec<PassTime>, BackendError> {
        match self.resolved() {
            Some((buf, bytes)) => {
                let raw = b.read_buffer(buf, bytes);
                self.give_back(b);
                Ok(Self::times_from_ticks(&self.passes, &raw?, self.period_ns))
            }
            _ => Ok(self
                .passes
                .iter()
                .zip(self.host.iter().chain(std::iter::repeat(&0.0)))
                .map(|(k, s)| PassTime {
                    kernel: k,
                    seconds: *s,
                })
                .collect()),
        }
    }
}

/// A timestamp query set for up to `capacity` kernels (two queries each) and the buffer
/// its ticks are resolved into.
pub struct TimestampQueries {
    pub set: wgpu::QuerySet,
    pub resolve: wgpu::Buffer,
    pub capacity: u32,
}

/// The free resources.
#[derive(Default)]
pub struct SubmissionPool {
    queries: Vec<TimestampQueries>,
    staging: HashMap<u64, Vec<wgpu::Buffer>>,
    /// Query sets and staging buffers created so far (what the pool saves shows here).
    pub created: u64,
}

/// Most free staging buffers kept per size (a frame's readbacks times the frames in
/// flight; beyond that they are dropped).
const MAX_FREE_PER_SIZE: usize = 8;

impl SubmissionPool {
    /// A query set for `kernels` kernels: the smallest free one that holds them, or a new
    /// one (capacity rounded up to a power of two, at least 16).
    pub fn queries(&mut self, device: &wgpu::Device, kernels: u32) -> TimestampQueries {
        let best = self
            .queries
            .iter()
            .enumerate()
            .filter(|(_, q)| q.capacity >= kernels)
            .min_by_key(|(_, q)| q.capacity)
            .map(|(i, _)| i);
        if let Some(i) = best {
            return self.queries.swap_remove(i);
        }
        self.created += 1;
        let capacity = kernels.next_power_of_two().max(16);
        TimestampQueries {
            set: device.create_query_set(&wgpu::QuerySetDescriptor {
                label: Some("pass timestamps"),
                ty: wgpu::QueryType::Timestamp,
                count: 2 * capacity,
            }),
            resolve: device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("timestamp resolve"),
                size: 16 * capacity as u64,
                usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
                mapped_at_creation: false,
            }),
            capacity,
        }
    }

    /// Gives a query set back.
    pub fn give_queries(&mut self, q: TimestampQueries) {
        self.queries.push(q);
    }

    /// A mappable staging buffer of `size` bytes (a multiple of the copy alignment).
    pub fn staging(&mut self, device: &wgpu::Device, size: u64) -> wgpu::Buffer {
        if let Some(b) = self.staging.get_mut(&size).and_then(Vec::pop) {
            return b;
        }
        self.created += 1;
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("submission readback"),
            size,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// Gives an unmapped staging buffer back.
    pub fn give_staging(&mut self, b: wgpu::Buffer) {
        let free = self.staging.entry(b.size()).or_default();
        if free.len() < MAX_FREE_PER_SIZE {
            free.push(b);
        }
    }
}
