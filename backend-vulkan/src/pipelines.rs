//! Pipelines: ray-tracing pipelines (ray generation, closest-hit and miss stages from the
//! GLSL sources under `shaders/`, compiled to SPIR-V kept in `spirv/`) with their shader
//! binding tables, and compute pipelines for the other kernels, from the WGSL of the
//! `caustica-shaders` crate through naga's SPIR-V writer (one source for this backend and
//! the wgpu backend). Every pipeline without compiled switches is made with the backend,
//! a variant on first use, kept by variant label; descriptor types come from core's
//! kernel declarations.

use crate::device::{vk_error, Context};
use crate::memory::Buffer;
use crate::VulkanBackend;
use ash::vk;
use caustica_core::backend::{driver_lifecycle, BackendError};
use caustica_core::kernels::{KernelInfo, ShaderBinding, KERNELS};
use caustica_core::recording::{Recording, Step};
use std::collections::HashMap;
use std::sync::Arc;

use caustica_shaders as wgsl;

pub(crate) const S: vk::DescriptorType = vk::DescriptorType::STORAGE_BUFFER;
pub(crate) const U: vk::DescriptorType = vk::DescriptorType::UNIFORM_BUFFER;
pub(crate) const AS: vk::DescriptorType = vk::DescriptorType::ACCELERATION_STRUCTURE_KHR;

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
pub(crate) fn descriptor_types(info: &KernelInfo) -> Vec<vk::DescriptorType> {
    info.descriptor_bindings()
        .into_iter()
        .map(descriptor_type)
        .collect()
}

/// SPIR-V of the GLSL stages (see `scripts/compile-shaders.sh`).
pub mod spirv {
    pub const PRIMARY_GBUFFER: &[u8] = include_bytes!("../spirv/primary_gbuffer.rgen.spv");
    pub const DIRECT_LIGHT: &[u8] = include_bytes!("../spirv/direct_light.rgen.spv");
    pub const TRACE_PHOTONS: &[u8] = include_bytes!("../spirv/trace_photons.rgen.spv");
    pub const CAUSTIC_MAP_LOOKUP: &[u8] = include_bytes!("../spirv/caustic_map_lookup.rgen.spv");
    pub const TRACE_INDIRECT: &[u8] = include_bytes!("../spirv/trace_indirect.rgen.spv");
    pub const CLOSEST_HIT: &[u8] = include_bytes!("../spirv/closest_hit.rchit.spv");
    pub const MISS: &[u8] = include_bytes!("../spirv/miss.rmiss.spv");
    pub const SHADOW_MISS: &[u8] = include_bytes!("../spirv/shadow_miss.rmiss.spv");
    pub const REDUCE_COUNTERS: &[u8] = include_bytes!("../spirv/reduce_counters.comp.spv");

    /// The ray generation stage of traced kernel `name` (`shaders/<name>.rgen`).
    pub fn raygen(name: &str) -> Option<&'static [u8]> {
        match name {
            "primary_gbuffer" => Some(PRIMARY_GBUFFER),
            "direct_light" => Some(DIRECT_LIGHT),
            "trace_photons" => Some(TRACE_PHOTONS),
            "caustic_map_lookup" => Some(CAUSTIC_MAP_LOOKUP),
            "trace_indirect" => Some(TRACE_INDIRECT),
            _ => None,
        }
    }
}

/// The shader binding table: ray generation, two miss records, one hit group.
pub struct Sbt {
    _buffer: Buffer,
    pub raygen: vk::StridedDeviceAddressRegionKHR,
    pub miss: vk::StridedDeviceAddressRegionKHR,
    pub hit: vk::StridedDeviceAddressRegionKHR,
    pub callable: vk::StridedDeviceAddressRegionKHR,
}

/// A pipeline with its layouts.
pub struct Pipeline {
    ctx: Arc<Context>,
    pub pipeline: vk::Pipeline,
    pub layout: vk::PipelineLayout,
    pub set_layout: vk::DescriptorSetLayout,
    pub bindings: Vec<vk::DescriptorType>,
    pub bind_point: vk::PipelineBindPoint,
    pub sbt: Option<Sbt>,
}

impl Drop for Pipeline {
    fn drop(&mut self) {
        // a ray-tracing pipeline's destruction enters the driver's CUDA layer: never at
        // once with a device's destruction (caustica_core::backend::driver_lifecycle)
        driver_lifecycle(|| unsafe {
            let d = &self.ctx.device;
            d.destroy_pipeline(self.pipeline, None);
            d.destroy_pipeline_layout(self.layout, None);
            d.destroy_descriptor_set_layout(self.set_layout, None);
        })
    }
}

fn shader_module(ctx: &Context, code: &[u32]) -> Result<vk::ShaderModule, BackendError> {
    unsafe {
        ctx.device
            .create_shader_module(&vk::ShaderModuleCreateInfo::default().code(code), None)
    }
    .map_err(vk_error("creating a shader module"))
}

fn words(bytes: &[u8]) -> Result<Vec<u32>, BackendError> {
    ash::util::read_spv(&mut std::io::Cursor::new(bytes))
        .map_err(|e| BackendError::Driver(format!("bad SPIR-V: {e}")))
}

fn layouts(
    ctx: &Context,
    bindings: &[vk::DescriptorType],
    stages: vk::ShaderStageFlags,
) -> Result<(vk::DescriptorSetLayout, vk::PipelineLayout), BackendError> {
    let b: Vec<_> = bindings
        .iter()
        .enumerate()
        .map(|(i, t)| {
            vk::DescriptorSetLayoutBinding::default()
                .binding(i as u32)
                .descriptor_type(*t)
                .descriptor_count(1)
                .stage_flags(stages)
        })
        .collect();
    let set_layout = unsafe {
        ctx.device.create_descriptor_set_layout(
            &vk::DescriptorSetLayoutCreateInfo::default().bindings(&b),
            None,
        )
    }
    .map_err(vk_error("creating a descriptor set layout"))?;
    let sets = [set_layout];
    let layout = unsafe {
        ctx.device.create_pipeline_layout(
            &vk::PipelineLayoutCreateInfo::default().set_layouts(&sets),
            None,
        )
    };
    match layout {
        Ok(l) => Ok((set_layout, l)),
        Err(e) => {
            unsafe { ctx.device.destroy_descriptor_set_layout(set_layout, None) };
            Err(vk_error("creating a pipeline layout")(e))
        }
    }
}

/// Releases the layouts of a pipeline whose creation failed.
fn destroy_layouts(ctx: &Context, set_layout: vk::DescriptorSetLayout, layout: vk::PipelineLayout) {
    unsafe {
        ctx.device.destroy_pipeline_layout(layout, None);
        ctx.device.destroy_descriptor_set_layout(set_layout, None);
    }
}

/// A compute pipeline from SPIR-V with entry point `main`.
pub fn compute(
    ctx: &Arc<Context>,
    code: &[u32],
    bindings: Vec<vk::DescriptorType>,
) -> Result<Pipeline, BackendError> {
    let (set_layout, layout) = layouts(ctx, &bindings, vk::ShaderStageFlags::COMPUTE)?;
    let module = shader_module(ctx, code)?;
    let stage = vk::PipelineShaderStageCreateInfo::default()
        .stage(vk::ShaderStageFlags::COMPUTE)
        .module(module)
        .name(c"main");
    let created = unsafe {
        ctx.device.create_compute_pipelines(
            vk::PipelineCache::null(),
            &[vk::ComputePipelineCreateInfo::default()
                .stage(stage)
                .layout(layout)],
            None,
        )
    };
    unsafe { ctx.device.destroy_shader_module(module, None) };
    let pipeline = match created {
        Ok(p) => p[0],
        Err((_, e)) => {
            destroy_layouts(ctx, set_layout, layout);
            return Err(vk_error("creating a compute pipeline")(e));
        }
    };
    Ok(Pipeline {
        ctx: Arc::clone(ctx),
        pipeline,
        layout,
        set_layout,
        bindings,
        bind_point: vk::PipelineBindPoint::COMPUTE,
        sbt: None,
    })
}

/// SPIR-V of WGSL kernel `name` (`caustica-shaders`, as the wgpu backend runs it), through
/// naga.
pub fn wgsl_to_spirv(name: &str) -> Result<Vec<u32>, BackendError> {
    if wgsl::VARIANT_KERNELS.contains(&name) {
        // override constants are resolved per variant; Vulkan runs these kernels as
        // ray-tracing pipelines with specialization constants instead
        return Err(BackendError::Unsupported(format!(
            "{name}.wgsl has compiled variants; Vulkan builds it from GLSL"
        )));
    }
    let src = wgsl::module_source(name).map_err(BackendError::Driver)?;
    let module = naga::front::wgsl::parse_str(&src)
        .map_err(|e| BackendError::Driver(format!("{name}.wgsl: {}", e.emit_to_string(&src))))?;
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .map_err(|e| BackendError::Driver(format!("{name}.wgsl does not validate: {e:?}")))?;
    let options = naga::back::spv::Options {
        lang_version: (1, 3),
        // no iteration counter in every loop: every loop of these kernels ends (the
        // argument is at the wgpu backend's `create_pipeline`, which does the same)
        force_loop_bounding: false,
        // kernels that write their workgroup memory before reading it skip the polyfill
        // (invocation 0 storing zeros over all of it before a barrier)
        zero_initialize_workgroup_memory: if wgsl::WORKGROUP_MEMORY_WRITTEN_FIRST.contains(&name) {
            naga::back::spv::ZeroInitializeWorkgroupMemoryMode::None
        } else {
            naga::back::spv::ZeroInitializeWorkgroupMemoryMode::Polyfill
        },
        ..Default::default()
    };
    let pipeline = naga::back::spv::PipelineOptions {
        shader_stage: naga::ShaderStage::Compute,
        entry_point: "main".into(),
    };
    naga::back::spv::write_vec(&module, &info, &options, Some(&pipeline))
        .map_err(|e| BackendError::Driver(format!("{name}: SPIR-V output: {e}")))
}

/// A ray-tracing pipeline of ray generation stage `raygen` (with the shared miss and
/// closest-hit stages); `specialization` sets the raygen's specialization constants
/// (32-bit; GLSL `bool` constants read 0/1), constant id = index (a kernel variant, core's
/// `TraceVariant`).
pub fn ray_tracing(
    ctx: &Arc<Context>,
    raygen: &[u8],
    bindings: Vec<vk::DescriptorType>,
    specialization: &[(&'static str, u32)],
) -> Result<Pipeline, BackendError> {
    let spec_data: Vec<u32> = specialization.iter().map(|(_, v)| *v).collect();
    let spec_entries: Vec<vk::SpecializationMapEntry> = (0..spec_data.len() as u32)
        .map(|i| {
            vk::SpecializationMapEntry::default()
                .constant_id(i)
                .offset(4 * i)
                .size(4)
        })
        .collect();
    let spec_info = vk::SpecializationInfo::default()
        .map_entries(&spec_entries)
        .data(bytemuck::cast_slice(&spec_data));
    let stages_all = vk::ShaderStageFlags::RAYGEN_KHR
        | vk::ShaderStageFlags::MISS_KHR
        | vk::ShaderStageFlags::CLOSEST_HIT_KHR;
    let (set_layout, layout) = layouts(ctx, &bindings, stages_all)?;
    let codes = [
        (vk::ShaderStageFlags::RAYGEN_KHR, words(raygen)?),
        (vk::ShaderStageFlags::MISS_KHR, words(spirv::MISS)?),
        (vk::ShaderStageFlags::MISS_KHR, words(spirv::SHADOW_MISS)?),
        (
            vk::ShaderStageFlags::CLOSEST_HIT_KHR,
            words(spirv::CLOSEST_HIT)?,
        ),
    ];
    let mut modules = Vec::new();
    for (_, c) in &codes {
        match shader_module(ctx, c) {
            Ok(m) => modules.push(m),
            Err(e) => {
                for m in &modules {
                    unsafe { ctx.device.destroy_shader_module(*m, None) };
                }
                destroy_layouts(ctx, set_layout, layout);
                return Err(e);
            }
        }
    }
    let stages: Vec<_> = codes
        .iter()
        .zip(&modules)
        .map(|((s, _), m)| {
            let info = vk::PipelineShaderStageCreateInfo::default()
                .stage(*s)
                .module(*m)
                .name(c"main");
            if *s == vk::ShaderStageFlags::RAYGEN_KHR && !spec_data.is_empty() {
                info.specialization_info(&spec_info)
            } else {
                info
            }
        })
        .collect();
    let general = |i: u32| {
        vk::RayTracingShaderGroupCreateInfoKHR::default()
            .ty(vk::RayTracingShaderGroupTypeKHR::GENERAL)
            .general_shader(i)
            .closest_hit_shader(vk::SHADER_UNUSED_KHR)
            .any_hit_shader(vk::SHADER_UNUSED_KHR)
            .intersection_shader(vk::SHADER_UNUSED_KHR)
    };
    let groups = [
        general(0),
        general(1),
        general(2),
        vk::RayTracingShaderGroupCreateInfoKHR::default()
            .ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
            .general_shader(vk::SHADER_UNUSED_KHR)
            .closest_hit_shader(3)
            .any_hit_shader(vk::SHADER_UNUSED_KHR)
            .intersection_shader(vk::SHADER_UNUSED_KHR),
    ];
    let created = unsafe {
        ctx.rt.create_ray_tracing_pipelines(
            vk::DeferredOperationKHR::null(),
            vk::PipelineCache::null(),
            &[vk::RayTracingPipelineCreateInfoKHR::default()
                .stages(&stages)
                .groups(&groups)
                .max_pipeline_ray_recursion_depth(1)
                .layout(layout)],
            None,
        )
    };
    unsafe {
        for m in &modules {
            ctx.device.destroy_shader_module(*m, None);
        }
    }
    let pipeline = match created {
        Ok(p) => p[0],
        Err((_, e)) => {
            destroy_layouts(ctx, set_layout, layout);
            return Err(vk_error("creating a ray-tracing pipeline")(e));
        }
    };
    let mut p = Pipeline {
        ctx: Arc::clone(ctx),
        pipeline,
        layout,
        set_layout,
        bindings,
        bind_point: vk::PipelineBindPoint::RAY_TRACING_KHR,
        sbt: None,
    };
    p.sbt = Some(binding_table(ctx, pipeline, groups.len() as u32)?);
    Ok(p)
}

/// Shader binding table: each region starts at `shaderGroupBaseAlignment` of the device
/// address; records are `shaderGroupHandleAlignment`-aligned; the ray generation region's
/// size equals its stride (rules of `vkCmdTraceRaysKHR`).
fn binding_table(
    ctx: &Arc<Context>,
    pipeline: vk::Pipeline,
    groups: u32,
) -> Result<Sbt, BackendError> {
    let p = ctx.rt_props;
    let handle = p.handle_size as u64;
    let record = handle.next_multiple_of(p.handle_alignment.max(1) as u64);
    let base = p.base_alignment.max(1) as u64;
    let handles = unsafe {
        ctx.rt.get_ray_tracing_shader_group_handles(
            pipeline,
            0,
            groups,
            (groups as u64 * handle) as usize,
        )
    }
    .map_err(vk_error("reading shader group handles"))?;
    let raygen_size = record.next_multiple_of(base);
    let miss_size = (2 * record).next_multiple_of(base);
    let hit_size = record.next_multiple_of(base);
    let total = base + raygen_size + miss_size + hit_size;
    let buffer = Buffer::new(
        ctx,
        total,
        vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        true,
        "shader binding table",
    )?;
    let address = buffer.address();
    let start = address.next_multiple_of(base);
    let offset = (start - address) as usize;
    let h = |i: usize| &handles[i * handle as usize..(i + 1) * handle as usize];
    buffer.write(offset, h(0));
    let miss_at = offset + raygen_size as usize;
    buffer.write(miss_at, h(1));
    buffer.write(miss_at + record as usize, h(2));
    let hit_at = miss_at + miss_size as usize;
    buffer.write(hit_at, h(3));
    Ok(Sbt {
        raygen: vk::StridedDeviceAddressRegionKHR::default()
            .device_address(start)
            .stride(raygen_size)
            .size(raygen_size),
        miss: vk::StridedDeviceAddressRegionKHR::default()
            .device_address(start + raygen_size)
            .stride(record)
            .size(miss_size),
        hit: vk::StridedDeviceAddressRegionKHR::default()
            .device_address(start + raygen_size + miss_size)
            .stride(record)
            .size(hit_size),
        callable: vk::StridedDeviceAddressRegionKHR::default(),
        _buffer: buffer,
    })
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
            ray_tracing(ctx, raygen, bindings, &[])?
        } else {
            compute(ctx, &wgsl_to_spirv(info.name)?, bindings)?
        };
        p.insert(info.name.to_string(), pipeline);
    }
    let reduce = ash::util::read_spv(&mut std::io::Cursor::new(spirv::REDUCE_COUNTERS))
        .map_err(|e| BackendError::Driver(format!("bad SPIR-V: {e}")))?;
    p.insert("reduce_counters".into(), compute(ctx, &reduce, vec![S, S])?);
    Ok(p)
}

/// Creates the pipeline of every kernel variant `rec` launches that does not exist yet
/// (`trace_photons`: one ray-tracing pipeline per `TraceVariant`, specialization
/// constants in switch order), one creation or destruction at a time (see `caustica_core::backend::driver_lifecycle`).
pub(crate) fn ensure_variants(b: &mut VulkanBackend, rec: &Recording) -> Result<(), BackendError> {
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
        let p = driver_lifecycle(|| {
            ray_tracing(&ctx, raygen, descriptor_types(info), &launch.constants)
        })?;
        b.pipelines.insert(label, p);
    }
    Ok(())
}
