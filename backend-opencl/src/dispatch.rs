//! Registry kernels to OpenCL launches: core's [`Launch`] description (argument order of
//! each kernel's signature in `kernels/<kernel>.cl`, buffer needs, thread count), mapped
//! to `clSetKernelArg` and one `clEnqueueNDRangeKernel` with a profiling event.

use crate::error::cl_error;
use crate::OpenClBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::launch::{check_buffer, Launch, LaunchArg};
use caustica_core::kernels::Kernel;
use ocl::core::{self, ArgVal, Event, Mem, MemFlags};

/// Threads per work-group (core's registry: 64 for every kernel).
const WORKGROUP: usize = 64;

/// Enqueues one registry kernel; returns its profiling event (`None` if it did no work).
pub fn run(b: &OpenClBackend, k: &Kernel) -> Result<Option<Event>, BackendError> {
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
        args,
    } = launch;
    // Parameter blocks live until the launch is enqueued; OpenCL keeps a memory object
    // alive until the commands that use it have finished.
    let mut params: Vec<Mem> = Vec::new();
    for a in &args {
        match a {
            LaunchArg::Buffer { id, .. } => check_buffer(a, b.buffer(*id)?.bytes)?,
            LaunchArg::Params(bytes) => params.push(
                unsafe {
                    core::create_buffer(
                        &b.state.context,
                        MemFlags::READ_ONLY | MemFlags::COPY_HOST_PTR,
                        bytes.len(),
                        Some(bytes.as_slice()),
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
    let program = b.state.program_for(name, &constants)?;
    let kernel = core::create_kernel(&program, name).map_err(cl_error("creating a kernel"))?;
    let mut next_params = params.iter();
    for (index, a) in args.iter().enumerate() {
        let v = match a {
            LaunchArg::Buffer { id, .. } => ArgVal::mem(&b.buffer(*id)?.mem),
            LaunchArg::Params(_) => ArgVal::mem(
                next_params
                    .next()
                    .ok_or_else(|| BackendError::Driver("parameter block missing".into()))?,
            ),
            LaunchArg::Count(n) => ArgVal::scalar(n),
        };
        core::set_kernel_arg(&kernel, index as u32, v)
            .map_err(cl_error("setting a kernel argument"))?;
    }
    let global = usize::try_from(threads)
        .ok()
        .and_then(|t| t.checked_next_multiple_of(WORKGROUP))
        .ok_or_else(|| BackendError::BadArgument(format!("{name}: {threads} threads")))?;
    let mut event = Event::null();
    unsafe {
        core::enqueue_kernel(
            &b.queue,
            &kernel,
            1,
            None,
            &[global, 1, 1],
            Some([WORKGROUP, 1, 1]),
            None::<Event>,
            Some(&mut event),
        )
    }
    .map_err(cl_error(name))?;
    Ok(Some(event))
}
