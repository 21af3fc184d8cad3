//! Recording one strip of a draw into one submit: target barriers (first use, or after the
//! previous draw's last use), the background and mesh passes with the viewport moved to the strip,
//! the resolved strip copied to its rows of the readback buffer, and the timestamps around each.

use crate::gpu::{
    Access, DescriptorSet, GpuContext, GraphicsPipeline, ImageUse, Layout, RenderTargets,
    TimestampPool,
};
use crate::raster::draw::DrawTimings;
use crate::raster::draw_targets::DrawTargets;
use crate::raster::gpu_mesh::GpuMesh;
use crate::Result;

/// Timestamps: start, before the pass, after the pass, after the copy. None inside the pass: on
/// llvmpipe a timestamp there ends the binned scene, so the pass after it reloads the
/// multisampled targets and a timed draw would cost more than an untimed one.
pub(crate) const TIMESTAMPS: u32 = 4;

/// The image rows one submit draws: `rows` rows from `first_row` of an image of the given size.
#[derive(Clone, Copy)]
pub(crate) struct Strip {
    pub first_row: u32,
    pub rows: u32,
    pub image_width: u32,
    pub image_height: u32,
}

/// Everything one submit draws with.
pub(crate) struct RecordedDraw<'a> {
    pub targets: &'a DrawTargets,
    pub strip: Strip,
    pub background: Option<(&'a GraphicsPipeline, &'a DescriptorSet)>,
    pub mesh_pipeline: &'a GraphicsPipeline,
    pub objects: Vec<(&'a GpuMesh, &'a DescriptorSet)>,
    pub clear_color: [f32; 4],
    pub stamps: Option<&'a TimestampPool>,
}

pub(crate) fn record_and_submit(gpu: &GpuContext, draw: &RecordedDraw<'_>) -> Result<()> {
    let targets = draw.targets;
    // First use: nothing to wait for. Reuse: the previous draw's last access to each target
    // (pipeline barriers order against earlier submissions on the queue too).
    let (color_before, output_before, depth_before, readback_before) = if targets.used {
        (
            Access::ColorAttachmentWrite,
            Access::TransferRead,
            Access::DepthAttachmentWrite,
            Access::TransferWrite,
        )
    } else {
        (
            Access::Nothing,
            Access::Nothing,
            Access::Nothing,
            Access::Nothing,
        )
    };
    let discard = |access| ImageUse::new(access, Layout::Undefined);
    let color_attachment = ImageUse::new(Access::ColorAttachmentWrite, Layout::ColorAttachment);
    let depth_attachment = ImageUse::new(Access::DepthAttachmentWrite, Layout::DepthAttachment);
    let transfer_src = ImageUse::new(Access::TransferRead, Layout::TransferSrc);
    let output = targets.output();
    gpu.submit_and_wait(|rec| {
        let mark = |rec: &mut crate::gpu::Recorder<'_>, index: u32| {
            if let Some(pool) = draw.stamps {
                if index == 0 {
                    rec.reset_timestamps(pool);
                }
                rec.timestamp(pool, index);
            }
        };
        mark(rec, 0);
        match &targets.resolve {
            Some(resolve) => {
                // The MSAA samples were last written as an attachment; the resolve image was
                // last read by the copy.
                rec.image_barrier(&targets.color, discard(color_before), color_attachment);
                rec.image_barrier(resolve, discard(output_before), color_attachment);
            }
            None => rec.image_barrier(&targets.color, discard(output_before), color_attachment),
        }
        rec.image_barrier(&targets.depth, discard(depth_before), depth_attachment);
        if targets.used {
            // The previous copy-out wrote the readback buffer; this one writes it again.
            rec.memory_barrier(readback_before, Access::TransferWrite);
        }
        mark(rec, 1);
        rec.begin_rendering(&RenderTargets {
            color: &targets.color,
            resolve: targets.resolve.as_ref(),
            depth: &targets.depth,
            clear_color: draw.clear_color,
        });
        // The whole image's viewport, moved up so the target holds this strip's rows: every
        // pixel keeps the position (and sample positions) it has in an undivided draw.
        let strip = draw.strip;
        rec.set_viewport(
            0.0,
            -(strip.first_row as f32),
            strip.image_width as f32,
            strip.image_height as f32,
        );
        if let Some((pipeline, set)) = draw.background {
            rec.bind_graphics(pipeline, set);
            rec.draw(3);
        }
        for (mesh, set) in &draw.objects {
            rec.bind_graphics(draw.mesh_pipeline, set);
            rec.bind_mesh_buffers(&mesh.vertices, &mesh.indices);
            rec.draw_indexed(mesh.index_count);
        }
        rec.end_rendering();
        mark(rec, 2);
        rec.image_barrier(output, color_attachment, transfer_src);
        let row_bytes = u64::from(strip.image_width) * 16;
        rec.copy_image_rows_to_buffer(
            output,
            strip.rows,
            &targets.readback,
            u64::from(strip.first_row) * row_bytes,
        );
        rec.memory_barrier(Access::TransferWrite, Access::HostRead);
        mark(rec, 3);
        Ok(())
    })?;
    Ok(())
}

pub(crate) fn timings_from(ns: &[f64]) -> DrawTimings {
    let span = |a: usize, b: usize| match (ns.get(a), ns.get(b)) {
        (Some(x), Some(y)) => (y - x).max(0.0) * 1e-9,
        _ => 0.0,
    };
    DrawTimings {
        pass: span(1, 2),
        copy_out: span(2, 3),
        total: span(0, 3),
    }
}
