//! Acceleration structures built by the driver (VK_KHR_acceleration_structure): one
//! bottom-level structure over the scene's triangles (positions read in place from the
//! vertex buffer, stride 32 bytes; indices packed from the triangle buffer) and one
//! top-level instance of it. The BLAS primitive order is the triangle buffer's order, so
//! `gl_PrimitiveID` is the triangle index the other backends use.

use crate::context::{vk_error, Context};
use crate::memory::Buffer;
use ash::vk;
use caustica_core::backend::BackendError;
use caustica_core::device::layout::{GpuTriangle, GpuVertex};
use std::sync::Arc;

/// Records a closure into a fresh command buffer, submits it and waits.
pub type SubmitFn<'a> = &'a dyn Fn(&dyn Fn(vk::CommandBuffer)) -> Result<(), BackendError>;

/// A built acceleration structure with its storage.
pub struct AccelStructure {
    ctx: Arc<Context>,
    pub handle: vk::AccelerationStructureKHR,
    _storage: Buffer,
}

impl Drop for AccelStructure {
    fn drop(&mut self) {
        unsafe {
            self.ctx
                .accel
                .destroy_acceleration_structure(self.handle, None)
        };
    }
}

/// The scene's structures: the TLAS the shaders trace, the BLAS it instances, and the
/// build inputs the BLAS keeps referring to.
pub struct SceneAccel {
    pub tlas: AccelStructure,
    _blas: AccelStructure,
    _inputs: Vec<Buffer>,
}

fn build(
    ctx: &Arc<Context>,
    run: SubmitFn<'_>,
    ty: vk::AccelerationStructureTypeKHR,
    geometry: vk::AccelerationStructureGeometryKHR<'_>,
    primitives: u32,
    what: &str,
) -> Result<AccelStructure, BackendError> {
    let geometries = [geometry];
    let mut info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(ty)
        .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(&geometries);
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    unsafe {
        ctx.accel.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &info,
            &[primitives],
            &mut sizes,
        )
    };
    let storage = Buffer::new(
        ctx,
        sizes.acceleration_structure_size,
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR,
        false,
        what,
    )?;
    let handle = unsafe {
        ctx.accel.create_acceleration_structure(
            &vk::AccelerationStructureCreateInfoKHR::default()
                .buffer(storage.buffer)
                .size(sizes.acceleration_structure_size)
                .ty(ty),
            None,
        )
    }
    .map_err(vk_error("creating an acceleration structure"))?;
    let structure = AccelStructure {
        ctx: Arc::clone(ctx),
        handle,
        _storage: storage,
    };
    let align = ctx.rt_props.scratch_alignment.max(1) as u64;
    let scratch = Buffer::new(
        ctx,
        sizes.build_scratch_size + align,
        vk::BufferUsageFlags::STORAGE_BUFFER,
        false,
        "acceleration structure scratch",
    )?;
    let scratch_address = scratch.address().next_multiple_of(align);
    info = info
        .dst_acceleration_structure(handle)
        .scratch_data(vk::DeviceOrHostAddressKHR {
            device_address: scratch_address,
        });
    let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(primitives)];
    run(&|cmd| unsafe {
        ctx.accel
            .cmd_build_acceleration_structures(cmd, std::slice::from_ref(&info), &[&range])
    })?;
    drop(scratch);
    Ok(structure)
}

impl SceneAccel {
    /// Builds the BLAS and TLAS over the device buffers `vertices` and the host copy of
    /// the triangles; `run` records a closure into a command buffer, submits it and waits.
    pub fn build(
        ctx: &Arc<Context>,
        run: SubmitFn<'_>,
        vertices: &Buffer,
        vertex_count: u32,
        triangles: &[GpuTriangle],
    ) -> Result<SceneAccel, BackendError> {
        let indices: Vec<u32> = triangles.iter().flat_map(|t| t.indices).collect();
        let input = vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        let index_buffer = Buffer::with_data(
            ctx,
            bytemuck::cast_slice(if indices.is_empty() {
                &[0u32; 3][..]
            } else {
                &indices
            }),
            input,
            "triangle indices",
        )?;
        let triangles_data = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR {
                device_address: vertices.address(),
            })
            .vertex_stride(std::mem::size_of::<GpuVertex>() as u64)
            // the highest vertex index, not the count
            .max_vertex(vertex_count.saturating_sub(1))
            .index_type(vk::IndexType::UINT32)
            .index_data(vk::DeviceOrHostAddressConstKHR {
                device_address: index_buffer.address(),
            });
        let geometry = vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
            .flags(vk::GeometryFlagsKHR::OPAQUE)
            .geometry(vk::AccelerationStructureGeometryDataKHR {
                triangles: triangles_data,
            });
        let blas = build(
            ctx,
            run,
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            geometry,
            triangles.len() as u32,
            "bottom-level acceleration structure",
        )?;
        let blas_address = unsafe {
            ctx.accel.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default()
                    .acceleration_structure(blas.handle),
            )
        };
        let instance = vk::AccelerationStructureInstanceKHR {
            transform: vk::TransformMatrixKHR {
                matrix: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            },
            instance_custom_index_and_mask: vk::Packed24_8::new(0, 0xff),
            instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                0,
                // two-sided, as the other backends' triangle test
                vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
            ),
            acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                device_handle: blas_address,
            },
        };
        // SAFETY: AccelerationStructureInstanceKHR is a plain repr(C) struct of 64 bytes.
        let bytes = unsafe {
            std::slice::from_raw_parts(
                &instance as *const _ as *const u8,
                std::mem::size_of::<vk::AccelerationStructureInstanceKHR>(),
            )
        };
        let instances = Buffer::with_data(ctx, bytes, input, "TLAS instances")?;
        let geometry = vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .flags(vk::GeometryFlagsKHR::OPAQUE)
            .geometry(vk::AccelerationStructureGeometryDataKHR {
                instances: vk::AccelerationStructureGeometryInstancesDataKHR::default().data(
                    vk::DeviceOrHostAddressConstKHR {
                        device_address: instances.address(),
                    },
                ),
            });
        let tlas = build(
            ctx,
            run,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            geometry,
            u32::from(!triangles.is_empty()),
            "top-level acceleration structure",
        )?;
        Ok(SceneAccel {
            tlas,
            _blas: blas,
            _inputs: vec![index_buffer, instances],
        })
    }
}
