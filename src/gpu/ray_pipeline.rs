//! A ray-tracing pipeline (`VK_KHR_ray_tracing_pipeline`) and its shader binding table: the way
//! shikki traces rays on a device without ray queries (NVIDIA's H100 and H200 have acceleration
//! structures and ray-tracing pipelines but no `VK_KHR_ray_query`).
//!
//! The pipeline has three shader groups, one record each: a ray generation shader (the shading
//! pass, shade_rt*.rgen), one miss shader and one triangle hit group with a closest-hit shader
//! (trace_miss.rmiss, trace_hit.rchit; shaders/common/ray_payload.glsl names their records). Like
//! every pipeline here it has one descriptor set (set 0) and an optional push-constant block, both
//! visible to the ray generation stage only.

use super::buffer::{Buffer, BufferDesc, BufferUsage};
use super::device::DeviceShared;
use super::error::{GpuError, VkResultExt};
use super::pipeline::{specialization_entries, Binding, PipelineLayout, ShaderModule};
use ash::vk;
use std::sync::Arc;

/// What a ray-tracing pipeline is made of.
pub struct RayTracingPipelineDesc<'a> {
    pub name: &'static str,
    pub raygen_spirv: &'a [u8],
    pub miss_spirv: &'a [u8],
    pub closest_hit_spirv: &'a [u8],
    pub bindings: &'a [Binding],
    pub push_constant_size: u32,
    /// The ray generation stage's 32-bit specialization constants: entry i sets `constant_id = i`.
    pub raygen_constants: &'a [u32],
}

/// A ray-tracing pipeline and its shader binding table.
pub struct RayTracingPipeline {
    pub(crate) raw: vk::Pipeline,
    pub(crate) layout: PipelineLayout,
    /// Holds the three records; kept alive for the regions' addresses.
    _table: Buffer,
    /// The ray generation, miss and hit regions of the table, and an empty callable one.
    pub(crate) regions: [vk::StridedDeviceAddressRegionKHR; 4],
}

/// `value` rounded up to a multiple of `to` (a power of two, as Vulkan's alignments are).
fn align_up(value: u64, to: u64) -> u64 {
    value.div_ceil(to) * to
}

impl RayTracingPipeline {
    pub(crate) fn new(
        shared: &Arc<DeviceShared>,
        desc: &RayTracingPipelineDesc<'_>,
    ) -> Result<Self, GpuError> {
        let functions = shared
            .ray_pipeline
            .as_ref()
            .ok_or_else(|| GpuError::MissingFeature {
                device: shared.info.name.clone(),
                what: format!("a ray-tracing pipeline ({})", desc.name),
            })?;
        let layout = PipelineLayout::new(
            shared,
            desc.bindings,
            vk::ShaderStageFlags::RAYGEN_KHR,
            desc.push_constant_size,
        )?;
        let raygen = ShaderModule::new(&shared.device, desc.name, desc.raygen_spirv)?;
        let miss = ShaderModule::new(&shared.device, desc.name, desc.miss_spirv)?;
        let hit = ShaderModule::new(&shared.device, desc.name, desc.closest_hit_spirv)?;
        let constant_entries = specialization_entries(desc.raygen_constants.len());
        let specialization = vk::SpecializationInfo::default()
            .map_entries(&constant_entries)
            .data(bytemuck::cast_slice(desc.raygen_constants));
        let stages = [
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::RAYGEN_KHR)
                .module(raygen.raw)
                .name(c"main")
                .specialization_info(&specialization),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::MISS_KHR)
                .module(miss.raw)
                .name(c"main"),
            vk::PipelineShaderStageCreateInfo::default()
                .stage(vk::ShaderStageFlags::CLOSEST_HIT_KHR)
                .module(hit.raw)
                .name(c"main"),
        ];
        let general = |stage: u32| {
            vk::RayTracingShaderGroupCreateInfoKHR::default()
                .ty(vk::RayTracingShaderGroupTypeKHR::GENERAL)
                .general_shader(stage)
                .closest_hit_shader(vk::SHADER_UNUSED_KHR)
                .any_hit_shader(vk::SHADER_UNUSED_KHR)
                .intersection_shader(vk::SHADER_UNUSED_KHR)
        };
        let groups = [
            general(0),
            general(1),
            vk::RayTracingShaderGroupCreateInfoKHR::default()
                .ty(vk::RayTracingShaderGroupTypeKHR::TRIANGLES_HIT_GROUP)
                .general_shader(vk::SHADER_UNUSED_KHR)
                .closest_hit_shader(2)
                .any_hit_shader(vk::SHADER_UNUSED_KHR)
                .intersection_shader(vk::SHADER_UNUSED_KHR),
        ];
        // Every ray is traced from the ray generation shader: no recursion.
        let info = vk::RayTracingPipelineCreateInfoKHR::default()
            .stages(&stages)
            .groups(&groups)
            .max_pipeline_ray_recursion_depth(1)
            .layout(layout.raw);
        // SAFETY: modules and layout are live; every struct info references lives on this frame.
        let raw = unsafe {
            functions.functions.create_ray_tracing_pipelines(
                vk::DeferredOperationKHR::null(),
                shared.pipeline_cache,
                std::slice::from_ref(&info),
                None,
            )
        }
        .map_err(|(_, result)| super::error::from_vk("vkCreateRayTracingPipelinesKHR", result))?[0];
        let destroy = |error: GpuError| {
            // SAFETY: created above and not yet used.
            unsafe { shared.device.destroy_pipeline(raw, None) };
            error
        };
        let (table, regions) =
            shader_binding_table(shared, raw, groups.len() as u32, desc.name).map_err(destroy)?;
        Ok(RayTracingPipeline {
            raw,
            layout,
            _table: table,
            regions,
        })
    }

    pub fn layout(&self) -> &PipelineLayout {
        &self.layout
    }
}

/// The pipeline's group handles laid out as the device wants them: each region (ray generation,
/// miss, hit) starts at a multiple of `shaderGroupBaseAlignment` of the buffer's address, one
/// record each of `handleSize` rounded up to `shaderGroupHandleAlignment`.
fn shader_binding_table(
    shared: &Arc<DeviceShared>,
    pipeline: vk::Pipeline,
    group_count: u32,
    name: &str,
) -> Result<(Buffer, [vk::StridedDeviceAddressRegionKHR; 4]), GpuError> {
    let layout = shared
        .ray_pipeline
        .as_ref()
        .ok_or_else(|| GpuError::MissingFeature {
            device: shared.info.name.clone(),
            what: "a shader binding table".into(),
        })?;
    let handle_size = u64::from(layout.handle_size);
    let stride = align_up(handle_size, u64::from(layout.handle_alignment));
    let base = u64::from(layout.base_alignment);
    let region = align_up(stride, base);
    // SAFETY: the pipeline is live and has `group_count` groups.
    let handles = unsafe {
        layout.functions.get_ray_tracing_shader_group_handles(
            pipeline,
            0,
            group_count,
            (handle_size * u64::from(group_count)) as usize,
        )
    }
    .during("vkGetRayTracingShaderGroupHandlesKHR")?;
    // The allocation's own alignment may be less than the base alignment: room to move the table.
    let size = region * u64::from(group_count) + base;
    let mut table = Buffer::new(
        shared,
        BufferDesc::upload(
            &format!("{name} shader binding table"),
            size,
            BufferUsage::SHADER_BINDING_TABLE,
        ),
    )?;
    let address = table.device_address()?;
    let start = align_up(address, base) - address;
    let mut bytes = vec![0u8; size as usize];
    for (group, handle) in handles.chunks(handle_size as usize).enumerate() {
        let at = (start + region * group as u64) as usize;
        bytes[at..at + handle.len()].copy_from_slice(handle);
    }
    table.write(&bytes)?;
    let region_of = |group: u64| {
        vk::StridedDeviceAddressRegionKHR::default()
            .device_address(address + start + region * group)
            .stride(stride)
            .size(stride)
    };
    Ok((
        table,
        [
            region_of(0),
            region_of(1),
            region_of(2),
            vk::StridedDeviceAddressRegionKHR::default(),
        ],
    ))
}

impl Drop for RayTracingPipeline {
    fn drop(&mut self) {
        // SAFETY: no pending work uses the pipeline.
        unsafe { self.layout.shared.device.destroy_pipeline(self.raw, None) };
    }
}
