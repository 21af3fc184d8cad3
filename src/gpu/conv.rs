//! Pure mappings between shikki's small vocabulary and Vulkan's flags. No `unsafe`, no state.

use ash::vk;

/// Texel formats shikki uses.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Format {
    /// Linear HDR colour: render targets, cube maps, readback.
    Rgba32Float,
    /// Depth buffer.
    Depth32Float,
}

/// The depth test of a pipeline: a fragment passes when `fragment depth <compare> stored depth`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct DepthTest {
    pub compare: DepthCompare,
    /// Whether passing fragments write their depth.
    pub write: bool,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthCompare {
    Less,
    LessOrEqual,
    Greater,
}

pub(crate) fn compare_op(compare: DepthCompare) -> vk::CompareOp {
    match compare {
        DepthCompare::Less => vk::CompareOp::LESS,
        DepthCompare::LessOrEqual => vk::CompareOp::LESS_OR_EQUAL,
        DepthCompare::Greater => vk::CompareOp::GREATER,
    }
}

/// How a piece of GPU memory was last touched or will next be touched; a barrier goes from one
/// `Access` to another. Each maps to one (stage, access) pair of synchronization2.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// Nothing before (first use).
    Nothing,
    /// Written by the host through a mapped pointer.
    HostWrite,
    /// Read by the host through a mapped pointer after a fence wait.
    HostRead,
    TransferRead,
    TransferWrite,
    ComputeShaderRead,
    ComputeShaderWrite,
    /// The arguments of an indirect dispatch or draw.
    IndirectCommandRead,
    /// Vertex and index fetch.
    VertexInput,
    /// Uniform or storage reads in the vertex or fragment stage.
    GraphicsShaderRead,
    ColorAttachmentWrite,
    DepthAttachmentWrite,
    /// An acceleration-structure build writing its structure.
    AccelerationStructureBuild,
    /// A top-level build reading the bottom-level structures.
    AccelerationStructureBuildRead,
    /// Ray queries in the fragment or compute stage.
    RayQuery,
    /// A ray-tracing pipeline's shaders reading images, uniforms or storage (including buffers
    /// by device address), or tracing against acceleration structures.
    RayTracingShaderRead,
    /// ... writing storage images or buffers.
    RayTracingShaderWrite,
    /// Reads in the fragment stage and a ray-tracing pipeline's shaders: the G-buffer, which the
    /// coverage draw and shade_rt*.rgen both read.
    FragmentAndRayTracingShaderRead,
}

pub(crate) fn stage_access(access: Access) -> (vk::PipelineStageFlags2, vk::AccessFlags2) {
    use vk::AccessFlags2 as A;
    use vk::PipelineStageFlags2 as S;
    match access {
        Access::Nothing => (S::NONE, A::NONE),
        Access::HostWrite => (S::HOST, A::HOST_WRITE),
        Access::HostRead => (S::HOST, A::HOST_READ),
        Access::TransferRead => (S::ALL_TRANSFER, A::TRANSFER_READ),
        Access::TransferWrite => (S::ALL_TRANSFER, A::TRANSFER_WRITE),
        Access::ComputeShaderRead => (
            S::COMPUTE_SHADER,
            A::SHADER_SAMPLED_READ | A::SHADER_STORAGE_READ | A::UNIFORM_READ,
        ),
        Access::ComputeShaderWrite => (S::COMPUTE_SHADER, A::SHADER_STORAGE_WRITE),
        Access::IndirectCommandRead => (S::DRAW_INDIRECT, A::INDIRECT_COMMAND_READ),
        Access::VertexInput => (
            S::VERTEX_ATTRIBUTE_INPUT | S::INDEX_INPUT,
            A::VERTEX_ATTRIBUTE_READ | A::INDEX_READ,
        ),
        Access::GraphicsShaderRead => (
            S::VERTEX_SHADER | S::FRAGMENT_SHADER,
            A::SHADER_SAMPLED_READ | A::SHADER_STORAGE_READ | A::UNIFORM_READ,
        ),
        Access::ColorAttachmentWrite => (
            S::COLOR_ATTACHMENT_OUTPUT,
            A::COLOR_ATTACHMENT_WRITE | A::COLOR_ATTACHMENT_READ,
        ),
        Access::DepthAttachmentWrite => (
            S::EARLY_FRAGMENT_TESTS | S::LATE_FRAGMENT_TESTS,
            A::DEPTH_STENCIL_ATTACHMENT_WRITE | A::DEPTH_STENCIL_ATTACHMENT_READ,
        ),
        Access::AccelerationStructureBuild => (
            S::ACCELERATION_STRUCTURE_BUILD_KHR,
            A::ACCELERATION_STRUCTURE_WRITE_KHR,
        ),
        Access::AccelerationStructureBuildRead => (
            S::ACCELERATION_STRUCTURE_BUILD_KHR,
            A::ACCELERATION_STRUCTURE_READ_KHR,
        ),
        Access::RayQuery => (
            S::FRAGMENT_SHADER | S::COMPUTE_SHADER,
            A::ACCELERATION_STRUCTURE_READ_KHR,
        ),
        Access::RayTracingShaderRead => (
            S::RAY_TRACING_SHADER_KHR,
            A::SHADER_SAMPLED_READ
                | A::SHADER_STORAGE_READ
                | A::UNIFORM_READ
                | A::ACCELERATION_STRUCTURE_READ_KHR,
        ),
        Access::RayTracingShaderWrite => (S::RAY_TRACING_SHADER_KHR, A::SHADER_STORAGE_WRITE),
        Access::FragmentAndRayTracingShaderRead => (
            S::FRAGMENT_SHADER | S::RAY_TRACING_SHADER_KHR,
            A::SHADER_SAMPLED_READ | A::SHADER_STORAGE_READ | A::UNIFORM_READ,
        ),
    }
}

/// Image layouts shikki moves between.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    Undefined,
    ColorAttachment,
    DepthAttachment,
    TransferSrc,
    TransferDst,
    ShaderRead,
    General,
}

pub(crate) fn image_layout(layout: Layout) -> vk::ImageLayout {
    match layout {
        Layout::Undefined => vk::ImageLayout::UNDEFINED,
        Layout::ColorAttachment => vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL,
        Layout::DepthAttachment => vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL,
        Layout::TransferSrc => vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
        Layout::TransferDst => vk::ImageLayout::TRANSFER_DST_OPTIMAL,
        Layout::ShaderRead => vk::ImageLayout::SHADER_READ_ONLY_OPTIMAL,
        Layout::General => vk::ImageLayout::GENERAL,
    }
}

pub(crate) fn vk_format(format: Format) -> vk::Format {
    match format {
        Format::Rgba32Float => vk::Format::R32G32B32A32_SFLOAT,
        Format::Depth32Float => vk::Format::D32_SFLOAT,
    }
}

pub(crate) fn aspect(format: Format) -> vk::ImageAspectFlags {
    match format {
        Format::Depth32Float => vk::ImageAspectFlags::DEPTH,
        Format::Rgba32Float => vk::ImageAspectFlags::COLOR,
    }
}

pub(crate) fn texel_bytes(format: Format) -> u64 {
    match format {
        Format::Rgba32Float => 16,
        Format::Depth32Float => 4,
    }
}

/// 1 or 4 → the flag; anything else is rejected earlier by the renderer.
pub(crate) fn sample_count_flag(samples: u32) -> vk::SampleCountFlags {
    match samples {
        2 => vk::SampleCountFlags::TYPE_2,
        4 => vk::SampleCountFlags::TYPE_4,
        8 => vk::SampleCountFlags::TYPE_8,
        16 => vk::SampleCountFlags::TYPE_16,
        _ => vk::SampleCountFlags::TYPE_1,
    }
}

pub(crate) fn sample_counts(flags: vk::SampleCountFlags) -> Vec<u32> {
    [1u32, 2, 4, 8, 16, 32, 64]
        .into_iter()
        .filter(|&n| flags.contains(sample_count_flag_exact(n)))
        .collect()
}

fn sample_count_flag_exact(samples: u32) -> vk::SampleCountFlags {
    vk::SampleCountFlags::from_raw(samples)
}

pub(crate) fn device_type_name(t: vk::PhysicalDeviceType) -> &'static str {
    match t {
        vk::PhysicalDeviceType::DISCRETE_GPU => "discrete GPU",
        vk::PhysicalDeviceType::INTEGRATED_GPU => "integrated GPU",
        vk::PhysicalDeviceType::VIRTUAL_GPU => "virtual GPU",
        vk::PhysicalDeviceType::CPU => "CPU",
        _ => "other",
    }
}
