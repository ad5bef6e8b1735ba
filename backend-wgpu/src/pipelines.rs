//! Compute pipelines: every registry kernel's WGSL (the `caustica-shaders` crate) compiled
//! once when the backend is made, a kernel with compiled switches once per variant on
//! first use, kept by variant label.

use crate::WgpuBackend;
use caustica_core::backend::BackendError;
use caustica_core::device::launch::Launch;
use caustica_shaders as shaders;

/// Compiles kernel `name` with its override constants set to `constants`; a WGSL or
/// pipeline validation error is a typed error.
pub(crate) fn create_pipeline(
    device: &wgpu::Device,
    name: &str,
    constants: &[(&'static str, u32)],
) -> Result<wgpu::ComputePipeline, BackendError> {
    let scope = device.push_error_scope(wgpu::ErrorFilter::Validation);
    let src = shaders::module_source(name).map_err(BackendError::Driver)?;
    let desc = wgpu::ShaderModuleDescriptor {
        label: Some(name),
        source: wgpu::ShaderSource::Wgsl(src.into()),
    };
    // Every check wgpu offers stays on but one: naga's loop bounding, which gives every
    // loop an iteration counter (a 64-bit decrement and a test per iteration) so that a
    // driver may not assume that an endless loop ends. In the traversal's inner loop that
    // costs on every node visit (see the README's 2 ms section for the measured gain).
    //
    // SAFETY: `force_loop_bounding: false` requires that no loop of these shaders runs
    // forever. Every loop of caustica's kernels (the `shaders` crate's WGSL, which nobody
    // else supplies) is bounded: by a count from the dispatch's parameters (photons,
    // bounces, splits, pixels of a footprint, A-Trous taps, cluster children), by a
    // fixed-size stack whose pushes are guarded by its size, or by the BVH traversal,
    // which visits each node of a tree at most once (the node buffer is built by
    // `DeviceScene`, never taken from a user). Bounds checks remain as wgpu sets them.
    let module = unsafe {
        device.create_shader_module_trusted(
            desc,
            wgpu::ShaderRuntimeChecks {
                force_loop_bounding: false,
                ..wgpu::ShaderRuntimeChecks::checked()
            },
        )
    };
    let overrides: Vec<(&str, f64)> = constants.iter().map(|(n, v)| (*n, *v as f64)).collect();
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some(name),
        layout: None,
        module: &module,
        entry_point: Some("main"),
        compilation_options: wgpu::PipelineCompilationOptions {
            constants: &overrides,
            zero_initialize_workgroup_memory: !shaders::WORKGROUP_MEMORY_WRITTEN_FIRST
                .contains(&name),
        },
        cache: None,
    });
    if let Some(e) = pollster::block_on(scope.pop()) {
        return Err(BackendError::Driver(format!(
            "WGSL pipeline creation failed ({name}): {e}"
        )));
    }
    Ok(pipeline)
}

impl WgpuBackend {
    /// Builds the pipeline of a launch's variant unless it exists.
    pub(crate) fn ensure_pipeline(&mut self, launch: &Launch) -> Result<(), BackendError> {
        let label = launch.variant_label();
        if !self.pipelines.contains_key(&label) {
            let p = create_pipeline(&self.device, launch.kernel, &launch.constants)?;
            self.pipelines.insert(label, p);
        }
        Ok(())
    }
}
