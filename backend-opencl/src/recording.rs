//! The recording interpreter: every step of a [`Recording`] enqueued in order on the
//! queue, its parameters and write data staged in a submission's slot
//! ([`crate::memory::StagingSlot`]), then the readbacks into the slot's pinned memory.
//! Registry kernels become OpenCL launches: core's [`Launch`] description (argument order
//! of each kernel's signature in `kernels/<kernel>.cl`, buffer needs, thread count), mapped
//! to `clSetKernelArg` and one `clEnqueueNDRangeKernel` with a profiling event.

use crate::device::cl_error;
use crate::memory::{fill_zero, StagingLayout, StagingSlot};
use crate::OpenClBackend;
use caustica_core::backend::{check_write, BackendError};
use caustica_core::device::handle::ResourceId;
use caustica_core::device::launch::{check_buffer, Launch, LaunchArg};
use caustica_core::recording::{RecordedKernel, Recording, Step};
use opencl3::event::Event;
use opencl3::kernel::Kernel as ClKernel;
use opencl3::memory::{Buffer, ClMem, CL_MEM_READ_ONLY};
use opencl3::types::CL_NON_BLOCKING;

impl OpenClBackend {
    /// Enqueues `recording` with its staging in `slot` (laid out by `layout`), then the
    /// readbacks into the slot's pinned memory.
    #[allow(clippy::type_complexity)]
    pub(crate) fn enqueue(
        &mut self,
        recording: &Recording,
        readbacks: &[ResourceId],
        layout: &StagingLayout,
        slot: &mut StagingSlot,
    ) -> Result<(Vec<(&'static str, Event)>, Vec<Buffer<u8>>), BackendError> {
        slot.prepare(
            &self.queue,
            &self.state.context,
            layout.params_bytes,
            layout.upload_bytes,
            layout.readback_bytes,
        )?;
        // the parameters: into pinned memory, one non-blocking copy to the device, one
        // sub-buffer per block
        let mut params = Vec::with_capacity(layout.params.len());
        {
            let upload = slot.upload.as_mut().expect("prepared");
            let mut k = 0;
            for step in &recording.steps {
                if let Step::Kernel(rk) = step {
                    if let Some(l) = rk.launch()? {
                        for a in &l.args {
                            if let LaunchArg::Params(p) = a {
                                let (at, len) = layout.params[k];
                                upload.bytes_mut(at, len).copy_from_slice(p);
                                k += 1;
                            }
                        }
                    }
                }
            }
        }
        if !layout.params.is_empty() {
            let upload = slot.upload.as_ref().expect("prepared");
            let src = upload.bytes(0, layout.params_bytes);
            let dst = slot.params.as_mut().expect("prepared");
            // SAFETY: `src` is pinned memory the slot keeps until the submission is done
            unsafe {
                self.queue
                    .enqueue_write_buffer(dst, CL_NON_BLOCKING, 0, src, &[])
            }
            .map_err(cl_error("uploading kernel parameters"))?;
            for (at, len) in &layout.params {
                params.push(
                    unsafe {
                        slot.params()
                            .create_sub_buffer(CL_MEM_READ_ONLY, *at, (*len).max(4))
                    }
                    .map_err(cl_error("making a parameter sub-buffer"))?,
                );
            }
        }
        let mut pending: Vec<(&'static str, Event)> = Vec::new();
        let (mut next_write, mut next_param) = (0usize, 0usize);
        for step in &recording.steps {
            match step {
                Step::Create { id, bytes, label } => self.create(*id, *bytes, label, None)?,
                Step::Upload { id, data, label } => {
                    self.create(*id, data.len() as u64, label, Some(data))?
                }
                Step::Write {
                    id,
                    offset,
                    data,
                    label,
                } => {
                    let at = layout.writes[next_write];
                    next_write += 1;
                    let b = self.buffers.get_mut(*id)?;
                    check_write(label, b.bytes, *offset, data.len())?;
                    if !data.is_empty() {
                        let upload = slot.upload.as_mut().expect("prepared");
                        upload.bytes_mut(at, data.len()).copy_from_slice(data);
                        let src = upload.bytes(at, data.len());
                        // SAFETY: pinned memory the slot keeps until the submission is done
                        unsafe {
                            self.queue.enqueue_write_buffer(
                                &mut b.mem,
                                CL_NON_BLOCKING,
                                *offset as usize,
                                src,
                                &[],
                            )
                        }
                        .map_err(cl_error("writing into a buffer"))?;
                    }
                }
                Step::Clear { id } => {
                    let b = self.buffers.get_mut(*id)?;
                    fill_zero(&self.queue, &mut b.mem, b.bytes.max(4) as usize)?;
                }
                Step::Free { id } => {
                    // OpenCL keeps the memory until the commands using it have finished
                    self.buffers.remove(*id);
                }
                Step::Kernel(k) => {
                    let blocks = match k.launch()? {
                        Some(l) => l
                            .args
                            .iter()
                            .filter(|a| matches!(a, LaunchArg::Params(_)))
                            .count(),
                        None => 0,
                    };
                    // parameter words an earlier step wrote on the device, copied into
                    // the launch's parameter block (the queue is in order)
                    if let (Some(l), true) = (k.launch()?, blocks > 0) {
                        for p in &l.patches {
                            let src = self.buffers.get(p.src)?;
                            p.check_source(src.bytes)?;
                            let dst = &mut params[next_param];
                            unsafe {
                                self.queue.enqueue_copy_buffer(
                                    &src.mem,
                                    dst,
                                    p.src_offset() as usize,
                                    p.offset as usize,
                                    p.bytes() as usize,
                                    &[],
                                )
                            }
                            .map_err(cl_error("copying parameter words from the device"))?;
                        }
                    }
                    let mine = &params[next_param..next_param + blocks];
                    next_param += blocks;
                    if let Some(event) = run(self, k, mine)? {
                        pending.push((k.name(), event));
                    }
                }
            }
        }
        if let Some(landing) = slot.readback.as_mut() {
            for (id, (at, bytes)) in readbacks.iter().zip(&layout.readbacks) {
                if *bytes == 0 {
                    continue;
                }
                let b = self.buffers.get(*id)?;
                let dst = landing.bytes_mut(*at, *bytes);
                // SAFETY: pinned memory the slot keeps, unread, until the marker completes
                unsafe {
                    self.queue
                        .enqueue_read_buffer(&b.mem, CL_NON_BLOCKING, 0, dst, &[])
                }
                .map_err(cl_error("reading a buffer back"))?;
            }
        }
        Ok((pending, params))
    }
}

/// Enqueues one registry kernel with the backend's kernel object for it (created on its
/// first launch, `OpenClBackend::kernels`); returns its profiling event (`None` if it did
/// no work). The submission keeps the parameter buffers until it has run: releasing an
/// object while its launch is queued made NVIDIA's driver wait for it (measured: a
/// non-blocking submission took the whole frame on the host).
/// `params` are the launch's parameter blocks, in argument order, already on the device
/// (sub-buffers of the submission's staging: [`crate::memory::StagingSlot`]).
fn run(
    b: &OpenClBackend,
    k: &RecordedKernel,
    params: &[Buffer<u8>],
) -> Result<Option<Event>, BackendError> {
    let Some(launch) = k.launch()? else {
        return Ok(None);
    };
    if !launch.constants.is_empty() {
        b.note_variant(launch.variant_label());
    }
    let Launch {
        kernel: name,
        constants,
        threads,
        workgroup_size,
        args,
        // OpenCL 1.2 has no indirect launch: an indirect kernel runs its recorded bound,
        // and its threads past the device count leave at once
        indirect: _,
        // copied into the parameter block before the launch (`OpenClBackend::enqueue`)
        patches: _,
    } = launch;
    let (name, threads) = (*name, *threads);
    let group = match crate::pipelines::workgroup_sizes_env() {
        Some(list) => crate::pipelines::workgroup_size_override(list, name)
            .map_err(BackendError::BadArgument)?
            .unwrap_or(*workgroup_size),
        None => *workgroup_size,
    } as usize;
    for a in args {
        if let LaunchArg::Buffer { id, .. } = a {
            check_buffer(a, b.buffers.get(*id)?.bytes)?;
        }
    }
    if threads == 0 {
        return Ok(None);
    }
    let program = b.state.program_for(name, constants)?;
    // arguments are set and the launch enqueued under the lock: one object, one launch
    // at a time
    let mut kernels = b.kernels.lock().unwrap_or_else(|e| e.into_inner());
    let kernel = match kernels.entry((program.get() as usize, name)) {
        std::collections::hash_map::Entry::Occupied(e) => e.into_mut(),
        std::collections::hash_map::Entry::Vacant(e) => {
            e.insert(ClKernel::create(&program, name).map_err(cl_error("creating a kernel"))?)
        }
    };
    let mut next_params = params.iter();
    for (index, a) in args.iter().enumerate() {
        let index = index as u32;
        // Buffers are passed as their `cl_mem` handle, counts as a 32-bit scalar.
        let set = match a {
            LaunchArg::Buffer { id, .. } => {
                let mem = b.buffers.get(*id)?.mem.get();
                unsafe { kernel.set_arg(index, &mem) }
            }
            LaunchArg::Params(_) => {
                let mem = next_params
                    .next()
                    .ok_or_else(|| BackendError::Driver("parameter block missing".into()))?
                    .get();
                unsafe { kernel.set_arg(index, &mem) }
            }
            LaunchArg::Count(n) => unsafe { kernel.set_arg(index, n) },
        };
        set.map_err(cl_error("setting a kernel argument"))?;
    }
    let global = usize::try_from(threads)
        .ok()
        .and_then(|t| t.checked_next_multiple_of(group))
        .ok_or_else(|| BackendError::BadArgument(format!("{name}: {threads} threads")))?;
    let global_size: [usize; 3] = [global, 1, 1];
    let local_size: [usize; 3] = [group, 1, 1];
    let event = unsafe {
        b.queue.enqueue_nd_range_kernel(
            kernel.get(),
            1,
            std::ptr::null(),
            global_size.as_ptr(),
            local_size.as_ptr(),
            &[],
        )
    }
    .map_err(cl_error(name))?;
    Ok(Some(event))
}
