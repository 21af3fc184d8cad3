//! The GPU draw: meshes shaded with the lacquer BRDF, lit by point/directional lights and the
//! prefiltered environment, over a background (the sharp environment, a colour, or transparent),
//! averaged over the MSAA samples and read back as an [`HdrImage`].
//!
//! The lacquer draw is deferred. Per draw, then per strip of image rows (one submit each):
//!
//! ```text
//!  frame data      frame.rs: the Frame, every object's ObjectMaterial and Fresnel knots → buffers
//!   ┌─ per strip ─────────────────────────────────────────────────────────────────────────────┐
//!   │ G-buffer pass  gbuffer.frag: each covered sample keeps position, normal and object     │
//!   │ shading pass   coverage.frag: coverage depth (+ the environment background)             │
//!   │                shade.frag: each pixel's distinct surfaces shaded once, samples averaged │
//!   │                (ray-traced: + the integral image, SPEC §6's term and its variance)       │
//!   │ copy-out       the strip's rows → the readback buffer → host                            │
//!   └─────────────────────────────────────────────────────────────────────────────────────────┘
//!  denoise         with rays traced and `RayTracing::denoise`: the integral image the shading
//!                  pass wrote beside the image, filtered on the device in the readback buffer
//!                  (denoise.rs: denoise_guide.comp, denoise_filter.comp; the host twin where
//!                  the image exceeds a storage buffer, or when `DrawOptions::denoise_on_host`)
//! ```
//!
//! That gives what forward shading and an MSAA resolve give, without llvmpipe shading whole 4×4
//! blocks per small triangle and every hidden surface (BENCHMARKS.md). The benchmark's trivial
//! shader ([`MeshShading::Trivial`]) is still drawn forward: it is the rasteriser's floor.
//!
//! The files: `types.rs` (what a caller passes and gets back, and its validation),
//! `pipelines.rs` (the pipeline table, the descriptor-set layouts and sets), `frame.rs` (the
//! frame data and its buffers), `passes.rs` (one function per pass), `targets.rs` (the render
//! targets, drawn in strips) and `gpu_mesh.rs` (meshes on the device). To add a pass: a function
//! in `passes.rs`, its pipeline kind in `pipelines.rs`, a line in the recipe below.
//!
//! Kept between draws: each pipeline, the sampler, the black stand-in environment, the render
//! targets and readback buffer of the last size, and the frame-data buffers. Meshes are uploaded
//! per draw by [`LacquerRenderer::render`]; callers that draw the same mesh again (the scene
//! renderer) upload a [`GpuMesh`] once and use [`LacquerRenderer::render_meshes`].

pub mod denoise;
pub(crate) mod frame;
pub mod gpu_mesh;
mod passes;
mod pipelines;
mod targets;
mod types;

pub use gpu_mesh::GpuMesh;
pub use types::{
    Background, DrawObject, DrawOptions, DrawScene, DrawTimings, MeshShading, RayTracing,
    RenderSettings, MAX_BOUNCES, MAX_DRAW_KNOTS, MAX_RAYS, SUPPORTED_SAMPLES,
};

use crate::environment::brdf_quadrature::AlbedoCache;
use crate::environment::gpu::{GpuEnvironment, LayerApronPass};
use crate::environment::{CubeImage, PrefilteredEnvironment};
use crate::gpu::shaders::interface::{
    Frame, ObjectGeometry, SELF_HITS_BACK_CLEAR, SELF_HITS_FRONT_CLEAR, TRACE_MASK_SHARED,
};
use crate::gpu::{
    AccelerationStructure, Buffer, BufferUsage, DescriptorSet, GpuContext, GraphicsPipeline,
    Instance, RayTracingPipeline, Sampler, TimestampPool,
};
use crate::output::HdrImage;
use crate::raster::camera::{PixelRect, SceneSphere};
use crate::{Error, Result};
use denoise::{denoise, denoise_params, denoise_sigma, DenoisePass};
use frame::{fresnel_knots, DrawBuffers};
use passes::{
    record_deferred, record_forward, strips, timings_from, DeferredPasses, DrawnMesh,
    ForwardPasses, Shading, TIMESTAMPS,
};
use pipelines::{
    fresnel_on_pow2_grid, graphics_set, shade_set, PipelineKey, PipelineKind, PipelineTable,
    ShadeVariant, TracedResources,
};
use std::sync::Arc;
use targets::{traced_strip_rows, TargetCache};
use types::validate;

/// The lacquer raster renderer; keeps its pipelines, targets and buffers between draws.
#[derive(Default)]
pub struct LacquerRenderer {
    pipelines: PipelineTable,
    targets: TargetCache,
    /// Each material's directional-albedo knots (the `brdf` quadrature's), computed once.
    albedo_cache: AlbedoCache,
    /// Made by the first draw.
    resources: Option<Resources>,
}

/// What a renderer makes on its first draw and keeps.
struct Resources {
    sampler: Sampler,
    buffers: DrawBuffers,
    /// Bound when a draw has no environment (every binding the shaders declare must hold a valid
    /// descriptor); made by the first such draw.
    black_environment: Option<GpuEnvironment>,
    /// Made by the first timed draw.
    timestamps: Option<TimestampPool>,
    /// Made by the first draw denoised on the device.
    denoise: Option<DenoisePass>,
    /// Made by the first draw that reads the `brdf` quadrature's layer texels (each
    /// environment's are written once, with their aprons, and kept with it).
    apron: Option<LayerApronPass>,
}

impl Resources {
    fn new(gpu: &GpuContext) -> Result<Self> {
        Ok(Resources {
            sampler: gpu.create_sampler()?,
            buffers: DrawBuffers::new(gpu)?,
            black_environment: None,
            timestamps: None,
            denoise: None,
            apron: None,
        })
    }
}

/// The value in `slot`, made by `make` first if there is none.
pub(crate) fn get_or_try_insert<T>(
    slot: &mut Option<T>,
    make: impl FnOnce() -> Result<T>,
) -> Result<&mut T> {
    match slot {
        Some(value) => Ok(value),
        None => Ok(slot.insert(make()?)),
    }
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

    /// Renders `scene` and reads the image back (linear radiance, alpha = coverage, row 0 top).
    /// Uploads each object's mesh for this draw.
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
    ) -> Result<HdrImage> {
        validate(gpu, scene, settings)?;
        let meshes = upload_meshes(gpu, scene)?;
        let meshes: Vec<&GpuMesh> = meshes.iter().collect();
        let (image, _) = self.draw(gpu, scene, &meshes, settings, DrawOptions::default())?;
        Ok(image)
    }

    /// The graphics pipelines a lacquer draw of `scene` into `samples`-sample targets will use
    /// that this renderer has not built, so that a caller can build them while it prepares the
    /// draw's other inputs: `scene.environment` is not read, the draw's will have `layers`
    /// layers (`None`: the draw has no environment). A guess that misses costs only the time:
    /// the draw builds what it lacks.
    pub fn pipelines_ahead(
        &self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        (samples, layers): (u32, Option<u32>),
    ) -> PipelinesAhead {
        let layer_count = layers.unwrap_or(BLACK_ENVIRONMENT_LAYERS as u32);
        let pow2_grid = scene
            .objects
            .iter()
            .all(|o| fresnel_on_pow2_grid(&fresnel_knots(o.fresnel)));
        let keys = DeferredKeys::of(scene, (samples, layer_count), pow2_grid);
        let traced = scene.ray_tracing.is_some_and(|rt| rt.traces());
        let shade_is_graphics = !(traced && gpu.info().ray_query.uses_pipeline());
        let mut wanted = vec![keys.gbuffer, keys.coverage];
        if shade_is_graphics {
            wanted.push(keys.shade);
        }
        wanted.retain(|key| !self.pipelines.has(key));
        PipelinesAhead(wanted)
    }

    /// Computes what a draw of `scene` reads of its materials' directional albedo (the `brdf`
    /// quadrature's knots, tens of milliseconds a material) ahead of it, as [`pipelines_ahead`] does for its
    /// pipelines: on the first core while the second builds those.
    ///
    /// [`pipelines_ahead`]: Self::pipelines_ahead
    pub fn albedo_ahead(&mut self, scene: &DrawScene<'_>) {
        if scene.reads_brdf_quadrature() {
            for object in scene.objects {
                self.albedo_cache.knots(object.brdf, object.fresnel);
            }
        }
    }

    /// Keeps pipelines built ahead ([`pipelines_ahead`](Self::pipelines_ahead)).
    pub fn add_pipelines(&mut self, built: BuiltAhead) {
        for (key, pipeline) in built.0 {
            self.pipelines.insert(key, pipeline);
        }
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

    /// [`render`](Self::render) without the denoise, and the integral image of a ray-traced
    /// draw (None without rays): per pixel, rgb the estimate of SPEC §6's integral that the
    /// image holds (sample-averaged, before the image's clamp at 0), alpha the variance of its
    /// grey value (r + g + b)/3 as the rays estimate it, −1 where no object covers the pixel.
    /// What the denoise filters, and what tests compare with the CPU twin's.
    pub fn render_with_integral(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
    ) -> Result<(HdrImage, Option<HdrImage>)> {
        validate(gpu, scene, settings)?;
        let meshes = upload_meshes(gpu, scene)?;
        let meshes: Vec<&GpuMesh> = meshes.iter().collect();
        let drawn = self.draw_once(gpu, scene, &meshes, settings, DrawOptions::default(), None)?;
        let image = match &drawn.integral {
            Some(_) => clamped(drawn.image),
            None => drawn.image,
        };
        Ok((image, drawn.integral))
    }

    /// The draw, and with the denoise on (and `rays` low enough for it: `denoise_sigma`) its
    /// integral image filtered (denoise.rs): on the device, or on the host with
    /// `options.denoise_on_host` or an image larger than a storage buffer.
    fn draw(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        meshes: &[&GpuMesh],
        settings: &RenderSettings,
        options: DrawOptions,
    ) -> Result<(HdrImage, Option<DrawTimings>)> {
        let sigma = scene
            .ray_tracing
            .filter(|rt| rt.denoise && rt.bounces > 0)
            .and_then(|rt| denoise_sigma(rt.rays));
        let on_device =
            !options.denoise_on_host && DenoisePass::fits(gpu, settings.width, settings.height);
        let device_sigma = sigma.filter(|_| on_device);
        let drawn = self.draw_once(gpu, scene, meshes, settings, options, device_sigma)?;
        // A ray-traced draw leaves the radiance unclamped, for the denoise.
        let image = match (sigma, &drawn.integral) {
            _ if drawn.denoised => drawn.image,
            (Some(sigma), Some(integral)) => denoise(&drawn.image, integral, sigma),
            (None, Some(_)) => clamped(drawn.image),
            (_, None) => drawn.image,
        };
        Ok((image, drawn.timings))
    }

    /// The recipe: the frame data, then the passes of `options.shading`, strip by strip; with
    /// `denoise_sigma` and rays traced, the denoise on the device at that σ.
    fn draw_once(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        meshes: &[&GpuMesh],
        settings: &RenderSettings,
        options: DrawOptions,
        denoise_sigma: Option<f64>,
    ) -> Result<Drawn> {
        let Resources {
            sampler,
            buffers,
            black_environment,
            timestamps,
            denoise,
            apron,
        } = get_or_try_insert(&mut self.resources, || Resources::new(gpu))?;
        let environment = match scene.environment {
            Some(environment) => environment,
            None => &*get_or_try_insert(black_environment, || upload_black_environment(gpu))?,
        };
        let stamps = match options.timed {
            true => Some(&*get_or_try_insert(timestamps, || {
                Ok(gpu.create_timestamp_pool(TIMESTAMPS)?)
            })?),
            false => None,
        };
        // Once per draw, for the knot buffer, the pipeline choice and the screen bounds.
        let knots: Vec<Vec<[f32; 4]>> = scene
            .objects
            .iter()
            .map(|o| fresnel_knots(o.fresnel))
            .collect();
        let scene_sphere =
            SceneSphere::around_boxes(scene.objects.iter().filter_map(|o| o.mesh.bounding_box()))
                .unwrap_or(SceneSphere::from(1.0));
        // The `brdf` model's quadrature normalises by each object's directional albedo A(nv);
        // a ray-traced draw runs it in either model (`integral_environment`).
        let albedo: Vec<Vec<[f32; 4]>> = match scene.reads_brdf_quadrature() {
            true => scene
                .objects
                .iter()
                .map(|o| self.albedo_cache.knots(o.brdf, o.fresnel))
                .collect(),
            false => Vec::new(),
        };
        let frame = buffers.write(
            gpu,
            scene,
            settings,
            environment,
            (&knots, &albedo, scene_sphere),
        )?;
        // The `brdf` quadrature's layer texels, made on the environment's first such draw.
        let layer_texels = match scene.reads_brdf_quadrature() {
            true => {
                let apron = get_or_try_insert(apron, || LayerApronPass::new(gpu))?;
                Some(environment.brdf_sources(gpu, apron)?.texels)
            }
            false => None,
        };
        let inputs = DrawInputs {
            gpu,
            scene,
            meshes,
            settings,
            environment,
            layer_texels,
            sampler,
            stamps,
            scene_sphere,
        };
        let (pipelines, targets) = (&mut self.pipelines, &mut self.targets);
        match options.shading {
            MeshShading::Lacquer => {
                let pow2_grid = knots.iter().all(|k| fresnel_on_pow2_grid(k));
                let denoise = match denoise_sigma {
                    Some(sigma) => {
                        Some((get_or_try_insert(denoise, || DenoisePass::new(gpu))?, sigma))
                    }
                    None => None,
                };
                let frame = (frame, pow2_grid);
                draw_deferred(&inputs, pipelines, targets, buffers, frame, denoise)
            }
            MeshShading::Trivial => draw_forward(&inputs, pipelines, targets, buffers, frame),
        }
    }
}

/// Each object's mesh uploaded for one draw.
fn upload_meshes(gpu: &GpuContext, scene: &DrawScene<'_>) -> Result<Vec<GpuMesh>> {
    scene
        .objects
        .iter()
        .map(|o| GpuMesh::upload(gpu, o.mesh))
        .collect()
}

/// `image` with every radiance below 0 raised to 0: what SPEC §6's estimate (unclamped in a
/// ray-traced draw's image) estimates cannot be negative.
fn clamped(mut image: HdrImage) -> HdrImage {
    for pixel in &mut image.pixels {
        for c in &mut pixel[..3] {
            *c = c.max(0.0);
        }
    }
    image
}

/// What one draw read back.
struct Drawn {
    image: HdrImage,
    /// The image was denoised on the device (filtered and clamped; no integral read back).
    denoised: bool,
    /// A ray-traced draw's integral image ([`LacquerRenderer::render_with_integral`]).
    integral: Option<HdrImage>,
    timings: Option<DrawTimings>,
}

/// What every pass of one draw reads.
struct DrawInputs<'a> {
    gpu: &'a GpuContext,
    scene: &'a DrawScene<'a>,
    meshes: &'a [&'a GpuMesh],
    settings: &'a RenderSettings,
    /// The scene's environment, or the black one.
    environment: &'a GpuEnvironment,
    /// Its `brdf` layer texels where the draw reads the quadrature.
    layer_texels: Option<&'a Buffer>,
    sampler: &'a Sampler,
    stamps: Option<&'a TimestampPool>,
    scene_sphere: SceneSphere,
}

impl DrawInputs<'_> {
    fn key(&self, kind: PipelineKind) -> PipelineKey {
        PipelineKey {
            kind,
            samples: self.settings.samples,
            layer_count: self.environment.layers.len() as u32,
        }
    }

    fn target_size(&self) -> (u32, u32, u32) {
        let s = self.settings;
        (s.width, s.height, s.samples)
    }

    /// Each object's set for the mesh pass: its frame and the environment.
    fn object_sets(
        &self,
        pipeline: &GraphicsPipeline,
        buffers: &DrawBuffers,
    ) -> Result<Vec<DescriptorSet>> {
        buffers.object_frames[..self.meshes.len()]
            .iter()
            .map(|frame| graphics_set(self.gpu, pipeline, frame, self.environment, self.sampler))
            .collect()
    }

    /// Adds one strip's timestamps to `sum` (timed draws only).
    fn add_strip_timings(&self, sum: &mut Option<DrawTimings>) -> Result<()> {
        if let (Some(pool), Some(sum)) = (self.stamps, sum.as_mut()) {
            *sum += timings_from(&pool.read_ns(TIMESTAMPS)?);
        }
        Ok(())
    }
}

/// The graphics pipelines of a lacquer draw (`draw_deferred`): its G-buffer, coverage and
/// shading passes (the last a ray-tracing pipeline instead on a device without ray queries).
struct DeferredKeys {
    gbuffer: PipelineKey,
    coverage: PipelineKey,
    shade: PipelineKey,
}

impl DeferredKeys {
    /// The keys of a draw of `scene` into targets of `samples` with an environment of
    /// `layer_count` layers; `fresnel_pow2_grid` whether every object's Fresnel knots lie on one
    /// ([`fresnel_on_pow2_grid`]).
    fn of(
        scene: &DrawScene<'_>,
        (samples, layer_count): (u32, u32),
        fresnel_pow2_grid: bool,
    ) -> Self {
        let environment_background = scene.background == Background::Environment;
        let traced = scene.ray_tracing.filter(RayTracing::traces);
        let ray_traced = traced.is_some();
        let key = |kind| PipelineKey {
            kind,
            samples,
            layer_count,
        };
        DeferredKeys {
            gbuffer: key(PipelineKind::GBuffer(ray_traced)),
            coverage: key(PipelineKind::Coverage(environment_background, ray_traced)),
            shade: key(PipelineKind::Shade(ShadeVariant {
                environment_background,
                fresnel_pow2_grid,
                environment_model: scene.environment_model,
                ray_traced,
                shadows: traced.is_some_and(|rt| rt.shadows),
                integral: traced.is_some_and(|rt| rt.bounces > 0),
            })),
        }
    }
}

/// Graphics pipelines a lacquer draw will need, to be built ahead of it on another thread
/// ([`LacquerRenderer::pipelines_ahead`]): lavapipe spends a third of a second of one core on a
/// ray-traced shading pipeline, warm caches or not (it keeps no pipeline in its pipeline cache,
/// only the machine code in Mesa's shader cache), and a render has about that much other
/// preparation for its first core (BENCHMARKS.md, "Rays that cannot meet their own mesh").
pub struct PipelinesAhead(Vec<PipelineKey>);

impl PipelinesAhead {
    /// Whether every pipeline the draw needs is built already.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Builds the pipelines (on any thread; Vulkan's pipeline cache is internally synchronised).
    pub fn build(self, gpu: &GpuContext) -> Result<BuiltAhead> {
        let mut built = Vec::with_capacity(self.0.len());
        for key in self.0 {
            built.push((key, PipelineTable::build(gpu, key)?));
        }
        Ok(BuiltAhead(built))
    }
}

/// What [`PipelinesAhead::build`] made, for [`LacquerRenderer::add_pipelines`].
pub struct BuiltAhead(Vec<(PipelineKey, GraphicsPipeline)>);

/// The lacquer draw: per strip, the G-buffer pass, the shading pass and the copy-out; then, with
/// `denoise` (the pass and σ) and rays traced, the denoise of the whole image on the device.
fn draw_deferred(
    inputs: &DrawInputs<'_>,
    pipelines: &mut PipelineTable,
    targets: &mut TargetCache,
    buffers: &mut DrawBuffers,
    (mut frame, fresnel_pow2_grid): (Frame, bool),
    denoise: Option<(&mut DenoisePass, f64)>,
) -> Result<Drawn> {
    let DrawInputs { gpu, scene, .. } = *inputs;
    let environment_background = scene.background == Background::Environment;
    // The ray tracing of this draw, if it traces any ray.
    let traced = scene.ray_tracing.filter(RayTracing::traces);
    let ray_traced = traced.is_some();
    let keys = DeferredKeys::of(
        scene,
        (
            inputs.settings.samples,
            inputs.environment.layers.len() as u32,
        ),
        fresnel_pow2_grid,
    );
    let gbuffer = pipelines.get(gpu, keys.gbuffer)?;
    let coverage = pipelines.get(gpu, keys.coverage)?;
    let shade_key = keys.shade;
    // A device without ray queries shades a ray-traced draw in a ray-tracing pipeline
    // (shade_rt*.rgen); its fragment shaders cannot trace.
    let ray_pipeline = ray_traced && gpu.info().ray_query.uses_pipeline();
    // The draw's top-level structure over the objects' meshes (each mesh's bottom level is
    // built once and kept with it).
    let structures = match traced {
        Some(rt) => {
            frame.light_transport = [rt.rays as i32, rt.bounces as i32, rt.seed as i32, 0];
            let masks = own_masks(inputs.meshes);
            Some((
                top_level(gpu, inputs.meshes, &masks)?,
                object_geometry(gpu, inputs.meshes, &masks)?,
            ))
        }
        None => None,
    };
    // Without the `brdf` model's quadrature nothing reads the layer texels: any texel buffer
    // fills the binding.
    let layer_texels = inputs.layer_texels.unwrap_or(&buffers.knots);
    let object_sets = inputs.object_sets(&gbuffer, buffers)?;
    let objects: Vec<DrawnMesh<'_>> = inputs.meshes.iter().copied().zip(&object_sets).collect();
    let targets = targets.deferred(gpu, inputs.target_size())?;
    if ray_traced {
        targets.integral(gpu)?;
    }
    let gbuffer_images = (&targets.attachments.position, &targets.attachments.normal);
    let scene_structures = structures
        .as_ref()
        .map(|(scene, geometry)| (scene, geometry));
    // The shading pass's resources in a set of `layout`'s, with `storage` the images a
    // ray-tracing pipeline writes.
    let set_of = |layout, storage| {
        shade_set(
            gpu,
            layout,
            buffers,
            (inputs.environment, layer_texels),
            inputs.sampler,
            gbuffer_images,
            scene_structures.map(|scene| TracedResources { scene, storage }),
        )
    };
    // coverage.frag's set, which shade*.frag shares (the same bindings).
    let coverage_set = set_of(coverage.layout(), None)?;
    let shade = match ray_pipeline {
        true => {
            let pipeline = pipelines.ray_pipeline(gpu, shade_key)?;
            // The images it writes: the shading pass's outputs (a ray-traced draw has both).
            let output = &targets.attachments.output;
            let integral = targets.attachments.integral.as_ref();
            let storage = (output, integral.map_or(output, |i| &i.image));
            let set = set_of(pipeline.layout(), Some(storage))?;
            ShadePipeline::Ray(pipeline, set)
        }
        false => ShadePipeline::Fragment(pipelines.get(gpu, shade_key)?),
    };
    let passes = DeferredPasses {
        gbuffer: &gbuffer,
        objects: &objects,
        coverage: &coverage,
        shade: shade.shading(),
        shade_set: &coverage_set,
        shaded: screen_bounds(inputs),
        // The environment background is drawn by the coverage pass.
        coverage_everywhere: environment_background,
        clear_color: scene.background.clear_color(),
        ray_traced,
        ray_pipeline_device: gpu.info().ray_query.uses_pipeline(),
    };
    let settings = inputs.settings;
    let mut timings = inputs.stamps.map(|_| DrawTimings::default());
    // A ray-traced strip also stays within a submit's share of paths.
    let rows = match traced {
        Some(rt) => {
            let paths = u64::from(rt.rays) * u64::from(rt.bounces);
            targets
                .strip_rows
                .min(traced_strip_rows(settings.width, paths))
        }
        None => targets.strip_rows,
    };
    for strip in strips(settings.width, settings.height, rows) {
        // The previous strip's submit has finished (submit_and_wait), so the frame can be
        // rewritten for this one.
        frame.strip_offset[1] = strip.first_row as f32;
        buffers.scene_frame.write(std::slice::from_ref(&frame))?;
        record_deferred(gpu, targets, &passes, strip, inputs.stamps)?;
        targets.used = true;
        inputs.add_strip_timings(&mut timings)?;
    }
    let integral = match targets.attachments.integral.as_mut() {
        Some(integral) if ray_traced => {
            integral.used = true;
            Some(&integral.readback)
        }
        _ => None,
    };
    if let (Some((pass, sigma)), Some(integral)) = (denoise, integral) {
        let params = denoise_params(settings.width, settings.height, sigma);
        let seconds = pass.run(gpu, (&targets.readback, integral), &params, inputs.stamps)?;
        if let Some(sum) = timings.as_mut() {
            sum.denoise += seconds;
            sum.total += seconds;
        }
        return Ok(Drawn {
            image: read_back(&targets.readback, settings)?,
            denoised: true,
            integral: None,
            timings,
        });
    }
    Ok(Drawn {
        image: read_back(&targets.readback, settings)?,
        denoised: false,
        integral: integral.map(|b| read_back(b, settings)).transpose()?,
        timings,
    })
}

/// The shading pass's pipeline of one draw ([`Shading`] borrows it).
enum ShadePipeline {
    Fragment(Arc<GraphicsPipeline>),
    /// With its set: the shading pass's and the two images it writes.
    Ray(Arc<RayTracingPipeline>, DescriptorSet),
}

impl ShadePipeline {
    fn shading(&self) -> Shading<'_> {
        match self {
            ShadePipeline::Fragment(pipeline) => Shading::Fragment(pipeline),
            ShadePipeline::Ray(pipeline, set) => Shading::RayPipeline(pipeline, set),
        }
    }
}

/// The forward draw (the benchmark's trivial shader): per strip, the background and the meshes
/// with an MSAA resolve, and the copy-out.
fn draw_forward(
    inputs: &DrawInputs<'_>,
    pipelines: &mut PipelineTable,
    targets: &mut TargetCache,
    buffers: &mut DrawBuffers,
    mut frame: Frame,
) -> Result<Drawn> {
    let DrawInputs { gpu, scene, .. } = *inputs;
    let mesh = pipelines.get(gpu, inputs.key(PipelineKind::Trivial))?;
    let with_background = scene.background == Background::Environment;
    let background = match with_background {
        true => {
            let pipeline = pipelines.get(gpu, inputs.key(PipelineKind::Background))?;
            let frame = &buffers.scene_frame;
            let set = graphics_set(gpu, &pipeline, frame, inputs.environment, inputs.sampler)?;
            Some((pipeline, set))
        }
        false => None,
    };
    let object_sets = inputs.object_sets(&mesh, buffers)?;
    let objects: Vec<DrawnMesh<'_>> = inputs.meshes.iter().copied().zip(&object_sets).collect();
    let targets = targets.forward(gpu, inputs.target_size())?;
    let passes = ForwardPasses {
        background: background.as_ref().map(|(p, set)| (&**p, set)),
        mesh: &mesh,
        objects: &objects,
        clear_color: scene.background.clear_color(),
    };
    let settings = inputs.settings;
    let mut timings = inputs.stamps.map(|_| DrawTimings::default());
    for strip in strips(settings.width, settings.height, targets.strip_rows) {
        if with_background {
            // As in the deferred draw: the previous strip has finished.
            frame.strip_offset[1] = strip.first_row as f32;
            buffers.scene_frame.write(std::slice::from_ref(&frame))?;
        }
        record_forward(gpu, targets, &passes, strip, inputs.stamps)?;
        targets.used = true;
        inputs.add_strip_timings(&mut timings)?;
    }
    Ok(Drawn {
        image: read_back(&targets.readback, settings)?,
        denoised: false,
        integral: None,
        timings,
    })
}

/// Per object, the instance mask bit that rays leaving it may leave out (raster/self_hits.rs,
/// visibility.glsl `trace_mask`): a bit of its own below `TRACE_MASK_SHARED` for each of the
/// first seven objects whose mesh some rays cannot meet again, 0 for every other object.
fn own_masks(meshes: &[&GpuMesh]) -> Vec<u32> {
    crate::raster::self_hits::own_mask_bits(
        meshes.iter().map(|m| (m.triangle_count(), m.self_hits)),
    )
}

/// A top-level acceleration structure over `meshes` (instance i is object i, its mask its own
/// bit of `own_masks` or else the shared one; meshes without triangles are left out).
fn top_level(gpu: &GpuContext, meshes: &[&GpuMesh], own: &[u32]) -> Result<AccelerationStructure> {
    let mut instances = Vec::with_capacity(meshes.len());
    for ((index, mesh), &own) in meshes.iter().enumerate().zip(own) {
        if mesh.triangle_count() > 0 {
            instances.push(Instance {
                geometry: mesh.bottom_level(gpu)?,
                custom_index: index as u32,
                mask: match own {
                    0 => TRACE_MASK_SHARED as u8,
                    bit => bit as u8,
                },
            });
        }
    }
    Ok(gpu.build_top_level("scene top-level structure", &instances)?)
}

/// Per object, its `ObjectGeometry` as ray_surface.glsl and visibility.glsl read it at
/// `OBJECT_GEOMETRY_BINDING`: its mesh's buffer addresses, which rays leaving it can meet it
/// again, and its bit of `own`. A mesh without triangles (never hit, never shaded) gets another
/// mesh's addresses: llvmpipe runs the loads of a branch no lane takes, and they must stay in
/// bounds (visibility.glsl's `trace_nearest`).
fn object_geometry(gpu: &GpuContext, meshes: &[&GpuMesh], own: &[u32]) -> Result<Buffer> {
    let stand_in = meshes.iter().find(|m| m.triangle_count() > 0).copied();
    let rows = meshes
        .iter()
        .zip(own)
        .map(|(&mesh, &own_mask)| {
            let addresses = match (mesh.triangle_count(), stand_in) {
                (0, Some(other)) => other.addresses()?,
                _ => mesh.addresses()?,
            };
            let hits = mesh.self_hits;
            Ok(ObjectGeometry {
                addresses,
                clear_sides: u32::from(hits.front_clear) * SELF_HITS_FRONT_CLEAR
                    + u32::from(hits.back_clear) * SELF_HITS_BACK_CLEAR,
                own_mask,
                unused0: 0,
                unused1: 0,
            })
        })
        .collect::<Result<Vec<ObjectGeometry>>>()?;
    gpu_mesh::upload(gpu, "object geometry", &rows, BufferUsage::STORAGE)
}

fn read_back(readback: &Buffer, settings: &RenderSettings) -> Result<HdrImage> {
    Ok(HdrImage {
        width: settings.width,
        height: settings.height,
        pixels: readback.read()?,
    })
}

/// The layers of [`upload_black_environment`]'s stand-in.
const BLACK_ENVIRONMENT_LAYERS: usize = 2;

/// The stand-in for a draw without an environment: black, uploaded rather than prefiltered, so
/// a context that never sees an environment builds no prefilter pipelines.
fn upload_black_environment(gpu: &GpuContext) -> Result<GpuEnvironment> {
    let face = crate::environment::params::MIN_LAYER_FACE;
    let black = || CubeImage {
        face_size: face,
        texels: vec![[0.0, 0.0, 0.0, 1.0]; 6 * (face as usize).pow(2)],
    };
    let env = PrefilteredEnvironment {
        // β of the sharp layer 0 and of one fully blurred layer.
        betas: vec![0.0, 1.0],
        layers: (0..BLACK_ENVIRONMENT_LAYERS).map(|_| black()).collect(),
        irradiance: black(),
    };
    GpuEnvironment::upload(gpu, &env)
}

/// The pixels any object can cover (the union of their boxes' screen bounds); empty without
/// objects.
fn screen_bounds(inputs: &DrawInputs<'_>) -> PixelRect {
    let (scene, settings) = (inputs.scene, inputs.settings);
    let mut union: Option<PixelRect> = None;
    for object in scene.objects {
        let Some(bounds) = object.mesh.bounding_box() else {
            continue;
        };
        let r = scene.camera.screen_bounds(
            bounds,
            settings.width,
            settings.height,
            inputs.scene_sphere,
        );
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
