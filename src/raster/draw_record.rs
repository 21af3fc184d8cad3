//! Recording one strip of a draw into one submit: target barriers (first use, or after the
//! previous draw's last use), then
//! - deferred (the lacquer draw): the G-buffer pass with the viewport moved to the strip, then the
//!   shading pass (coverage.frag: background and coverage depth; shade.frag) into a
//!   single-sampled image;
//! - forward (the benchmark's trivial shader): the background and mesh passes with an MSAA resolve;
//!
//! and the strip's image copied to its rows of the readback buffer,
//!
//! with the timestamps around each.

use crate::gpu::{
    Access, DescriptorSet, GpuContext, GraphicsPipeline, Image, ImageUse, Layout, Recorder,
    RenderTargets, TimestampPool,
};
use crate::raster::camera::PixelRect;
use crate::raster::draw::DrawTimings;
use crate::raster::draw_targets::{Attachments, DrawTargets};
use crate::raster::gpu_mesh::GpuMesh;
use crate::{Error, Result};

/// Timestamps: start, before the pass, after the pass (and the shading), after the copy. None
/// inside the pass: on llvmpipe a timestamp there ends the binned scene, so the pass after it
/// reloads the multisampled targets and a timed draw would cost more than an untimed one.
pub(crate) const TIMESTAMPS: u32 = 4;

/// The image rows one submit draws: `rows` rows from `first_row` of an image of the given size.
#[derive(Clone, Copy)]
pub(crate) struct Strip {
    pub first_row: u32,
    pub rows: u32,
    pub image_width: u32,
    pub image_height: u32,
}

/// The passes of one draw.
pub(crate) enum Passes<'a> {
    Deferred(DeferredPasses<'a>),
    Forward {
        background: Option<(&'a GraphicsPipeline, &'a DescriptorSet)>,
        mesh_pipeline: &'a GraphicsPipeline,
        objects: Vec<(&'a GpuMesh, &'a DescriptorSet)>,
        clear_color: [f32; 4],
    },
}

/// The lacquer draw's passes.
pub(crate) struct DeferredPasses<'a> {
    pub gbuffer_pipeline: &'a GraphicsPipeline,
    pub objects: Vec<(&'a GpuMesh, &'a DescriptorSet)>,
    /// coverage.frag and shade.frag, sharing one descriptor set.
    pub coverage_pipeline: &'a GraphicsPipeline,
    pub shade_pipeline: &'a GraphicsPipeline,
    pub shade_set: &'a DescriptorSet,
    /// Image pixels that may be covered (the meshes' screen bounds): the shading pass touches
    /// only these, the rest keep the clear colour.
    pub shaded: PixelRect,
    /// Whether the coverage draw fills every pixel (it writes the background), not only
    /// `shaded`.
    pub coverage_everywhere: bool,
    pub clear_color: [f32; 4],
}

/// Everything one submit draws with.
pub(crate) struct RecordedDraw<'a> {
    pub targets: &'a DrawTargets,
    pub strip: Strip,
    pub passes: Passes<'a>,
    pub stamps: Option<&'a TimestampPool>,
}

const COLOR_ATTACHMENT: ImageUse =
    ImageUse::new(Access::ColorAttachmentWrite, Layout::ColorAttachment);
const DEPTH_ATTACHMENT: ImageUse =
    ImageUse::new(Access::DepthAttachmentWrite, Layout::DepthAttachment);

fn discard(access: Access) -> ImageUse {
    ImageUse::new(access, Layout::Undefined)
}

pub(crate) fn record_and_submit(gpu: &GpuContext, draw: &RecordedDraw<'_>) -> Result<()> {
    let mismatch = || Error::invalid("render targets", "of the other kind", "internal error");
    match (&draw.passes, &draw.targets.attachments) {
        (Passes::Deferred(_), Attachments::Deferred { .. })
        | (Passes::Forward { .. }, Attachments::Forward { .. }) => {}
        _ => return Err(mismatch()),
    }
    gpu.submit_and_wait(|rec| {
        mark(rec, draw.stamps, 0);
        match (&draw.passes, &draw.targets.attachments) {
            (
                Passes::Deferred(passes),
                Attachments::Deferred {
                    position,
                    normal,
                    output,
                    coverage,
                },
            ) => record_deferred(
                rec,
                draw,
                DeferredTargets {
                    gbuffer: [position, normal],
                    output,
                    coverage,
                },
                passes,
            ),
            (
                Passes::Forward {
                    background,
                    mesh_pipeline,
                    objects,
                    clear_color,
                },
                Attachments::Forward { color, resolve },
            ) => record_forward(
                rec,
                draw,
                (color, resolve.as_ref()),
                *background,
                mesh_pipeline,
                objects,
                *clear_color,
            ),
            // Checked above.
            _ => {}
        }
        mark(rec, draw.stamps, 3);
        Ok(())
    })?;
    Ok(())
}

fn mark(rec: &mut Recorder<'_>, stamps: Option<&TimestampPool>, index: u32) {
    if let Some(pool) = stamps {
        if index == 0 {
            rec.reset_timestamps(pool);
        }
        rec.timestamp(pool, index);
    }
}

/// The whole image's viewport, moved up so the target holds this strip's rows: every pixel keeps
/// the position (and sample positions) it has in an undivided draw.
fn set_strip_viewport(rec: &mut Recorder<'_>, strip: Strip) {
    rec.set_viewport(
        0.0,
        -(strip.first_row as f32),
        strip.image_width as f32,
        strip.image_height as f32,
    );
}

fn draw_objects(
    rec: &mut Recorder<'_>,
    pipeline: &GraphicsPipeline,
    objects: &[(&GpuMesh, &DescriptorSet)],
) {
    for (mesh, set) in objects {
        rec.bind_graphics(pipeline, set);
        rec.bind_mesh_buffers(&mesh.vertices, &mesh.indices);
        rec.draw_indexed(mesh.index_count);
    }
}

struct DeferredTargets<'a> {
    gbuffer: [&'a Image; 2],
    output: &'a Image,
    coverage: &'a Image,
}

fn record_deferred(
    rec: &mut Recorder<'_>,
    draw: &RecordedDraw<'_>,
    images: DeferredTargets<'_>,
    passes: &DeferredPasses<'_>,
) {
    let DeferredPasses {
        gbuffer_pipeline,
        objects,
        coverage_pipeline,
        shade_pipeline,
        shade_set,
        shaded,
        coverage_everywhere,
        clear_color,
    } = passes;
    let (shaded, coverage_everywhere, clear_color) = (*shaded, *coverage_everywhere, *clear_color);
    let targets = draw.targets;
    let shader_read = ImageUse::new(Access::GraphicsShaderRead, Layout::ShaderRead);
    // First use: nothing to wait for. Reuse: the previous strip's or draw's shading pass read the
    // G-buffer, its depth tests wrote both depth targets and its copy read the output and wrote
    // the readback buffer.
    let (gbuffer_before, depth_before, output_before) = if targets.used {
        (
            Access::GraphicsShaderRead,
            Access::DepthAttachmentWrite,
            Access::TransferRead,
        )
    } else {
        (Access::Nothing, Access::Nothing, Access::Nothing)
    };
    for image in images.gbuffer {
        rec.image_barrier(image, discard(gbuffer_before), COLOR_ATTACHMENT);
    }
    for depth in [&targets.depth, images.coverage] {
        rec.image_barrier(depth, discard(depth_before), DEPTH_ATTACHMENT);
    }
    rec.image_barrier(images.output, discard(output_before), COLOR_ATTACHMENT);
    if targets.used {
        rec.memory_barrier(Access::TransferWrite, Access::TransferWrite);
    }
    mark(rec, draw.stamps, 1);
    rec.begin_rendering(&RenderTargets {
        colors: &images.gbuffer,
        // Both cleared: the shading pass compares every sample's normal (llvmpipe evaluates both
        // sides of a branch), and a comparison with uncleared memory is a use of uninitialised
        // values, which valgrind reports in the C API tests.
        cleared_colors: 2,
        resolve: None,
        depth: Some(&targets.depth),
        // w = 0: no object covers the sample.
        clear_color: [0.0; 4],
    });
    set_strip_viewport(rec, draw.strip);
    draw_objects(rec, gbuffer_pipeline, objects);
    rec.end_rendering();
    for image in images.gbuffer {
        rec.image_barrier(image, COLOR_ATTACHMENT, shader_read);
    }
    rec.begin_rendering(&RenderTargets {
        colors: &[images.output],
        cleared_colors: 1,
        resolve: None,
        depth: Some(images.coverage),
        // The background where it is a colour (or transparent); coverage.frag draws the
        // environment one.
        clear_color,
    });
    set_strip_viewport(rec, draw.strip);
    let strip = draw.strip;
    // `shaded` in target rows (the target holds image rows first_row..).
    let rows = (
        shaded.y0.max(strip.first_row),
        shaded.y1.min(strip.first_row + strip.rows),
    );
    let in_strip = (rows.0 < rows.1 && !shaded.is_empty()).then(|| {
        (
            shaded.x0,
            rows.0 - strip.first_row,
            shaded.x1 - shaded.x0,
            rows.1 - rows.0,
        )
    });
    if coverage_everywhere {
        rec.bind_graphics(coverage_pipeline, shade_set);
        rec.draw(3);
    }
    if let Some((x, y, width, height)) = in_strip {
        rec.set_scissor(x, y, width, height);
        let pipelines: &[&GraphicsPipeline] = match coverage_everywhere {
            true => &[shade_pipeline],
            false => &[coverage_pipeline, shade_pipeline],
        };
        for pipeline in pipelines {
            rec.bind_graphics(pipeline, shade_set);
            rec.draw(3);
        }
    }
    rec.end_rendering();
    mark(rec, draw.stamps, 2);
    copy_out(rec, draw, images.output);
}

/// The strip's single-sampled image to its rows of the readback buffer, visible to the host.
fn copy_out(rec: &mut Recorder<'_>, draw: &RecordedDraw<'_>, image: &Image) {
    rec.image_barrier(
        image,
        COLOR_ATTACHMENT,
        ImageUse::new(Access::TransferRead, Layout::TransferSrc),
    );
    let strip = draw.strip;
    let row_bytes = u64::from(strip.image_width) * 16;
    rec.copy_image_rows_to_buffer(
        image,
        strip.rows,
        &draw.targets.readback,
        u64::from(strip.first_row) * row_bytes,
    );
    rec.memory_barrier(Access::TransferWrite, Access::HostRead);
}

fn record_forward(
    rec: &mut Recorder<'_>,
    draw: &RecordedDraw<'_>,
    (color, resolve): (&Image, Option<&Image>),
    background: Option<(&GraphicsPipeline, &DescriptorSet)>,
    mesh_pipeline: &GraphicsPipeline,
    objects: &[(&GpuMesh, &DescriptorSet)],
    clear_color: [f32; 4],
) {
    let targets = draw.targets;
    // First use: nothing to wait for. Reuse: the previous draw's last access to each target.
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
    match resolve {
        Some(resolve) => {
            // The MSAA samples were last written as an attachment; the resolve image was
            // last read by the copy.
            rec.image_barrier(color, discard(color_before), COLOR_ATTACHMENT);
            rec.image_barrier(resolve, discard(output_before), COLOR_ATTACHMENT);
        }
        None => rec.image_barrier(color, discard(output_before), COLOR_ATTACHMENT),
    }
    rec.image_barrier(&targets.depth, discard(depth_before), DEPTH_ATTACHMENT);
    if targets.used {
        // The previous copy-out wrote the readback buffer; this one writes it again.
        rec.memory_barrier(readback_before, Access::TransferWrite);
    }
    mark(rec, draw.stamps, 1);
    rec.begin_rendering(&RenderTargets {
        colors: &[color],
        cleared_colors: 1,
        resolve,
        depth: Some(&targets.depth),
        clear_color,
    });
    set_strip_viewport(rec, draw.strip);
    if let Some((pipeline, set)) = background {
        rec.bind_graphics(pipeline, set);
        rec.draw(3);
    }
    draw_objects(rec, mesh_pipeline, objects);
    rec.end_rendering();
    mark(rec, draw.stamps, 2);
    copy_out(rec, draw, resolve.unwrap_or(color));
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
