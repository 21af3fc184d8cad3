//! Buffers and their memory. Host-visible buffers are persistently mapped (gpu-allocator only
//! hands out HOST_COHERENT memory for them, so no flush/invalidate is needed; the submit and fence
//! are the host↔device synchronisation).

use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// What a buffer is used for (combine with `|`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BufferUsage(vk::BufferUsageFlags);

impl BufferUsage {
    pub const VERTEX: Self = Self(vk::BufferUsageFlags::VERTEX_BUFFER);
    pub const INDEX: Self = Self(vk::BufferUsageFlags::INDEX_BUFFER);
    pub const UNIFORM: Self = Self(vk::BufferUsageFlags::UNIFORM_BUFFER);
    pub const STORAGE: Self = Self(vk::BufferUsageFlags::STORAGE_BUFFER);
    /// Read in shaders as a `textureBuffer` of RGBA32F texels (`Resource::TexelBuffer`), or a
    /// `utextureBuffer` of RGBA32UI ones (`Resource::UintTexelBuffer`).
    pub const UNIFORM_TEXEL: Self = Self(vk::BufferUsageFlags::UNIFORM_TEXEL_BUFFER);
    /// Written in shaders as an `imageBuffer` of RGBA32F texels, or a `uimageBuffer` of RGBA32UI
    /// ones (`Resource::TexelBuffer` or `UintTexelBuffer` at a
    /// `BindingKind::StorageTexelBuffer`): unlike a storage buffer, as large as a texel buffer
    /// may be (maxTexelBufferElements, not maxStorageBufferRange).
    pub const STORAGE_TEXEL: Self = Self(vk::BufferUsageFlags::STORAGE_TEXEL_BUFFER);
    /// Holds the arguments of an indirect dispatch (`Recorder::dispatch_indirect`).
    pub const INDIRECT: Self = Self(vk::BufferUsageFlags::INDIRECT_BUFFER);
    /// Read by an acceleration-structure build (vertices, indices, instances), by address.
    pub const ACCELERATION_INPUT: Self = Self(vk::BufferUsageFlags::from_raw(
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_BUILD_INPUT_READ_ONLY_KHR.as_raw()
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
    ));
    /// Holds an acceleration structure.
    pub(crate) const ACCELERATION_STORAGE: Self = Self(vk::BufferUsageFlags::from_raw(
        vk::BufferUsageFlags::ACCELERATION_STRUCTURE_STORAGE_KHR.as_raw()
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
    ));
    /// An acceleration-structure build's scratch memory.
    pub(crate) const ACCELERATION_SCRATCH: Self = Self(vk::BufferUsageFlags::from_raw(
        vk::BufferUsageFlags::STORAGE_BUFFER.as_raw()
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
    ));
    /// A ray-tracing pipeline's shader binding table (gpu/ray_pipeline.rs), read by address.
    pub(crate) const SHADER_BINDING_TABLE: Self = Self(vk::BufferUsageFlags::from_raw(
        vk::BufferUsageFlags::SHADER_BINDING_TABLE_KHR.as_raw()
            | vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS.as_raw(),
    ));
    pub const TRANSFER_SRC: Self = Self(vk::BufferUsageFlags::TRANSFER_SRC);
    pub const TRANSFER_DST: Self = Self(vk::BufferUsageFlags::TRANSFER_DST);
}

impl std::ops::BitOr for BufferUsage {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

/// Where the memory lives, as intent.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MemoryUse {
    /// Written by the host, read by the device.
    Upload,
    /// Written by the device, read back by the host.
    Readback,
    /// Device only.
    DeviceLocal,
}

#[derive(Clone, Debug)]
pub struct BufferDesc {
    pub name: String,
    pub size: u64,
    pub usage: BufferUsage,
    pub memory: MemoryUse,
}

impl BufferDesc {
    pub fn upload(name: &str, size: u64, usage: BufferUsage) -> Self {
        Self {
            name: name.into(),
            size,
            usage,
            memory: MemoryUse::Upload,
        }
    }
    pub fn readback(name: &str, size: u64) -> Self {
        Self {
            name: name.into(),
            size,
            usage: BufferUsage::TRANSFER_DST | BufferUsage::STORAGE,
            memory: MemoryUse::Readback,
        }
    }
    pub fn device_local(name: &str, size: u64, usage: BufferUsage) -> Self {
        Self {
            name: name.into(),
            size,
            usage,
            memory: MemoryUse::DeviceLocal,
        }
    }
}

/// A buffer with its memory; freed on drop.
pub struct Buffer {
    pub(crate) raw: vk::Buffer,
    allocation: Option<Allocation>,
    desc: BufferDesc,
    shared: Arc<DeviceShared>,
}

impl Buffer {
    pub(crate) fn new(shared: &Arc<DeviceShared>, desc: BufferDesc) -> Result<Self, GpuError> {
        // Zero-sized buffers are invalid in Vulkan; round up so empty inputs stay representable.
        let size = desc.size.max(4);
        let info = vk::BufferCreateInfo::default()
            .size(size)
            .usage(desc.usage.0)
            .sharing_mode(vk::SharingMode::EXCLUSIVE);
        // SAFETY: valid device, create info lives until return.
        let raw = unsafe { shared.device.create_buffer(&info, None) }.during("vkCreateBuffer")?;
        // SAFETY: raw was just created from this device.
        let requirements = unsafe { shared.device.get_buffer_memory_requirements(raw) };
        let location = match desc.memory {
            MemoryUse::Upload => MemoryLocation::CpuToGpu,
            MemoryUse::Readback => MemoryLocation::GpuToCpu,
            MemoryUse::DeviceLocal => MemoryLocation::GpuOnly,
        };
        let allocation = shared.allocator().allocate(&AllocationCreateDesc {
            name: &desc.name,
            requirements,
            location,
            linear: true,
            allocation_scheme: AllocationScheme::GpuAllocatorManaged,
        });
        let allocation = match allocation {
            Ok(a) => a,
            Err(e) => {
                // SAFETY: the buffer is unused and has no memory bound.
                unsafe { shared.device.destroy_buffer(raw, None) };
                return Err(GpuError::Allocation {
                    name: desc.name.clone(),
                    detail: e.to_string(),
                });
            }
        };
        // SAFETY: the allocation satisfies the buffer's requirements and is bound once.
        let bound = unsafe {
            shared
                .device
                .bind_buffer_memory(raw, allocation.memory(), allocation.offset())
        }
        .during("vkBindBufferMemory");
        let buffer = Buffer {
            raw,
            allocation: Some(allocation),
            desc,
            shared: Arc::clone(shared),
        };
        bound.map(|()| buffer)
    }

    pub fn size(&self) -> u64 {
        self.desc.size
    }

    /// The buffer's device address (made with a `SHADER_DEVICE_ADDRESS` usage, on a device with
    /// ray queries: the only one with `bufferDeviceAddress` enabled).
    pub(crate) fn device_address(&self) -> Result<u64, GpuError> {
        if !self.shared.info.ray_query.is_enabled()
            || !self
                .desc
                .usage
                .0
                .contains(vk::BufferUsageFlags::SHADER_DEVICE_ADDRESS)
        {
            return Err(GpuError::MissingFeature {
                device: self.shared.info.name.clone(),
                what: format!("the device address of buffer {:?}", self.desc.name),
            });
        }
        let info = vk::BufferDeviceAddressInfo::default().buffer(self.raw);
        // SAFETY: the buffer is live and was made with SHADER_DEVICE_ADDRESS on a device with
        // bufferDeviceAddress enabled (checked above).
        Ok(unsafe { self.shared.device.get_buffer_device_address(&info) })
    }

    /// Copies `data` to the start of a host-visible buffer.
    pub fn write<T: bytemuck::Pod>(&mut self, data: &[T]) -> Result<(), GpuError> {
        let bytes: &[u8] = bytemuck::cast_slice(data);
        let name = self.desc.name.clone();
        let mapped = self
            .allocation
            .as_mut()
            .and_then(|a| a.mapped_slice_mut())
            .ok_or_else(|| GpuError::Allocation {
                name: name.clone(),
                detail: "buffer is not host-visible".into(),
            })?;
        if bytes.len() > mapped.len() {
            return Err(GpuError::Allocation {
                name,
                detail: format!("{} bytes do not fit in {}", bytes.len(), mapped.len()),
            });
        }
        mapped[..bytes.len()].copy_from_slice(bytes);
        Ok(())
    }

    /// The first `self.size()` bytes of a host-visible buffer as `T`s. Call only after the fence
    /// of the work that wrote it, with a device→host barrier in that work.
    pub fn read<T: bytemuck::Pod>(&self) -> Result<Vec<T>, GpuError> {
        let mapped = self
            .allocation
            .as_ref()
            .and_then(|a| a.mapped_slice())
            .ok_or_else(|| GpuError::Allocation {
                name: self.desc.name.clone(),
                detail: "buffer is not host-visible".into(),
            })?;
        let len = (self.desc.size as usize).min(mapped.len());
        Ok(bytemuck::pod_collect_to_vec(&mapped[..len]))
    }
}

impl Drop for Buffer {
    fn drop(&mut self) {
        // SAFETY: work using the buffer has completed (every submit waits on its fence).
        unsafe { self.shared.device.destroy_buffer(self.raw, None) };
        if let Some(allocation) = self.allocation.take() {
            self.shared.free(allocation);
        }
    }
}
