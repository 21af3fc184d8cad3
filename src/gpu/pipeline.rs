//! Pipelines (compute and graphics), their layouts, and descriptor sets.
//!
//! Each pipeline has one descriptor set (set 0) whose bindings it declares, and an optional push
//! constant block visible to all its stages. Descriptor sets are allocated from a small pool of
//! their own, so a set and its pool live and die together.

use super::accel::AccelerationStructure;
use super::buffer::Buffer;
use super::conv::{self, DepthTest, Format};
use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use super::image::{Image, Sampler};
use ash::vk;
use std::sync::Arc;

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BindingKind {
    UniformBuffer,
    StorageBuffer,
    SampledImage,
    StorageImage,
    /// A `textureBuffer` of RGBA32F texels, for gathered reads (quirk `ssbo_gather_is_per_lane`).
    UniformTexelBuffer,
    /// A `layout(rgba32f) imageBuffer` written texel by texel.
    StorageTexelBuffer,
    /// An `accelerationStructureEXT` for ray queries.
    AccelerationStructure,
}

/// One binding of set 0 (an array of `count` descriptors when count > 1).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Binding {
    pub index: u32,
    pub kind: BindingKind,
    pub count: u32,
}

impl Binding {
    pub const fn new(index: u32, kind: BindingKind) -> Self {
        Self {
            index,
            kind,
            count: 1,
        }
    }

    pub const fn array(index: u32, kind: BindingKind, count: u32) -> Self {
        Self { index, kind, count }
    }
}

fn descriptor_type(kind: BindingKind) -> vk::DescriptorType {
    match kind {
        BindingKind::UniformBuffer => vk::DescriptorType::UNIFORM_BUFFER,
        BindingKind::StorageBuffer => vk::DescriptorType::STORAGE_BUFFER,
        BindingKind::SampledImage => vk::DescriptorType::COMBINED_IMAGE_SAMPLER,
        BindingKind::StorageImage => vk::DescriptorType::STORAGE_IMAGE,
        BindingKind::UniformTexelBuffer => vk::DescriptorType::UNIFORM_TEXEL_BUFFER,
        BindingKind::StorageTexelBuffer => vk::DescriptorType::STORAGE_TEXEL_BUFFER,
        BindingKind::AccelerationStructure => vk::DescriptorType::ACCELERATION_STRUCTURE_KHR,
    }
}

/// Set layout + pipeline layout, shared by both pipeline kinds.
pub struct PipelineLayout {
    pub(crate) set_layout: vk::DescriptorSetLayout,
    pub(crate) raw: vk::PipelineLayout,
    pub(crate) stages: vk::ShaderStageFlags,
    pub(crate) push_constant_size: u32,
    bindings: Vec<Binding>,
    pub(super) shared: Arc<DeviceShared>,
}

impl PipelineLayout {
    pub(super) fn new(
        shared: &Arc<DeviceShared>,
        bindings: &[Binding],
        stages: vk::ShaderStageFlags,
        push_constant_size: u32,
    ) -> Result<Self, GpuError> {
        let vk_bindings: Vec<vk::DescriptorSetLayoutBinding> = bindings
            .iter()
            .map(|b| {
                vk::DescriptorSetLayoutBinding::default()
                    .binding(b.index)
                    .descriptor_type(descriptor_type(b.kind))
                    .descriptor_count(b.count)
                    .stage_flags(stages)
            })
            .collect();
        let info = vk::DescriptorSetLayoutCreateInfo::default().bindings(&vk_bindings);
        // SAFETY: valid device; info lives until return.
        let set_layout = unsafe { shared.device.create_descriptor_set_layout(&info, None) }
            .during("vkCreateDescriptorSetLayout")?;
        let ranges = [vk::PushConstantRange::default()
            .stage_flags(stages)
            .offset(0)
            .size(push_constant_size)];
        let mut info =
            vk::PipelineLayoutCreateInfo::default().set_layouts(std::slice::from_ref(&set_layout));
        if push_constant_size > 0 {
            info = info.push_constant_ranges(&ranges);
        }
        // SAFETY: valid device; set_layout is live.
        let raw = match unsafe { shared.device.create_pipeline_layout(&info, None) } {
            Ok(raw) => raw,
            Err(result) => {
                // SAFETY: created above, unused.
                unsafe {
                    shared
                        .device
                        .destroy_descriptor_set_layout(set_layout, None)
                };
                return Err(super::error::from_vk("vkCreatePipelineLayout", result));
            }
        };
        Ok(PipelineLayout {
            set_layout,
            raw,
            stages,
            push_constant_size,
            bindings: bindings.to_vec(),
            shared: Arc::clone(shared),
        })
    }
}

impl Drop for PipelineLayout {
    fn drop(&mut self) {
        // SAFETY: no pipeline or set made from these layouts is in use any more.
        unsafe {
            self.shared.device.destroy_pipeline_layout(self.raw, None);
            self.shared
                .device
                .destroy_descriptor_set_layout(self.set_layout, None);
        }
    }
}

/// A shader module that lives only while a pipeline is being created.
pub(super) struct ShaderModule<'a> {
    pub(super) raw: vk::ShaderModule,
    device: &'a ash::Device,
}

impl<'a> ShaderModule<'a> {
    pub(super) fn new(
        device: &'a ash::Device,
        name: &'static str,
        spirv: &[u8],
    ) -> Result<Self, GpuError> {
        let words = ash::util::read_spv(&mut std::io::Cursor::new(spirv)).map_err(|e| {
            GpuError::Shader {
                name,
                detail: e.to_string(),
            }
        })?;
        let info = vk::ShaderModuleCreateInfo::default().code(&words);
        // SAFETY: the words are SPIR-V produced by build.rs; info lives until return.
        let raw =
            unsafe { device.create_shader_module(&info, None) }.during("vkCreateShaderModule")?;
        Ok(ShaderModule { raw, device })
    }
}

impl Drop for ShaderModule<'_> {
    fn drop(&mut self) {
        // SAFETY: modules are only needed during pipeline creation.
        unsafe { self.device.destroy_shader_module(self.raw, None) };
    }
}

/// Map entries for `count` 32-bit specialization constants packed in order: entry i sets
/// `constant_id = i`.
pub(super) fn specialization_entries(count: usize) -> Vec<vk::SpecializationMapEntry> {
    (0..count)
        .map(|i| vk::SpecializationMapEntry {
            constant_id: i as u32,
            offset: (i * 4) as u32,
            size: 4,
        })
        .collect()
}

/// A compute pipeline.
pub struct ComputePipeline {
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: PipelineLayout,
}

impl ComputePipeline {
    pub(crate) fn new(
        shared: &Arc<DeviceShared>,
        name: &'static str,
        spirv: &[u8],
        bindings: &[Binding],
        push_constant_size: u32,
        constants: &[u32],
    ) -> Result<Self, GpuError> {
        let layout = PipelineLayout::new(
            shared,
            bindings,
            vk::ShaderStageFlags::COMPUTE,
            push_constant_size,
        )?;
        let module = ShaderModule::new(&shared.device, name, spirv)?;
        let constant_entries = specialization_entries(constants.len());
        let specialization = vk::SpecializationInfo::default()
            .map_entries(&constant_entries)
            .data(bytemuck::cast_slice(constants));
        let stage = vk::PipelineShaderStageCreateInfo::default()
            .stage(vk::ShaderStageFlags::COMPUTE)
            .module(module.raw)
            .name(c"main")
            .specialization_info(&specialization);
        let info = vk::ComputePipelineCreateInfo::default()
            .stage(stage)
            .layout(layout.raw);
        // SAFETY: module and layout are live; info lives until return.
        let raw = unsafe {
            shared.device.create_compute_pipelines(
                shared.pipeline_cache,
                std::slice::from_ref(&info),
                None,
            )
        }
        .map_err(|(_, result)| super::error::from_vk("vkCreateComputePipelines", result))?;
        Ok(ComputePipeline {
            raw: raw[0],
            layout,
        })
    }

    pub fn layout(&self) -> &PipelineLayout {
        &self.layout
    }
}

impl Drop for ComputePipeline {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the pipeline.
        unsafe { self.layout.shared.device.destroy_pipeline(self.raw, None) };
    }
}

/// One vertex attribute of an interleaved f32 vertex buffer (binding 0).
#[derive(Clone, Copy, Debug)]
pub struct VertexAttribute {
    pub location: u32,
    pub offset: u32,
    /// Number of f32 components (1–4).
    pub components: u32,
}

pub struct GraphicsPipelineDesc<'a> {
    pub name: &'static str,
    pub vertex_spirv: &'a [u8],
    pub fragment_spirv: &'a [u8],
    pub bindings: &'a [Binding],
    pub vertex_stride: u32,
    pub vertex_attributes: &'a [VertexAttribute],
    /// One format per colour attachment, in location order.
    pub color_formats: &'a [Format],
    /// None: the pipeline draws in passes without a depth attachment.
    pub depth_format: Option<Format>,
    pub samples: u32,
    /// None: no depth test (full-screen passes such as the background).
    pub depth_test: Option<DepthTest>,
    /// The fragment stage's 32-bit specialization constants: entry i sets `constant_id = i`.
    pub fragment_constants: &'a [u32],
    /// The first `written_colors` colour attachments are written; the rest keep their values
    /// (0: a depth-only draw).
    pub written_colors: usize,
}

/// A graphics pipeline for dynamic rendering (no render pass objects), with dynamic viewport and
/// scissor, an optional depth test, no culling (the BRDF is zero for back faces: nv <= 0).
pub struct GraphicsPipeline {
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: PipelineLayout,
}

impl GraphicsPipeline {
    pub(crate) fn new(
        shared: &Arc<DeviceShared>,
        desc: &GraphicsPipelineDesc<'_>,
    ) -> Result<Self, GpuError> {
        let layout = PipelineLayout::new(
            shared,
            desc.bindings,
            vk::ShaderStageFlags::VERTEX | vk::ShaderStageFlags::FRAGMENT,
            0,
        )?;
        let vertex = ShaderModule::new(&shared.device, desc.name, desc.vertex_spirv)?;
        let fragment = ShaderModule::new(&shared.device, desc.name, desc.fragment_spirv)?;
        let constant_entries = specialization_entries(desc.fragment_constants.len());
        let specialization = vk::SpecializationInfo::default()
            .map_entries(&constant_entries)
            .data(bytemuck::cast_slice(desc.fragment_constants));
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::VERTEX)
                .module(vertex.raw)
                .name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::FRAGMENT)
                .module(fragment.raw)
                .name(c"main")
                .specialization_info(&specialization),
        ];
        let binding = vk::VertexInputBindingDescription::default()
            .binding(0)
            .stride(desc.vertex_stride)
            .input_rate(vk::VertexInputRate::VERTEX);
        let attributes: Vec<_> = desc.vertex_attributes.iter().map(attribute).collect();
        // No attributes: a pass that makes its vertices from gl_VertexIndex.
        let vertex_input = if attributes.is_empty() {
            vk::PipelineVertexInputStateCreateInfo::default()
        } else {
            vk::PipelineVertexInputStateCreateInfo::default()
                .vertex_binding_descriptions(std::slice::from_ref(&binding))
                .vertex_attribute_descriptions(&attributes)
        };
        let input_assembly = vk::PipelineInputAssemblyStateCreateInfo::default()
            .topology(vk::PrimitiveTopology::TRIANGLE_LIST);
        let (viewport, raster) = (viewport_state(), raster_state());
        let multisample = vk::PipelineMultisampleStateCreateInfo::default()
            .rasterization_samples(conv::sample_count_flag(desc.samples));
        let depth = depth_state(desc.depth_test);
        let blend_attachments: Vec<_> = (0..desc.color_formats.len())
            .map(|i| blend_attachment(i < desc.written_colors))
            .collect();
        let blend =
            vk::PipelineColorBlendStateCreateInfo::default().attachments(&blend_attachments);
        let dynamic = vk::PipelineDynamicStateCreateInfo::default().dynamic_states(&DYNAMIC_STATES);
        let color_formats: Vec<vk::Format> = desc
            .color_formats
            .iter()
            .map(|&f| conv::vk_format(f))
            .collect();
        let mut rendering = vk::PipelineRenderingCreateInfo::default()
            .color_attachment_formats(&color_formats)
            .depth_attachment_format(
                desc.depth_format
                    .map_or(vk::Format::UNDEFINED, conv::vk_format),
            );
        let info = vk::GraphicsPipelineCreateInfo::default()
            .stages(&stages)
            .vertex_input_state(&vertex_input)
            .input_assembly_state(&input_assembly)
            .viewport_state(&viewport)
            .rasterization_state(&raster)
            .multisample_state(&multisample)
            .depth_stencil_state(&depth)
            .color_blend_state(&blend)
            .dynamic_state(&dynamic)
            .layout(layout.raw)
            .push_next(&mut rendering);
        // SAFETY: every struct referenced by info lives on this stack frame until return.
        let raw = unsafe {
            shared.device.create_graphics_pipelines(
                shared.pipeline_cache,
                std::slice::from_ref(&info),
                None,
            )
        }
        .map_err(|(_, result)| super::error::from_vk("vkCreateGraphicsPipelines", result))?;
        Ok(GraphicsPipeline {
            raw: raw[0],
            layout,
        })
    }

    pub fn layout(&self) -> &PipelineLayout {
        &self.layout
    }
}

impl Drop for GraphicsPipeline {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the pipeline.
        unsafe { self.layout.shared.device.destroy_pipeline(self.raw, None) };
    }
}

/// The viewport and scissor are set when recording.
const DYNAMIC_STATES: [vk::DynamicState; 2] =
    [vk::DynamicState::VIEWPORT, vk::DynamicState::SCISSOR];

fn viewport_state() -> vk::PipelineViewportStateCreateInfo<'static> {
    vk::PipelineViewportStateCreateInfo::default()
        .viewport_count(1)
        .scissor_count(1)
}

/// Filled triangles, both faces (the BRDF is zero for back faces: nv <= 0).
fn raster_state() -> vk::PipelineRasterizationStateCreateInfo<'static> {
    vk::PipelineRasterizationStateCreateInfo::default()
        .polygon_mode(vk::PolygonMode::FILL)
        .cull_mode(vk::CullModeFlags::NONE)
        .front_face(vk::FrontFace::COUNTER_CLOCKWISE)
        .line_width(1.0)
}

/// Vertex attribute `a` of binding 0, f32 components.
fn attribute(a: &VertexAttribute) -> vk::VertexInputAttributeDescription {
    vk::VertexInputAttributeDescription::default()
        .location(a.location)
        .binding(0)
        .format(match a.components {
            1 => vk::Format::R32_SFLOAT,
            2 => vk::Format::R32G32_SFLOAT,
            3 => vk::Format::R32G32B32_SFLOAT,
            _ => vk::Format::R32G32B32A32_SFLOAT,
        })
        .offset(a.offset)
}

fn depth_state(test: Option<DepthTest>) -> vk::PipelineDepthStencilStateCreateInfo<'static> {
    vk::PipelineDepthStencilStateCreateInfo::default()
        .depth_test_enable(test.is_some())
        .depth_write_enable(test.is_some_and(|t| t.write))
        .depth_compare_op(test.map_or(vk::CompareOp::ALWAYS, |t| conv::compare_op(t.compare)))
}

/// No blending; `writes` false keeps the attachment's values (a depth-only draw).
fn blend_attachment(writes: bool) -> vk::PipelineColorBlendAttachmentState {
    vk::PipelineColorBlendAttachmentState::default()
        .blend_enable(false)
        .color_write_mask(if writes {
            vk::ColorComponentFlags::RGBA
        } else {
            vk::ColorComponentFlags::empty()
        })
}

/// What a binding points at.
pub enum Resource<'a> {
    Buffer(&'a Buffer),
    SampledImage(&'a Image, &'a Sampler),
    /// Every element of an array binding, in order; its length must equal the binding's count.
    SampledImages(Vec<&'a Image>, &'a Sampler),
    StorageImage(&'a Image),
    /// The whole buffer as RGBA32F texels (created with `BufferUsage::UNIFORM_TEXEL`, or
    /// `STORAGE_TEXEL` for a `BindingKind::StorageTexelBuffer`).
    TexelBuffer(&'a Buffer),
    /// The same as RGBA32UI texels (the `brdf` layer texels, environment/layer_pair.rs).
    UintTexelBuffer(&'a Buffer),
    AccelerationStructure(&'a AccelerationStructure),
}

/// Set 0 of a pipeline, filled in once.
pub struct DescriptorSet {
    pub(crate) raw: vk::DescriptorSet,
    pool: vk::DescriptorPool,
    /// Views of the texel buffers the set points at: they must outlive it.
    buffer_views: Vec<vk::BufferView>,
    shared: Arc<DeviceShared>,
}

impl DescriptorSet {
    pub(crate) fn new(
        shared: &Arc<DeviceShared>,
        layout: &PipelineLayout,
        resources: &[(u32, Resource<'_>)],
    ) -> Result<Self, GpuError> {
        let sizes: Vec<vk::DescriptorPoolSize> = layout
            .bindings
            .iter()
            .map(|b| vk::DescriptorPoolSize {
                ty: descriptor_type(b.kind),
                descriptor_count: b.count,
            })
            .collect();
        let info = vk::DescriptorPoolCreateInfo::default()
            .max_sets(1)
            .pool_sizes(&sizes);
        // SAFETY: valid device; info lives until return.
        let pool = unsafe { shared.device.create_descriptor_pool(&info, None) }
            .during("vkCreateDescriptorPool")?;
        let mut set = DescriptorSet {
            raw: vk::DescriptorSet::null(),
            pool,
            buffer_views: Vec::new(),
            shared: Arc::clone(shared),
        };
        let alloc = vk::DescriptorSetAllocateInfo::default()
            .descriptor_pool(pool)
            .set_layouts(std::slice::from_ref(&layout.set_layout));
        // SAFETY: pool and layout are live.
        set.raw = unsafe { shared.device.allocate_descriptor_sets(&alloc) }
            .during("vkAllocateDescriptorSets")?[0];
        set.write(layout, resources)?;
        Ok(set)
    }

    /// A view of the whole of `buffer` as 16-byte texels of `format` (RGBA32F or RGBA32UI),
    /// owned by this set.
    fn texel_view(
        &mut self,
        buffer: &Buffer,
        format: vk::Format,
    ) -> Result<vk::BufferView, GpuError> {
        let texels = buffer.size() / 16;
        let limit = self.shared.info.max_texel_buffer_elements;
        if texels > u64::from(limit) {
            return Err(GpuError::Limit {
                what: "16-byte texels in one texel buffer (maxTexelBufferElements)",
                value: texels,
                limit: u64::from(limit),
            });
        }
        let info = vk::BufferViewCreateInfo::default()
            .buffer(buffer.raw)
            .format(format)
            .offset(0)
            .range(vk::WHOLE_SIZE);
        // SAFETY: valid device; the buffer is live; the view is destroyed with the set.
        let view = unsafe { self.shared.device.create_buffer_view(&info, None) }
            .during("vkCreateBufferView")?;
        self.buffer_views.push(view);
        Ok(view)
    }

    fn write(
        &mut self,
        layout: &PipelineLayout,
        resources: &[(u32, Resource<'_>)],
    ) -> Result<(), GpuError> {
        let infos = self.infos(resources)?;
        let mut writes = self.writes(layout, &infos)?;
        // An acceleration structure's descriptor is a chained struct, not a buffer or image info.
        let mut structures: Vec<vk::WriteDescriptorSetAccelerationStructureKHR> = infos
            .structures
            .iter()
            .map(|(_, raw)| {
                vk::WriteDescriptorSetAccelerationStructureKHR::default()
                    .acceleration_structures(raw)
            })
            .collect();
        for ((index, _), chained) in infos.structures.iter().zip(&mut structures) {
            let binding = layout
                .bindings
                .iter()
                .find(|b| b.index == *index && b.kind == BindingKind::AccelerationStructure)
                .ok_or(GpuError::Limit {
                    what: "acceleration-structure binding index (not in the pipeline layout)",
                    value: u64::from(*index),
                    limit: layout.bindings.len() as u64,
                })?;
            writes.push(
                vk::WriteDescriptorSet::default()
                    .dst_set(self.raw)
                    .dst_binding(binding.index)
                    .descriptor_type(vk::DescriptorType::ACCELERATION_STRUCTURE_KHR)
                    .descriptor_count(1)
                    .push_next(chained),
            );
        }
        // SAFETY: the set is not in use by any pending command buffer; infos outlive the call.
        unsafe { self.shared.device.update_descriptor_sets(&writes, &[]) };
        Ok(())
    }

    /// Each resource as Vulkan describes it, by binding index (texel buffers get their views).
    fn infos(&mut self, resources: &[(u32, Resource<'_>)]) -> Result<DescriptorInfos, GpuError> {
        let mut infos = DescriptorInfos::default();
        let sampled = |image: &Image, sampler: &Sampler| vk::DescriptorImageInfo {
            sampler: sampler.raw,
            image_view: image.view,
            image_layout: vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        };
        for (index, resource) in resources {
            match resource {
                Resource::Buffer(b) => infos.buffers.push((
                    *index,
                    vk::DescriptorBufferInfo {
                        buffer: b.raw,
                        offset: 0,
                        range: vk::WHOLE_SIZE,
                    },
                )),
                Resource::SampledImage(image, sampler) => {
                    infos.images.push((*index, vec![sampled(image, sampler)]))
                }
                Resource::SampledImages(images, sampler) => infos.images.push((
                    *index,
                    images.iter().map(|image| sampled(image, sampler)).collect(),
                )),
                Resource::StorageImage(image) => infos.images.push((
                    *index,
                    vec![vk::DescriptorImageInfo {
                        sampler: vk::Sampler::null(),
                        image_view: image.storage_view.unwrap_or(image.view),
                        image_layout: vk::ImageLayout::GENERAL,
                    }],
                )),
                Resource::TexelBuffer(b) => infos
                    .texel_views
                    .push((*index, self.texel_view(b, vk::Format::R32G32B32A32_SFLOAT)?)),
                Resource::UintTexelBuffer(b) => infos
                    .texel_views
                    .push((*index, self.texel_view(b, vk::Format::R32G32B32A32_UINT)?)),
                Resource::AccelerationStructure(a) => infos.structures.push((*index, [a.raw])),
            }
        }
        Ok(infos)
    }

    /// One write per binding of `infos`, checked against `layout`.
    fn writes<'i>(
        &self,
        layout: &PipelineLayout,
        infos: &'i DescriptorInfos,
    ) -> Result<Vec<vk::WriteDescriptorSet<'i>>, GpuError> {
        let binding_of = |index: u32| -> Result<Binding, GpuError> {
            layout
                .bindings
                .iter()
                .find(|b| b.index == index)
                .copied()
                .ok_or(GpuError::Limit {
                    what: "descriptor binding index (not in the pipeline layout)",
                    value: u64::from(index),
                    limit: layout.bindings.len() as u64,
                })
        };
        let write = |index: u32, binding: Binding| {
            vk::WriteDescriptorSet::default()
                .dst_set(self.raw)
                .dst_binding(index)
                .descriptor_type(descriptor_type(binding.kind))
        };
        let mut writes = Vec::new();
        for (index, info) in &infos.buffers {
            writes.push(write(*index, binding_of(*index)?).buffer_info(std::slice::from_ref(info)));
        }
        for (index, view) in &infos.texel_views {
            let binding = binding_of(*index)?;
            writes.push(write(*index, binding).texel_buffer_view(std::slice::from_ref(view)));
        }
        for (index, images) in &infos.images {
            let binding = binding_of(*index)?;
            if images.len() != binding.count as usize {
                return Err(GpuError::Limit {
                    what: "descriptors for an array binding (must equal its count)",
                    value: images.len() as u64,
                    limit: u64::from(binding.count),
                });
            }
            writes.push(write(*index, binding).image_info(images));
        }
        Ok(writes)
    }
}

/// The descriptors of one [`DescriptorSet::write`], by binding index.
#[derive(Default)]
struct DescriptorInfos {
    buffers: Vec<(u32, vk::DescriptorBufferInfo)>,
    texel_views: Vec<(u32, vk::BufferView)>,
    images: Vec<(u32, Vec<vk::DescriptorImageInfo>)>,
    structures: Vec<(u32, [vk::AccelerationStructureKHR; 1])>,
}

impl Drop for DescriptorSet {
    fn drop(&mut self) {
        // SAFETY: destroying the pool frees its set; no pending work uses it or its views.
        unsafe {
            self.shared.device.destroy_descriptor_pool(self.pool, None);
            for view in &self.buffer_views {
                self.shared.device.destroy_buffer_view(*view, None);
            }
        }
    }
}
