//! The GPU draw: meshes shaded with the lacquer BRDF, lit by point/directional lights and the
//! prefiltered environment, over a background (the sharp environment, a colour, or transparent),
//! averaged over the MSAA samples and read back as an [`HdrImage`].
//!
//! Per draw: write the frame uniforms, the objects' materials and their Fresnel knots → G-buffer
//! pass (gbuffer.frag: each covered sample keeps its interpolated position, normal and object) →
//! shading pass, single-sampled: coverage.frag marks in a depth target the pixels with a covered
//! sample (and draws the environment background), then shade.frag, behind an early depth test and
//! a scissor to the meshes' screen bounds, shades each pixel's distinct surfaces once, gives the
//! uncovered samples the background and averages the samples → copy to the readback buffer →
//! barrier to host. The result is what forward shading and an MSAA resolve give, without llvmpipe shading
//! whole 4×4 blocks per small triangle and every hidden surface (BENCHMARKS.md). The benchmark's
//! trivial shader (`MeshShading::Trivial`) is still drawn forward: it is the rasteriser's floor.
//!
//! Kept between draws: each pipeline (built on first use, so a command builds only the ones it
//! draws with), the sampler, the black stand-in environment, the render targets and readback
//! buffer of the last size (`draw_targets.rs`) and the uniform, material and knot buffers. Meshes
//! are uploaded per draw by [`LacquerRenderer::render`]; callers that draw the same mesh again
//! (the scene renderer) upload a [`GpuMesh`] once and use [`LacquerRenderer::render_meshes`].

use crate::environment::gpu::GpuEnvironment;
use crate::environment::params::ViewBlur;
use crate::environment::{CubeImage, PrefilteredEnvironment};
use crate::gpu::{
    Binding, BindingKind, Buffer, BufferUsage, DepthCompare, DepthTest, DescriptorSet, Format,
    GpuContext, GraphicsPipeline, GraphicsPipelineDesc, Image, Resource, Sampler, TimestampPool,
};
use crate::model::{BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::camera::{Camera, PixelRect};
use crate::raster::draw_record::{
    record_and_submit, timings_from, DeferredPasses, Passes, RecordedDraw, Strip, TIMESTAMPS,
};
use crate::raster::draw_targets::{Attachments, TargetCache, TargetKind};
use crate::raster::gpu_mesh::{upload, GpuMesh, VERTEX_ATTRIBUTES, VERTEX_STRIDE};
use crate::raster::lights::{Light, MAX_LIGHTS};
use crate::raster::mesh::Mesh;
use crate::shading::{self, EnvironmentUniforms, FrameUniforms, MAX_ENV_LAYERS};
use crate::{Error, Result};
use std::collections::hash_map::Entry;
use std::collections::HashMap;

/// Sample counts the renderer offers (the issue's `--samples 1|4`; lavapipe supports exactly these).
pub const SUPPORTED_SAMPLES: [u32; 2] = [1, 4];

/// Image size and anti-aliasing of one render.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RenderSettings {
    pub width: u32,
    pub height: u32,
    pub samples: u32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        Self {
            width: 1024,
            height: 1024,
            samples: 4,
        }
    }
}

/// What fills the pixels the mesh does not cover.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
pub enum Background {
    /// Alpha 0 (coverage): compose the render over anything later.
    #[default]
    Transparent,
    /// An opaque colour (linear radiance).
    Color([f32; 3]),
    /// The sharp environment (layer 0) along each pixel's primary ray; black without one.
    Environment,
}

/// One lacquered object: a mesh in world space and its material.
#[derive(Clone, Copy)]
pub struct DrawObject<'a> {
    pub mesh: &'a Mesh,
    pub brdf: &'a BrdfParams,
    pub fresnel: &'a FresnelTable,
    pub view_blur: ViewBlur,
}

/// What one draw shows.
pub struct DrawScene<'a> {
    pub objects: &'a [DrawObject<'a>],
    pub camera: &'a Camera,
    pub lights: &'a [Light],
    /// The prefiltered environment lighting the objects, if any.
    pub environment: Option<&'a GpuEnvironment>,
    pub background: Background,
}

/// The graphics passes' set: frame uniforms and the environment (background.frag samples it).
const GRAPHICS_BINDINGS: [Binding; 3] = [
    Binding::new(0, BindingKind::UniformBuffer),
    Binding::array(2, BindingKind::SampledImage, MAX_ENV_LAYERS as u32),
    Binding::new(3, BindingKind::SampledImage),
];

/// shade_body.glsl's set: the frame, the Fresnel knots, the environment, the materials and the
/// G-buffer.
const SHADE_BINDINGS: [Binding; 7] = [
    Binding::new(0, BindingKind::UniformBuffer),
    Binding::new(1, BindingKind::UniformTexelBuffer),
    Binding::array(2, BindingKind::SampledImage, MAX_ENV_LAYERS as u32),
    Binding::new(3, BindingKind::SampledImage),
    Binding::new(4, BindingKind::UniformTexelBuffer),
    Binding::new(5, BindingKind::SampledImage),
    Binding::new(6, BindingKind::SampledImage),
];

/// The fragment shader of the mesh pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MeshShading {
    /// The lacquer model (every real render): G-buffer pass + shading pass.
    #[default]
    Lacquer,
    /// trivial.frag drawn forward: a constant colour, the rasteriser's floor for the same
    /// geometry (benchmarks).
    Trivial,
}

/// The specialization constants of a shading pipeline that depend on the draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
struct ShadeVariant {
    /// frame.glsl's BACKGROUND_KIND: the environment (else a colour) fills uncovered samples.
    environment_background: bool,
    /// lacquer_brdf.glsl's FRESNEL_POW2_GRID: see [`fresnel_on_pow2_grid`].
    fresnel_pow2_grid: bool,
}

/// Whether a table's knots (as the shader reads them, f32) lie at exactly i·step degrees from 0
/// with step a power of two, so that θ/step is exact and its integer part is the interval the
/// shader's search would find. The built-in tables (a knot per degree) do.
fn fresnel_on_pow2_grid(knots: &[[f32; 4]]) -> bool {
    let step = match knots {
        [first, second, ..] if first[0] == 0.0 => second[0] - first[0],
        _ => return false,
    };
    let power_of_two = step.is_normal() && step > 0.0 && step.to_bits() & 0x007f_ffff == 0;
    power_of_two
        && knots
            .iter()
            .enumerate()
            .all(|(i, knot)| i < (1 << 24) && knot[0] == i as f32 * step)
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum PipelineKind {
    GBuffer,
    /// The shading pass's first draw (coverage_body.glsl); keyed by the G-buffer's sample count,
    /// draws single-sampled. `true`: the environment is the background (then it writes colour).
    Coverage(bool),
    /// The shading pass's second draw (shade_body.glsl); keyed like Coverage.
    Shade(ShadeVariant),
    Trivial,
    /// The background of a forward draw.
    Background,
}

/// GPU time of one draw's passes from timestamp queries, in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DrawTimings {
    /// The drawing: for the lacquer draw the G-buffer pass and the shading pass; for the forward
    /// draw the background (if any), the mesh draws, the end of the pass and the MSAA resolve.
    pub pass: f64,
    /// The image (shaded or resolved) → readback buffer.
    pub copy_out: f64,
    /// From the first command to the last.
    pub total: f64,
}

/// How [`LacquerRenderer::render_meshes`] draws.
#[derive(Clone, Copy, Debug, Default)]
pub struct DrawOptions {
    pub shading: MeshShading,
    /// Record timestamp queries and return [`DrawTimings`].
    pub timed: bool,
}

/// Fresnel knots the knot buffer holds before it must grow (the built-in tables have 91 each).
const INITIAL_KNOTS: usize = 512;
/// Objects the material buffer holds before it must grow.
const INITIAL_OBJECTS: usize = 8;
/// Most Fresnel knots of one draw, all objects together: shade_body.glsl receives each table's
/// first knot as an f32, exact below 2^24.
pub const MAX_DRAW_KNOTS: usize = 1 << 24;

/// The buffers the draws write, rewritten by every draw (the previous draw has finished:
/// `submit_and_wait` waits on its fence before returning) and grown when a draw needs more.
#[derive(Default)]
struct DrawBuffers {
    /// The shared frame uniforms of the background and shading passes.
    scene_frame: Option<Buffer>,
    /// Object i's frame uniforms for the G-buffer or forward pass (`draw_info.x` = i + 1).
    object_frames: Vec<Buffer>,
    /// Every object's Fresnel table, concatenated.
    knots: Option<Buffer>,
    /// [`shading::object_material_vec4s`] of every object.
    materials: Option<Buffer>,
}

/// Writes `data` into `slot`'s buffer, replacing it with a bigger one when it is too small.
fn write_growing<T: bytemuck::Pod>(
    gpu: &GpuContext,
    slot: &mut Option<Buffer>,
    name: &str,
    data: &[T],
    min_elements: usize,
    usage: BufferUsage,
) -> Result<()> {
    let bytes = std::mem::size_of_val(data) as u64;
    if slot.as_ref().is_some_and(|b| b.size() < bytes) {
        *slot = None;
    }
    match slot {
        Some(buffer) => buffer.write(data)?,
        None => {
            let mut contents = data.to_vec();
            contents.resize(data.len().max(min_elements), T::zeroed());
            *slot = Some(upload(gpu, name, &contents, usage)?);
        }
    }
    Ok(())
}

/// The lacquer raster renderer; keeps its pipelines, targets and buffers between draws.
#[derive(Default)]
pub struct LacquerRenderer {
    /// Keyed by kind, MSAA samples and the environment's layer count K (a specialization constant).
    pipelines: HashMap<(PipelineKind, u32, u32), GraphicsPipeline>,
    sampler: Option<Sampler>,
    black_environment: Option<GpuEnvironment>,
    targets: TargetCache,
    buffers: DrawBuffers,
    timestamps: Option<TimestampPool>,
}

impl LacquerRenderer {
    pub fn new() -> Self {
        Self::default()
    }

    /// Tests draw small images in many strips with a tiny colour-target budget.
    #[cfg(test)]
    pub(crate) fn set_color_target_budget(&mut self, bytes: u64) {
        self.targets.color_budget = bytes;
    }

    fn ensure_pipeline(
        &mut self,
        gpu: &GpuContext,
        kind: PipelineKind,
        samples: u32,
        layer_count: u32,
    ) -> Result<()> {
        if let Entry::Vacant(entry) = self.pipelines.entry((kind, samples, layer_count)) {
            use crate::gpu::shaders::*;
            const GBUFFER_FORMATS: [Format; 2] = [Format::Rgba32Float, Format::Rgba32Float];
            const COLOR_FORMAT: [Format; 1] = [Format::Rgba32Float];
            // frame.glsl's ENV_LAYER_COUNT (constant_id 0): a sampler array may only be indexed
            // by constants on lavapipe, and a constant K lets the shader skip the absent layers.
            // shade_body.glsl's SAMPLE_COUNT is constant_id 1, frame.glsl's BACKGROUND_KIND 2.
            let variant = match kind {
                PipelineKind::Shade(variant) => variant,
                PipelineKind::Coverage(environment_background) => ShadeVariant {
                    environment_background,
                    fresnel_pow2_grid: false,
                },
                _ => ShadeVariant::default(),
            };
            let constants = [
                layer_count,
                samples,
                u32::from(variant.environment_background),
                u32::from(variant.fresnel_pow2_grid),
            ];
            let mesh = |name, fragment_spirv, color_formats| GraphicsPipelineDesc {
                name,
                vertex_spirv: MESH_VERT,
                fragment_spirv,
                bindings: &GRAPHICS_BINDINGS,
                vertex_stride: VERTEX_STRIDE,
                vertex_attributes: &VERTEX_ATTRIBUTES,
                color_formats,
                depth_format: Some(Format::Depth32Float),
                samples,
                depth_test: Some(DepthTest {
                    compare: DepthCompare::Less,
                    write: true,
                }),
                fragment_constants: &constants[..1],
                color_writes: true,
            };
            // background.vert's triangle lies at depth 1.
            let full_screen =
                |name, fragment_spirv, bindings, samples, depth_test| GraphicsPipelineDesc {
                    name,
                    vertex_spirv: BACKGROUND_VERT,
                    fragment_spirv,
                    bindings,
                    vertex_stride: VERTEX_STRIDE,
                    vertex_attributes: &[],
                    color_formats: &COLOR_FORMAT,
                    depth_format: Some(Format::Depth32Float),
                    samples,
                    depth_test,
                    fragment_constants: &constants,
                    // A colour background is the clear colour: coverage.frag writes only depth.
                    color_writes: kind != PipelineKind::Coverage(false),
                };
            let multisampled = samples > 1;
            let desc = match kind {
                PipelineKind::GBuffer => mesh("gbuffer", GBUFFER_FRAG, &GBUFFER_FORMATS),
                PipelineKind::Trivial => mesh("trivial", TRIVIAL_FRAG, &COLOR_FORMAT),
                // Writes 0 (covered) or 1 (the clear value, passing as equal so the background
                // colour is written too) into the coverage depth.
                PipelineKind::Coverage(_) => full_screen(
                    "coverage",
                    if multisampled {
                        COVERAGE_MS_FRAG
                    } else {
                        COVERAGE_FRAG
                    },
                    &SHADE_BINDINGS[..],
                    1,
                    Some(DepthTest {
                        compare: DepthCompare::LessOrEqual,
                        write: true,
                    }),
                ),
                // 1 > 0 passes where a sample is covered; early, so uncovered blocks are skipped.
                PipelineKind::Shade(_) => full_screen(
                    "shade",
                    if multisampled {
                        SHADE_MS_FRAG
                    } else {
                        SHADE_FRAG
                    },
                    &SHADE_BINDINGS[..],
                    1,
                    Some(DepthTest {
                        compare: DepthCompare::Greater,
                        write: false,
                    }),
                ),
                PipelineKind::Background => full_screen(
                    "background",
                    BACKGROUND_FRAG,
                    &GRAPHICS_BINDINGS[..],
                    samples,
                    None,
                ),
            };
            entry.insert(gpu.create_graphics_pipeline(&desc)?);
        }
        Ok(())
    }

    /// Made once: the sampler, and the black environment bound only when a draw has none (every
    /// binding the shaders declare must hold a valid descriptor).
    fn prepare_shared(&mut self, gpu: &GpuContext, needs_black: bool) -> Result<()> {
        if self.sampler.is_none() {
            self.sampler = Some(gpu.create_sampler()?);
        }
        if needs_black && self.black_environment.is_none() {
            // Uploaded, not prefiltered: a context that never sees an environment builds no
            // prefilter pipelines.
            let face = crate::environment::params::MIN_LAYER_FACE;
            let black = || CubeImage {
                face_size: face,
                texels: vec![[0.0, 0.0, 0.0, 1.0]; 6 * (face as usize).pow(2)],
            };
            let env = PrefilteredEnvironment {
                betas: vec![0.0, 1.0],
                layers: vec![black(), black()],
                irradiance: black(),
            };
            self.black_environment = Some(GpuEnvironment::upload(gpu, &env)?);
        }
        Ok(())
    }

    /// Renders `scene` and reads the image back (linear radiance, alpha = coverage, row 0 top).
    /// Uploads each object's mesh for this draw.
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
    ) -> Result<HdrImage> {
        validate(gpu, scene, settings)?;
        let meshes: Vec<GpuMesh> = scene
            .objects
            .iter()
            .map(|o| GpuMesh::upload(gpu, o.mesh))
            .collect::<Result<_>>()?;
        let meshes: Vec<&GpuMesh> = meshes.iter().collect();
        let (image, _) = self.draw(gpu, scene, &meshes, settings, DrawOptions::default())?;
        Ok(image)
    }

    /// [`render`](Self::render) with each object's mesh already on the device: `meshes[i]` must
    /// be the upload of `scene.objects[i].mesh`. Returns the pass timings with `options.timed`.
    pub fn render_meshes(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        meshes: &[&GpuMesh],
        settings: &RenderSettings,
        options: DrawOptions,
    ) -> Result<(HdrImage, Option<DrawTimings>)> {
        validate(gpu, scene, settings)?;
        if meshes.len() != scene.objects.len() {
            return Err(Error::invalid(
                "meshes",
                meshes.len(),
                format!("one GPU mesh per object ({} objects)", scene.objects.len()),
            ));
        }
        self.draw(gpu, scene, meshes, settings, options)
    }

    fn draw(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        meshes: &[&GpuMesh],
        settings: &RenderSettings,
        options: DrawOptions,
    ) -> Result<(HdrImage, Option<DrawTimings>)> {
        let samples = settings.samples;
        let deferred = options.shading == MeshShading::Lacquer;
        let with_background = scene.background == Background::Environment;
        self.prepare_shared(gpu, scene.environment.is_none())?;
        let internal = || Error::invalid("renderer", "uninitialised", "internal error");
        let layer_count = match scene.environment {
            Some(env) => env.layers.len(),
            None => self
                .black_environment
                .as_ref()
                .ok_or_else(internal)?
                .layers
                .len(),
        } as u32;
        // Once per draw, for the pipeline choice, the knot buffer and the screen bounds.
        let object_knots: Vec<Vec<[f32; 4]>> = scene
            .objects
            .iter()
            .map(|o| shading::fresnel_knots(o.fresnel))
            .collect();
        let scene_radius = scene
            .objects
            .iter()
            .map(|o| o.mesh.bounding_radius())
            .fold(0.0, f64::max);
        let mesh_kind = match options.shading {
            MeshShading::Lacquer => PipelineKind::GBuffer,
            MeshShading::Trivial => PipelineKind::Trivial,
        };
        self.ensure_pipeline(gpu, mesh_kind, samples, layer_count)?;
        let (coverage_kind, shade_kind) = (
            PipelineKind::Coverage(with_background),
            PipelineKind::Shade(ShadeVariant {
                environment_background: with_background,
                fresnel_pow2_grid: object_knots.iter().all(|k| fresnel_on_pow2_grid(k)),
            }),
        );
        if deferred {
            self.ensure_pipeline(gpu, coverage_kind, samples, layer_count)?;
            self.ensure_pipeline(gpu, shade_kind, samples, layer_count)?;
        }
        let forward_background = !deferred && with_background;
        if forward_background {
            self.ensure_pipeline(gpu, PipelineKind::Background, samples, layer_count)?;
        }
        if options.timed && self.timestamps.is_none() {
            self.timestamps = Some(gpu.create_timestamp_pool(TIMESTAMPS)?);
        }
        let mut scene_frame =
            self.write_buffers(gpu, scene, settings, (&object_knots, scene_radius))?;
        let environment = match scene.environment {
            Some(env) => env,
            None => self.black_environment.as_ref().ok_or_else(internal)?,
        };
        let sampler = self.sampler.as_ref().ok_or_else(internal)?;
        let buffers = &self.buffers;
        let scene_frame_buffer = buffers.scene_frame.as_ref().ok_or_else(internal)?;
        let pipeline = |kind| {
            self.pipelines
                .get(&(kind, samples, layer_count))
                .ok_or_else(internal)
        };
        let mesh_pipeline = pipeline(mesh_kind)?;
        // Descriptor sets name the environment's images (and the shading pass the targets),
        // which may differ from the last draw's; they are cheap (one small pool each), so they
        // are made per draw.
        let graphics_set = |pipeline: &GraphicsPipeline, frame: &Buffer| {
            graphics_descriptor_set(gpu, pipeline, frame, environment, sampler)
        };
        let background = match forward_background {
            true => {
                let p = pipeline(PipelineKind::Background)?;
                Some((p, graphics_set(p, scene_frame_buffer)?))
            }
            false => None,
        };
        let object_sets: Vec<DescriptorSet> = buffers.object_frames[..meshes.len()]
            .iter()
            .map(|frame| graphics_set(mesh_pipeline, frame))
            .collect::<Result<_>>()?;
        let stamps = if options.timed {
            self.timestamps.as_ref()
        } else {
            None
        };
        let kind = match deferred {
            true => TargetKind::Deferred,
            false => TargetKind::Forward,
        };
        let targets = self
            .targets
            .get(gpu, (settings.width, settings.height, samples, kind))?;
        let shade = match &targets.attachments {
            Attachments::Deferred {
                position, normal, ..
            } => {
                let shade_pipeline = pipeline(shade_kind)?;
                let set = shade_descriptor_set(
                    gpu,
                    shade_pipeline,
                    buffers,
                    environment,
                    sampler,
                    (position, normal),
                )?;
                Some((pipeline(coverage_kind)?, shade_pipeline, set))
            }
            Attachments::Forward { .. } => None,
        };
        let objects: Vec<(&GpuMesh, &DescriptorSet)> =
            meshes.iter().copied().zip(&object_sets).collect();
        let clear_color = match scene.background {
            Background::Transparent | Background::Environment => [0.0; 4],
            Background::Color([r, g, b]) => [r, g, b, 1.0],
        };
        let shaded = screen_bounds(scene, settings, scene_radius);
        let mut timings: Option<DrawTimings> = stamps.map(|_| DrawTimings::default());
        let mut first_row = 0;
        while first_row < settings.height {
            let rows = targets.strip_rows.min(settings.height - first_row);
            if deferred || forward_background {
                // The previous strip's submit has finished (submit_and_wait), so the scene
                // uniforms can be rewritten for this one.
                scene_frame.strip_offset[1] = first_row as f32;
                match self.buffers.scene_frame.as_mut() {
                    Some(buffer) => buffer.write(std::slice::from_ref(&scene_frame))?,
                    None => return Err(internal()),
                }
            }
            let passes = match &shade {
                Some((coverage_pipeline, shade_pipeline, shade_set)) => {
                    Passes::Deferred(DeferredPasses {
                        gbuffer_pipeline: mesh_pipeline,
                        objects: objects.clone(),
                        coverage_pipeline,
                        shade_pipeline,
                        shade_set,
                        shaded,
                        // The environment background is drawn by the coverage pass.
                        coverage_everywhere: with_background,
                        clear_color,
                    })
                }
                None => Passes::Forward {
                    background: background.as_ref().map(|(p, s)| (*p, s)),
                    mesh_pipeline,
                    objects: objects.clone(),
                    clear_color,
                },
            };
            let recorded = RecordedDraw {
                targets,
                strip: Strip {
                    first_row,
                    rows,
                    image_width: settings.width,
                    image_height: settings.height,
                },
                passes,
                stamps,
            };
            record_and_submit(gpu, &recorded)?;
            targets.used = true;
            if let (Some(pool), Some(sum)) = (stamps, timings.as_mut()) {
                let t = timings_from(&pool.read_ns(TIMESTAMPS)?);
                sum.pass += t.pass;
                sum.copy_out += t.copy_out;
                sum.total += t.total;
            }
            first_row += rows;
        }
        let pixels: Vec<[f32; 4]> = targets.readback.read()?;
        let image = HdrImage {
            width: settings.width,
            height: settings.height,
            pixels,
        };
        Ok((image, timings))
    }

    /// Writes the frame uniforms (shared and per object), the materials and the Fresnel knots;
    /// returns the shared frame uniforms (the caller sets each strip's offset).
    fn write_buffers(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
        (object_knots, scene_radius): (&[Vec<[f32; 4]>], f64),
    ) -> Result<FrameUniforms> {
        let layer_betas = match scene.environment {
            Some(env) => env.betas.clone(),
            None => self
                .black_environment
                .as_ref()
                .map(|e| e.betas.clone())
                .unwrap_or_default(),
        };
        let mut frame = FrameUniforms::new(
            scene.camera,
            settings.width,
            settings.height,
            scene_radius,
            scene.lights,
            &EnvironmentUniforms {
                enabled: scene.environment.is_some(),
                layer_betas,
            },
        );
        let buffers = &mut self.buffers;
        let mut knots: Vec<[f32; 4]> = Vec::new();
        let mut materials: Vec<[f32; 4]> = Vec::new();
        for (i, (object, object_knots)) in scene.objects.iter().zip(object_knots).enumerate() {
            let first_knot = knots.len();
            knots.extend_from_slice(object_knots);
            materials.extend(shading::object_material_vec4s(
                object.brdf,
                object.fresnel,
                first_knot,
                &object.view_blur,
            ));
            frame.draw_info = [i as i32 + 1, 0, 0, 0];
            if buffers.object_frames.len() <= i {
                let buffer = upload(
                    gpu,
                    "object frame uniforms",
                    std::slice::from_ref(&frame),
                    BufferUsage::UNIFORM,
                )?;
                buffers.object_frames.push(buffer);
            } else {
                buffers.object_frames[i].write(std::slice::from_ref(&frame))?;
            }
        }
        frame.draw_info = [0; 4];
        frame.background_color = match scene.background {
            Background::Color([r, g, b]) => [r, g, b, 1.0],
            Background::Transparent | Background::Environment => [0.0; 4],
        };
        write_growing(
            gpu,
            &mut buffers.scene_frame,
            "scene frame uniforms",
            std::slice::from_ref(&frame),
            1,
            BufferUsage::UNIFORM,
        )?;
        write_growing(
            gpu,
            &mut buffers.knots,
            "fresnel knots",
            &knots,
            INITIAL_KNOTS,
            BufferUsage::UNIFORM_TEXEL,
        )?;
        write_growing(
            gpu,
            &mut buffers.materials,
            "object materials",
            &materials,
            4 * INITIAL_OBJECTS,
            BufferUsage::UNIFORM_TEXEL,
        )?;
        Ok(frame)
    }
}

/// The environment layers as the sampler array binding wants them: unused array slots repeat the
/// last layer, since every element needs a valid descriptor.
fn layer_images(environment: &GpuEnvironment) -> Vec<&Image> {
    let mut layer_images: Vec<&Image> = environment.layers.iter().collect();
    while layer_images.len() < MAX_ENV_LAYERS {
        let last = layer_images[layer_images.len() - 1];
        layer_images.push(last);
    }
    layer_images.truncate(MAX_ENV_LAYERS);
    layer_images
}

fn graphics_descriptor_set(
    gpu: &GpuContext,
    pipeline: &GraphicsPipeline,
    frame: &Buffer,
    environment: &GpuEnvironment,
    sampler: &Sampler,
) -> Result<DescriptorSet> {
    Ok(gpu.create_descriptor_set(
        pipeline.layout(),
        &[
            (0, Resource::Buffer(frame)),
            (
                2,
                Resource::SampledImages(layer_images(environment), sampler),
            ),
            (3, Resource::SampledImage(&environment.irradiance, sampler)),
        ],
    )?)
}

fn shade_descriptor_set(
    gpu: &GpuContext,
    pipeline: &GraphicsPipeline,
    buffers: &DrawBuffers,
    environment: &GpuEnvironment,
    sampler: &Sampler,
    (position, normal): (&Image, &Image),
) -> Result<DescriptorSet> {
    let internal = || Error::invalid("renderer", "buffers unwritten", "internal error");
    let frame = buffers.scene_frame.as_ref().ok_or_else(internal)?;
    let knots = buffers.knots.as_ref().ok_or_else(internal)?;
    let materials = buffers.materials.as_ref().ok_or_else(internal)?;
    Ok(gpu.create_descriptor_set(
        pipeline.layout(),
        &[
            (0, Resource::Buffer(frame)),
            (1, Resource::TexelBuffer(knots)),
            (
                2,
                Resource::SampledImages(layer_images(environment), sampler),
            ),
            (3, Resource::SampledImage(&environment.irradiance, sampler)),
            (4, Resource::TexelBuffer(materials)),
            (5, Resource::SampledImage(position, sampler)),
            (6, Resource::SampledImage(normal, sampler)),
        ],
    )?)
}

/// The pixels any object can cover (the union of their boxes' screen bounds); empty without
/// objects.
fn screen_bounds(scene: &DrawScene<'_>, settings: &RenderSettings, scene_radius: f64) -> PixelRect {
    let mut union: Option<PixelRect> = None;
    for object in scene.objects {
        let Some(bounds) = object.mesh.bounding_box() else {
            continue;
        };
        let r = scene
            .camera
            .screen_bounds(bounds, settings.width, settings.height, scene_radius);
        union = Some(match union {
            None => r,
            Some(u) => PixelRect {
                x0: u.x0.min(r.x0),
                y0: u.y0.min(r.y0),
                x1: u.x1.max(r.x1),
                y1: u.y1.max(r.y1),
            },
        });
    }
    union.unwrap_or(PixelRect {
        x0: 0,
        y0: 0,
        x1: 0,
        y1: 0,
    })
}

fn validate(gpu: &GpuContext, scene: &DrawScene<'_>, settings: &RenderSettings) -> Result<()> {
    let max = gpu.info().max_image_dimension_2d;
    for (field, value) in [("width", settings.width), ("height", settings.height)] {
        if value == 0 || value > max {
            return Err(Error::invalid(
                field,
                value,
                format!("the image size must be 1..={max} pixels on this device"),
            ));
        }
    }
    if !SUPPORTED_SAMPLES.contains(&settings.samples) {
        return Err(Error::invalid(
            "samples",
            settings.samples,
            "valid sample counts are 1 and 4",
        ));
    }
    if scene.lights.len() > MAX_LIGHTS {
        return Err(Error::invalid(
            "lights",
            scene.lights.len(),
            format!("at most {MAX_LIGHTS} lights per draw"),
        ));
    }
    if let Some(env) = scene.environment {
        if env.layers.len() > MAX_ENV_LAYERS {
            return Err(Error::invalid(
                "layers",
                env.layers.len(),
                format!("at most {MAX_ENV_LAYERS} environment layers"),
            ));
        }
    }
    scene.camera.validate()?;
    for light in scene.lights {
        light.validate()?;
    }
    let knots: usize = scene
        .objects
        .iter()
        .map(|o| o.fresnel.angles_deg().len())
        .sum();
    if knots > MAX_DRAW_KNOTS {
        return Err(Error::invalid(
            "Fresnel knots",
            knots,
            format!(
                "at most {MAX_DRAW_KNOTS} Fresnel table knots per draw, all objects together; \
                 use coarser tables or render fewer objects at once"
            ),
        ));
    }
    for object in scene.objects {
        object.mesh.validate()?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::fresnel_on_pow2_grid;

    fn knots(angles: &[f32]) -> Vec<[f32; 4]> {
        angles.iter().map(|&a| [a, 0.1, 0.2, 0.3]).collect()
    }

    /// The shader skips its interval search only for tables whose knots are exactly i·2^e.
    #[test]
    fn pow2_grid_is_recognised_exactly() {
        let degrees: Vec<f32> = (0..=90).map(|i| i as f32).collect();
        assert!(fresnel_on_pow2_grid(&knots(&degrees)));
        let halves: Vec<f32> = (0..=180).map(|i| i as f32 * 0.5).collect();
        assert!(fresnel_on_pow2_grid(&knots(&halves)));
        let fives: Vec<f32> = (0..=18).map(|i| i as f32 * 5.0).collect();
        assert!(
            !fresnel_on_pow2_grid(&knots(&fives)),
            "5 is not a power of two"
        );
        let mut uneven = degrees.clone();
        uneven[40] = 40.5;
        assert!(!fresnel_on_pow2_grid(&knots(&uneven)));
        assert!(
            !fresnel_on_pow2_grid(&knots(&[1.0, 2.0, 3.0])),
            "must start at 0"
        );
        assert!(!fresnel_on_pow2_grid(&knots(&[0.0])));
        assert!(!fresnel_on_pow2_grid(&knots(&[0.0, 0.0])));
    }
}
