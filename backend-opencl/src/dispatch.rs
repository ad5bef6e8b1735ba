//! Registry kernels to OpenCL launches: core's [`Launch`] description (argument order of
//! each kernel's signature in `kernels/<kernel>.cl`, buffer needs, thread count), mapped
//! to `clSetKernelArg` and one `clEnqueueNDRangeKernel` with a profiling event.

use crate::error::cl_error;
use crate::OpenClBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::launch::{check_buffer, Launch, LaunchArg};
use caustica_core::recording::RecordedKernel;
use opencl3::event::Event;
use opencl3::kernel::Kernel as ClKernel;
use opencl3::memory::{Buffer, ClMem};

/// What an enqueued launch must keep alive until it has run: its kernel object and
/// parameter buffers. Releasing them while the launch is queued made NVIDIA's driver wait
/// for it (measured: a non-blocking submission took the whole frame on the host).
pub struct Launched {
    _kernel: ClKernel,
}

/// Enqueues one registry kernel; returns its profiling event and what must outlive it
/// (`None` if it did no work).
/// `params` are the launch's parameter blocks, in argument order, already on the device
/// (sub-buffers of the submission's staging: [`crate::staging`]).
pub fn run(
    b: &OpenClBackend,
    k: &RecordedKernel,
    params: &[Buffer<u8>],
) -> Result<Option<(Event, Launched)>, BackendError> {
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
    } = launch;
    let (name, threads, group) = (*name, *threads, *workgroup_size as usize);
    for a in args {
        if let LaunchArg::Buffer { id, .. } = a {
            check_buffer(a, b.buffer(*id)?.bytes)?;
        }
    }
    if threads == 0 {
        return Ok(None);
    }
    let program = b.state.program_for(name, constants)?;
    let kernel = ClKernel::create(&program, name).map_err(cl_error("creating a kernel"))?;
    let mut next_params = params.iter();
    for (index, a) in args.iter().enumerate() {
        let index = index as u32;
        // Buffers are passed as their `cl_mem` handle, counts as a 32-bit scalar.
        let set = match a {
            LaunchArg::Buffer { id, .. } => {
                let mem = b.buffer(*id)?.mem.get();
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
    Ok(Some((event, Launched { _kernel: kernel })))
}
