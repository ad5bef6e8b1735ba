//! The recording interpreter: every step of a [`Recording`] recorded in order into a
//! submission's command buffer: buffer steps as fills and staged copies, kernels as
//! ray-tracing launches (G-buffer, direct light, photons) or compute dispatches (the
//! rest), each bound with core's launch description, separated by full memory barriers
//! and bracketed by timestamps; `prepare_scene` as the acceleration structures' build or
//! refit ([`crate::accel`]).

use crate::accel::{prepare_scene, refit_in_frame};
use crate::device::{vk_error, Context};
use crate::memory::{next_generation, Buffer, DeviceBuffer, COUNTER_BANK_BYTES, MIN_BINDING_BYTES};
use crate::pipelines::{Pipeline, AS, S, U};
use crate::submission::Frame;
use crate::VulkanBackend;
use ash::vk;
use caustica_core::backend::{check_write, BackendError};
use caustica_core::device::handle::SceneArgs;
use caustica_core::device::launch::{check_buffer, LaunchArg};
use caustica_core::kernels::Kernel;
use caustica_core::kernels::{PrepareScene, TraceIndirect, TracePhotons};
use caustica_core::recording::{RecordedKernel, Recording, Step};
use std::sync::Arc;

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

/// `data` in host-visible memory the device can copy from: in the frame's arena, or (too
/// large, or the arena full) in a staging buffer of its own, retired with the frame.
pub(crate) fn staged(
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

pub(crate) fn record_all(
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
        // a step that touches the counters whose sums are in the banks reads them whole
        if let Some(c) = frame.banked_counters {
            let touches = match step {
                Step::Create { id, .. }
                | Step::Upload { id, .. }
                | Step::Write { id, .. }
                | Step::Clear { id }
                | Step::Free { id } => *id == c,
                Step::Kernel(k) => matches!(k.kernel(), Kernel::PrepareScene(_)),
            };
            if touches {
                flush_counter_banks(b, frame)?;
            }
        }
        match step {
            Step::Create { id, bytes, label } => {
                let buffer = b.new_storage(*bytes, label)?;
                unsafe { d.cmd_fill_buffer(frame.cmd, buffer.buffer, 0, vk::WHOLE_SIZE, 0) };
                if let Some(old) = b.buffers.insert(
                    *id,
                    DeviceBuffer {
                        buffer,
                        bytes: *bytes,
                        generation: next_generation(),
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
                        generation: next_generation(),
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
                let dst = b.buffers.get(*id)?;
                check_write(label, dst.bytes, *offset, data.len())?;
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
                let buf = b.buffers.get(*id)?.buffer.buffer;
                unsafe { d.cmd_fill_buffer(frame.cmd, buf, 0, vk::WHOLE_SIZE, 0) };
                barrier(&d, frame.cmd);
            }
            Step::Free { id } => {
                if let Some(old) = b.buffers.remove(*id) {
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
    flush_counter_banks(b, frame)
}

/// Folds the counter banks into the counters buffer they stand for (`reduce_counters`),
/// where traced launches left sums there. A traced launch adds its counts into the banks
/// ([`Frame::banked_counters`]); further launches for the same counters add to them, and
/// they are folded once, before anything else touches that buffer (a launch binding it,
/// a parameter patch reading it, a write, clear or free), before a traced launch for
/// other counters, and at the end of the recording: the counts equal a fold after every
/// launch (the u64 words carry, the u32 words wrap mod 2^32 either way), with one
/// dispatch instead of one per launch, outside the launches' timestamps.
pub(crate) fn flush_counter_banks(
    b: &VulkanBackend,
    frame: &mut Frame,
) -> Result<(), BackendError> {
    let Some(c) = frame.banked_counters.take() else {
        return Ok(());
    };
    let d = &b.ctx.device;
    barrier(d, frame.cmd);
    let reduce = &b.pipelines["reduce_counters"];
    let descs = [
        Desc::Storage(b.counter_banks.buffer, COUNTER_BANK_BYTES),
        Desc::Storage(b.buffers.get(c)?.buffer.buffer, 80),
    ];
    let set = bind_set(b, frame, reduce, &descs)?;
    unsafe {
        d.cmd_bind_pipeline(frame.cmd, reduce.bind_point, reduce.pipeline);
        d.cmd_bind_descriptor_sets(frame.cmd, reduce.bind_point, reduce.layout, 0, &[set], &[]);
        d.cmd_dispatch(frame.cmd, 1, 1, 1);
    }
    barrier(d, frame.cmd);
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
    // the banks hold one counters buffer's sums: folded before a launch for other
    // counters, or one that reads the banked buffer itself
    if let Some(c) = frame.banked_counters {
        let binds = launch
            .args
            .iter()
            .any(|a| matches!(a, LaunchArg::Buffer { id, .. } if *id == c))
            || launch.patches.iter().any(|p| p.src == c);
        if counters.is_some_and(|k| k != c) || (counters.is_none() && binds) {
            flush_counter_banks(b, frame)?;
        }
    }
    let mut descs = Vec::new();
    // the launch's parameter block (buffer, offset)
    let mut block = None;
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
                check_buffer(a, b.buffers.get(*id)?.bytes)?;
                descs.push(Desc::Storage(b.counter_banks.buffer, COUNTER_BANK_BYTES));
            }
            LaunchArg::Buffer { id, bytes, .. } => {
                check_buffer(a, b.buffers.get(*id)?.bytes)?;
                descs.push(Desc::Storage(
                    b.buffers.get(*id)?.buffer.buffer,
                    (*bytes).max(MIN_BINDING_BYTES),
                ));
            }
            LaunchArg::Params(p) => {
                let align = b.ctx.limits.min_uniform_buffer_offset_alignment;
                let (buf, at) = match frame.slot.arena.put(p, align) {
                    Some(at) => at,
                    None => {
                        let u = Buffer::with_data(
                            &b.ctx,
                            p,
                            vk::BufferUsageFlags::UNIFORM_BUFFER
                                | vk::BufferUsageFlags::TRANSFER_DST,
                            "kernel parameters",
                        )?;
                        let buf = u.buffer;
                        frame.retired.push(u);
                        (buf, 0)
                    }
                };
                descs.push(Desc::Uniform(buf, at, p.len() as u64));
                block = Some((buf, at));
            }
        }
    }
    // parameter words an earlier step wrote on the device, copied into the launch's
    // uniform block between full barriers (after the writer, before the launch)
    if let (Some((buf, at)), false) = (block, launch.patches.is_empty()) {
        barrier(d, frame.cmd);
        for p in &launch.patches {
            let src = b.buffers.get(p.src)?;
            p.check_source(src.bytes)?;
            unsafe {
                d.cmd_copy_buffer(
                    frame.cmd,
                    src.buffer.buffer,
                    buf,
                    &[vk::BufferCopy::default()
                        .src_offset(p.src_offset())
                        .dst_offset(at + p.offset as u64)
                        .size(p.bytes())],
                )
            };
        }
        barrier(d, frame.cmd);
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
    // an indirect launch: its record's buffer (handle and device address)
    let indirect = match launch.indirect {
        Some(i) => {
            let args = &b.buffers.get(i.args)?.buffer;
            Some(((args.buffer, args.address()), i))
        }
        None => None,
    };
    if n > 0 {
        if let Some(sbt) = &pipeline.sbt {
            match indirect {
                Some((args, i)) if b.ctx.trace_rays_indirect => unsafe {
                    b.ctx.rt.cmd_trace_rays_indirect(
                        frame.cmd,
                        &sbt.raygen,
                        &sbt.miss,
                        &sbt.hit,
                        &sbt.callable,
                        args.1 + i.grid_offset(),
                    )
                },
                _ => {
                    // the bound (the kernel leaves past its device count)
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
                }
            }
        } else if let Some((args, i)) = indirect {
            unsafe { d.cmd_dispatch_indirect(frame.cmd, args.0, i.groups_offset()) };
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
    if counters.is_some() {
        frame.banked_counters = counters;
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
