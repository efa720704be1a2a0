//! Acceleration structures (`VK_KHR_acceleration_structure`): one BLAS per mesh, one TLAS over instances.
//! Builds are recorded into a command buffer and waited for; the scratch buffer is sized and aligned per the
//! device's `minAccelerationStructureScratchOffsetAlignment`.
use super::commands::{memory_barrier, submit_and_wait, Access};
use super::device::Device;
use super::memory::{Buffer, MemoryLocation};
use anyhow::{bail, Context as _, Result};
use ash::vk;
use glam::Mat4;
use std::sync::Arc;

/// Usage for buffers that feed an acceleration-structure build (vertices, indices, instances).
pub const BUILD_INPUT_USAGE: vk::BufferUsageFlags = vk::BufferUsageFlags::from_raw(
    vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR.as_raw()
        | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
);

/// An acceleration structure with the buffer that stores it.
pub struct AccelerationStructure {
    pub raw: vk::AccelerationStructureKHR,
    pub address: vk::DeviceAddress,
    pub name: String,
    _storage: Buffer,
    device: Arc<Device>,
}

impl Drop for AccelerationStructure {
    fn drop(&mut self) {
        unsafe { self.device.accel.destroy_acceleration_structure(self.raw, None) };
    }
}

/// Triangles for a BLAS: `f32x3` positions at `vertex_stride` and `u32` indices, both by device address.
#[derive(Debug, Clone, Copy)]
pub struct TriangleGeometry {
    pub vertex_address: vk::DeviceAddress,
    pub vertex_stride: u64,
    pub vertex_count: u32,
    pub index_address: vk::DeviceAddress,
    pub triangle_count: u32,
    pub opaque: bool,
}

/// One TLAS instance: a BLAS placed by `transform`, with the id shaders read as `instanceCustomIndex`.
#[derive(Clone, Copy)]
pub struct TlasInstance<'a> {
    pub blas: &'a AccelerationStructure,
    pub transform: Mat4,
    pub custom_index: u32,
    pub mask: u8,
}

/// `VkAccelerationStructureInstanceKHR` as plain bytes (ash's own has unions and bitfields).
#[repr(C)]
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
struct InstanceRecord {
    /// 3x4 row-major (`VkTransformMatrixKHR`); glam is column-major, so this is the transpose's first 12.
    transform: [f32; 12],
    custom_index_and_mask: u32,
    sbt_offset_and_flags: u32,
    blas_address: u64,
}

fn instance_record(instance: &TlasInstance<'_>) -> Result<InstanceRecord> {
    if instance.custom_index >= 1 << 24 {
        bail!("TLAS instance custom index {} does not fit in 24 bits", instance.custom_index);
    }
    let rows = instance.transform.transpose().to_cols_array();
    let mut transform = [0.0; 12];
    transform.copy_from_slice(&rows[..12]);
    let flags = vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE.as_raw();
    Ok(InstanceRecord {
        transform,
        custom_index_and_mask: instance.custom_index | (u32::from(instance.mask) << 24),
        sbt_offset_and_flags: flags << 24,
        blas_address: instance.blas.address,
    })
}

impl AccelerationStructure {
    /// Builds a bottom-level structure over triangle geometries and waits for it.
    pub fn build_blas(device: &Arc<Device>, name: &str, geometries: &[TriangleGeometry]) -> Result<Self> {
        if geometries.is_empty() {
            bail!("BLAS \"{name}\": no geometry");
        }
        let raw_geometries: Vec<vk::AccelerationStructureGeometryKHR> = geometries.iter().map(triangles).collect();
        let counts: Vec<u32> = geometries.iter().map(|g| g.triangle_count).collect();
        Self::build(device, name, vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, &raw_geometries, &counts)
    }

    /// Builds a top-level structure over instances and waits for it.
    pub fn build_tlas(device: &Arc<Device>, name: &str, instances: &[TlasInstance<'_>]) -> Result<Self> {
        let records = instances.iter().map(instance_record).collect::<Result<Vec<_>>>()?;
        // An empty scene still gets a valid (empty) TLAS: one dummy record keeps the buffer non-empty.
        let bytes: Vec<InstanceRecord> =
            if records.is_empty() { vec![bytemuck::Zeroable::zeroed()] } else { records.clone() };
        // Instance data must be 16-byte aligned (VUID-vkCmdBuildAccelerationStructuresKHR-pInfos-03715).
        let instance_buffer = Buffer::with_data(device, &format!("{name} instances"), &bytes, BUILD_INPUT_USAGE, 16)?;
        let geometry = [instances_geometry(instance_buffer.address)];
        Self::build(device, name, vk::AccelerationStructureTypeKHR::TOP_LEVEL, &geometry, &[records.len() as u32])
    }

    fn build(
        device: &Arc<Device>,
        name: &str,
        kind: vk::AccelerationStructureTypeKHR,
        geometries: &[vk::AccelerationStructureGeometryKHR<'_>],
        primitive_counts: &[u32],
    ) -> Result<Self> {
        let sizes = build_sizes(device, kind, geometries, primitive_counts);
        let structure = Self::allocate(device, name, kind, sizes.acceleration_structure_size)?;
        let scratch = scratch_buffer(device, name, sizes.build_scratch_size)?;
        let build_info = build_info(kind, geometries)
            .dst_acceleration_structure(structure.raw)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: scratch.address });
        let ranges: Vec<vk::AccelerationStructureBuildRangeInfoKHR> = primitive_counts
            .iter()
            .map(|&count| vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count))
            .collect();
        submit_and_wait(device, &format!("build {name}"), |cmd| {
            unsafe { device.accel.cmd_build_acceleration_structures(cmd, &[build_info], &[&ranges]) };
            // Make the build visible to later builds and to ray queries in shaders.
            memory_barrier(
                device,
                cmd,
                Access::AS_BUILD_WRITE,
                Access {
                    stage: Access::AS_BUILD_READ.stage | Access::AS_COMPUTE_READ.stage,
                    access: vk::AccessFlags2::ACCELERATION_STRUCTURE_READ_KHR,
                },
            );
            Ok(())
        })?;
        drop(scratch);
        Ok(structure)
    }

    /// An unbuilt structure of `kind` with `size` bytes of storage, named both ways.
    fn allocate(device: &Arc<Device>, name: &str, kind: vk::AccelerationStructureTypeKHR, size: u64) -> Result<Self> {
        let storage = Buffer::new(
            device,
            &format!("{name} storage"),
            size,
            vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
            MemoryLocation::GpuOnly,
            256, // VUID-VkAccelerationStructureCreateInfoKHR-offset-03734: offset multiple of 256
        )?;
        let create_info = vk::AccelerationStructureCreateInfoKHR::default().buffer(storage.raw).size(size).ty(kind);
        let raw = unsafe { device.accel.create_acceleration_structure(&create_info, None) }
            .with_context(|| format!("vkCreateAccelerationStructureKHR \"{name}\""))?;
        device.set_name(raw, name);
        let address = unsafe {
            device.accel.get_acceleration_structure_device_address(
                &vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw),
            )
        };
        Ok(Self { raw, address, name: name.to_owned(), _storage: storage, device: device.clone() })
    }
}

/// One triangle geometry as a build reads it.
fn triangles(g: &TriangleGeometry) -> vk::AccelerationStructureGeometryKHR<'static> {
    let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
        .vertex_format(vk::Format::R32G32B32_SFLOAT)
        .vertex_data(vk::DeviceOrHostAddressConstKHR { device_address: g.vertex_address })
        .vertex_stride(g.vertex_stride)
        .max_vertex(g.vertex_count.saturating_sub(1))
        .index_type(vk::IndexType::UINT32)
        .index_data(vk::DeviceOrHostAddressConstKHR { device_address: g.index_address });
    vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
        .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
        .flags(if g.opaque { vk::GeometryFlagsKHR::OPAQUE } else { vk::GeometryFlagsKHR::empty() })
}

/// What every build here asks for: a full build, tuned for tracing.
fn build_info<'a>(
    kind: vk::AccelerationStructureTypeKHR,
    geometries: &'a [vk::AccelerationStructureGeometryKHR<'a>],
) -> vk::AccelerationStructureBuildGeometryInfoKHR<'a> {
    vk::AccelerationStructureBuildGeometryInfoKHR::default()
        .ty(kind)
        .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
        .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
        .geometries(geometries)
}

fn build_sizes(
    device: &Device,
    kind: vk::AccelerationStructureTypeKHR,
    geometries: &[vk::AccelerationStructureGeometryKHR<'_>],
    primitive_counts: &[u32],
) -> vk::AccelerationStructureBuildSizesInfoKHR<'static> {
    let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
    unsafe {
        device.accel.get_acceleration_structure_build_sizes(
            vk::AccelerationStructureBuildTypeKHR::DEVICE,
            &build_info(kind, geometries),
            primitive_counts,
            &mut sizes,
        )
    };
    sizes
}

/// Build scratch, aligned per the device's `minAccelerationStructureScratchOffsetAlignment`.
fn scratch_buffer(device: &Arc<Device>, name: &str, size: u64) -> Result<Buffer> {
    Buffer::new(
        device,
        &format!("{name} scratch"),
        size.max(1),
        vk::BufferUsageFlags::STORAGE_BUFFER | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS,
        MemoryLocation::GpuOnly,
        device.limits.min_scratch_offset_alignment,
    )
}

/// One geometry of tightly packed instance records at `address`.
fn instances_geometry(address: vk::DeviceAddress) -> vk::AccelerationStructureGeometryKHR<'static> {
    let instances = vk::AccelerationStructureGeometryInstancesDataKHR::default()
        .array_of_pointers(false)
        .data(vk::DeviceOrHostAddressConstKHR { device_address: address });
    vk::AccelerationStructureGeometryKHR::default()
        .geometry_type(vk::GeometryTypeKHR::INSTANCES)
        .geometry(vk::AccelerationStructureGeometryDataKHR { instances })
}

/// A TLAS rebuilt many times over the same instances at different transforms (one rebuild per sample time in
/// the sample loop): its storage and scratch are allocated once for `instance_count` instances, and a
/// host-visible instance buffer holds `slots` sets of records, so several builds can be recorded into one
/// submission, each from its own slot.
pub struct DynamicTlas {
    pub structure: AccelerationStructure,
    scratch: Buffer,
    instances: Buffer,
    instance_count: u32,
    slots: u32,
    device: Arc<Device>,
}

const INSTANCE_RECORD_SIZE: u64 = std::mem::size_of::<InstanceRecord>() as u64;

impl DynamicTlas {
    pub fn new(device: &Arc<Device>, name: &str, instance_count: u32, slots: u32) -> Result<Self> {
        let slots = slots.max(1);
        let records = u64::from(instance_count.max(1)) * u64::from(slots);
        // Instance data must be 16-byte aligned (VUID-vkCmdBuildAccelerationStructuresKHR-pInfos-03715).
        let instances = Buffer::new(
            device,
            &format!("{name} instances"),
            records * INSTANCE_RECORD_SIZE,
            BUILD_INPUT_USAGE,
            MemoryLocation::CpuToGpu,
            16,
        )?;
        let kind = vk::AccelerationStructureTypeKHR::TOP_LEVEL;
        let sizes = build_sizes(device, kind, &[instances_geometry(instances.address)], &[instance_count]);
        let structure = AccelerationStructure::allocate(device, name, kind, sizes.acceleration_structure_size)?;
        let scratch = scratch_buffer(device, name, sizes.build_scratch_size)?;
        Ok(Self { structure, scratch, instances, instance_count, slots, device: device.clone() })
    }

    /// Writes the instances of `slot` (the GPU must not be reading that slot).
    pub fn write_slot(&mut self, slot: u32, instances: &[TlasInstance<'_>]) -> Result<()> {
        if slot >= self.slots || instances.len() != self.instance_count as usize {
            bail!(
                "TLAS \"{}\": slot {slot} with {} instances (has {} slots of {})",
                self.structure.name,
                instances.len(),
                self.slots,
                self.instance_count
            );
        }
        let records = instances.iter().map(instance_record).collect::<Result<Vec<_>>>()?;
        let offset = u64::from(slot) * u64::from(self.instance_count.max(1)) * INSTANCE_RECORD_SIZE;
        self.instances.write(offset, bytemuck::cast_slice(&records))
    }

    /// Records a full rebuild from `slot`'s instances; the caller orders it after earlier builds and readers of
    /// the TLAS and before its next readers (`record_rebuild`).
    pub fn record_build(&self, cmd: vk::CommandBuffer, slot: u32) {
        let offset = u64::from(slot) * u64::from(self.instance_count.max(1)) * INSTANCE_RECORD_SIZE;
        let geometry = [instances_geometry(self.instances.address + offset)];
        let build_info = build_info(vk::AccelerationStructureTypeKHR::TOP_LEVEL, &geometry)
            .dst_acceleration_structure(self.structure.raw)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: self.scratch.address });
        let ranges = [vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(self.instance_count)];
        record_rebuild(&self.device, cmd, build_info, &ranges);
    }
}

/// Records a build into `build_info`'s destination. Earlier builds and ray queries may still use the structure
/// and its scratch, and later ones read the result: the caller's frame-graph pass orders it both ways, by
/// declaring that it writes the structures (`vk::frame_graph`).
fn record_rebuild(
    device: &Device,
    cmd: vk::CommandBuffer,
    build_info: vk::AccelerationStructureBuildGeometryInfoKHR<'_>,
    ranges: &[vk::AccelerationStructureBuildRangeInfoKHR],
) {
    unsafe { device.accel.cmd_build_acceleration_structures(cmd, &[build_info], &[ranges]) };
}

/// A BLAS rebuilt many times over geometry of the same shape whose vertices move (a deformed instance, once per
/// sample): storage and scratch are allocated once, for the first geometries' counts; each rebuild may read its
/// vertices from another address.
pub struct DynamicBlas {
    pub structure: AccelerationStructure,
    scratch: Buffer,
    counts: Vec<u32>,
    device: Arc<Device>,
}

impl DynamicBlas {
    pub fn new(device: &Arc<Device>, name: &str, geometries: &[TriangleGeometry]) -> Result<Self> {
        if geometries.is_empty() {
            bail!("BLAS \"{name}\": no geometry");
        }
        let raw: Vec<vk::AccelerationStructureGeometryKHR> = geometries.iter().map(triangles).collect();
        let counts: Vec<u32> = geometries.iter().map(|g| g.triangle_count).collect();
        let kind = vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL;
        let sizes = build_sizes(device, kind, &raw, &counts);
        let structure = AccelerationStructure::allocate(device, name, kind, sizes.acceleration_structure_size)?;
        let scratch = scratch_buffer(device, name, sizes.build_scratch_size)?;
        Ok(Self { structure, scratch, counts, device: device.clone() })
    }

    /// Records a full rebuild from `geometries` (the same triangle counts as at creation). The caller orders it
    /// after the writes of the vertices it reads, and against the structure's other uses (`record_rebuild`).
    pub fn record_build(&self, cmd: vk::CommandBuffer, geometries: &[TriangleGeometry]) {
        let raw: Vec<vk::AccelerationStructureGeometryKHR> = geometries.iter().map(triangles).collect();
        debug_assert_eq!(geometries.iter().map(|g| g.triangle_count).collect::<Vec<_>>(), self.counts);
        let build_info = build_info(vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL, &raw)
            .dst_acceleration_structure(self.structure.raw)
            .scratch_data(vk::DeviceOrHostAddressKHR { device_address: self.scratch.address });
        let ranges: Vec<vk::AccelerationStructureBuildRangeInfoKHR> = self
            .counts
            .iter()
            .map(|&count| vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(count))
            .collect();
        record_rebuild(&self.device, cmd, build_info, &ranges);
    }
}
