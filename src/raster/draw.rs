//! The GPU draw: a mesh shaded with the lacquer BRDF (lacquer.frag) into an offscreen HDR target,
//! lit by point/directional lights and the prefiltered environment, over a background (the sharp
//! environment, a colour, or transparent), resolved (MSAA) and read back as an [`HdrImage`].
//!
//! Per draw: write uniforms and Fresnel knots → transition targets → background pass → mesh pass
//! → resolve → copy to a readback buffer → barrier to host. Kept between draws: each pipeline
//! (built on first use, so a command builds only the ones it draws with), the sampler, the black
//! stand-in environment, the render targets and readback buffer of the last size
//! (`draw_targets.rs`) and each object slot's uniform and knot buffers. Meshes are uploaded per
//! draw by [`LacquerRenderer::render`]; callers that draw the same mesh again (the scene renderer)
//! upload a [`GpuMesh`] once and use [`LacquerRenderer::render_meshes`].

use crate::environment::gpu::GpuEnvironment;
use crate::environment::params::ViewBlur;
use crate::environment::{CubeImage, PrefilteredEnvironment};
use crate::gpu::{
    Binding, BindingKind, Buffer, BufferUsage, DescriptorSet, Format, GpuContext, GraphicsPipeline,
    GraphicsPipelineDesc, Image, Resource, Sampler, TimestampPool,
};
use crate::model::{BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::camera::Camera;
use crate::raster::draw_record::{
    record_and_submit, timings_from, RecordedDraw, Strip, TIMESTAMPS,
};
use crate::raster::draw_targets::TargetCache;
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

const BINDINGS: [Binding; 4] = [
    Binding::new(0, BindingKind::UniformBuffer),
    Binding::new(1, BindingKind::StorageBuffer),
    Binding::array(2, BindingKind::SampledImage, MAX_ENV_LAYERS as u32),
    Binding::new(3, BindingKind::SampledImage),
];

/// The fragment shader of the mesh pass.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum MeshShading {
    /// lacquer.frag: the model (every real render).
    #[default]
    Lacquer,
    /// trivial.frag: a constant colour, the rasteriser's floor for the same geometry (benchmarks).
    Trivial,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
enum PipelineKind {
    Mesh(MeshShading),
    Background,
}

/// GPU time of one draw's passes from timestamp queries, in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DrawTimings {
    /// The rendering pass: background (if any), mesh draws, the end of the pass and the MSAA
    /// resolve.
    pub pass: f64,
    /// Resolved image → readback buffer.
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

/// The per-object buffers of one draw slot, rewritten by every draw (the previous draw has
/// finished: `submit_and_wait` waits on its fence before returning).
struct ObjectSlot {
    frame: Buffer,
    knots: Buffer,
}

/// Fresnel tables up to this many knots fit a slot's first knot buffer (the built-in tables have
/// 91); a longer table replaces it with a bigger one.
const SLOT_KNOTS: usize = 128;

/// The lacquer raster renderer; keeps its pipelines, targets and buffers between draws.
#[derive(Default)]
pub struct LacquerRenderer {
    /// Keyed by kind, MSAA samples and the environment's layer count K (a specialization constant).
    pipelines: HashMap<(PipelineKind, u32, u32), GraphicsPipeline>,
    sampler: Option<Sampler>,
    black_environment: Option<GpuEnvironment>,
    targets: TargetCache,
    /// Slot 0 is the background pass; slot i + 1 is object i.
    slots: Vec<ObjectSlot>,
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
            let (name, vertex_spirv, fragment_spirv, attributes, depth_test): (_, _, _, &[_], _) =
                match kind {
                    PipelineKind::Mesh(MeshShading::Lacquer) => {
                        ("lacquer", MESH_VERT, LACQUER_FRAG, &VERTEX_ATTRIBUTES, true)
                    }
                    PipelineKind::Mesh(MeshShading::Trivial) => {
                        ("trivial", MESH_VERT, TRIVIAL_FRAG, &VERTEX_ATTRIBUTES, true)
                    }
                    PipelineKind::Background => {
                        ("background", BACKGROUND_VERT, BACKGROUND_FRAG, &[], false)
                    }
                };
            entry.insert(gpu.create_graphics_pipeline(&GraphicsPipelineDesc {
                name,
                vertex_spirv,
                fragment_spirv,
                bindings: &BINDINGS,
                vertex_stride: VERTEX_STRIDE,
                vertex_attributes: attributes,
                color_format: Format::Rgba32Float,
                depth_format: Format::Depth32Float,
                samples,
                depth_test,
                // frame.glsl's ENV_LAYER_COUNT: a sampler array may only be indexed by constants
                // on lavapipe, and a constant K lets the shader skip the absent layers.
                fragment_constants: &[layer_count],
            })?);
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
        let mesh_kind = PipelineKind::Mesh(options.shading);
        self.ensure_pipeline(gpu, mesh_kind, samples, layer_count)?;
        if with_background {
            self.ensure_pipeline(gpu, PipelineKind::Background, samples, layer_count)?;
        }
        if options.timed && self.timestamps.is_none() {
            self.timestamps = Some(gpu.create_timestamp_pool(TIMESTAMPS)?);
        }
        let mut background_frame = self.write_slots(gpu, scene, settings)?;
        let environment = match scene.environment {
            Some(env) => env,
            None => self.black_environment.as_ref().ok_or_else(internal)?,
        };
        let sampler = self.sampler.as_ref().ok_or_else(internal)?;
        let pipeline = |kind| {
            self.pipelines
                .get(&(kind, samples, layer_count))
                .ok_or_else(internal)
        };
        let mesh_pipeline = pipeline(mesh_kind)?;
        // Descriptor sets name the environment's images, which may differ from the last draw's;
        // they are cheap (one small pool each), so they are made per draw.
        let bind = |pipeline: &GraphicsPipeline, slot: &ObjectSlot| {
            bind_set(gpu, pipeline, slot, environment, sampler)
        };
        let background = match with_background {
            true => {
                let p = pipeline(PipelineKind::Background)?;
                Some((p, bind(p, &self.slots[0])?))
            }
            false => None,
        };
        let object_sets: Vec<DescriptorSet> = self.slots[1..=meshes.len()]
            .iter()
            .map(|slot| bind(mesh_pipeline, slot))
            .collect::<Result<_>>()?;
        let stamps = if options.timed {
            self.timestamps.as_ref()
        } else {
            None
        };
        let targets = self
            .targets
            .get(gpu, (settings.width, settings.height, samples))?;
        let objects: Vec<(&GpuMesh, &DescriptorSet)> =
            meshes.iter().copied().zip(&object_sets).collect();
        let clear_color = match scene.background {
            Background::Transparent | Background::Environment => [0.0; 4],
            Background::Color([r, g, b]) => [r, g, b, 1.0],
        };
        let mut timings: Option<DrawTimings> = stamps.map(|_| DrawTimings::default());
        let mut first_row = 0;
        while first_row < settings.height {
            let rows = targets.strip_rows.min(settings.height - first_row);
            if with_background {
                // The previous strip's submit has finished (submit_and_wait), so slot 0's
                // uniforms can be rewritten for this one.
                background_frame.strip_offset[1] = first_row as f32;
                self.slots[0]
                    .frame
                    .write(std::slice::from_ref(&background_frame))?;
            }
            let recorded = RecordedDraw {
                targets,
                strip: Strip {
                    first_row,
                    rows,
                    image_width: settings.width,
                    image_height: settings.height,
                },
                background: background.as_ref().map(|(p, s)| (*p, s)),
                mesh_pipeline,
                objects: objects.clone(),
                clear_color,
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

    /// Writes the frame uniforms and knots of the background (slot 0) and of every object.
    fn write_slots(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
    ) -> Result<FrameUniforms> {
        let environment_betas = match scene.environment {
            Some(env) => env.betas.clone(),
            None => self
                .black_environment
                .as_ref()
                .map(|e| e.betas.clone())
                .unwrap_or_default(),
        };
        let scene_radius = scene
            .objects
            .iter()
            .map(|o| o.mesh.bounding_radius())
            .fold(0.0, f64::max);
        let uniforms = |brdf: &BrdfParams, fresnel: &FresnelTable, view_blur: ViewBlur| {
            FrameUniforms::new(
                scene.camera,
                settings.width,
                settings.height,
                scene_radius,
                scene.lights,
                brdf,
                fresnel,
                &EnvironmentUniforms {
                    enabled: scene.environment.is_some(),
                    layer_betas: environment_betas.clone(),
                    view_blur,
                },
            )
        };
        // The background pass needs only the camera and the environment: the uniforms of any
        // material will do (a default one when the scene has no object).
        let default_brdf;
        let default_fresnel;
        let (brdf, fresnel) = match scene.objects.first() {
            Some(o) => (o.brdf, o.fresnel),
            None => {
                default_brdf = crate::model::LacquerMaterial::default().brdf_params()?;
                default_fresnel = FresnelTable::new(vec![0.0, 90.0], vec![[0.0; 3], [1.0; 3]])?;
                (&default_brdf, &default_fresnel)
            }
        };
        let mut contents = vec![(uniforms(brdf, fresnel, ViewBlur::default()), fresnel)];
        for object in scene.objects {
            contents.push((
                uniforms(object.brdf, object.fresnel, object.view_blur),
                object.fresnel,
            ));
        }
        for (i, (frame, fresnel)) in contents.iter().enumerate() {
            let knots = shading::fresnel_knots(fresnel);
            let fits = |slot: &ObjectSlot| slot.knots.size() as usize >= knots.len() * 16;
            if self.slots.get(i).is_some_and(|slot| !fits(slot)) {
                self.slots.truncate(i);
            }
            if self.slots.len() <= i {
                let capacity = vec![[0.0f32; 4]; knots.len().max(SLOT_KNOTS)];
                self.slots.insert(
                    i,
                    ObjectSlot {
                        frame: upload(
                            gpu,
                            "frame uniforms",
                            std::slice::from_ref(frame),
                            BufferUsage::UNIFORM,
                        )?,
                        knots: upload(gpu, "fresnel knots", &capacity, BufferUsage::STORAGE)?,
                    },
                );
            }
            let slot = &mut self.slots[i];
            slot.frame.write(std::slice::from_ref(frame))?;
            slot.knots.write(&knots)?;
        }
        Ok(contents[0].0)
    }
}

fn bind_set(
    gpu: &GpuContext,
    pipeline: &GraphicsPipeline,
    slot: &ObjectSlot,
    environment: &GpuEnvironment,
    sampler: &Sampler,
) -> Result<DescriptorSet> {
    // Unused array slots repeat the last layer: every element needs a valid descriptor.
    let mut layer_images: Vec<&Image> = environment.layers.iter().collect();
    while layer_images.len() < MAX_ENV_LAYERS {
        let last = layer_images[layer_images.len() - 1];
        layer_images.push(last);
    }
    layer_images.truncate(MAX_ENV_LAYERS);
    Ok(gpu.create_descriptor_set(
        pipeline.layout(),
        &[
            (0, Resource::Buffer(&slot.frame)),
            (1, Resource::Buffer(&slot.knots)),
            (2, Resource::SampledImages(layer_images, sampler)),
            (3, Resource::SampledImage(&environment.irradiance, sampler)),
        ],
    )?)
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
    for object in scene.objects {
        object.mesh.validate()?;
    }
    Ok(())
}
