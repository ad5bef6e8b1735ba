//! The non-blocking submission (docs/embedding.md, "A host's frame loop"): each submission
//! records into the command buffer of a *frame slot* (its own descriptor pool, timestamp
//! query pool, parameter and staging arena, readback buffer and fence, all kept and reset,
//! never made per frame) and is submitted once with the slot's fence, signalling the
//! backend's timeline semaphore with its number when the host asked for one
//! ([`VulkanBackend::completion_semaphore`]). Nothing waits: a slot is reused once its
//! fence has signalled, and only when [`MAX_FRAMES_IN_FLIGHT`] are on the device does a new
//! submission wait for the oldest. [`caustica_core::backend::Backend::poll`] checks a fence
//! without blocking and hands out the times and readbacks.

use crate::accel::SceneAccel;
use crate::device::{vk_error, Context};
use crate::memory::{Arena, Buffer};
use crate::pipelines::{ensure_variants, AS, S, U};
use crate::recording::{barrier, record_all};
use crate::VulkanBackend;
use ash::vk;
use caustica_core::backend::{BackendError, Finished, PassTime, Submission, MAX_FRAMES_IN_FLIGHT};
use caustica_core::kernels::{ShaderBinding, KERNELS};
use caustica_core::recording::Recording;
use std::sync::Arc;

/// What one submission records with, reused once its fence has signalled.
pub struct FrameSlot {
    ctx: Arc<Context>,
    descriptor_pool: Option<(vk::DescriptorPool, u32)>,
    query_pool: Option<(vk::QueryPool, u32)>,
    /// Kernel parameters and staging ([`crate::memory::Arena`]).
    pub arena: Arena,
    readback: Option<Buffer>,
    pub fence: vk::Fence,
    /// The command buffer of the slot's last submission (its pool's flag lets it be
    /// reset and recorded again).
    pub cmd: Option<vk::CommandBuffer>,
}

impl FrameSlot {
    fn new(ctx: &Arc<Context>) -> Result<FrameSlot, BackendError> {
        let fence = unsafe {
            ctx.device
                .create_fence(&vk::FenceCreateInfo::default(), None)
        }
        .map_err(vk_error("creating a fence"))?;
        Ok(FrameSlot {
            ctx: Arc::clone(ctx),
            descriptor_pool: None,
            query_pool: None,
            arena: Arena::default(),
            readback: None,
            fence,
            cmd: None,
        })
    }

    /// Readies the slot for a submission of `sets` descriptor sets (each with
    /// `per_set` descriptors of each type) and `queries` timestamps: pools reset, or
    /// made anew larger; the arena emptied (and grown to what its last use wanted).
    pub fn prepare(
        &mut self,
        ctx: &Arc<Context>,
        sets: u32,
        per_set: &[vk::DescriptorPoolSize; 3],
        queries: u32,
    ) -> Result<(), BackendError> {
        let d = &ctx.device;
        match self.descriptor_pool {
            Some((p, cap)) if cap >= sets => {
                unsafe { d.reset_descriptor_pool(p, vk::DescriptorPoolResetFlags::empty()) }
                    .map_err(vk_error("resetting the descriptor pool"))?;
            }
            old => {
                if let Some((p, _)) = old {
                    unsafe { d.destroy_descriptor_pool(p, None) };
                    self.descriptor_pool = None;
                }
                let cap = sets.max(64).next_power_of_two();
                let sizes = per_set.map(|s| s.descriptor_count(s.descriptor_count * cap));
                let p = unsafe {
                    d.create_descriptor_pool(
                        &vk::DescriptorPoolCreateInfo::default()
                            .max_sets(cap)
                            .pool_sizes(&sizes),
                        None,
                    )
                }
                .map_err(vk_error("creating a descriptor pool"))?;
                self.descriptor_pool = Some((p, cap));
            }
        }
        if queries > 0 && !matches!(self.query_pool, Some((_, cap)) if cap >= queries) {
            if let Some((q, _)) = self.query_pool.take() {
                unsafe { d.destroy_query_pool(q, None) };
            }
            let cap = queries.max(128).next_power_of_two();
            let q = unsafe {
                d.create_query_pool(
                    &vk::QueryPoolCreateInfo::default()
                        .query_type(vk::QueryType::TIMESTAMP)
                        .query_count(cap),
                    None,
                )
            }
            .map_err(vk_error("creating a query pool"))?;
            self.query_pool = Some((q, cap));
        }
        self.arena.reset(ctx)
    }

    pub fn descriptor_pool(&self) -> vk::DescriptorPool {
        self.descriptor_pool
            .map_or(vk::DescriptorPool::null(), |p| p.0)
    }

    pub fn query_pool(&self) -> Option<vk::QueryPool> {
        self.query_pool.map(|q| q.0)
    }

    /// The slot's host-visible readback buffer, at least `bytes` long.
    pub fn readback_buffer(
        &mut self,
        ctx: &Arc<Context>,
        bytes: u64,
    ) -> Result<vk::Buffer, BackendError> {
        if self.readback.as_ref().is_none_or(|b| b.size < bytes) {
            self.readback = Some(Buffer::new(
                ctx,
                bytes.max(256).next_power_of_two(),
                vk::BufferUsageFlags::TRANSFER_DST,
                true,
                "submission readback",
            )?);
        }
        Ok(self.readback.as_ref().expect("made above").buffer)
    }

    fn read_back(&self, offset: u64, bytes: u64) -> Result<Vec<u8>, BackendError> {
        let Some(b) = &self.readback else {
            return Ok(Vec::new());
        };
        let all = b.read((offset + bytes) as usize)?;
        Ok(all[offset as usize..].to_vec())
    }
}

impl Drop for FrameSlot {
    fn drop(&mut self) {
        // the device is idle: the backend waited before dropping its slots
        unsafe {
            if let Some((p, _)) = self.descriptor_pool.take() {
                self.ctx.device.destroy_descriptor_pool(p, None);
            }
            if let Some((q, _)) = self.query_pool.take() {
                self.ctx.device.destroy_query_pool(q, None);
            }
            self.ctx.device.destroy_fence(self.fence, None);
        }
    }
}

/// A submission on the device.
pub struct InFlight {
    pub cmd: vk::CommandBuffer,
    pub frame: Frame,
    /// Offset and size of each readback in the slot's readback buffer.
    pub readbacks: Vec<(u64, u64)>,
}

impl VulkanBackend {
    /// A free frame slot: a finished one, a new one, or (with
    /// [`MAX_FRAMES_IN_FLIGHT`] on the device) the oldest's once it has finished, its
    /// result kept for [`caustica_core::backend::Backend::poll`].
    pub(crate) fn take_slot(&mut self) -> Result<FrameSlot, BackendError> {
        if let Some(s) = self.free_slots.pop() {
            return Ok(s);
        }
        if self.submissions.len() >= MAX_FRAMES_IN_FLIGHT {
            let (id, oldest) = self.submissions.take_oldest().expect("not empty");
            let result = self.retire(oldest, true);
            self.submissions.keep(id, result);
            if let Some(s) = self.free_slots.pop() {
                return Ok(s);
            }
        }
        FrameSlot::new(&self.ctx)
    }

    /// Gives a slot back unused (a submission that failed before it was submitted).
    pub(crate) fn return_slot(&mut self, slot: FrameSlot) {
        self.free_slots.push(slot);
    }

    /// Ends `cmd` and submits it with `fence`, signalling the timeline semaphore with `id`
    /// if there is one.
    pub(crate) fn submit_signalled(
        &self,
        cmd: vk::CommandBuffer,
        fence: vk::Fence,
        id: u64,
    ) -> Result<(), BackendError> {
        let d = &self.ctx.device;
        unsafe { d.end_command_buffer(cmd) }.map_err(vk_error("ending a command buffer"))?;
        let cmds = [cmd];
        let semaphores = self.timeline.map(|t| [t]);
        let values = [id];
        let mut timeline =
            vk::TimelineSemaphoreSubmitInfo::default().signal_semaphore_values(&values);
        let mut info = vk::SubmitInfo::default().command_buffers(&cmds);
        if let Some(s) = &semaphores {
            info = info.signal_semaphores(s).push_next(&mut timeline);
        }
        unsafe { d.queue_submit(self.ctx.queue, &[info], fence) }.map_err(vk_error("vkQueueSubmit"))
    }

    /// A finished (or, with `wait`, waited-for) submission's times and readbacks; its
    /// slot back in the free list, its retired objects released.
    fn retire(&mut self, f: InFlight, wait: bool) -> Result<Finished, BackendError> {
        let d = self.ctx.device.clone();
        let waited = if wait {
            unsafe { d.wait_for_fences(&[f.frame.slot.fence], true, u64::MAX) }
                .map_err(vk_error("waiting for the device"))
        } else {
            Ok(())
        };
        let result = waited.and_then(|_| {
            let times = read_times(&self.ctx, &f.frame)?;
            let readbacks = f
                .readbacks
                .iter()
                .map(|(at, bytes)| f.frame.slot.read_back(*at, *bytes))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Finished { times, readbacks })
        });
        let Frame {
            retired,
            retired_scenes,
            slot,
            ..
        } = f.frame;
        drop(retired);
        drop(retired_scenes);
        unsafe {
            let _ = d.reset_fences(&[slot.fence]);
        }
        // the command buffer stays with its slot, reset when the slot records again
        let mut slot = slot;
        if let Some(old) = slot.cmd.replace(f.cmd) {
            unsafe { d.free_command_buffers(self.pool, &[old]) };
        }
        self.free_slots.push(slot);
        let result = result?;
        self.check_validation()?;
        Ok(result)
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

    /// [`caustica_core::backend::Backend::submit`]'s body.
    pub(crate) fn submit_recording(
        &mut self,
        recording: &Recording,
        readbacks: &[caustica_core::device::handle::ResourceId],
    ) -> Result<Submission, BackendError> {
        let id = self.submissions.next_id();
        let f = record_submission(self, recording, readbacks, id)?;
        Ok(self.submissions.push(f))
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
            let done = unsafe { self.ctx.device.get_fence_status(f.frame.slot.fence) }
                .map_err(vk_error("querying a fence"))?;
            if !done {
                return Ok(None);
            }
        }
        let f = self.submissions.collect(s).expect("looked up above");
        self.retire(f, wait).map(Some)
    }

    /// The device and queue the backend submits to (a host's own submissions that wait
    /// on [`VulkanBackend::completion_semaphore`] go to its queues of this device).
    pub fn device(&self) -> (&ash::Device, vk::Queue) {
        (&self.ctx.device, self.ctx.queue)
    }

    /// The timeline semaphore every later submission signals with its number
    /// ([`Submission::id`]): a host that submits its own work on another queue, or that
    /// presents, waits on it for value `id` instead of the CPU waiting (made on first call;
    /// a device from [`VulkanBackend::from_raw`] must have enabled `timelineSemaphore`).
    pub fn completion_semaphore(&mut self) -> Result<vk::Semaphore, BackendError> {
        if let Some(t) = self.timeline {
            return Ok(t);
        }
        let mut ty = vk::SemaphoreTypeCreateInfo::default()
            .semaphore_type(vk::SemaphoreType::TIMELINE)
            .initial_value(self.submissions.last_id());
        let t = unsafe {
            self.ctx
                .device
                .create_semaphore(&vk::SemaphoreCreateInfo::default().push_next(&mut ty), None)
        }
        .map_err(vk_error("creating the timeline semaphore"))?;
        self.timeline = Some(t);
        Ok(t)
    }
}

impl VulkanBackend {
    /// Records `f` into a fresh command buffer, submits it and waits.
    pub(crate) fn one_shot(&self, f: &dyn Fn(vk::CommandBuffer)) -> Result<(), BackendError> {
        let cmd = self.begin()?;
        f(cmd);
        self.submit_and_wait(cmd)
    }

    pub(crate) fn begin(&self) -> Result<vk::CommandBuffer, BackendError> {
        self.begin_reusing(None)
    }

    /// Begins `reuse` (a finished submission's command buffer, reset here) or a newly
    /// allocated command buffer.
    pub(crate) fn begin_reusing(
        &self,
        reuse: Option<vk::CommandBuffer>,
    ) -> Result<vk::CommandBuffer, BackendError> {
        let d = &self.ctx.device;
        let cmd = match reuse {
            Some(cmd) => {
                unsafe { d.reset_command_buffer(cmd, vk::CommandBufferResetFlags::empty()) }
                    .map_err(vk_error("resetting a command buffer"))?;
                cmd
            }
            None => unsafe {
                d.allocate_command_buffers(
                    &vk::CommandBufferAllocateInfo::default()
                        .command_pool(self.pool)
                        .level(vk::CommandBufferLevel::PRIMARY)
                        .command_buffer_count(1),
                )
            }
            .map_err(vk_error("allocating a command buffer"))?[0],
        };
        unsafe {
            d.begin_command_buffer(
                cmd,
                &vk::CommandBufferBeginInfo::default()
                    .flags(vk::CommandBufferUsageFlags::ONE_TIME_SUBMIT),
            )
        }
        .map_err(vk_error("beginning a command buffer"))?;
        // ordered after every earlier submission's work on the queue (submissions do not
        // wait for each other on the host; a barrier's first scope reaches back through
        // submission order)
        barrier(d, cmd);
        Ok(cmd)
    }

    pub(crate) fn submit_and_wait(&self, cmd: vk::CommandBuffer) -> Result<(), BackendError> {
        let d = &self.ctx.device;
        let result = (|| unsafe {
            d.end_command_buffer(cmd)
                .map_err(vk_error("ending a command buffer"))?;
            let cmds = [cmd];
            d.queue_submit(
                self.ctx.queue,
                &[vk::SubmitInfo::default().command_buffers(&cmds)],
                self.fence,
            )
            .map_err(vk_error("vkQueueSubmit"))?;
            d.wait_for_fences(&[self.fence], true, u64::MAX)
                .map_err(vk_error("waiting for the device"))?;
            d.reset_fences(&[self.fence])
                .map_err(vk_error("resetting a fence"))
        })();
        unsafe { d.free_command_buffers(self.pool, &[cmd]) };
        result?;
        self.check_validation()
    }
}

/// Per-submission state: the command buffer being recorded and what must outlive it.
pub struct Frame {
    pub cmd: vk::CommandBuffer,
    pub retired: Vec<Buffer>,
    pub retired_scenes: Vec<SceneAccel>,
    pub queries: Option<vk::QueryPool>,
    pub passes: Vec<&'static str>,
    /// The counters buffer whose sums are still in the counter banks
    /// ([`crate::recording::flush_counter_banks`]).
    pub banked_counters: Option<caustica_core::device::handle::ResourceId>,
    /// The slot's descriptor pool, arena and readback buffer while it runs.
    pub slot: FrameSlot,
}

/// Descriptor sets and descriptors of each type that `kernels` kernel steps need: two
/// sets per kernel; storage descriptors per set the most any kernel binds (the G-buffer
/// and photon map count one per plane).
fn descriptor_needs(kernels: u32) -> (u32, [vk::DescriptorPoolSize; 3]) {
    let sets = 2 * kernels.max(1);
    let storage_per_set = KERNELS
        .iter()
        .map(|k| {
            k.descriptor_bindings()
                .iter()
                .filter(|b| {
                    matches!(
                        b,
                        ShaderBinding::StorageRead | ShaderBinding::StorageReadWrite
                    )
                })
                .count() as u32
        })
        .max()
        .unwrap_or(0)
        .max(1);
    (
        sets,
        [
            vk::DescriptorPoolSize::default()
                .ty(S)
                .descriptor_count(storage_per_set),
            vk::DescriptorPoolSize::default().ty(U).descriptor_count(1),
            vk::DescriptorPoolSize::default().ty(AS).descriptor_count(1),
        ],
    )
}

/// Records `rec` into a command buffer of a free frame slot and submits it with the
/// slot's fence (and the backend's timeline value `id`), copying `readbacks` into the
/// slot's host-visible buffer at the end. Does not wait, except for a `prepare_scene` that
/// builds acceleration structures (a set-up step: it reads the uploads back).
fn record_submission(
    b: &mut VulkanBackend,
    rec: &Recording,
    readbacks: &[caustica_core::device::handle::ResourceId],
    id: u64,
) -> Result<InFlight, BackendError> {
    ensure_variants(b, rec)?;
    let kernels = rec.kernel_count();
    let d = b.ctx.device.clone();
    let mut slot = b.take_slot()?;
    // the slot's pools are kept: reset, or made anew when this recording needs more than
    // they hold (no pool made and destroyed per recording)
    let (sets, per_set) = descriptor_needs(kernels);
    if let Err(e) = slot.prepare(
        &b.ctx,
        sets,
        &per_set,
        if b.ctx.timestamps { 2 * kernels } else { 0 },
    ) {
        b.return_slot(slot);
        return Err(e);
    }
    let queries = slot.query_pool().filter(|_| kernels > 0);
    let mut frame = Frame {
        cmd: vk::CommandBuffer::null(),
        retired: Vec::new(),
        retired_scenes: Vec::new(),
        queries,
        passes: Vec::new(),
        banked_counters: None,
        slot,
    };
    let recorded = record_all(b, rec, &mut frame, kernels)
        .and_then(|_| record_readbacks(b, &mut frame, readbacks));
    let sizes = match recorded {
        Ok(sizes) => sizes,
        Err(e) => {
            // wait for what was recorded before the frame's objects go
            if frame.cmd != vk::CommandBuffer::null() {
                // the banks are left zero for the next submission
                let _ = crate::recording::flush_counter_banks(b, &mut frame);
                let cmd = std::mem::replace(&mut frame.cmd, vk::CommandBuffer::null());
                let _ = b.submit_and_wait(cmd);
            }
            b.return_slot(frame.slot);
            return Err(e);
        }
    };
    let cmd = std::mem::replace(&mut frame.cmd, vk::CommandBuffer::null());
    if let Err(e) = b.submit_signalled(cmd, frame.slot.fence, id) {
        unsafe {
            let _ = d.queue_wait_idle(b.ctx.queue);
        }
        b.return_slot(frame.slot);
        return Err(e);
    }
    Ok(InFlight {
        cmd,
        frame,
        readbacks: sizes,
    })
}

/// Copies of `readbacks` into the slot's host-visible readback buffer, after a barrier;
/// returns each one's offset and size.
fn record_readbacks(
    b: &mut VulkanBackend,
    frame: &mut Frame,
    readbacks: &[caustica_core::device::handle::ResourceId],
) -> Result<Vec<(u64, u64)>, BackendError> {
    if readbacks.is_empty() {
        return Ok(Vec::new());
    }
    let mut at = 0u64;
    let mut sizes = Vec::with_capacity(readbacks.len());
    for id in readbacks {
        let bytes = b.buffers.get(*id)?.bytes;
        sizes.push((at, bytes));
        at = (at + bytes).next_multiple_of(16);
    }
    let dst = frame.slot.readback_buffer(&b.ctx, at)?;
    let d = &b.ctx.device;
    barrier(d, frame.cmd);
    for (id, (offset, bytes)) in readbacks.iter().zip(&sizes) {
        if *bytes > 0 {
            let src = b.buffers.get(*id)?.buffer.buffer;
            unsafe {
                d.cmd_copy_buffer(
                    frame.cmd,
                    src,
                    dst,
                    &[vk::BufferCopy::default().dst_offset(*offset).size(*bytes)],
                )
            };
        }
    }
    // host reads after the fence: make the transfer writes visible to the host
    let m = [vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::TRANSFER_WRITE)
        .dst_access_mask(vk::AccessFlags::HOST_READ)];
    unsafe {
        d.cmd_pipeline_barrier(
            frame.cmd,
            vk::PipelineStageFlags::TRANSFER,
            vk::PipelineStageFlags::HOST,
            vk::DependencyFlags::empty(),
            &m,
            &[],
            &[],
        )
    };
    Ok(sizes)
}

/// The frame's kernel times (its fence has signalled).
fn read_times(ctx: &Context, frame: &Frame) -> Result<Vec<PassTime>, BackendError> {
    let Some(q) = frame.queries else {
        return Ok(frame
            .passes
            .iter()
            .map(|k| PassTime {
                kernel: k,
                seconds: 0.0,
            })
            .collect());
    };
    if frame.passes.is_empty() {
        return Ok(Vec::new());
    }
    let mut ticks = vec![0u64; 2 * frame.passes.len()];
    unsafe {
        ctx.device.get_query_pool_results(
            q,
            0,
            &mut ticks,
            vk::QueryResultFlags::TYPE_64 | vk::QueryResultFlags::WAIT,
        )
    }
    .map_err(vk_error("reading timestamps"))?;
    let period = ctx.limits.timestamp_period as f64;
    Ok(caustica_core::backend::pass_times_from_ticks(
        &frame.passes,
        &ticks,
        period,
    ))
}
