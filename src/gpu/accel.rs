//! Acceleration structures (`VK_KHR_acceleration_structure`) for the shaders' ray queries: a
//! bottom-level structure per mesh (built once, kept with the mesh) and a top-level one per draw
//! over the objects. Built on the device, in a submit of their own (lavapipe builds in command
//! buffers only); the work that reads one starts with a barrier from
//! `Access::AccelerationStructureBuild` (earlier submits are in its first scope).

use super::buffer::{Buffer, BufferDesc, BufferUsage};
use super::conv::Access;
use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use super::GpuContext;
use ash::vk;
use std::sync::Arc;

/// Vulkan requires `minAccelerationStructureScratchOffsetAlignment` ≤ 256 on every device, so a
/// scratch address rounded up to 256 is always aligned.
const SCRATCH_ALIGNMENT: u64 = 256;

/// One built acceleration structure and the buffer that holds it; destroyed on drop.
pub struct AccelerationStructure {
    pub(crate) raw: vk::AccelerationStructureKHR,
    /// What `VkAccelerationStructureInstanceKHR` names a bottom-level structure by.
    address: u64,
    buffer: Buffer,
    /// Device time of the build (timestamps around it), in seconds.
    build_seconds: f64,
    shared: Arc<DeviceShared>,
}

impl AccelerationStructure {
    /// Bytes of device memory the structure itself holds (scratch memory is freed after the
    /// build).
    pub fn byte_size(&self) -> u64 {
        self.buffer.size()
    }

    /// Device time its build took, in seconds.
    pub fn build_seconds(&self) -> f64 {
        self.build_seconds
    }
}

impl Drop for AccelerationStructure {
    fn drop(&mut self) {
        if let Some(loader) = &self.shared.acceleration {
            // SAFETY: every submit that used the structure has completed (each waits on its
            // fence); the buffer is freed after the structure that lives in it.
            unsafe { loader.destroy_acceleration_structure(self.raw, None) };
        }
    }
}

/// A triangle mesh on the device as a bottom-level build reads it: positions as the first three
/// f32 of each `vertex_stride`-byte vertex, u32 indices, three per triangle. Both buffers made
/// with [`BufferUsage::ACCELERATION_INPUT`].
pub struct TriangleGeometry<'a> {
    pub vertices: &'a Buffer,
    pub vertex_count: u32,
    pub vertex_stride: u32,
    pub indices: &'a Buffer,
    pub triangle_count: u32,
}

/// One instance of a top-level structure: a bottom-level structure in world space (identity
/// transform: shikki's meshes are already placed), the number the shaders read back as
/// `rayQueryGetIntersectionInstanceCustomIndexEXT` (24 bits) and its mask (a ray meets it when
/// its own mask shares a bit).
pub struct Instance<'a> {
    pub geometry: &'a AccelerationStructure,
    pub custom_index: u32,
    pub mask: u8,
}

impl GpuContext {
    /// Builds the bottom-level structure of `geometry`: opaque triangles, both faces.
    pub fn build_bottom_level(
        &self,
        name: &str,
        geometry: &TriangleGeometry<'_>,
    ) -> Result<AccelerationStructure, GpuError> {
        let triangles = vk::AccelerationStructureGeometryTrianglesDataKHR::default()
            .vertex_format(vk::Format::R32G32B32_SFLOAT)
            .vertex_data(vk::DeviceOrHostAddressConstKHR {
                device_address: geometry.vertices.device_address()?,
            })
            .vertex_stride(u64::from(geometry.vertex_stride))
            .max_vertex(geometry.vertex_count.saturating_sub(1))
            .index_type(vk::IndexType::UINT32)
            .index_data(vk::DeviceOrHostAddressConstKHR {
                device_address: geometry.indices.device_address()?,
            });
        let geometries = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::TRIANGLES)
            .geometry(vk::AccelerationStructureGeometryDataKHR { triangles })
            .flags(vk::GeometryFlagsKHR::OPAQUE)];
        self.build(
            name,
            vk::AccelerationStructureTypeKHR::BOTTOM_LEVEL,
            &geometries,
            geometry.triangle_count,
        )
    }

    /// Builds a top-level structure over `instances` (each opaque, seen from both sides).
    pub fn build_top_level(
        &self,
        name: &str,
        instances: &[Instance<'_>],
    ) -> Result<AccelerationStructure, GpuError> {
        let records: Vec<vk::AccelerationStructureInstanceKHR> = instances
            .iter()
            .map(|instance| vk::AccelerationStructureInstanceKHR {
                transform: vk::TransformMatrixKHR {
                    matrix: [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
                },
                instance_custom_index_and_mask: vk::Packed24_8::new(
                    instance.custom_index,
                    instance.mask,
                ),
                instance_shader_binding_table_record_offset_and_flags: vk::Packed24_8::new(
                    0,
                    (vk::GeometryInstanceFlagsKHR::TRIANGLE_FACING_CULL_DISABLE
                        | vk::GeometryInstanceFlagsKHR::FORCE_OPAQUE)
                        .as_raw() as u8,
                ),
                acceleration_structure_reference: vk::AccelerationStructureReferenceKHR {
                    device_handle: instance.geometry.address,
                },
            })
            .collect();
        // SAFETY: the instance record is plain data (integers, floats and a u64 union).
        let bytes: &[u8] = unsafe {
            std::slice::from_raw_parts(
                records.as_ptr().cast::<u8>(),
                std::mem::size_of_val(records.as_slice()),
            )
        };
        let mut instance_buffer = self.create_buffer(BufferDesc::upload(
            &format!("{name} instances"),
            bytes.len() as u64,
            BufferUsage::ACCELERATION_INPUT,
        ))?;
        instance_buffer.write(bytes)?;
        let instances_data = vk::AccelerationStructureGeometryInstancesDataKHR::default()
            .array_of_pointers(false)
            .data(vk::DeviceOrHostAddressConstKHR {
                device_address: instance_buffer.device_address()?,
            });
        let geometries = [vk::AccelerationStructureGeometryKHR::default()
            .geometry_type(vk::GeometryTypeKHR::INSTANCES)
            .geometry(vk::AccelerationStructureGeometryDataKHR {
                instances: instances_data,
            })];
        self.build(
            name,
            vk::AccelerationStructureTypeKHR::TOP_LEVEL,
            &geometries,
            records.len() as u32,
        )
    }

    /// Sizes, creates and builds one structure of `geometries` (one range of `primitives`), in a
    /// submit of its own that waits for the bottom-level builds before it.
    fn build(
        &self,
        name: &str,
        ty: vk::AccelerationStructureTypeKHR,
        geometries: &[vk::AccelerationStructureGeometryKHR<'_>],
        primitives: u32,
    ) -> Result<AccelerationStructure, GpuError> {
        let shared = &self.shared;
        let loader = shared
            .acceleration
            .as_ref()
            .ok_or_else(|| GpuError::MissingFeature {
                device: shared.info.name.clone(),
                what: "acceleration structures (VK_KHR_acceleration_structure, ray queries off)"
                    .into(),
            })?;
        let mut info = vk::AccelerationStructureBuildGeometryInfoKHR::default()
            .ty(ty)
            .flags(vk::BuildAccelerationStructureFlagsKHR::PREFER_FAST_TRACE)
            .mode(vk::BuildAccelerationStructureModeKHR::BUILD)
            .geometries(geometries);
        let mut sizes = vk::AccelerationStructureBuildSizesInfoKHR::default();
        // SAFETY: valid device with the extension enabled; info and sizes live until return.
        unsafe {
            loader.get_acceleration_structure_build_sizes(
                vk::AccelerationStructureBuildTypeKHR::DEVICE,
                &info,
                &[primitives],
                &mut sizes,
            )
        };
        let buffer = self.create_buffer(BufferDesc::device_local(
            name,
            sizes.acceleration_structure_size,
            BufferUsage::ACCELERATION_STORAGE,
        ))?;
        let create = vk::AccelerationStructureCreateInfoKHR::default()
            .buffer(buffer.raw)
            .offset(0)
            .size(sizes.acceleration_structure_size)
            .ty(ty);
        // SAFETY: the buffer is live, has ACCELERATION_STRUCTURE_STORAGE usage and the size the
        // driver asked for; the structure is destroyed (Drop) before the buffer.
        let raw = unsafe { loader.create_acceleration_structure(&create, None) }
            .during("vkCreateAccelerationStructureKHR")?;
        let mut structure = AccelerationStructure {
            raw,
            address: 0,
            buffer,
            build_seconds: 0.0,
            shared: Arc::clone(shared),
        };
        let address_info =
            vk::AccelerationStructureDeviceAddressInfoKHR::default().acceleration_structure(raw);
        // SAFETY: the structure was just created on this device.
        structure.address =
            unsafe { loader.get_acceleration_structure_device_address(&address_info) };
        let scratch = self.create_buffer(BufferDesc::device_local(
            &format!("{name} scratch"),
            sizes.build_scratch_size.max(1) + SCRATCH_ALIGNMENT,
            BufferUsage::ACCELERATION_SCRATCH,
        ))?;
        let scratch_address = scratch
            .device_address()?
            .next_multiple_of(SCRATCH_ALIGNMENT);
        info = info
            .dst_acceleration_structure(raw)
            .scratch_data(vk::DeviceOrHostAddressKHR {
                device_address: scratch_address,
            });
        let range =
            vk::AccelerationStructureBuildRangeInfoKHR::default().primitive_count(primitives);
        let stamps = self.create_timestamp_pool(2)?;
        self.submit_and_wait(|rec| {
            rec.reset_timestamps(&stamps);
            // A top-level build reads the bottom-level structures built by earlier submits.
            rec.memory_barrier(
                Access::AccelerationStructureBuild,
                Access::AccelerationStructureBuildRead,
            );
            rec.timestamp(&stamps, 0);
            // SAFETY: recording; the geometry buffers, the destination and the scratch buffer
            // are live until the fence wait inside submit_and_wait returns.
            unsafe {
                loader.cmd_build_acceleration_structures(
                    rec.cmd,
                    std::slice::from_ref(&info),
                    &[std::slice::from_ref(&range)],
                )
            };
            rec.timestamp(&stamps, 1);
            Ok(())
        })?;
        let ns = stamps.read_ns(2)?;
        structure.build_seconds = (ns[1] - ns[0]) * 1e-9;
        drop(scratch);
        Ok(structure)
    }
}
