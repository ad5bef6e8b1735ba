//! Recordings to Vulkan command buffers: buffer steps as fills and staged copies, kernels
//! as ray-tracing launches (G-buffer, direct light, photons) or compute dispatches (the
//! rest), each bound with core's launch description, separated by full memory barriers
//! and bracketed by timestamps. `prepare_scene` reads the triangles back and has the
//! driver build the acceleration structures.

use crate::accel::{SceneAccel, SceneSources};
use crate::context::{vk_error, Context};
use crate::memory::Buffer;
use crate::pipelines::{self, spirv, Pipeline};
use crate::{is_kernel, DeviceBuffer, VulkanBackend, MIN_BINDING_BYTES};
use ash::vk;
use caustica_core::backend::{BackendError, PassTime};
use caustica_core::device::handle::SceneArgs;
use caustica_core::device::launch::{check_buffer, LaunchArg};
use caustica_core::device::layout::{GpuTriangle, GpuVertex};
use caustica_core::kernels::Kernel;
use caustica_core::kernels::{KernelInfo, ShaderBinding, KERNELS};
use caustica_core::kernels::{PrepareScene, TraceIndirect, TracePhotons};
use caustica_core::recording::{RecordedKernel, Recording, Step};
use std::collections::HashMap;
use std::sync::Arc;

const S: vk::DescriptorType = vk::DescriptorType::STORAGE_BUFFER;
const U: vk::DescriptorType = vk::DescriptorType::UNIFORM_BUFFER;
const AS: vk::DescriptorType = vk::DescriptorType::ACCELERATION_STRUCTURE_KHR;

/// The Vulkan descriptor type of a binding as core's kernel declaration states it.
fn descriptor_type(b: ShaderBinding) -> vk::DescriptorType {
    match b {
        ShaderBinding::AccelerationStructure => AS,
        ShaderBinding::Uniform => U,
        ShaderBinding::StorageRead | ShaderBinding::StorageReadWrite => S,
    }
}

/// The descriptor types of kernel `info`'s pipeline, derived from its declaration
/// ([`KernelInfo::descriptor_bindings`]).
fn descriptor_types(info: &KernelInfo) -> Vec<vk::DescriptorType> {
    info.descriptor_bindings()
        .into_iter()
        .map(descriptor_type)
        .collect()
}

/// Width of a ray-generation launch grid (`i = y * width + x` in the shaders).
const RAYGEN_WIDTH: u64 = 8192;

/// Width of `trace_photons`' launch grid. Its threads are photons in tile order (core's
/// `math::sampling::tiled_photon_index`: 64 consecutive threads, an 8 x 8 block of the
/// photon grid). NVIDIA's driver appears to pack a 2D block of launch ids into a warp
/// (the times below fit that; it is not documented): on an 8192-wide grid such a block
/// takes rows 8192 threads apart, photons of distant tiles. Eight columns make any such
/// block a run of consecutive threads. Measured on the H200 (`sphere` / `cornell`, 2048^2
/// photons): trace 4.95 / 2.50 ms at width 8192, 3.31 / 1.73 at width 32, 2.89 / 1.60 at
/// width 8, 2.90 / 1.59 in one row (3.13 / 1.78 in row order without tile order).
const PHOTON_LAUNCH_WIDTH: u64 = 8;

/// The launch grid's width for `n` threads of `kernel`: [`PHOTON_LAUNCH_WIDTH`] for
/// `trace_photons` and `trace_indirect` (whose warps trace neighbouring samples,
/// `core::math::rsm::coherent_sample_order`) where the device takes a grid that tall,
/// else [`RAYGEN_WIDTH`].
fn raygen_width(limits: &vk::PhysicalDeviceLimits, kernel: &str, n: u64) -> u64 {
    let max_height = limits.max_compute_work_group_count[1] as u64
        * limits.max_compute_work_group_size[1] as u64;
    if matches!(kernel, "trace_photons" | "trace_indirect")
        && n.div_ceil(PHOTON_LAUNCH_WIDTH) <= max_height
    {
        PHOTON_LAUNCH_WIDTH
    } else {
        RAYGEN_WIDTH
    }
}

/// Every pipeline without compiled switches, created once, from core's kernel list:
/// traced kernels as ray-tracing pipelines (GLSL ray generation stage, binding the TLAS at
/// 0 in place of the CWBVH nodes), the others as compute pipelines from the WGSL through
/// naga; bindings from each kernel's declaration. Kernels with switches are built per
/// variant on first use ([`ensure_variants`]). `trace_photons` and `trace_indirect` add
/// into 64 counter banks that `reduce_counters` folds into the frame's counters.
pub fn create_pipelines(ctx: &Arc<Context>) -> Result<HashMap<String, Pipeline>, BackendError> {
    let mut p = HashMap::new();
    for info in KERNELS {
        if info.name == "prepare_scene" || !info.switches.is_empty() {
            continue;
        }
        let bindings = descriptor_types(info);
        let pipeline = if info.traced {
            let raygen = spirv::raygen(info.name).ok_or_else(|| {
                BackendError::Unsupported(format!("{}: no ray generation stage", info.name))
            })?;
            pipelines::ray_tracing(ctx, raygen, bindings, &[])?
        } else {
            pipelines::compute(ctx, &pipelines::wgsl_to_spirv(info.name)?, bindings)?
        };
        p.insert(info.name.to_string(), pipeline);
    }
    let reduce = ash::util::read_spv(&mut std::io::Cursor::new(spirv::REDUCE_COUNTERS))
        .map_err(|e| BackendError::Driver(format!("bad SPIR-V: {e}")))?;
    p.insert(
        "reduce_counters".into(),
        pipelines::compute(ctx, &reduce, vec![S, S])?,
    );
    Ok(p)
}

/// Creates the pipeline of every kernel variant `rec` launches that does not exist yet
/// (`trace_photons`: one ray-tracing pipeline per `TraceVariant`, specialization
/// constants in switch order), one creation or destruction at a time (see `context::serialised`).
fn ensure_variants(b: &mut VulkanBackend, rec: &Recording) -> Result<(), BackendError> {
    for step in &rec.steps {
        let Step::Kernel(k) = step else { continue };
        let Some(launch) = k.launch()? else { continue };
        let label = launch.variant_label();
        if launch.constants.is_empty() || b.pipelines.contains_key(&label) {
            continue;
        }
        let info = k.kernel().info();
        let raygen = spirv::raygen(info.name)
            .filter(|_| info.traced)
            .ok_or_else(|| {
                BackendError::Unsupported(format!(
                    "{}: variants exist only for ray-traced kernels",
                    info.name
                ))
            })?;
        let ctx = Arc::clone(&b.ctx);
        let p = crate::context::serialised(|| {
            pipelines::ray_tracing(&ctx, raygen, descriptor_types(info), &launch.constants)
        })?;
        b.pipelines.insert(label, p);
    }
    Ok(())
}

pub(crate) fn barrier(d: &ash::Device, cmd: vk::CommandBuffer) {
    let m = [vk::MemoryBarrier::default()
        .src_access_mask(vk::AccessFlags::MEMORY_WRITE)
        .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)];
    unsafe {
        d.cmd_pipeline_barrier(
            cmd,
            vk::PipelineStageFlags::ALL_COMMANDS,
            vk::PipelineStageFlags::ALL_COMMANDS,
            vk::DependencyFlags::empty(),
            &m,
            &[],
            &[],
        )
    };
}

enum Desc {
    Tlas(vk::AccelerationStructureKHR),
    Storage(vk::Buffer, u64),
    /// A uniform buffer, its offset and range.
    Uniform(vk::Buffer, u64, u64),
}

/// Per-submission state: the command buffer being recorded and what must outlive it.
pub struct Frame {
    pub cmd: vk::CommandBuffer,
    pub retired: Vec<Buffer>,
    pub retired_scenes: Vec<SceneAccel>,
    pub queries: Option<vk::QueryPool>,
    pub passes: Vec<&'static str>,
    /// The slot's descriptor pool, arena and readback buffer while it runs.
    pub slot: crate::submission::FrameSlot,
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
pub fn submit(
    b: &mut VulkanBackend,
    rec: &Recording,
    readbacks: &[caustica_core::device::handle::ResourceId],
    id: u64,
) -> Result<crate::submission::InFlight, BackendError> {
    ensure_variants(b, rec)?;
    let kernels = rec.steps.iter().filter(|s| is_kernel(s)).count() as u32;
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
        slot,
    };
    let recorded = record_all(b, rec, &mut frame, kernels)
        .and_then(|_| record_readbacks(b, &mut frame, readbacks));
    let sizes = match recorded {
        Ok(sizes) => sizes,
        Err(e) => {
            // wait for what was recorded before the frame's objects go
            if frame.cmd != vk::CommandBuffer::null() {
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
    Ok(crate::submission::InFlight {
        id,
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
        let bytes = b.get(*id)?.bytes;
        sizes.push((at, bytes));
        at = (at + bytes).next_multiple_of(16);
    }
    let dst = frame.slot.readback_buffer(&b.ctx, at)?;
    let d = &b.ctx.device;
    barrier(d, frame.cmd);
    for (id, (offset, bytes)) in readbacks.iter().zip(&sizes) {
        if *bytes > 0 {
            let src = b.get(*id)?.buffer.buffer;
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

/// `data` in host-visible memory the device can copy from: in the frame's arena, or (too
/// large, or the arena full) in a staging buffer of its own, retired with the frame.
fn staged(
    ctx: &Arc<Context>,
    frame: &mut Frame,
    data: &[u8],
    what: &str,
) -> Result<(vk::Buffer, u64), BackendError> {
    if let Some(at) = frame.slot.arena.put(data, 16) {
        return Ok(at);
    }
    let staging = Buffer::with_data(ctx, data, vk::BufferUsageFlags::TRANSFER_SRC, what)?;
    let buffer = staging.buffer;
    frame.retired.push(staging);
    Ok((buffer, 0))
}

/// The frame's kernel times (its fence has signalled).
pub fn read_times(ctx: &Context, frame: &Frame) -> Result<Vec<PassTime>, BackendError> {
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
    Ok(frame
        .passes
        .iter()
        .enumerate()
        .map(|(i, k)| PassTime {
            kernel: k,
            seconds: ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64 * period * 1e-9,
        })
        .collect())
}

fn record_all(
    b: &mut VulkanBackend,
    rec: &Recording,
    frame: &mut Frame,
    kernels: u32,
) -> Result<(), BackendError> {
    let d = b.ctx.device.clone();
    // the slot's command buffer from its last submission, reset, else a new one
    frame.cmd = b.begin_reusing(frame.slot.cmd.take())?;
    if let Some(q) = frame.queries {
        unsafe { d.cmd_reset_query_pool(frame.cmd, q, 0, 2 * kernels) };
    }
    for step in &rec.steps {
        match step {
            Step::Create { id, bytes, label } => {
                let buffer = b.new_storage(*bytes, label)?;
                unsafe { d.cmd_fill_buffer(frame.cmd, buffer.buffer, 0, vk::WHOLE_SIZE, 0) };
                if let Some(old) = b.buffers.insert(
                    *id,
                    DeviceBuffer {
                        buffer,
                        bytes: *bytes,
                        generation: crate::next_generation(),
                    },
                ) {
                    frame.retired.push(old.buffer);
                }
                barrier(&d, frame.cmd);
            }
            Step::Upload { id, data, label } => {
                let buffer = b.new_storage(data.len() as u64, label)?;
                if !data.is_empty() {
                    let (src, at) = staged(&b.ctx, frame, data, "upload staging")?;
                    unsafe {
                        d.cmd_copy_buffer(
                            frame.cmd,
                            src,
                            buffer.buffer,
                            &[vk::BufferCopy::default()
                                .src_offset(at)
                                .size(data.len() as u64)],
                        )
                    };
                }
                if let Some(old) = b.buffers.insert(
                    *id,
                    DeviceBuffer {
                        buffer,
                        bytes: data.len() as u64,
                        generation: crate::next_generation(),
                    },
                ) {
                    frame.retired.push(old.buffer);
                }
                barrier(&d, frame.cmd);
            }
            Step::Write {
                id,
                offset,
                data,
                label,
            } => {
                if *offset == 0 && b.scenes.contains_key(id) {
                    // a prepared scene's TLAS and records rewritten (moved instances): kept
                    // on the host for the refit that follows, so it reads nothing back
                    b.written_top_levels
                        .insert(*id, bytemuck::pod_collect_to_vec(data));
                }
                let dst = b.get(*id)?;
                if offset + data.len() as u64 > dst.bytes {
                    return Err(BackendError::BadArgument(format!(
                        "{label}: write of {} bytes at {offset} into a buffer of {}",
                        data.len(),
                        dst.bytes
                    )));
                }
                if !data.is_empty() {
                    let dst = dst.buffer.buffer;
                    let (src, at) = staged(&b.ctx, frame, data, "write staging")?;
                    unsafe {
                        d.cmd_copy_buffer(
                            frame.cmd,
                            src,
                            dst,
                            &[vk::BufferCopy::default()
                                .src_offset(at)
                                .dst_offset(*offset)
                                .size(data.len() as u64)],
                        )
                    };
                }
                barrier(&d, frame.cmd);
            }
            Step::Clear { id } => {
                let buf = b.get(*id)?.buffer.buffer;
                unsafe { d.cmd_fill_buffer(frame.cmd, buf, 0, vk::WHOLE_SIZE, 0) };
                barrier(&d, frame.cmd);
            }
            Step::Free { id } => {
                if let Some(old) = b.buffers.remove(id) {
                    frame.retired.push(old.buffer);
                }
                if let Some(s) = b.scenes.remove(id) {
                    frame.retired_scenes.push(s);
                }
                b.written_top_levels.remove(id);
            }
            Step::Kernel(k) => {
                if let Kernel::PrepareScene(PrepareScene { scene }) = k.kernel() {
                    k.launch()?; // the node buffer's shape is checked
                    if refit_in_frame(b, frame, scene)? {
                        continue;
                    }
                    // The build reads the uploads: finish what is recorded, then build.
                    let cmd = std::mem::replace(&mut frame.cmd, vk::CommandBuffer::null());
                    b.submit_and_wait(cmd)?;
                    prepare_scene(b, scene)?;
                    frame.cmd = b.begin()?;
                } else {
                    record_kernel(b, frame, k)?
                }
            }
        }
    }
    Ok(())
}

/// The records of `scene`'s levels from the top level written into its node buffer in
/// this recording (`Step::Write` at offset 0), if there was one of the right length.
fn written_records(
    b: &mut VulkanBackend,
    scene: &SceneArgs,
) -> Option<Vec<caustica_core::device::acceleration::InstanceRecord>> {
    use caustica_core::device::acceleration::{
        tlas_capacity, InstanceRecord, RECORD_SLOTS, SLOT_VEC4S,
    };
    let prefix = b.written_top_levels.remove(&scene.bvh_nodes.id)?;
    let levels = scene.levels as usize;
    let capacity = tlas_capacity(levels) as usize;
    if prefix.len() != (capacity + RECORD_SLOTS as usize * levels) * SLOT_VEC4S {
        return None;
    }
    Some(
        (0..levels)
            .map(|p| {
                let at = (capacity + RECORD_SLOTS as usize * p) * SLOT_VEC4S;
                InstanceRecord::decode(&prefix[at..at + 10])
            })
            .collect(),
    )
}

/// Moved instances, the common case of a frame loop: when this recording wrote the scene's
/// top level and its BLASes still serve it, the TLAS is rebuilt in place into the frame's
/// command buffer (no readback, no submit, no wait, no allocation). Returns whether it
/// did; otherwise `prepare_scene` builds what is needed.
fn refit_in_frame(
    b: &mut VulkanBackend,
    frame: &mut Frame,
    scene: &SceneArgs,
) -> Result<bool, BackendError> {
    let Some(records) = written_records(b, scene) else {
        return Ok(false);
    };
    let generations = [
        b.get(scene.vertices.id)?.generation,
        b.get(scene.triangles.id)?.generation,
        b.get(scene.bvh_nodes.id)?.generation,
    ];
    let Some(accel) = b.scenes.get_mut(&scene.bvh_nodes.id) else {
        return Ok(false);
    };
    if !accel.keeps_bottom_levels(&records, generations) {
        return Ok(false);
    }
    accel.record_top_level_rebuild(frame.cmd, &records)?;
    Ok(true)
}

/// Builds (or, when only instance transforms changed, updates) the scene's acceleration
/// structures from core's two-level layout: the records are read back from the node
/// buffer; the BLASes are kept when the vertex, triangle and node buffers are the ones they
/// were built from and the levels are the same, and only the TLAS is rebuilt.
fn prepare_scene(b: &mut VulkanBackend, scene: &SceneArgs) -> Result<(), BackendError> {
    use caustica_core::device::acceleration::{
        tlas_capacity, InstanceRecord, RECORD_SLOTS, SLOT_VEC4S,
    };
    let levels = scene.levels as usize;
    let capacity = tlas_capacity(levels) as usize;
    let prefix_vec4s = (capacity + RECORD_SLOTS as usize * levels) * SLOT_VEC4S;
    if prefix_vec4s > scene.bvh_nodes.len as usize {
        return Err(BackendError::BadArgument(format!(
            "the node buffer ({} vectors) is shorter than the {levels} levels' records",
            scene.bvh_nodes.len
        )));
    }
    let nodes_buf = b.get(scene.bvh_nodes.id)?;
    let prefix: Vec<[u32; 4]> = bytemuck::pod_collect_to_vec(
        &b.read_device(nodes_buf.buffer.buffer, prefix_vec4s as u64 * 16)?,
    );
    let records: Vec<InstanceRecord> = (0..levels)
        .map(|p| {
            let at = (capacity + RECORD_SLOTS as usize * p) * SLOT_VEC4S;
            InstanceRecord::decode(&prefix[at..at + 10])
        })
        .collect();
    let generations = [
        b.get(scene.vertices.id)?.generation,
        b.get(scene.triangles.id)?.generation,
        b.get(scene.bvh_nodes.id)?.generation,
    ];
    let mut previous = None;
    if let Some(mut accel) = b.scenes.remove(&scene.bvh_nodes.id) {
        if accel.keeps_bottom_levels(&records, generations) {
            // only transforms moved: the TLAS rebuilt in place over the same BLASes (the
            // device is idle: the caller waited)
            let shared: &VulkanBackend = b;
            let result = accel.restage(&records).and_then(|_| {
                shared.one_shot(&|cmd| accel.record_build(cmd, records.len() as u32))
            });
            b.scenes.insert(scene.bvh_nodes.id, accel);
            return result;
        }
        // a level changed (deformed): its BLAS is built, the others are kept
        previous = Some(accel);
    }
    let vertex_count = scene.vertices.len;
    let triangle_buffer = b.get(scene.triangles.id)?.buffer.buffer;
    let triangle_count = scene.triangles.len;
    debug_assert_eq!(std::mem::size_of::<GpuVertex>(), 32);
    let shared: &VulkanBackend = b;
    // triangles `first .. first + count` read back (only the levels whose BLAS is built:
    // all at a first build, a deformed level's after a deformation)
    let fetch = |first: u32, count: u32| -> Result<Vec<GpuTriangle>, BackendError> {
        if first as u64 + count as u64 > triangle_count as u64 {
            return Err(BackendError::BadArgument(
                "an instance record names triangles past the buffer".into(),
            ));
        }
        let size = std::mem::size_of::<GpuTriangle>() as u64;
        let bytes =
            shared.read_device_range(triangle_buffer, first as u64 * size, count as u64 * size)?;
        let triangles: Vec<GpuTriangle> = bytemuck::pod_collect_to_vec(&bytes);
        if triangles
            .iter()
            .flat_map(|t| t.indices)
            .any(|i| i >= vertex_count)
        {
            return Err(BackendError::BadArgument(
                "a triangle indexes past the vertex buffer".into(),
            ));
        }
        Ok(triangles)
    };
    let sources = SceneSources {
        vertices: &shared.get(scene.vertices.id)?.buffer,
        vertex_count,
        nodes: &shared.get(scene.bvh_nodes.id)?.buffer,
        generations,
    };
    let accel = SceneAccel::build(
        &shared.ctx,
        &|f| shared.one_shot(f),
        &sources,
        triangle_count,
        &fetch,
        &records,
        previous,
    )?;
    b.bottom_level_builds += accel.built_blases as u64;
    if let Some(old) = b.scenes.insert(scene.bvh_nodes.id, accel) {
        drop(old); // the device is idle here: prepare_scene waited for it
    }
    Ok(())
}

fn scene_of(k: &Kernel) -> Option<&SceneArgs> {
    k.scene()
}

fn record_kernel(
    b: &VulkanBackend,
    frame: &mut Frame,
    k: &RecordedKernel,
) -> Result<(), BackendError> {
    let d = &b.ctx.device;
    let Some(launch) = k.launch()? else {
        return Ok(());
    };
    let label = launch.variant_label();
    let pipeline = b
        .pipelines
        .get(&label)
        .ok_or_else(|| BackendError::Unsupported(label.clone()))?;
    let scene = scene_of(k.kernel());
    if k.kernel().info().traced && scene.is_none() {
        return Err(BackendError::BadArgument(format!(
            "{}: a traced kernel must name its scene (KernelDecl::scene)",
            label
        )));
    }
    let counters = match k.kernel() {
        Kernel::TracePhotons(TracePhotons { counters, .. }) => Some(counters.id),
        Kernel::TraceIndirect(TraceIndirect { counters, .. }) => Some(counters.id),
        _ => None,
    };
    let mut descs = Vec::new();
    if let Some(s) = scene {
        let accel = b
            .scenes
            .get(&s.bvh_nodes.id)
            .ok_or_else(|| BackendError::BadArgument("scene used before prepare_scene".into()))?;
        descs.push(Desc::Tlas(accel.tlas.handle));
    }
    for a in &launch.args {
        match a {
            LaunchArg::Count(_) => {}
            LaunchArg::Buffer { id, .. } if scene.is_some_and(|s| s.bvh_nodes.id == *id) => {}
            LaunchArg::Buffer { id, .. } if counters == Some(*id) => {
                check_buffer(a, b.get(*id)?.bytes)?;
                descs.push(Desc::Storage(
                    b.counter_banks.buffer,
                    crate::COUNTER_BANK_BYTES,
                ));
            }
            LaunchArg::Buffer { id, bytes, .. } => {
                check_buffer(a, b.get(*id)?.bytes)?;
                descs.push(Desc::Storage(
                    b.get(*id)?.buffer.buffer,
                    (*bytes).max(MIN_BINDING_BYTES),
                ));
            }
            LaunchArg::Params(p) => {
                let align = b.ctx.limits.min_uniform_buffer_offset_alignment;
                match frame.slot.arena.put(p, align) {
                    Some((buf, at)) => descs.push(Desc::Uniform(buf, at, p.len() as u64)),
                    None => {
                        let u = Buffer::with_data(
                            &b.ctx,
                            p,
                            vk::BufferUsageFlags::UNIFORM_BUFFER,
                            "kernel parameters",
                        )?;
                        descs.push(Desc::Uniform(u.buffer, 0, p.len() as u64));
                        frame.retired.push(u);
                    }
                }
            }
        }
    }
    if descs.len() != pipeline.bindings.len() {
        return Err(BackendError::Driver(format!(
            "{}: {} descriptors for {} bindings",
            launch.kernel,
            descs.len(),
            pipeline.bindings.len()
        )));
    }
    let set = bind_set(b, frame, pipeline, &descs)?;
    let index = frame.passes.len() as u32;
    if let Some(q) = frame.queries {
        unsafe {
            d.cmd_write_timestamp(frame.cmd, vk::PipelineStageFlags::TOP_OF_PIPE, q, 2 * index)
        };
    }
    let n = launch.threads;
    unsafe {
        d.cmd_bind_pipeline(frame.cmd, pipeline.bind_point, pipeline.pipeline);
        d.cmd_bind_descriptor_sets(
            frame.cmd,
            pipeline.bind_point,
            pipeline.layout,
            0,
            &[set],
            &[],
        );
    }
    if n > 0 {
        if let Some(sbt) = &pipeline.sbt {
            let w = n.min(raygen_width(&b.ctx.limits, launch.kernel, n));
            let h = n.div_ceil(w);
            unsafe {
                b.ctx.rt.cmd_trace_rays(
                    frame.cmd,
                    &sbt.raygen,
                    &sbt.miss,
                    &sbt.hit,
                    &sbt.callable,
                    w as u32,
                    h as u32,
                    1,
                )
            };
        } else {
            let groups = n.div_ceil(launch.workgroup_size as u64);
            let max = b.ctx.limits.max_compute_work_group_count[0] as u64;
            let x = groups.min(max);
            let y = groups.div_ceil(x);
            if y > b.ctx.limits.max_compute_work_group_count[1] as u64 {
                return Err(BackendError::BadArgument(format!(
                    "{}: {n} threads",
                    launch.kernel
                )));
            }
            unsafe { d.cmd_dispatch(frame.cmd, x as u32, y as u32, 1) };
        }
    }
    if let Some(c) = counters {
        barrier(d, frame.cmd);
        let reduce = &b.pipelines["reduce_counters"];
        let descs = [
            Desc::Storage(b.counter_banks.buffer, crate::COUNTER_BANK_BYTES),
            Desc::Storage(b.get(c)?.buffer.buffer, 80),
        ];
        let set = bind_set(b, frame, reduce, &descs)?;
        unsafe {
            d.cmd_bind_pipeline(frame.cmd, reduce.bind_point, reduce.pipeline);
            d.cmd_bind_descriptor_sets(frame.cmd, reduce.bind_point, reduce.layout, 0, &[set], &[]);
            d.cmd_dispatch(frame.cmd, 1, 1, 1);
        }
    }
    if let Some(q) = frame.queries {
        unsafe {
            d.cmd_write_timestamp(
                frame.cmd,
                vk::PipelineStageFlags::BOTTOM_OF_PIPE,
                q,
                2 * index + 1,
            )
        };
    }
    frame.passes.push(launch.kernel);
    barrier(d, frame.cmd);
    Ok(())
}

fn bind_set(
    b: &VulkanBackend,
    frame: &Frame,
    pipeline: &Pipeline,
    descs: &[Desc],
) -> Result<vk::DescriptorSet, BackendError> {
    let d = &b.ctx.device;
    let layouts = [pipeline.set_layout];
    let set = unsafe {
        d.allocate_descriptor_sets(
            &vk::DescriptorSetAllocateInfo::default()
                .descriptor_pool(frame.slot.descriptor_pool())
                .set_layouts(&layouts),
        )
    }
    .map_err(vk_error("allocating a descriptor set"))?[0];
    let mut buffer_infos = Vec::new();
    let mut tlas = Vec::new();
    for desc in descs {
        match desc {
            Desc::Storage(buf, range) => buffer_infos.push([vk::DescriptorBufferInfo::default()
                .buffer(*buf)
                .offset(0)
                .range(*range)]),
            Desc::Uniform(buf, offset, range) => {
                buffer_infos.push([vk::DescriptorBufferInfo::default()
                    .buffer(*buf)
                    .offset(*offset)
                    .range(*range)])
            }
            Desc::Tlas(h) => tlas.push([*h]),
        }
    }
    let mut as_writes: Vec<_> = tlas
        .iter()
        .map(|h| {
            vk::WriteDescriptorSetAccelerationStructureKHR::default().acceleration_structures(h)
        })
        .collect();
    let mut writes = Vec::new();
    let (mut bi, mut ai) = (buffer_infos.iter(), as_writes.iter_mut());
    for (i, desc) in descs.iter().enumerate() {
        let w = vk::WriteDescriptorSet::default()
            .dst_set(set)
            .dst_binding(i as u32);
        writes.push(match desc {
            Desc::Storage(..) => w
                .descriptor_type(S)
                .buffer_info(bi.next().expect("one info per buffer")),
            Desc::Uniform(..) => w
                .descriptor_type(U)
                .buffer_info(bi.next().expect("one info per buffer")),
            Desc::Tlas(_) => {
                let a = ai.next().expect("one write per TLAS");
                w.descriptor_type(AS).descriptor_count(1).push_next(a)
            }
        });
    }
    unsafe { d.update_descriptor_sets(&writes, &[]) };
    Ok(set)
}
