//! OpenCL errors as typed backend errors: allocation failures become `OutOfMemory`, the
//! rest `Driver` with the call that failed.

use caustica_core::backend::BackendError;
use ocl::core::Status;

/// Maps an ocl error raised while doing `what`.
pub fn cl_error(what: &'static str) -> impl Fn(ocl::core::Error) -> BackendError {
    move |e| match e.api_status() {
        Some(Status::CL_MEM_OBJECT_ALLOCATION_FAILURE)
        | Some(Status::CL_OUT_OF_RESOURCES)
        | Some(Status::CL_OUT_OF_HOST_MEMORY) => BackendError::OutOfMemory {
            bytes: 0,
            what: format!("{what} ({e})"),
        },
        _ => BackendError::Driver(format!("{what}: {e}")),
    }
}
