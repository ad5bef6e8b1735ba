//! OpenCL errors as typed backend errors: allocation failures become `OutOfMemory`, the
//! rest `Driver` with the call that failed and the status name.

use caustica_core::backend::BackendError;
use opencl3::error_codes::{
    error_text, ClError, CL_MEM_OBJECT_ALLOCATION_FAILURE, CL_OUT_OF_HOST_MEMORY,
    CL_OUT_OF_RESOURCES,
};
use opencl3::types::cl_int;

/// An OpenCL status code as its name and number, e.g. `CL_INVALID_VALUE (-30)`.
pub fn status_text(status: cl_int) -> String {
    format!("{} ({status})", error_text(status))
}

/// Maps the OpenCL error of a call made while doing `what` to a backend error.
pub fn cl_error(what: &'static str) -> impl Fn(ClError) -> BackendError {
    move |e| match e.0 {
        CL_MEM_OBJECT_ALLOCATION_FAILURE | CL_OUT_OF_RESOURCES | CL_OUT_OF_HOST_MEMORY => {
            BackendError::OutOfMemory {
                bytes: 0,
                what: format!("{what} ({})", status_text(e.0)),
            }
        }
        _ => BackendError::Driver(format!("{what}: {}", status_text(e.0))),
    }
}
