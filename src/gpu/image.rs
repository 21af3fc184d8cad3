//! Images (render targets, depth, cube maps) with their views and memory, and samplers.

use super::conv::{self, Format};
use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use ash::vk;
use gpu_allocator::vulkan::{Allocation, AllocationCreateDesc, AllocationScheme};
use gpu_allocator::MemoryLocation;
use std::sync::Arc;

/// What an image is used for (combine with `|`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ImageUsage(vk::ImageUsageFlags);

impl ImageUsage {
    pub const COLOR_ATTACHMENT: Self = Self(vk::ImageUsageFlags::COLOR_ATTACHMENT);
    pub const DEPTH_ATTACHMENT: Self = Self(vk::ImageUsageFlags::DEPTH_STENCIL_ATTACHMENT);
    pub const TRANSFER_SRC: Self = Self(vk::ImageUsageFlags::TRANSFER_SRC);
    pub const TRANSFER_DST: Self = Self(vk::ImageUsageFlags::TRANSFER_DST);
    pub const SAMPLED: Self = Self(vk::ImageUsageFlags::SAMPLED);
    pub const STORAGE: Self = Self(vk::ImageUsageFlags::STORAGE);
}

impl std::ops::BitOr for ImageUsage {
    type Output = Self;
    fn bitor(self, rhs: Self) -> Self {
        Self(self.0 | rhs.0)
    }
}

#[derive(Clone, Debug)]
pub struct ImageDesc {
    pub name: String,
    pub width: u32,
    pub height: u32,
    pub format: Format,
    pub usage: ImageUsage,
    pub samples: u32,
    /// 6 for a cube map.
    pub layers: u32,
    pub cube: bool,
}

impl ImageDesc {
    /// A 2D colour render target that can be copied out (or resolved into).
    pub fn color_target(name: &str, width: u32, height: u32, samples: u32) -> Self {
        Self {
            name: name.into(),
            width,
            height,
            format: Format::Rgba32Float,
            usage: ImageUsage::COLOR_ATTACHMENT | ImageUsage::TRANSFER_SRC,
            samples,
            layers: 1,
            cube: false,
        }
    }
    /// A 2D colour render target that compute shaders read afterwards (a G-buffer).
    pub fn sampled_target(name: &str, width: u32, height: u32, samples: u32) -> Self {
        Self::color_target(name, width, height, samples)
            .usage(ImageUsage::COLOR_ATTACHMENT | ImageUsage::SAMPLED)
    }
    pub fn depth_target(name: &str, width: u32, height: u32, samples: u32) -> Self {
        Self {
            name: name.into(),
            width,
            height,
            format: Format::Depth32Float,
            usage: ImageUsage::DEPTH_ATTACHMENT,
            samples,
            layers: 1,
            cube: false,
        }
    }
    /// A cube map of linear HDR texels, written by compute and sampled by shaders.
    pub fn cube(name: &str, face_size: u32) -> Self {
        Self {
            name: name.into(),
            width: face_size,
            height: face_size,
            format: Format::Rgba32Float,
            usage: ImageUsage::STORAGE | ImageUsage::SAMPLED | ImageUsage::TRANSFER_SRC,
            samples: 1,
            layers: 6,
            cube: true,
        }
    }
    pub fn usage(mut self, usage: ImageUsage) -> Self {
        self.usage = usage;
        self
    }
}

/// An image with one view of all its layers (cube view for cube maps) and, for storage cube maps,
/// a 2D-array view compute shaders write through.
pub struct Image {
    pub(crate) raw: vk::Image,
    pub(crate) view: vk::ImageView,
    pub(crate) storage_view: Option<vk::ImageView>,
    allocation: Option<Allocation>,
    desc: ImageDesc,
    shared: Arc<DeviceShared>,
}

impl Image {
    pub(crate) fn new(shared: &Arc<DeviceShared>, desc: ImageDesc) -> Result<Self, GpuError> {
        check_limits(shared, &desc)?;
        let flags = if desc.cube {
            vk::ImageCreateFlags::CUBE_COMPATIBLE
        } else {
            vk::ImageCreateFlags::empty()
        };
        let info = vk::ImageCreateInfo::default()
            .flags(flags)
            .image_type(vk::ImageType::TYPE_2D)
            .format(conv::vk_format(desc.format))
            .extent(vk::Extent3D {
                width: desc.width,
                height: desc.height,
                depth: 1,
            })
            .mip_levels(1)
            .array_layers(desc.layers)
            .samples(conv::sample_count_flag(desc.samples))
            .tiling(vk::ImageTiling::OPTIMAL)
            .usage(desc.usage.0)
            .sharing_mode(vk::SharingMode::EXCLUSIVE)
            .initial_layout(vk::ImageLayout::UNDEFINED);
        // SAFETY: valid device; create info lives until return.
        let raw = unsafe { shared.device.create_image(&info, None) }.during("vkCreateImage")?;
        let mut image = Image {
            raw,
            view: vk::ImageView::null(),
            storage_view: None,
            allocation: None,
            desc,
            shared: Arc::clone(shared),
        };
        // From here on, Drop cleans up whatever was created if a later step fails.
        image.bind_memory()?;
        let view_type = if image.desc.cube {
            vk::ImageViewType::CUBE
        } else if image.desc.layers > 1 {
            vk::ImageViewType::TYPE_2D_ARRAY
        } else {
            vk::ImageViewType::TYPE_2D
        };
        image.view = image.create_view(view_type)?;
        if image.desc.cube && image.desc.usage.0.contains(vk::ImageUsageFlags::STORAGE) {
            image.storage_view = Some(image.create_view(vk::ImageViewType::TYPE_2D_ARRAY)?);
        }
        Ok(image)
    }

    fn bind_memory(&mut self) -> Result<(), GpuError> {
        // SAFETY: raw was created from this device.
        let requirements = unsafe { self.shared.device.get_image_memory_requirements(self.raw) };
        let allocation = self
            .shared
            .allocator()
            .allocate(&AllocationCreateDesc {
                name: &self.desc.name,
                requirements,
                location: MemoryLocation::GpuOnly,
                linear: false,
                allocation_scheme: AllocationScheme::GpuAllocatorManaged,
            })
            .map_err(|e| GpuError::Allocation {
                name: self.desc.name.clone(),
                detail: e.to_string(),
            })?;
        // SAFETY: the allocation satisfies the requirements and is bound once.
        let bound = unsafe {
            self.shared
                .device
                .bind_image_memory(self.raw, allocation.memory(), allocation.offset())
        };
        self.allocation = Some(allocation);
        bound.during("vkBindImageMemory")
    }

    fn create_view(&self, view_type: vk::ImageViewType) -> Result<vk::ImageView, GpuError> {
        let info = vk::ImageViewCreateInfo::default()
            .image(self.raw)
            .view_type(view_type)
            .format(conv::vk_format(self.desc.format))
            .subresource_range(self.full_range());
        // SAFETY: the image is valid and has memory bound.
        unsafe { self.shared.device.create_image_view(&info, None) }.during("vkCreateImageView")
    }

    pub(crate) fn full_range(&self) -> vk::ImageSubresourceRange {
        vk::ImageSubresourceRange::default()
            .aspect_mask(conv::aspect(self.desc.format))
            .base_mip_level(0)
            .level_count(1)
            .base_array_layer(0)
            .layer_count(self.desc.layers)
    }

    pub fn desc(&self) -> &ImageDesc {
        &self.desc
    }

    /// Bytes of one full copy of the image (all layers) into a buffer.
    pub fn byte_size(&self) -> u64 {
        u64::from(self.desc.width)
            * u64::from(self.desc.height)
            * u64::from(self.desc.layers)
            * conv::texel_bytes(self.desc.format)
    }
}

fn check_limits(shared: &DeviceShared, desc: &ImageDesc) -> Result<(), GpuError> {
    let limit = if desc.cube {
        shared.info.max_image_dimension_cube
    } else {
        shared.info.max_image_dimension_2d
    };
    for (what, value) in [("image width", desc.width), ("image height", desc.height)] {
        if value == 0 || value > limit {
            return Err(GpuError::Limit {
                what,
                value: u64::from(value),
                limit: u64::from(limit),
            });
        }
    }
    if !shared
        .info
        .framebuffer_color_sample_counts
        .contains(&desc.samples)
    {
        return Err(GpuError::Limit {
            what: "sample count",
            value: u64::from(desc.samples),
            limit: shared
                .info
                .framebuffer_color_sample_counts
                .iter()
                .copied()
                .max()
                .map_or(1, u64::from),
        });
    }
    Ok(())
}

impl Drop for Image {
    fn drop(&mut self) {
        // SAFETY: all work using the image has completed (every submit waits on its fence);
        // null handles are ignored by Vulkan.
        unsafe {
            if let Some(view) = self.storage_view.take() {
                self.shared.device.destroy_image_view(view, None);
            }
            self.shared.device.destroy_image_view(self.view, None);
            self.shared.device.destroy_image(self.raw, None);
        }
        if let Some(allocation) = self.allocation.take() {
            self.shared.free(allocation);
        }
    }
}

/// A linear, clamp-to-edge sampler.
pub struct Sampler {
    pub(crate) raw: vk::Sampler,
    shared: Arc<DeviceShared>,
}

impl Sampler {
    pub(crate) fn linear_clamp(shared: &Arc<DeviceShared>) -> Result<Self, GpuError> {
        let info = vk::SamplerCreateInfo::default()
            .mag_filter(vk::Filter::LINEAR)
            .min_filter(vk::Filter::LINEAR)
            .mipmap_mode(vk::SamplerMipmapMode::LINEAR)
            .address_mode_u(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_v(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .address_mode_w(vk::SamplerAddressMode::CLAMP_TO_EDGE)
            .max_lod(vk::LOD_CLAMP_NONE);
        // SAFETY: valid device; create info lives until return.
        let raw = unsafe { shared.device.create_sampler(&info, None) }.during("vkCreateSampler")?;
        Ok(Sampler {
            raw,
            shared: Arc::clone(shared),
        })
    }
}

impl Drop for Sampler {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the sampler (submits wait on their fences).
        unsafe { self.shared.device.destroy_sampler(self.raw, None) };
    }
}
