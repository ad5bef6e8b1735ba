//! Kernel launches as every GPU-style backend receives them: a kernel's arguments in the
//! order of its declaration ([`crate::kernels`]: its OpenCL C signature and WGSL bindings),
//! the bytes every buffer must hold, the number of threads and the workgroup size. The
//! lowering in [`crate::kernels`] checks the arguments, so a wrong argument is an error,
//! never an out-of-bounds device write; a backend maps the arguments to its own API.

use crate::device::error::BackendError;
use crate::device::handle::ResourceId;

/// One argument of a launch.
#[derive(Clone, Debug, PartialEq)]
pub enum LaunchArg {
    /// A device buffer, bound with its logical size `bytes`; the launch reads or writes
    /// up to `need` bytes of it.
    Buffer {
        /// The buffer.
        id: ResourceId,
        /// Its logical size (bytes): elements x element size.
        bytes: u64,
        /// Bytes the launch may read or write; the buffer must hold at least this many.
        need: u64,
        /// Name of the binding (for error messages).
        what: &'static str,
    },
    /// A parameter block (`#[repr(C)]` Pod bytes): a uniform buffer in WGSL, a small
    /// read-only buffer in OpenCL.
    Params(Vec<u8>),
    /// An element count passed as a scalar to OpenCL kernels; WGSL derives it with
    /// `arrayLength` of the matching buffer, so wgpu skips it.
    Count(u32),
}

/// Threads per workgroup of the kernels that do not say otherwise (every kernel today; the
/// shaders' `WORKGROUP_SIZE`).
pub const DEFAULT_WORKGROUP_SIZE: u32 = 64;

/// A kernel launch: `threads` work-items in groups of `workgroup_size` (kernels skip the
/// excess of the last group).
#[derive(Clone, Debug, PartialEq)]
pub struct Launch {
    /// Registry name of the kernel.
    pub kernel: &'static str,
    /// Compiled switches of this launch's variant (empty for kernels without variants);
    /// see [`crate::kernels::TraceVariant`].
    pub constants: Vec<(&'static str, u32)>,
    /// Number of work-items (one per pixel, photon slot or tile, as the kernel declares).
    pub threads: u64,
    /// Threads per workgroup (the kernel's declared size; its shaders declare the same).
    pub workgroup_size: u32,
    /// Arguments in declaration order.
    pub args: Vec<LaunchArg>,
}

impl Launch {
    /// The variant's label (`kernel[NAME=0,...]`), the key of a backend's pipeline cache.
    pub fn variant_label(&self) -> String {
        variant_label(self.kernel, &self.constants)
    }
}

/// Checks that a device buffer of `held` bytes can serve `arg` (a backend calls this with
/// its own buffer sizes).
pub fn check_buffer(arg: &LaunchArg, held: u64) -> Result<(), BackendError> {
    if let LaunchArg::Buffer { id, need, what, .. } = arg {
        if held < *need {
            return Err(BackendError::BadArgument(format!(
                "{what}: buffer {id:?} holds {held} bytes, the launch needs {need}"
            )));
        }
    }
    Ok(())
}

/// The name a backend lists a compiled kernel variant under, e.g.
/// `trace_photons[DIELECTRIC=1,DISPERSION=0,ABSORPTION=0]`; a kernel without switches is
/// its bare name.
pub fn variant_label(kernel: &str, constants: &[(&'static str, u32)]) -> String {
    if constants.is_empty() {
        return kernel.to_string();
    }
    let parts: Vec<String> = constants.iter().map(|(n, v)| format!("{n}={v}")).collect();
    format!("{kernel}[{}]", parts.join(","))
}

/// The labels with switches among a pipeline cache's keys, sorted: what a GPU backend's
/// `Backend::variants` lists.
pub fn variant_labels<'a>(keys: impl IntoIterator<Item = &'a String>) -> Vec<String> {
    let mut v: Vec<String> = keys
        .into_iter()
        .filter(|k| k.contains('['))
        .cloned()
        .collect();
    v.sort();
    v
}
