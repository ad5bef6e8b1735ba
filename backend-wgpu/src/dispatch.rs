//! Registry kernels to wgpu compute passes: core's [`Launch`] description (buffers and
//! parameter blocks in the binding order of each kernel's `wgsl/<kernel>.wgsl` in
//! `caustica-shaders`; counts are derived in WGSL with `arrayLength`), 2-D workgroup grids
//! for launches beyond 65535 groups, and per-pass timestamps.

use crate::WgpuBackend;
use caustica_core::backend::{BackendError, PassTime};
use caustica_core::device::launch::{check_buffer, Launch, LaunchArg};
use caustica_core::recording::RecordedKernel;
use wgpu::util::DeviceExt;

/// Per-pass timing: a timestamp pair per kernel where the device has timestamp queries,
/// else host times of kernels submitted alone.
pub struct Timer {
    queries: Option<crate::pool::TimestampQueries>,
    passes: Vec<&'static str>,
    host: Vec<f64>,
    period_ns: f32,
}

impl Timer {
    /// A timer for `kernels` kernels, its query set from the backend's pool (give it back
    /// with [`Timer::give_back`] once its ticks are read).
    pub fn new(b: &mut WgpuBackend, kernels: u32) -> Timer {
        let queries = (b.timestamps && kernels > 0).then(|| b.pool.queries(&b.device, kernels));
        Timer {
            queries,
            passes: Vec::new(),
            host: Vec::new(),
            period_ns: b.queue.get_timestamp_period(),
        }
    }

    /// The query set, taken out (to be kept until the GPU has resolved it).
    pub fn take_queries(&mut self) -> Option<crate::pool::TimestampQueries> {
        self.queries.take()
    }

    /// Returns the query set to the backend's pool.
    pub fn give_back(&mut self, b: &mut WgpuBackend) {
        if let Some(q) = self.queries.take() {
            b.pool.give_queries(q);
        }
    }

    fn writes(&self) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let i = self.passes.len() as u32;
        self.queries
            .as_ref()
            .map(|q| wgpu::ComputePassTimestampWrites {
                query_set: &q.set,
                beginning_of_pass_write_index: Some(2 * i),
                end_of_pass_write_index: Some(2 * i + 1),
            })
    }

    pub fn host_time(&mut self, seconds: f64) {
        self.host.push(seconds);
    }

    pub fn resolve(&self, enc: &mut wgpu::CommandEncoder) {
        if let Some(q) = &self.queries {
            if !self.passes.is_empty() {
                enc.resolve_query_set(&q.set, 0..2 * self.passes.len() as u32, &q.resolve, 0);
            }
        }
    }

    /// The resolved timestamps' buffer and its length in bytes (after [`Timer::resolve`]),
    /// if the passes were timed on the device.
    pub fn resolved(&self) -> Option<(&wgpu::Buffer, u64)> {
        match &self.queries {
            Some(q) if !self.passes.is_empty() => Some((&q.resolve, 16 * self.passes.len() as u64)),
            _ => None,
        }
    }

    /// The kernels recorded, in order.
    pub fn passes(&self) -> &[&'static str] {
        &self.passes
    }

    /// Pass times from resolved timestamp pairs (`raw`: the bytes of [`Timer::resolved`]).
    pub fn times_from_ticks(passes: &[&'static str], raw: &[u8], period_ns: f32) -> Vec<PassTime> {
        let ticks: Vec<u64> = bytemuck::pod_collect_to_vec(raw);
        passes
            .iter()
            .enumerate()
            .map(|(i, k)| PassTime {
                kernel: k,
                seconds: ticks[2 * i + 1].saturating_sub(ticks[2 * i]) as f64
                    * period_ns as f64
                    * 1e-9,
            })
            .collect()
    }

    /// The timestamp period (ns per tick).
    pub fn period_ns(&self) -> f32 {
        self.period_ns
    }

    pub fn finish(mut self, b: &mut WgpuBackend) -> Result<Vec<PassTime>, BackendError> {
        match self.resolved() {
            Some((buf, bytes)) => {
                let raw = b.read_buffer(buf, bytes);
                self.give_back(b);
                Ok(Self::times_from_ticks(&self.passes, &raw?, self.period_ns))
            }
            _ => Ok(self
                .passes
                .iter()
                .zip(self.host.iter().chain(std::iter::repeat(&0.0)))
                .map(|(k, s)| PassTime {
                    kernel: k,
                    seconds: *s,
                })
                .collect()),
        }
    }
}

/// Records one registry kernel into `enc`.
pub fn record(
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
                check_buffer(a, b.get(*id)?.bytes)?;
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
                    usage: wgpu::BufferUsages::UNIFORM,
                },
            )),
            LaunchArg::Count(_) => {}
        }
    }
    if threads == 0 {
        return Ok(());
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
                    buffer: &b.get(*id)?.buffer,
                    offset: 0,
                    // an empty buffer binds as a dummy of MIN_BINDING_BYTES
                    size: std::num::NonZeroU64::new((*bytes).max(crate::MIN_BINDING_BYTES)),
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
        pass.dispatch_workgroups(x as u32, y as u32, 1);
    }
    timer.passes.push(name);
    Ok(())
}
