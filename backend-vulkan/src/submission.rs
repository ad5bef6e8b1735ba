//! The non-blocking submission (docs/embedding.md, "A host's frame loop"): each submission
//! records into the command buffer of a *frame slot* (its own descriptor pool, timestamp
//! query pool, parameter and staging arena, readback buffer and fence, all kept and reset,
//! never made per frame) and is submitted once with the slot's fence, signalling the
//! backend's timeline semaphore with its number when the host asked for one
//! ([`VulkanBackend::completion_semaphore`]). Nothing waits: a slot is reused once its
//! fence has signalled, and only when [`MAX_FRAMES_IN_FLIGHT`] are on the device does a new
//! submission wait for the oldest. [`caustica_core::backend::Backend::poll`] checks a fence
//! without blocking and hands out the times and readbacks.

use crate::arena::Arena;
use crate::context::{vk_error, Context};
use crate::dispatch::Frame;
use crate::memory::Buffer;
use crate::VulkanBackend;
use ash::vk;
use caustica_core::backend::{BackendError, Finished, Submission};
use std::sync::Arc;

/// Submissions on the device at once; the next waits for the oldest (a host running more
/// frames ahead than this is paced by the device).
pub const MAX_FRAMES_IN_FLIGHT: usize = 3;

/// What one submission records with, reused once its fence has signalled.
pub struct FrameSlot {
    ctx: Arc<Context>,
    descriptor_pool: Option<(vk::DescriptorPool, u32)>,
    query_pool: Option<(vk::QueryPool, u32)>,
    /// Kernel parameters and staging ([`crate::arena`]).
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
    pub id: u64,
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
        if self.in_flight.len() >= MAX_FRAMES_IN_FLIGHT {
            let oldest = self.in_flight.remove(0);
            let id = oldest.id;
            let result = self.retire(oldest, true);
            self.finished.keep(id, result);
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
            let times = crate::dispatch::read_times(&self.ctx, &f.frame)?;
            let readbacks = f
                .readbacks
                .iter()
                .map(|(at, bytes)| f.frame.slot.read_back(*at, *bytes))
                .collect::<Result<Vec<_>, _>>()?;
            Ok(Finished { times, readbacks })
        });
        let crate::dispatch::Frame {
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

    /// [`caustica_core::backend::Backend::submit`]'s body.
    pub(crate) fn submit_recording(
        &mut self,
        recording: &caustica_core::recording::Recording,
        readbacks: &[caustica_core::device::handle::ResourceId],
    ) -> Result<Submission, BackendError> {
        let id = self.next_submission + 1;
        let f = crate::dispatch::submit(self, recording, readbacks, id)?;
        self.next_submission = id;
        self.in_flight.push(f);
        Ok(Submission::pending(id))
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
        let Some(k) = self.in_flight.iter().position(|f| f.id == s.id) else {
            return Err(caustica_core::backend::unknown_submission(s.id));
        };
        if !wait {
            let done = unsafe {
                self.ctx
                    .device
                    .get_fence_status(self.in_flight[k].frame.slot.fence)
            }
            .map_err(vk_error("querying a fence"))?;
            if !done {
                return Ok(None);
            }
        }
        let f = self.in_flight.remove(k);
        s.mark_collected();
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
            .initial_value(self.next_submission);
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
