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
use opencl3::memory::{Buffer, ClMem, CL_MEM_COPY_HOST_PTR, CL_MEM_READ_ONLY};

/// What an enqueued launch must keep alive until it has run: its kernel object and
/// parameter buffers. Releasing them while the launch is queued made NVIDIA's driver wait
/// for it (measured: a non-blocking submission took the whole frame on the host).
pub struct Launched {
    _kernel: ClKernel,
    _params: Vec<Buffer<u8>>,
}

/// Enqueues one registry kernel; returns its profiling event and what must outlive it
/// (`None` if it did no work).
pub fn run(
    b: &OpenClBackend,
    k: &RecordedKernel,
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
    // Parameter blocks live until the launch is enqueued; OpenCL keeps a memory object
    // alive until the commands that use it have finished.
    let mut params: Vec<Buffer<u8>> = Vec::new();
    for a in args {
        match a {
            LaunchArg::Buffer { id, .. } => check_buffer(a, b.buffer(*id)?.bytes)?,
            LaunchArg::Params(bytes) => params.push(
                // COPY_HOST_PTR: the driver copies `bytes` during the call and never
                // writes through the pointer.
                unsafe {
                    Buffer::<u8>::create(
                        &b.state.context,
                        CL_MEM_READ_ONLY | CL_MEM_COPY_HOST_PTR,
                        bytes.len(),
                        bytes.as_ptr() as *mut std::ffi::c_void,
                    )
                }
                .map_err(cl_error("uploading kernel parameters"))?,
            ),
            LaunchArg::Count(_) => {}
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
    Ok(Some((
        event,
        Launched {
            _kernel: kernel,
            _params: params,
        },
    )))
}
