//! The recording interpreter: every step of a [`Recording`] encoded in order into a
//! command encoder (creations at once, writes as staging copies in the encoder, kernels as
//! compute passes), and [`Backend::execute`](caustica_core::backend::Backend::execute),
//! which submits and waits.

use crate::submission::Timer;
use crate::WgpuBackend;
use caustica_core::backend::{check_write, BackendError, PassTime};
use caustica_core::device::launch::{check_buffer, Launch, LaunchArg};
use caustica_core::recording::{RecordedKernel, Recording, Step};
use wgpu::util::DeviceExt;

impl WgpuBackend {
    /// [`caustica_core::backend::Backend::execute`]'s body (core runs it inside
    /// [`caustica_core::backend::driver_entry`]).
    pub(crate) fn execute_recording(
        &mut self,
        recording: &Recording,
    ) -> Result<Vec<PassTime>, BackendError> {
        self.check_uncaptured()?;
        let mut timer = Timer::new(self, recording.kernel_count());
        let mut enc = self.device.create_command_encoder(&Default::default());
        self.encode_steps(recording, &mut enc, &mut timer, true)?;
        timer.resolve(&mut enc);
        self.queue.submit([enc.finish()]);
        self.wait()?;
        timer.finish(self)
    }

    /// Records every step of `recording` into `enc`, in order. Creations happen at once
    /// (zeroed or mapped at creation); writes go through staging copies in `enc`.
    /// `alone`: without timestamp queries, each kernel is submitted and waited for on its
    /// own so the host can time it (never in a non-blocking submission).
    pub(crate) fn encode_steps(
        &mut self,
        recording: &Recording,
        enc: &mut wgpu::CommandEncoder,
        timer: &mut Timer,
        alone: bool,
    ) -> Result<(), BackendError> {
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
                    let dst = self.buffers.get(*id)?;
                    check_write(label, dst.bytes, *offset, data.len())?;
                    if !data.is_empty() {
                        // a staging copy in the encoder, ordered with the kernels around it
                        // (queue.write_buffer would land before the whole submission)
                        let staging = self.device.create_buffer(&wgpu::BufferDescriptor {
                            label: Some("write staging"),
                            size: data.len() as u64,
                            usage: wgpu::BufferUsages::COPY_SRC,
                            mapped_at_creation: true,
                        });
                        {
                            let mut view =
                                staging.slice(..).get_mapped_range_mut().map_err(|e| {
                                    BackendError::Driver(format!("mapping {label}: {e}"))
                                })?;
                            view.copy_from_slice(data);
                        }
                        staging.unmap();
                        enc.copy_buffer_to_buffer(
                            &staging,
                            0,
                            &dst.buffer,
                            *offset,
                            data.len() as u64,
                        );
                    }
                }
                Step::Clear { id } => enc.clear_buffer(&self.buffers.get(*id)?.buffer, 0, None),
                Step::Free { id } => {
                    // wgpu keeps the memory until the commands using it have finished
                    self.buffers.remove(*id);
                }
                Step::Kernel(k) => {
                    if let Some(l) = k.launch()? {
                        self.ensure_pipeline(l)?;
                    }
                    record(self, enc, timer, k)?;
                    if !self.timestamps && alone {
                        // No GPU timestamps: each kernel runs alone, timed by the host.
                        let done = std::mem::replace(
                            enc,
                            self.device.create_command_encoder(&Default::default()),
                        );
                        let t0 = std::time::Instant::now();
                        self.queue.submit([done.finish()]);
                        self.wait()?;
                        timer.host_time(t0.elapsed().as_secs_f64());
                    }
                }
            }
        }
        Ok(())
    }
}

/// Records one registry kernel into `enc`.
fn record(
    b: &WgpuBackend,
    enc: &mut wgpu::CommandEncoder,
    timer: &mut Timer,
    k: &RecordedKernel,
) -> Result<(), BackendError> {
    let Some(launch) = k.launch()? else {
        return Ok(());
    };
    let label = launch.variant_label();
    let Launch {
        kernel: name,
        threads,
        workgroup_size,
        args,
        ..
    } = launch;
    let (name, threads) = (*name, *threads);
    let max_binding = b.limits.max_storage_buffer_binding_size;
    let mut uniforms = Vec::new();
    for a in args {
        match a {
            LaunchArg::Buffer {
                id, bytes, what, ..
            } => {
                check_buffer(a, b.buffers.get(*id)?.bytes)?;
                if *bytes > max_binding {
                    return Err(BackendError::OutOfMemory {
                        bytes: *bytes,
                        what: format!("{what}: the adapter binds at most {max_binding} bytes"),
                    });
                }
            }
            LaunchArg::Params(p) => uniforms.push(b.device.create_buffer_init(
                &wgpu::util::BufferInitDescriptor {
                    label: Some("kernel parameters"),
                    contents: p,
                    // words from the device are copied in (`ParamPatch`)
                    usage: if launch.patches.is_empty() {
                        wgpu::BufferUsages::UNIFORM
                    } else {
                        wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST
                    },
                },
            )),
            LaunchArg::Count(_) => {}
        }
    }
    if threads == 0 {
        return Ok(());
    }
    // parameter words an earlier step wrote on the device, copied into the launch's
    // uniform block (ordered after every earlier pass of the encoder)
    if let Some(block) = uniforms.first() {
        for p in &launch.patches {
            let src = b.buffers.get(p.src)?;
            p.check_source(src.bytes)?;
            enc.copy_buffer_to_buffer(
                &src.buffer,
                p.src_offset(),
                block,
                p.offset as u64,
                p.bytes(),
            );
        }
    }
    let groups = threads.div_ceil(*workgroup_size as u64);
    let max = b.limits.max_compute_workgroups_per_dimension as u64;
    let x = groups.min(max);
    let y = groups.div_ceil(x);
    if y > max {
        return Err(BackendError::BadArgument(format!(
            "{name}: {threads} threads exceed a {max} x {max} grid of workgroups"
        )));
    }
    let pipeline = b
        .pipelines
        .get(&label)
        .ok_or_else(|| BackendError::Unsupported(label.clone()))?;
    let mut entries = Vec::with_capacity(args.len());
    let mut next_uniform = uniforms.iter();
    for a in args {
        let resource = match a {
            LaunchArg::Buffer { id, bytes, .. } => {
                wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &b.buffers.get(*id)?.buffer,
                    offset: 0,
                    // an empty buffer binds as a dummy of MIN_BINDING_BYTES
                    size: std::num::NonZeroU64::new((*bytes).max(crate::memory::MIN_BINDING_BYTES)),
                })
            }
            LaunchArg::Params(_) => next_uniform
                .next()
                .ok_or_else(|| BackendError::Driver("parameter block missing".into()))?
                .as_entire_binding(),
            LaunchArg::Count(_) => continue,
        };
        entries.push(wgpu::BindGroupEntry {
            binding: entries.len() as u32,
            resource,
        });
    }
    let group = b.device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some(name),
        layout: &pipeline.get_bind_group_layout(0),
        entries: &entries,
    });
    {
        let mut pass = enc.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(name),
            timestamp_writes: timer.writes(),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &group, &[]);
        match launch.indirect {
            // the record an earlier kernel wrote (the kernel bounds itself by its count)
            Some(i) => {
                pass.dispatch_workgroups_indirect(&b.buffers.get(i.args)?.buffer, i.groups_offset())
            }
            None => pass.dispatch_workgroups(x as u32, y as u32, 1),
        }
    }
    timer.passes.push(name);
    Ok(())
}
