//! Acceleration structures built by the driver (VK_KHR_acceleration_structure) from core's
//! two-level layout (`caustica_core::device::acceleration`): one bottom-level structure
//! per level (the static level over the world-space vertex buffer, stride 32 bytes; each
//! instance over its object-space positions in the node buffer, stride 16 bytes; indices
//! packed from the triangle buffer, an instance's rebased to its own positions) and a
//! top-level structure with one instance per level, transform `world_from_object` from
//! the level's record and custom index its first triangle. The closest-hit stage reports
//! `gl_InstanceCustomIndexEXT + gl_PrimitiveID`: a BLAS holds its level's triangles in the
//! triangle buffer's order, so that is the triangle index the other backends use.
//!
//! Moving instances rewrites the records: [`SceneAccel::record_top_level_rebuild`]
//! rebuilds the TLAS in place over the BLASes it keeps, recorded into the frame's command
//! buffer (no wait, no allocation). A recording's `prepare_scene` step comes here
//! ([`prepare_scene`], [`refit_in_frame`]).

use crate::device::{vk_error, Context};
use crate::memory::Buffer;
use crate::submission::Frame;
use crate::VulkanBackend;
use ash::vk;
use caustica_core::backend::{driver_lifecycle, BackendError};
use caustica_core::device::acceleration::{instance_flags, InstanceRecord};
use caustica_core::device::handle::SceneArgs;
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
        // with the other creations and destructions below the API
        // (caustica_core::backend::driver_lifecycle)
        driver_lifecycle(|| unsafe {
            self.ctx
                .accel
                .destroy_acceleration_structure(self.handle, None)
        });
    }
}

/// What a BLAS was built from: equal keys mean the BLAS can be kept.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BlasKey {
    flags: u32,
    triangle_base: u32,
    triangle_count: u32,
    vertex_base: u32,
    vertex_count: u32,
    position_base: u32,
    /// The level's deformations (core's `InstanceRecord::geometry_version`): a deformed
    /// level's BLAS is rebuilt, the others kept.
    geometry_version: u32,
}

impl BlasKey {
    fn of(r: &InstanceRecord) -> BlasKey {
        BlasKey {
            flags: r.flags,
            triangle_base: r.triangle_base,
            triangle_count: r.triangle_count,
            vertex_base: r.vertex_base,
            vertex_count: r.vertex_count,
            position_base: r.position_base,
            geometry_version: r.geometry_version,
        }
    }
}

/// The scene's structures: the TLAS the shaders trace, the BLASes it instances (by
/// [`BlasKey`]) and the build inputs.
pub struct SceneAccel {
    pub tlas: AccelStructure,
    blases: Vec<(BlasKey, AccelStructure)>,
    _index_buffer: Buffer,
    /// The TLAS's instances (host-visible, mapped) and build scratch, kept for rebuilds
    /// in place ([`SceneAccel::record_top_level_rebuild`]).
    instances: Buffer,
    _scratch: Buffer,
    scratch_address: u64,
    /// Generations of the vertex, triangle and node buffers the BLASes were built from.
    pub sources: [u64; 3],
    /// BLASes this build made (the others were kept from the previous structures).
    pub built_blases: u32,
    /// Triangles the index buffer holds.
    triangle_count: u32,
}

/// Creates an acceleration structure of type `ty` sized for `info` over `primitives`,
/// with its storage and a build scratch buffer (the scratch and its aligned address are
/// returned: a one-off build drops them, the TLAS keeps them for rebuilds in place).
fn allocate(
    ctx: &Arc<Context>,
    ty: vk::AccelerationStructureTypeKHR,
    info: &vk::AccelerationStructureBuildGeometryInfoKHR<'_>,
    primitives: u32,
    what: &str,
) -> Result<(AccelStructure, Buffer, u64), BackendError> {
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    unsafe {
        ctx.accel.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            info,
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
    Ok((structure, scratch, scratch_address))
}

/// Builds an acceleration structure of type `ty` over `geometry` once (`run` records,
/// submits and waits); its scratch is dropped.
fn build(
    ctx: &Arc<Context>,
    run: SubmitFn<'_>,
    ty: vk::AccelerationStructureTypeKHR,
    geometry: vk::AccelerationStructureGeometryKHR<'_>,
    primitives: u32,
    what: &str,
) -> Result<AccelStructure, BackendError> {
    let geometries = [geometry];
    let info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(ty)
        .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(&geometries);
    let (structure, scratch, scratch_address) = allocate(ctx, ty, &info, primitives, what)?;
    let info = info
        .dst_acceleration_structure(structure.handle)
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

/// The device buffers a scene's structures are built from.
pub struct SceneSources<'a> {
    /// World-space vertices (`GpuVertex`, 32 bytes).
    pub vertices: &'a Buffer,
    /// Their count.
    pub vertex_count: u32,
    /// The node buffer (instances' object-space positions inside).
    pub nodes: &'a Buffer,
    /// Generations of vertices, triangles and nodes.
    pub generations: [u64; 3],
}

/// Largest triangle index a TLAS instance's 24-bit custom index can carry.
const MAX_CUSTOM_INDEX: u32 = (1 << 24) - 1;

impl SceneAccel {
    /// Builds every level's BLAS and the TLAS; `run` records a closure into a command
    /// buffer, submits it and waits. The BLASes of `previous` (the scene's structures
    /// until now, built from the same buffers) whose levels are unchanged are kept: after
    /// a deformation only the deformed level's BLAS is built.
    pub fn build(
        ctx: &Arc<Context>,
        run: SubmitFn<'_>,
        src: &SceneSources<'_>,
        triangle_count: u32,
        fetch: &dyn Fn(u32, u32) -> Result<Vec<GpuTriangle>, BackendError>,
        records: &[InstanceRecord],
        previous: Option<SceneAccel>,
    ) -> Result<SceneAccel, BackendError> {
        let input = vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS;
        // one index buffer in the triangle buffer's order (records come in TLAS leaf
        // order; each fills its own range, an instance's indices rebased to its positions);
        // kept from `previous` (host-visible) with the kept levels' ranges as they are
        let (index_buffer, mut kept) = match previous {
            Some(p) if p.sources == src.generations && p.triangle_count == triangle_count => {
                (p._index_buffer, p.blases)
            }
            _ => (
                Buffer::new(
                    ctx,
                    (triangle_count.max(1) as u64) * 12,
                    input,
                    true,
                    "triangle indices",
                )?,
                Vec::new(),
            ),
        };
        let building: Vec<&InstanceRecord> = records
            .iter()
            .filter(|r| !kept.iter().any(|(k, _)| *k == BlasKey::of(r)))
            .collect();
        // a first build reads every triangle back at once, a deformation its level's only
        let all = if kept.is_empty() {
            Some(fetch(0, triangle_count)?)
        } else {
            None
        };
        for r in &building {
            let fetched;
            let tris = match &all {
                Some(t) => t
                    .get(r.triangle_base as usize..(r.triangle_base + r.triangle_count) as usize)
                    .ok_or_else(|| {
                        BackendError::BadArgument(
                            "an instance record names triangles past the buffer".into(),
                        )
                    })?,
                None => {
                    fetched = fetch(r.triangle_base, r.triangle_count)?;
                    &fetched[..]
                }
            };
            let identity = r.flags & instance_flags::IDENTITY != 0;
            let mut indices: Vec<u32> = Vec::with_capacity(tris.len() * 3);
            for t in tris {
                for i in t.indices {
                    let local = if identity {
                        i
                    } else {
                        i.checked_sub(r.vertex_base)
                            .filter(|l| *l < r.vertex_count)
                            .ok_or_else(|| {
                                BackendError::BadArgument(
                                    "an instance's triangle indexes outside its vertices".into(),
                                )
                            })?
                    };
                    indices.push(local);
                }
            }
            index_buffer.write(
                r.triangle_base as usize * 12,
                bytemuck::cast_slice(&indices),
            );
        }
        let mut blases = Vec::with_capacity(records.len());
        let mut built_blases = 0;
        for r in records {
            if let Some(at) = kept.iter().position(|(k, _)| *k == BlasKey::of(r)) {
                blases.push(kept.swap_remove(at));
                continue;
            }
            let identity = r.flags & instance_flags::IDENTITY != 0;
            let (address, stride, max_vertex) = if identity {
                (
                    src.vertices.address(),
                    std::mem::size_of::<GpuVertex>() as u64,
                    src.vertex_count.saturating_sub(1),
                )
            } else {
                (
                    src.nodes.address() + r.position_base as u64 * 16,
                    16,
                    r.vertex_count.saturating_sub(1),
                )
            };
            let triangles_data = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
                .vertex_format(vk::Format::R32G32B32_SFLOAT)
                .vertex_data(vk::DeviceOrHostAddressConstKHR {
                    device_address: address,
                })
                .vertex_stride(stride)
                // the highest vertex index, not the count
                .max_vertex(max_vertex)
                .index_type(vk::IndexType::UINT32)
                .index_data(vk::DeviceOrHostAddressConstKHR {
                    device_address: index_buffer.address() + r.triangle_base as u64 * 12,
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
                r.triangle_count,
                "bottom-level acceleration structure",
            )?;
            blases.push((BlasKey::of(r), blas));
            built_blases += 1;
        }
        let instances = Buffer::new(
            ctx,
            (records.len().max(1) * std::mem::size_of::<vk::AccelerationStructureInstanceKHR>())
                as u64,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR
                | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            true,
            "TLAS instances",
        )?;
        Self::write_instances(ctx, &instances, &blases, records)?;
        let (geometry, count) = Self::top_level_geometry(&instances, records);
        let geometries = [geometry];
        let info = Self::top_level_info(&geometries);
        let (tlas, scratch, scratch_address) = allocate(
            ctx,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            &info,
            count,
            "top-level acceleration structure",
        )?;
        let accel = SceneAccel {
            tlas,
            blases,
            _index_buffer: index_buffer,
            instances,
            _scratch: scratch,
            scratch_address,
            sources: src.generations,
            built_blases,
            triangle_count,
        };
        run(&|cmd| accel.record_build(cmd, records.len() as u32))?;
        Ok(accel)
    }

    fn top_level_geometry<'a>(
        instances: &Buffer,
        records: &[InstanceRecord],
    ) -> (vk::AccelerationStructureGeometryKHR<'a>, u32) {
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
        (geometry, records.len() as u32)
    }

    fn top_level_info<'a>(
        geometries: &'a [vk::AccelerationStructureGeometryKHR<'a>],
    ) -> vk::AccelerationStructureBuildGeometryInfoKHR<'a> {
        vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(vk::AccelerationStructureTypeKHR::TOP_LEVEL)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(geometries)
    }

    /// Records the TLAS build over the instance buffer into `cmd`, between barriers: the
    /// traces recorded before it read the old TLAS, those after it the new one.
    pub fn record_build(&self, cmd: vk::CommandBuffer, count: u32) {
        let ctx = &self.tlas.ctx;
        let (geometry, _) = Self::top_level_geometry(&self.instances, &[]);
        let geometries = [geometry];
        let info = Self::top_level_info(&geometries)
            .dst_acceleration_structure(self.tlas.handle)
            .scratch_data(vk::DeviceOrHostAddressKHR {
                device_address: self.scratch_address,
            });
        let range = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count)];
        let all = vk::MemoryBarrier::default()
            .src_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE)
            .dst_access_mask(vk::AccessFlags::MEMORY_READ | vk::AccessFlags::MEMORY_WRITE);
        unsafe {
            let d = &ctx.device;
            d.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::DependencyFlags::empty(),
                &[all],
                &[],
                &[],
            );
            ctx.accel.cmd_build_acceleration_structures(
                cmd,
                std::slice::from_ref(&info),
                &[&range],
            );
            d.cmd_pipeline_barrier(
                cmd,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::PipelineStageFlags::ALL_COMMANDS,
                vk::DependencyFlags::empty(),
                &[all],
                &[],
                &[],
            );
        }
    }

    /// The TLAS rebuilt in place for moved instances, recorded into `cmd` (no submit, no
    /// wait): `records` (the same levels, new transforms) written into the mapped instance
    /// buffer, then a build into the same storage with the kept scratch. The device must
    /// not be running an earlier build of this TLAS (every `execute` waits for its work,
    /// and core records one `prepare_scene` per recording).
    pub fn record_top_level_rebuild(
        &mut self,
        cmd: vk::CommandBuffer,
        records: &[InstanceRecord],
    ) -> Result<(), BackendError> {
        self.restage(records)?;
        self.record_build(cmd, records.len() as u32);
        Ok(())
    }

    /// Writes `records`' instances into the mapped instance buffer (same levels, new
    /// transforms) for the next [`SceneAccel::record_build`].
    pub fn restage(&mut self, records: &[InstanceRecord]) -> Result<(), BackendError> {
        let ctx = Arc::clone(&self.tlas.ctx);
        Self::write_instances(&ctx, &self.instances, &self.blases, records)
    }

    /// Whether the BLASes can serve `records` built from buffers of `generations`.
    pub fn keeps_bottom_levels(&self, records: &[InstanceRecord], generations: [u64; 3]) -> bool {
        self.sources == generations
            && self.blases.len() == records.len()
            && records
                .iter()
                .all(|r| self.blases.iter().any(|(k, _)| *k == BlasKey::of(r)))
    }

    /// Writes one TLAS instance per record into the mapped `buffer`: the level's BLAS,
    /// its `world_from_object`, and its first triangle as the custom index.
    fn write_instances(
        ctx: &Arc<Context>,
        buffer: &Buffer,
        blases: &[(BlasKey, AccelStructure)],
        records: &[InstanceRecord],
    ) -> Result<(), BackendError> {
        let mut instances = Vec::with_capacity(records.len());
        for r in records {
            let blas = &blases
                .iter()
                .find(|(k, _)| *k == BlasKey::of(r))
                .ok_or_else(|| BackendError::BadArgument("a level without its BLAS".into()))?
                .1;
            if r.triangle_base > MAX_CUSTOM_INDEX {
                return Err(BackendError::Unsupported(format!(
                    "an instance's first triangle is {}, past the {} a Vulkan instance index \
                     can carry (24 bits)",
                    r.triangle_base, MAX_CUSTOM_INDEX
                )));
            }
            let address = unsafe {
                ctx.accel.get_acceleration_structure_device_address(
                    &vk::AccelerationStructureDeviceAddressInfoKHR::default()
                        .acceleration_structure(blas.handle),
                )
            };
            let m = r.world_from_object;
            instances.push(vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR {
                    matrix: [
                        m[0][0], m[0][1], m[0][2], m[0][3], m[1][0], m[1][1], m[1][2], m[1][3],
                        m[2][0], m[2][1], m[2][2], m[2][3],
                    ],
                },
                instance_custom_index_and_mask: vk::Packed24_8::new(r.triangle_base, 0xff),
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    // two-sided, as the other backends' triangle test
                    vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw() as u8,
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                    device_handle: address,
                },
            });
        }
        // SAFETY: AccelerationStructureInstanceKHR is a plain repr(C) struct of 64 bytes.
        let bytes = unsafe {
            std::slice::from_raw_parts(
                instances.as_ptr() as *const u8,
                std::mem::size_of_val(instances.as_slice()),
            )
        };
        buffer.write(0, bytes);
        Ok(())
    }
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
pub(crate) fn refit_in_frame(
    b: &mut VulkanBackend,
    frame: &mut Frame,
    scene: &SceneArgs,
) -> Result<bool, BackendError> {
    let Some(records) = written_records(b, scene) else {
        return Ok(false);
    };
    let generations = [
        b.buffers.get(scene.vertices.id)?.generation,
        b.buffers.get(scene.triangles.id)?.generation,
        b.buffers.get(scene.bvh_nodes.id)?.generation,
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
pub(crate) fn prepare_scene(b: &mut VulkanBackend, scene: &SceneArgs) -> Result<(), BackendError> {
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
    let nodes_buf = b.buffers.get(scene.bvh_nodes.id)?;
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
        b.buffers.get(scene.vertices.id)?.generation,
        b.buffers.get(scene.triangles.id)?.generation,
        b.buffers.get(scene.bvh_nodes.id)?.generation,
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
    let triangle_buffer = b.buffers.get(scene.triangles.id)?.buffer.buffer;
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
        vertices: &shared.buffers.get(scene.vertices.id)?.buffer,
        vertex_count,
        nodes: &shared.buffers.get(scene.bvh_nodes.id)?.buffer,
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
