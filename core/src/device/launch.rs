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
    /// Where the launch's shape is on the device, when an earlier kernel of the same
    /// recording computes it (`dispatch_args`); `threads` is then its upper bound.
    pub indirect: Option<Indirect>,
    /// Words of the launch's parameter block that an earlier step of the same recording
    /// wrote to the device ([`ParamPatch`]): empty for a launch whose parameters the host
    /// knows whole.
    pub patches: Vec<ParamPatch>,
}

/// Parameter words that come from the device: before the launch, `words` 4-byte words of
/// buffer `src` from word `src_word` on replace the launch's parameter block from byte
/// `offset` on (the block's only parameter argument). A backend copies them on the
/// device, ordered after every earlier step (wgpu and Vulkan: a buffer copy into the
/// launch's uniform block; OpenCL: a copy into its parameter buffer on the in-order
/// queue; the CPU: the words read from host memory into the typed parameters), so a
/// kernel reads values that an earlier kernel decided without the host reading them
/// back. The kernel's code is the same as with host parameters.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ParamPatch {
    /// First byte of the parameter block replaced (a multiple of 4).
    pub offset: u32,
    /// The buffer the words come from.
    pub src: ResourceId,
    /// Its first word copied.
    pub src_word: u32,
    /// Words copied.
    pub words: u32,
}

impl ParamPatch {
    /// Byte offset of the first word copied in `src`.
    pub fn src_offset(&self) -> u64 {
        self.src_word as u64 * 4
    }

    /// Bytes copied.
    pub fn bytes(&self) -> u64 {
        self.words as u64 * 4
    }

    /// Checks that a source buffer of `held` bytes holds the words copied.
    pub fn check_source(&self, held: u64) -> Result<(), BackendError> {
        if self.src_offset() + self.bytes() > held {
            return Err(BackendError::BadArgument(format!(
                "a parameter patch reads words {}..{} of a buffer of {held} bytes",
                self.src_word,
                self.src_word as u64 + self.words as u64
            )));
        }
        Ok(())
    }

    /// Checks the patch against a parameter block of `len` bytes: aligned to words,
    /// inside the block, at least one word.
    pub fn check_block(&self, len: usize) -> Result<(), BackendError> {
        let end = self.offset as u64 + self.bytes();
        if self.words == 0 || !self.offset.is_multiple_of(4) || end > len as u64 {
            return Err(BackendError::BadArgument(format!(
                "a parameter patch of {} words at byte {} of a {len}-byte parameter block",
                self.words, self.offset
            )));
        }
        Ok(())
    }
}

/// A launch whose size an earlier kernel wrote to the device: record `record` of the
/// `dispatch_args` buffer `args` ([`DISPATCH_RECORD_WORDS`] `u32` words each:
/// [`dispatch_word`]). A backend with indirect dispatch launches that shape (wgpu
/// `dispatch_workgroups_indirect`, Vulkan `vkCmdDispatchIndirect` and
/// `vkCmdTraceRaysIndirectKHR`); one without (OpenCL 1.2) launches the bound, and the
/// kernel's threads past the device count leave at once (every indirect kernel reads its
/// own count, so both give the same results).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Indirect {
    /// The buffer of dispatch records.
    pub args: ResourceId,
    /// The record's index.
    pub record: u32,
}

impl Indirect {
    /// Byte offset of the record's workgroup counts (x, y, z: wgpu's and Vulkan's
    /// dispatch-indirect layout).
    pub fn groups_offset(&self) -> u64 {
        (self.record as u64 * DISPATCH_RECORD_WORDS as u64 + dispatch_word::GROUPS_X as u64) * 4
    }

    /// Byte offset of the record's launch grid (width, height, depth:
    /// `VkTraceRaysIndirectCommandKHR`).
    pub fn grid_offset(&self) -> u64 {
        (self.record as u64 * DISPATCH_RECORD_WORDS as u64 + dispatch_word::WIDTH as u64) * 4
    }
}

/// Words of one dispatch record (`dispatch_args`' output).
pub const DISPATCH_RECORD_WORDS: usize = 8;

/// Word indices within a dispatch record.
pub mod dispatch_word {
    /// Workgroups along x (at most [`super::DISPATCH_MAX_GROUPS_X`]).
    pub const GROUPS_X: usize = 0;
    /// Workgroups along y.
    pub const GROUPS_Y: usize = 1;
    /// Workgroups along z (1).
    pub const GROUPS_Z: usize = 2;
    /// A traced kernel's launch width ([`super::DISPATCH_TRACE_WIDTH`] or fewer).
    pub const WIDTH: usize = 3;
    /// Its launch height.
    pub const HEIGHT: usize = 4;
    /// Its launch depth (1).
    pub const DEPTH: usize = 5;
    /// The launch's threads (items times threads per item).
    pub const THREADS: usize = 6;
    /// The items (clusters, photons) the launch covers.
    pub const ITEMS: usize = 7;
}

/// Most workgroups along x of an indirect launch: the smallest
/// `maxComputeWorkGroupCount[0]` Vulkan allows and wgpu's default limit; more groups go
/// along y (kernels index threads as `(y * groups_x + x) * size + local`).
pub const DISPATCH_MAX_GROUPS_X: u32 = 65535;

/// Width of a traced kernel's indirect launch grid: eight columns (see the Vulkan
/// backend's launch width of `trace_photons`: a warp then traces a run of consecutive
/// threads).
pub const DISPATCH_TRACE_WIDTH: u32 = 8;

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
