//! Recording commands. A [`Recorder`] wraps one command buffer between begin and end; its methods
//! are the whole vocabulary the renderer uses, so no raw handle leaves `gpu/`.
//!
//! Synchronisation is explicit: every hazard between two uses is a barrier named by the two
//! [`Access`]es, mapped to synchronization2 stages and access masks in `conv.rs`.

use super::buffer::Buffer;
use super::conv::{self, Access, Layout};
use super::image::Image;
use super::pipeline::{ComputePipeline, DescriptorSet, GraphicsPipeline, PipelineLayout};
use super::query::TimestampPool;
use super::ray_pipeline::RayTracingPipeline;
use ash::vk;

/// A use of an image: the access and the layout it must be in.
#[derive(Clone, Copy, Debug)]
pub struct ImageUse {
    pub access: Access,
    pub layout: Layout,
}

impl ImageUse {
    pub const fn new(access: Access, layout: Layout) -> Self {
        Self { access, layout }
    }
}

/// The attachments of one dynamic-rendering pass.
pub struct RenderTargets<'a> {
    /// Multisampled (or single-sampled) colour targets in location order; at least one. The
    /// first `clear_colors.len()` are cleared, colour i to `clear_colors[i]`; the rest start
    /// undefined (every sample a draw covers is written, and the rest are never read).
    pub colors: &'a [&'a Image],
    pub clear_colors: &'a [[f32; 4]],
    /// Single-sampled image the first colour is resolved into (averaged) when it is multisampled.
    pub resolve: Option<&'a Image>,
    /// Cleared to 1; None for a pass without depth (its colour targets may differ in samples).
    pub depth: Option<&'a Image>,
}

pub struct Recorder<'a> {
    pub(crate) device: &'a ash::Device,
    pub(crate) cmd: vk::CommandBuffer,
}

impl Recorder<'_> {
    /// Resets every query of `pool`; record before the first `timestamp` of a submit.
    pub fn reset_timestamps(&mut self, pool: &TimestampPool) {
        // SAFETY: recording; the pool is live and not in use by pending work.
        unsafe {
            self.device
                .cmd_reset_query_pool(self.cmd, pool.raw, 0, pool.capacity())
        };
    }

    /// Writes timestamp `index` once all previously recorded work has completed (later than that
    /// after a graphics pass where the driver has quirk `late_timestamps_after_graphics`).
    pub fn timestamp(&mut self, pool: &TimestampPool, index: u32) {
        if index >= pool.capacity() {
            return;
        }
        // SAFETY: recording; index is within the pool, reset earlier in this command buffer.
        unsafe {
            self.device.cmd_write_timestamp2(
                self.cmd,
                vk::PipelineStageFlags2::ALL_COMMANDS,
                pool.raw,
                index,
            )
        };
    }

    /// A global memory barrier: everything written with `from` is visible to `to`.
    pub fn memory_barrier(&mut self, from: Access, to: Access) {
        let (src_stage, src_access) = conv::stage_access(from);
        let (dst_stage, dst_access) = conv::stage_access(to);
        let barrier = vk::MemoryBarrier2::default()
            .src_stage_mask(src_stage)
            .src_access_mask(src_access)
            .dst_stage_mask(dst_stage)
            .dst_access_mask(dst_access);
        let info = vk::DependencyInfo::default().memory_barriers(std::slice::from_ref(&barrier));
        // SAFETY: recording into a command buffer in the recording state.
        unsafe { self.device.cmd_pipeline_barrier2(self.cmd, &info) };
    }

    /// An image barrier with a layout transition (all layers).
    pub fn image_barrier(&mut self, image: &Image, from: ImageUse, to: ImageUse) {
        let (src_stage, src_access) = conv::stage_access(from.access);
        let (dst_stage, dst_access) = conv::stage_access(to.access);
        let barrier = vk::ImageMemoryBarrier2::default()
            .src_stage_mask(src_stage)
            .src_access_mask(src_access)
            .dst_stage_mask(dst_stage)
            .dst_access_mask(dst_access)
            .old_layout(conv::image_layout(from.layout))
            .new_layout(conv::image_layout(to.layout))
            .src_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .dst_queue_family_index(vk::QUEUE_FAMILY_IGNORED)
            .image(image.raw)
            .subresource_range(image.full_range());
        let info =
            vk::DependencyInfo::default().image_memory_barriers(std::slice::from_ref(&barrier));
        // SAFETY: recording; the image is live for the duration of the submit.
        unsafe { self.device.cmd_pipeline_barrier2(self.cmd, &info) };
    }

    /// Begins dynamic rendering into `targets` (colour cleared, depth cleared to 1), with the
    /// viewport and scissor covering the whole target. The images must already be in the
    /// attachment layouts.
    pub fn begin_rendering(&mut self, targets: &RenderTargets<'_>) {
        // The render area is the first colour target (or the depth target without colour).
        let extent = match (targets.colors.first().copied(), targets.depth) {
            (Some(image), _) | (None, Some(image)) => vk::Extent2D {
                width: image.desc().width,
                height: image.desc().height,
            },
            (None, None) => vk::Extent2D::default(),
        };
        let mut colors: Vec<vk::RenderingAttachmentInfo> = targets
            .colors
            .iter()
            .enumerate()
            .map(|(i, image)| {
                vk::RenderingAttachmentInfo::default()
                    .image_view(image.view)
                    .image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                    .load_op(if i < targets.clear_colors.len() {
                        vk::AttachmentLoadOp::CLEAR
                    } else {
                        vk::AttachmentLoadOp::DONT_CARE
                    })
                    .store_op(vk::AttachmentStoreOp::STORE)
                    .clear_value(vk::ClearValue {
                        color: vk::ClearColorValue {
                            float32: targets.clear_colors.get(i).copied().unwrap_or_default(),
                        },
                    })
            })
            .collect();
        if let (Some(resolve), Some(first)) = (targets.resolve, colors.first_mut()) {
            *first = first
                .resolve_mode(vk::ResolveModeFlags::AVERAGE)
                .resolve_image_view(resolve.view)
                .resolve_image_layout(vk::ImageLayout::COLOR_ATTACHMENT_OPTIMAL)
                // The multisampled samples are not needed after the resolve.
                .store_op(vk::AttachmentStoreOp::DONT_CARE);
        }
        let depth = targets.depth.map(|depth| {
            vk::RenderingAttachmentInfo::default()
                .image_view(depth.view)
                .image_layout(vk::ImageLayout::DEPTH_ATTACHMENT_OPTIMAL)
                .load_op(vk::AttachmentLoadOp::CLEAR)
                .store_op(vk::AttachmentStoreOp::DONT_CARE)
                .clear_value(vk::ClearValue {
                    depth_stencil: vk::ClearDepthStencilValue {
                        depth: 1.0,
                        stencil: 0,
                    },
                })
        });
        let mut info = vk::RenderingInfo::default()
            .render_area(vk::Rect2D {
                offset: vk::Offset2D { x: 0, y: 0 },
                extent,
            })
            .layer_count(1)
            .color_attachments(&colors);
        if let Some(depth) = &depth {
            info = info.depth_attachment(depth);
        }
        let viewport = vk::Viewport {
            x: 0.0,
            y: 0.0,
            width: extent.width as f32,
            height: extent.height as f32,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        let scissor = vk::Rect2D {
            offset: vk::Offset2D { x: 0, y: 0 },
            extent,
        };
        // SAFETY: recording; attachments are live and in the layouts named above.
        unsafe {
            self.device.cmd_begin_rendering(self.cmd, &info);
            self.device
                .cmd_set_viewport(self.cmd, 0, std::slice::from_ref(&viewport));
            self.device
                .cmd_set_scissor(self.cmd, 0, std::slice::from_ref(&scissor));
        }
    }

    /// Replaces the viewport `begin_rendering` set (the scissor stays the whole target): a target
    /// holding rows `y..` of a taller image is drawn with the image's viewport moved up by `y`.
    pub fn set_viewport(&mut self, x: f32, y: f32, width: f32, height: f32) {
        let viewport = vk::Viewport {
            x,
            y,
            width,
            height,
            min_depth: 0.0,
            max_depth: 1.0,
        };
        // SAFETY: recording; the pipeline declares the viewport dynamic.
        unsafe {
            self.device
                .cmd_set_viewport(self.cmd, 0, std::slice::from_ref(&viewport))
        };
    }

    /// Limits the following draws to the target pixels `x..x + width`, `y..y + height`
    /// (`begin_rendering` sets the whole target).
    pub fn set_scissor(&mut self, x: u32, y: u32, width: u32, height: u32) {
        let scissor = vk::Rect2D {
            offset: vk::Offset2D {
                x: x.min(i32::MAX as u32) as i32,
                y: y.min(i32::MAX as u32) as i32,
            },
            extent: vk::Extent2D { width, height },
        };
        // SAFETY: recording; the pipelines declare the scissor dynamic.
        unsafe {
            self.device
                .cmd_set_scissor(self.cmd, 0, std::slice::from_ref(&scissor))
        };
    }

    pub fn end_rendering(&mut self) {
        // SAFETY: matches begin_rendering.
        unsafe { self.device.cmd_end_rendering(self.cmd) };
    }

    pub fn bind_graphics(&mut self, pipeline: &GraphicsPipeline, set: &DescriptorSet) {
        let point = vk::PipelineBindPoint::GRAPHICS;
        self.bind(point, pipeline.raw, &pipeline.layout, set);
    }

    /// Binds a pipeline at `point` and its set 0.
    fn bind(
        &mut self,
        point: vk::PipelineBindPoint,
        pipeline: vk::Pipeline,
        layout: &PipelineLayout,
        set: &DescriptorSet,
    ) {
        // SAFETY: recording; pipeline and set are live and compatible (the set was made from
        // this layout).
        unsafe {
            self.device.cmd_bind_pipeline(self.cmd, point, pipeline);
            self.device.cmd_bind_descriptor_sets(
                self.cmd,
                point,
                layout.raw,
                0,
                std::slice::from_ref(&set.raw),
                &[],
            );
        }
    }

    /// Push constants for a pipeline of `layout`; `bytes` must fit its declared block.
    fn push(&mut self, layout: &PipelineLayout, bytes: &[u8]) {
        let len = bytes.len().min(layout.push_constant_size as usize);
        if len == 0 {
            return;
        }
        // SAFETY: recording; the range is within the layout's push constant block.
        unsafe {
            self.device
                .cmd_push_constants(self.cmd, layout.raw, layout.stages, 0, &bytes[..len])
        };
    }

    /// Binds the interleaved vertex buffer (binding 0) and the u32 index buffer.
    pub fn bind_mesh_buffers(&mut self, vertices: &Buffer, indices: &Buffer) {
        // SAFETY: recording; buffers are live for the submit.
        unsafe {
            self.device.cmd_bind_vertex_buffers(
                self.cmd,
                0,
                std::slice::from_ref(&vertices.raw),
                &[0],
            );
            self.device
                .cmd_bind_index_buffer(self.cmd, indices.raw, 0, vk::IndexType::UINT32);
        }
    }

    /// Draws `vertex_count` vertices with no vertex buffer (e.g. a full-screen triangle).
    pub fn draw(&mut self, vertex_count: u32) {
        // SAFETY: recording inside a rendering pass with a pipeline bound.
        unsafe { self.device.cmd_draw(self.cmd, vertex_count, 1, 0, 0) };
    }

    pub fn draw_indexed(&mut self, index_count: u32) {
        // SAFETY: recording inside a rendering pass with a pipeline and buffers bound.
        unsafe {
            self.device
                .cmd_draw_indexed(self.cmd, index_count, 1, 0, 0, 0)
        };
    }

    pub fn bind_compute(&mut self, pipeline: &ComputePipeline, set: &DescriptorSet) {
        let point = vk::PipelineBindPoint::COMPUTE;
        self.bind(point, pipeline.raw, &pipeline.layout, set);
    }

    /// Push constants for a compute pipeline; `bytes` must fit its declared block.
    pub fn push_constants(&mut self, pipeline: &ComputePipeline, bytes: &[u8]) {
        self.push(&pipeline.layout, bytes);
    }

    pub fn bind_ray_tracing(&mut self, pipeline: &RayTracingPipeline, set: &DescriptorSet) {
        let point = vk::PipelineBindPoint::RAY_TRACING_KHR;
        self.bind(point, pipeline.raw, &pipeline.layout, set);
    }

    /// Push constants for a ray-tracing pipeline; `bytes` must fit its declared block.
    pub fn push_ray_tracing_constants(&mut self, pipeline: &RayTracingPipeline, bytes: &[u8]) {
        self.push(&pipeline.layout, bytes);
    }

    /// Launches `pipeline`'s ray generation shader `width` × `height` times (it is bound).
    pub fn trace_rays(&mut self, pipeline: &RayTracingPipeline, width: u32, height: u32) {
        let Some(functions) = pipeline.layout.shared.ray_pipeline.as_ref() else {
            // A RayTracingPipeline exists only on a device with the functions.
            return;
        };
        let [raygen, miss, hit, callable] = &pipeline.regions;
        // SAFETY: recording with the pipeline bound; its table's regions are live with it.
        unsafe {
            functions
                .functions
                .cmd_trace_rays(self.cmd, raygen, miss, hit, callable, width, height, 1)
        };
    }

    pub fn dispatch(&mut self, x: u32, y: u32, z: u32) {
        // SAFETY: recording with a compute pipeline bound.
        unsafe { self.device.cmd_dispatch(self.cmd, x, y, z) };
    }

    /// A dispatch whose group counts (three u32) the GPU reads from `buffer` at byte `offset` (a
    /// multiple of 4), e.g. written by an earlier dispatch behind an `IndirectCommandRead` barrier.
    pub fn dispatch_indirect(&mut self, buffer: &Buffer, offset: u64) {
        // SAFETY: recording with a compute pipeline bound; the buffer was made with INDIRECT usage.
        unsafe {
            self.device
                .cmd_dispatch_indirect(self.cmd, buffer.raw, offset)
        };
    }

    /// Copies every layer of a single-sampled image (in TransferSrc layout) to the start of
    /// `buffer`, tightly packed, layer after layer, row 0 first.
    pub fn copy_image_to_buffer(&mut self, image: &Image, buffer: &Buffer) {
        self.copy_image_rows_to_buffer(image, image.desc().height, buffer, 0);
    }

    /// Copies the first `rows` rows of a single-sampled 2D image (in TransferSrc layout) into
    /// `buffer` at byte `offset`, tightly packed.
    pub fn copy_image_rows_to_buffer(
        &mut self,
        image: &Image,
        rows: u32,
        buffer: &Buffer,
        offset: u64,
    ) {
        let mut region = whole_image_region(image);
        region.buffer_offset = offset;
        region.image_extent.height = rows.min(image.desc().height);
        // SAFETY: recording; the caller sizes `buffer` to hold `offset` plus the rows copied.
        unsafe {
            self.device.cmd_copy_image_to_buffer(
                self.cmd,
                image.raw,
                vk::ImageLayout::TRANSFER_SRC_OPTIMAL,
                buffer.raw,
                std::slice::from_ref(&region),
            )
        };
    }

    /// Copies all of `src` to the start of `dst`.
    pub fn copy_buffer(&mut self, src: &Buffer, dst: &Buffer) {
        let region = vk::BufferCopy {
            src_offset: 0,
            dst_offset: 0,
            size: src.size().min(dst.size()),
        };
        // SAFETY: recording; both buffers are live and the region fits both.
        unsafe {
            self.device
                .cmd_copy_buffer(self.cmd, src.raw, dst.raw, std::slice::from_ref(&region))
        };
    }

    /// Copies all of `src` into `dst` from byte `dst_offset`.
    pub fn copy_buffer_at(&mut self, src: &Buffer, dst: &Buffer, dst_offset: u64) {
        let region = vk::BufferCopy {
            src_offset: 0,
            dst_offset,
            size: src.size().min(dst.size().saturating_sub(dst_offset)),
        };
        // SAFETY: recording; both buffers are live and the region fits both.
        unsafe {
            self.device
                .cmd_copy_buffer(self.cmd, src.raw, dst.raw, std::slice::from_ref(&region))
        };
    }

    /// Fills every layer of `image` (in TransferDst layout) from `buffer`, tightly packed layer
    /// after layer, row 0 first: the inverse of `copy_image_to_buffer`.
    pub fn copy_buffer_to_image(&mut self, buffer: &Buffer, image: &Image) {
        let region = whole_image_region(image);
        // SAFETY: recording; the buffer holds image.byte_size() bytes and both are live.
        unsafe {
            self.device.cmd_copy_buffer_to_image(
                self.cmd,
                buffer.raw,
                image.raw,
                vk::ImageLayout::TRANSFER_DST_OPTIMAL,
                std::slice::from_ref(&region),
            )
        };
    }
}

/// Every layer of a colour image ⇄ a tightly packed buffer (layer after layer, row 0 first).
fn whole_image_region(image: &Image) -> vk::BufferImageCopy {
    let desc = image.desc();
    vk::BufferImageCopy::default()
        .image_subresource(
            vk::ImageSubresourceLayers::default()
                .aspect_mask(vk::ImageAspectFlags::COLOR)
                .mip_level(0)
                .base_array_layer(0)
                .layer_count(desc.layers),
        )
        .image_extent(vk::Extent3D {
            width: desc.width,
            height: desc.height,
            depth: 1,
        })
}
