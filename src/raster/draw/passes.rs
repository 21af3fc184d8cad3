//! The passes of one strip of a draw, one function each, recorded into one submit:
//!
//! - the lacquer draw (deferred): barriers → [`gbuffer_pass`] → [`shading_pass`] (its
//!   [`coverage_draw`], then its [`shade_draw`], or on a device that traces rays by a
//!   ray-tracing pipeline its [`trace_pass`]) → [`copy_out`] (of the integral image too where
//!   rays are traced);
//! - the forward draw (the benchmark's trivial shader): barriers → [`forward_pass`] (background,
//!   meshes, MSAA resolve) → [`copy_out`];
//!
//! with a timestamp before and after the drawing and after the copy.

use super::gpu_mesh::GpuMesh;
use super::targets::{Deferred, DrawTargets, Forward, IntegralTarget};
use super::types::DrawTimings;
use crate::gpu::shaders::interface::TraceOrigin;
use crate::gpu::{
    Access, Buffer, DescriptorSet, GpuContext, GraphicsPipeline, Image, ImageUse, Layout,
    RayTracingPipeline, Recorder, RenderTargets, TimestampPool,
};
use crate::raster::camera::PixelRect;
use crate::Result;

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

/// The strips of an image `width` × `height` drawn `strip_rows` rows at a time, top first.
pub(crate) fn strips(width: u32, height: u32, strip_rows: u32) -> impl Iterator<Item = Strip> {
    (0..height)
        .step_by(strip_rows as usize)
        .map(move |first_row| Strip {
            first_row,
            rows: strip_rows.min(height - first_row),
            image_width: width,
            image_height: height,
        })
}

/// One mesh and its descriptor set (its frame and the environment).
pub(crate) type DrawnMesh<'a> = (&'a GpuMesh, &'a DescriptorSet);

/// What the lacquer draw's passes draw with, the same for every strip.
pub(crate) struct DeferredPasses<'a> {
    pub gbuffer: &'a GraphicsPipeline,
    pub objects: &'a [DrawnMesh<'a>],
    /// coverage.frag and the shading (shade.frag, sharing its descriptor set, or shade_rt*.rgen).
    pub coverage: &'a GraphicsPipeline,
    pub shade: Shading<'a>,
    pub shade_set: &'a DescriptorSet,
    /// Image pixels that may be covered (the meshes' screen bounds): the shading pass touches
    /// only these, the rest keep the clear colour.
    pub shaded: PixelRect,
    /// Whether the coverage draw fills every pixel (it draws the environment background), not
    /// only `shaded`.
    pub coverage_everywhere: bool,
    pub clear_color: [f32; 4],
    /// The shading pass traces rays: its top-level structure was built by an earlier submit,
    /// and it writes the integral image too (the targets hold one).
    pub ray_traced: bool,
    /// The device shades ray-traced draws in a ray-tracing pipeline: an earlier draw's may have
    /// read these targets' G-buffer.
    pub ray_pipeline_device: bool,
}

/// How the shading pass shades the covered pixels after its coverage draw.
pub(crate) enum Shading<'a> {
    /// shade*.frag behind the coverage draw's early depth test, with ray queries if it traces.
    Fragment(&'a GraphicsPipeline),
    /// shade_rt*.rgen, one launch per pixel of the shaded rectangle, writing the image and the
    /// integral image as storage images: a device that traces rays by a ray-tracing pipeline
    /// (`RayQuery::Pipeline`; its fragment shaders cannot trace). Its set adds those two images.
    RayPipeline(&'a RayTracingPipeline, &'a DescriptorSet),
}

impl DeferredPasses<'_> {
    fn ray_pipeline(&self) -> bool {
        matches!(self.shade, Shading::RayPipeline(..))
    }

    /// The last use of the shading pass's outputs before the copy-out.
    fn shaded_use(&self) -> ImageUse {
        match self.ray_pipeline() {
            true => ImageUse::new(Access::RayTracingShaderWrite, Layout::General),
            false => COLOR_ATTACHMENT,
        }
    }
}

/// The integral image's value where no object covers the pixel: no integral, and a variance of
/// −1, which no covered pixel has (shade_body.glsl).
pub(crate) const NO_INTEGRAL: [f32; 4] = [0.0, 0.0, 0.0, -1.0];

/// What the forward draw's pass draws with, the same for every strip.
pub(crate) struct ForwardPasses<'a> {
    pub background: Option<(&'a GraphicsPipeline, &'a DescriptorSet)>,
    pub mesh: &'a GraphicsPipeline,
    pub objects: &'a [DrawnMesh<'a>],
    pub clear_color: [f32; 4],
}

const COLOR_ATTACHMENT: ImageUse =
    ImageUse::new(Access::ColorAttachmentWrite, Layout::ColorAttachment);
const DEPTH_ATTACHMENT: ImageUse =
    ImageUse::new(Access::DepthAttachmentWrite, Layout::DepthAttachment);

fn discard(access: Access) -> ImageUse {
    ImageUse::new(access, Layout::Undefined)
}

/// Records and submits one strip of the lacquer draw, and waits for it.
pub(crate) fn record_deferred(
    gpu: &GpuContext,
    targets: &DrawTargets<Deferred>,
    passes: &DeferredPasses<'_>,
    strip: Strip,
    stamps: Option<&TimestampPool>,
) -> Result<()> {
    gpu.submit_and_wait(|rec| {
        mark(rec, stamps, 0);
        deferred_barriers(rec, targets, passes);
        match (passes.ray_traced, passes.ray_pipeline()) {
            // The acceleration-structure builds (earlier submits) before the shading pass's
            // ray queries.
            (true, false) => {
                rec.memory_barrier(Access::AccelerationStructureBuild, Access::RayQuery)
            }
            (true, true) => {
                // ... or before its ray-tracing pipeline; which also reads what earlier submits'
                // copies and compute steps wrote (meshes by address, the environment), whose
                // barriers named the fragment stage.
                rec.memory_barrier(
                    Access::AccelerationStructureBuild,
                    Access::RayTracingShaderRead,
                );
                rec.memory_barrier(Access::TransferWrite, Access::RayTracingShaderRead);
                rec.memory_barrier(Access::ComputeShaderWrite, Access::RayTracingShaderRead);
            }
            (false, _) => {}
        }
        mark(rec, stamps, 1);
        gbuffer_pass(rec, targets, passes, strip);
        shading_pass(rec, targets, passes, strip);
        mark(rec, stamps, 2);
        let shaded = passes.shaded_use();
        copy_out(
            rec,
            (&targets.attachments.output, shaded),
            &targets.readback,
            strip,
        );
        if let Some(integral) = integral_of(targets, passes) {
            copy_out(rec, (&integral.image, shaded), &integral.readback, strip);
        }
        mark(rec, stamps, 3);
        Ok(())
    })?;
    Ok(())
}

/// Records and submits one strip of the forward draw, and waits for it.
pub(crate) fn record_forward(
    gpu: &GpuContext,
    targets: &DrawTargets<Forward>,
    passes: &ForwardPasses<'_>,
    strip: Strip,
    stamps: Option<&TimestampPool>,
) -> Result<()> {
    gpu.submit_and_wait(|rec| {
        mark(rec, stamps, 0);
        forward_barriers(rec, targets);
        mark(rec, stamps, 1);
        forward_pass(rec, targets, passes, strip);
        mark(rec, stamps, 2);
        let output = targets.attachments.resolve.as_ref();
        let output = output.unwrap_or(&targets.attachments.color);
        copy_out(rec, (output, COLOR_ATTACHMENT), &targets.readback, strip);
        mark(rec, stamps, 3);
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

fn draw_objects(rec: &mut Recorder<'_>, pipeline: &GraphicsPipeline, objects: &[DrawnMesh<'_>]) {
    for (mesh, set) in objects {
        rec.bind_graphics(pipeline, set);
        rec.bind_mesh_buffers(&mesh.vertices, &mesh.indices);
        rec.draw_indexed(mesh.index_count);
    }
}

/// The integral image the shading pass writes, if it traces rays.
fn integral_of<'a>(
    targets: &'a DrawTargets<Deferred>,
    passes: &DeferredPasses<'_>,
) -> Option<&'a IntegralTarget> {
    targets
        .attachments
        .integral
        .as_ref()
        .filter(|_| passes.ray_traced)
}

/// The shading pass's reads of the G-buffer: the coverage and fragment shading passes', and
/// with `ray_pipeline` the ray-tracing pipeline's too.
fn gbuffer_read(ray_pipeline: bool) -> Access {
    match ray_pipeline {
        true => Access::FragmentAndRayTracingShaderRead,
        false => Access::GraphicsShaderRead,
    }
}

/// First use: nothing to wait for. Reuse: the previous strip's or draw's shading pass read the
/// G-buffer, its depth tests wrote both depth targets and its copy read the output (and the
/// integral image) and wrote the readback buffer (and the integral's).
fn deferred_barriers(
    rec: &mut Recorder<'_>,
    targets: &DrawTargets<Deferred>,
    passes: &DeferredPasses<'_>,
) {
    let (gbuffer_before, depth_before, output_before) = if targets.used {
        (
            gbuffer_read(passes.ray_pipeline_device),
            Access::DepthAttachmentWrite,
            Access::TransferRead,
        )
    } else {
        (Access::Nothing, Access::Nothing, Access::Nothing)
    };
    let images = &targets.attachments;
    for image in [&images.position, &images.normal] {
        rec.image_barrier(image, discard(gbuffer_before), COLOR_ATTACHMENT);
    }
    for depth in [&targets.depth, &images.coverage] {
        rec.image_barrier(depth, discard(depth_before), DEPTH_ATTACHMENT);
    }
    rec.image_barrier(&images.output, discard(output_before), COLOR_ATTACHMENT);
    let integral = integral_of(targets, passes);
    if let Some(integral) = integral {
        let before = match integral.used {
            true => Access::TransferRead,
            false => Access::Nothing,
        };
        rec.image_barrier(&integral.image, discard(before), COLOR_ATTACHMENT);
    }
    if targets.used || integral.is_some_and(|i| i.used) {
        rec.memory_barrier(Access::TransferWrite, Access::TransferWrite);
        // The last draw's denoise (denoise.rs) read both readback buffers and wrote the image's.
        rec.memory_barrier(Access::ComputeShaderWrite, Access::TransferWrite);
    }
}

/// The G-buffer pass (gbuffer.frag): each covered sample keeps its interpolated position and
/// normal and its object; then the G-buffer becomes readable by the shading pass.
fn gbuffer_pass(
    rec: &mut Recorder<'_>,
    targets: &DrawTargets<Deferred>,
    passes: &DeferredPasses<'_>,
    strip: Strip,
) {
    let gbuffer = [&targets.attachments.position, &targets.attachments.normal];
    rec.begin_rendering(&RenderTargets {
        colors: &gbuffer,
        // Both cleared: the shading pass compares every sample's normal (both sides of a branch
        // run: quirk `loop_body_runs_when_no_lane_enters`), and a comparison with uncleared
        // memory is a use of uninitialised values, which valgrind reports in the C API tests.
        // w = 0: no object covers the sample.
        clear_colors: &[[0.0; 4]; 2],
        resolve: None,
        depth: Some(&targets.depth),
    });
    set_strip_viewport(rec, strip);
    draw_objects(rec, passes.gbuffer, passes.objects);
    rec.end_rendering();
    let read = ImageUse::new(gbuffer_read(passes.ray_pipeline()), Layout::ShaderRead);
    for image in gbuffer {
        rec.image_barrier(image, COLOR_ATTACHMENT, read);
    }
}

/// The shading pass, single-sampled: the coverage draw, then the shade draw behind its early
/// depth test, both scissored to the strip's part of the meshes' screen bounds (the coverage draw
/// unscissored when it draws the environment background everywhere).
fn shading_pass(
    rec: &mut Recorder<'_>,
    targets: &DrawTargets<Deferred>,
    passes: &DeferredPasses<'_>,
    strip: Strip,
) {
    let output = &targets.attachments.output;
    let integral = integral_of(targets, passes).map(|i| &i.image);
    let (colors, clear_colors) = match integral {
        Some(integral) => (
            vec![output, integral],
            vec![passes.clear_color, NO_INTEGRAL],
        ),
        None => (vec![output], vec![passes.clear_color]),
    };
    rec.begin_rendering(&RenderTargets {
        colors: &colors,
        // The background where it is a colour (or transparent); coverage.frag draws the
        // environment one.
        clear_colors: &clear_colors,
        resolve: None,
        depth: Some(&targets.attachments.coverage),
    });
    set_strip_viewport(rec, strip);
    if passes.coverage_everywhere {
        coverage_draw(rec, passes);
    }
    let shaded = shaded_in_strip(passes.shaded, strip);
    if let Some((x, y, width, height)) = shaded {
        rec.set_scissor(x, y, width, height);
        if !passes.coverage_everywhere {
            coverage_draw(rec, passes);
        }
        if let Shading::Fragment(shade) = passes.shade {
            shade_draw(rec, shade, passes.shade_set);
        }
    }
    rec.end_rendering();
    if let Shading::RayPipeline(pipeline, set) = passes.shade {
        trace_pass(rec, (pipeline, set), shaded_images(targets, passes), shaded);
    }
}

/// The shading pass's outputs: the image, and the integral image where rays are traced (as
/// `copy_out` copies them).
fn shaded_images<'a>(
    targets: &'a DrawTargets<Deferred>,
    passes: &DeferredPasses<'_>,
) -> Vec<&'a Image> {
    let integral = integral_of(targets, passes).map(|i| &i.image);
    std::iter::once(&targets.attachments.output)
        .chain(integral)
        .collect()
}

/// shade_rt*.rgen over the strip's shaded rectangle (x, y, width, height in target pixels), after
/// the coverage draw: the image and the integral image become storage images it writes where a
/// sample is covered (the background and `NO_INTEGRAL` stay elsewhere).
fn trace_pass(
    rec: &mut Recorder<'_>,
    (pipeline, set): (&RayTracingPipeline, &DescriptorSet),
    images: Vec<&Image>,
    shaded: Option<(u32, u32, u32, u32)>,
) {
    let storage = ImageUse::new(Access::RayTracingShaderWrite, Layout::General);
    for image in images {
        rec.image_barrier(image, COLOR_ATTACHMENT, storage);
    }
    if let Some((x, y, width, height)) = shaded {
        rec.bind_ray_tracing(pipeline, set);
        let origin = TraceOrigin {
            origin_x: x as i32,
            origin_y: y as i32,
        };
        rec.push_ray_tracing_constants(pipeline, bytemuck::bytes_of(&origin));
        rec.trace_rays(pipeline, width, height);
    }
}

/// `shaded` in the strip's target rows (the target holds image rows `first_row..`) as a scissor
/// (x, y, width, height); None where the strip holds none of it.
fn shaded_in_strip(shaded: PixelRect, strip: Strip) -> Option<(u32, u32, u32, u32)> {
    let rows = (
        shaded.y0.max(strip.first_row),
        shaded.y1.min(strip.first_row + strip.rows),
    );
    (rows.0 < rows.1 && !shaded.is_empty()).then(|| {
        (
            shaded.x0,
            rows.0 - strip.first_row,
            shaded.x1 - shaded.x0,
            rows.1 - rows.0,
        )
    })
}

/// coverage.frag: writes 0 (covered) or 1 (the clear value, passing as equal so the background
/// is written too) into the coverage depth.
fn coverage_draw(rec: &mut Recorder<'_>, passes: &DeferredPasses<'_>) {
    rec.bind_graphics(passes.coverage, passes.shade_set);
    rec.draw(3);
}

/// shade.frag: 1 > 0 passes where a sample is covered; early, so uncovered blocks are skipped.
fn shade_draw(rec: &mut Recorder<'_>, shade: &GraphicsPipeline, set: &DescriptorSet) {
    rec.bind_graphics(shade, set);
    rec.draw(3);
}

/// The strip's single-sampled image (last used as `before`) to its rows of the readback buffer,
/// visible to the host.
fn copy_out(
    rec: &mut Recorder<'_>,
    (image, before): (&Image, ImageUse),
    readback: &Buffer,
    strip: Strip,
) {
    rec.image_barrier(
        image,
        before,
        ImageUse::new(Access::TransferRead, Layout::TransferSrc),
    );
    let row_bytes = u64::from(strip.image_width) * 16;
    rec.copy_image_rows_to_buffer(
        image,
        strip.rows,
        readback,
        u64::from(strip.first_row) * row_bytes,
    );
    rec.memory_barrier(Access::TransferWrite, Access::HostRead);
}

/// First use: nothing to wait for. Reuse: the previous draw's last access to each target.
fn forward_barriers(rec: &mut Recorder<'_>, targets: &DrawTargets<Forward>) {
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
    let Forward { color, resolve } = &targets.attachments;
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
}

/// The forward pass: the background (if any), then the meshes, resolved from MSAA at its end.
fn forward_pass(
    rec: &mut Recorder<'_>,
    targets: &DrawTargets<Forward>,
    passes: &ForwardPasses<'_>,
    strip: Strip,
) {
    rec.begin_rendering(&RenderTargets {
        colors: &[&targets.attachments.color],
        clear_colors: &[passes.clear_color],
        resolve: targets.attachments.resolve.as_ref(),
        depth: Some(&targets.depth),
    });
    set_strip_viewport(rec, strip);
    if let Some((pipeline, set)) = passes.background {
        rec.bind_graphics(pipeline, set);
        rec.draw(3);
    }
    draw_objects(rec, passes.mesh, passes.objects);
    rec.end_rendering();
}

/// The timings of one strip from its timestamps (ns).
pub(crate) fn timings_from(ns: &[f64]) -> DrawTimings {
    let span = |a: usize, b: usize| match (ns.get(a), ns.get(b)) {
        (Some(x), Some(y)) => (y - x).max(0.0) * 1e-9,
        _ => 0.0,
    };
    DrawTimings {
        pass: span(1, 2),
        copy_out: span(2, 3),
        total: span(0, 3),
        denoise: 0.0,
    }
}
