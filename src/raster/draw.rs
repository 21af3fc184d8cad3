//! The GPU draw: a mesh shaded with the lacquer BRDF (lacquer.frag) into an offscreen HDR target,
//! lit by point/directional lights and the prefiltered environment, over a background (the sharp
//! environment, a colour, or transparent), resolved (MSAA) and read back as an [`HdrImage`].
//!
//! Per draw: upload mesh, uniforms and Fresnel knots → transition targets → background pass →
//! mesh pass → resolve → copy to a readback buffer → barrier to host. Pipelines, the sampler and
//! the black stand-in environment are made once and kept.

use crate::environment::gpu::{GpuEnvironment, GpuPrefilter};
use crate::environment::params::ViewBlur;
use crate::environment::{Equirect, PrefilterParams};
use crate::gpu::{
    Access, Binding, BindingKind, Buffer, BufferDesc, BufferUsage, DescriptorSet, Format,
    GpuContext, GraphicsPipeline, GraphicsPipelineDesc, Image, ImageDesc, ImageUse, Layout,
    RenderTargets, Resource, Sampler, VertexAttribute,
};
use crate::model::{BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::camera::Camera;
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

/// Interleaved position (xyz) + normal (xyz), f32.
const VERTEX_STRIDE: u32 = 24;
const VERTEX_ATTRIBUTES: [VertexAttribute; 2] = [
    VertexAttribute {
        location: 0,
        offset: 0,
        components: 3,
    },
    VertexAttribute {
        location: 1,
        offset: 12,
        components: 3,
    },
];

/// The two pipelines of one sample count.
struct Pipelines {
    lacquer: GraphicsPipeline,
    background: GraphicsPipeline,
}

/// The lacquer raster renderer; keeps its pipelines between draws.
#[derive(Default)]
pub struct LacquerRenderer {
    pipelines: HashMap<u32, Pipelines>,
    sampler: Option<Sampler>,
    black_environment: Option<GpuEnvironment>,
}

impl LacquerRenderer {
    pub fn new() -> Self {
        Self::default()
    }

    fn ensure_pipelines(&mut self, gpu: &GpuContext, samples: u32) -> Result<()> {
        match self.pipelines.entry(samples) {
            Entry::Occupied(_) => Ok(()),
            Entry::Vacant(entry) => {
                use crate::gpu::shaders::*;
                let desc = |name, vertex_spirv, fragment_spirv, attributes, depth_test| {
                    GraphicsPipelineDesc {
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
                    }
                };
                let lacquer = gpu.create_graphics_pipeline(&desc(
                    "lacquer",
                    MESH_VERT,
                    LACQUER_FRAG,
                    &VERTEX_ATTRIBUTES,
                    true,
                ))?;
                let background = gpu.create_graphics_pipeline(&desc(
                    "background",
                    BACKGROUND_VERT,
                    BACKGROUND_FRAG,
                    &[],
                    false,
                ))?;
                entry.insert(Pipelines {
                    lacquer,
                    background,
                });
                Ok(())
            }
        }
    }

    /// Made once: the sampler and a black environment bound when a draw has none (every binding
    /// the shaders declare must hold a valid descriptor).
    fn prepare_shared(&mut self, gpu: &GpuContext) -> Result<()> {
        if self.sampler.is_none() {
            self.sampler = Some(gpu.create_sampler()?);
        }
        if self.black_environment.is_none() {
            let black = Equirect::constant(2, 1, [0.0; 3]);
            let params = PrefilterParams {
                face_size: crate::environment::params::MIN_LAYER_FACE,
                layers: 2,
                beta_min: 1.0,
                beta_max: 1.0,
            };
            let env = GpuPrefilter::new(gpu)?.run(gpu, &black, &params, 1.0, 0.0)?;
            self.black_environment = Some(env);
        }
        Ok(())
    }

    /// Renders `scene` and reads the image back (linear radiance, alpha = coverage, row 0 top).
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
    ) -> Result<HdrImage> {
        validate(gpu, scene, settings)?;
        self.prepare_shared(gpu)?;
        self.ensure_pipelines(gpu, settings.samples)?;
        let internal = || Error::invalid("renderer", "uninitialised", "internal error");
        let pipelines = self.pipelines.get(&settings.samples).ok_or_else(internal)?;
        let sampler = self.sampler.as_ref().ok_or_else(internal)?;
        let black = self.black_environment.as_ref().ok_or_else(internal)?;
        let environment = scene.environment.unwrap_or(black);
        draw(gpu, pipelines, sampler, environment, scene, settings)
    }
}

/// The GPU resources of one object for one draw.
struct ObjectResources {
    vertices: Buffer,
    indices: Buffer,
    index_count: u32,
    lacquer_set: DescriptorSet,
    // Bound through `lacquer_set`; kept alive until the submit has finished.
    _frame: Buffer,
    _knots: Buffer,
}

fn draw(
    gpu: &GpuContext,
    pipelines: &Pipelines,
    sampler: &Sampler,
    environment: &GpuEnvironment,
    scene: &DrawScene<'_>,
    settings: &RenderSettings,
) -> Result<HdrImage> {
    let RenderSettings {
        width,
        height,
        samples,
    } = *settings;
    // Unused array slots repeat the last layer: every element needs a valid descriptor.
    let mut layer_images: Vec<&Image> = environment.layers.iter().collect();
    while layer_images.len() < MAX_ENV_LAYERS {
        let last = layer_images[layer_images.len() - 1];
        layer_images.push(last);
    }
    layer_images.truncate(MAX_ENV_LAYERS);
    let scene_radius = scene
        .objects
        .iter()
        .map(|o| o.mesh.bounding_radius())
        .fold(0.0, f64::max);
    let uniforms = |object: &DrawObject<'_>| {
        FrameUniforms::new(
            scene.camera,
            width,
            height,
            scene_radius,
            scene.lights,
            object.brdf,
            object.fresnel,
            &EnvironmentUniforms {
                enabled: scene.environment.is_some(),
                layer_betas: environment.betas.clone(),
                view_blur: object.view_blur,
            },
        )
    };
    let bind = |layout, frame: &Buffer, knots: &Buffer| {
        gpu.create_descriptor_set(
            layout,
            &[
                (0, Resource::Buffer(frame)),
                (1, Resource::Buffer(knots)),
                (2, Resource::SampledImages(layer_images.clone(), sampler)),
                (3, Resource::SampledImage(&environment.irradiance, sampler)),
            ],
        )
    };

    let mut objects = Vec::with_capacity(scene.objects.len());
    for object in scene.objects {
        let vertices: Vec<[f32; 6]> = object
            .mesh
            .positions
            .iter()
            .zip(&object.mesh.normals)
            .map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]])
            .collect();
        let vertices = upload(gpu, "mesh vertices", &vertices, BufferUsage::VERTEX)?;
        let indices = upload(
            gpu,
            "mesh indices",
            &object.mesh.indices,
            BufferUsage::INDEX,
        )?;
        let frame = upload(
            gpu,
            "frame uniforms",
            std::slice::from_ref(&uniforms(object)),
            BufferUsage::UNIFORM,
        )?;
        let knots = shading::fresnel_knots(object.fresnel);
        let knots = upload(gpu, "fresnel knots", &knots, BufferUsage::STORAGE)?;
        let lacquer_set = bind(pipelines.lacquer.layout(), &frame, &knots)?;
        objects.push(ObjectResources {
            vertices,
            indices,
            index_count: object.mesh.indices.len() as u32,
            lacquer_set,
            _frame: frame,
            _knots: knots,
        });
    }
    // The background pass needs only the camera and the environment: the uniforms of any
    // material will do (a default one when the scene has no object).
    let default_brdf = crate::model::LacquerMaterial::default().brdf_params()?;
    let default_fresnel =
        crate::model::FresnelTable::new(vec![0.0, 90.0], vec![[0.0; 3], [1.0; 3]])?;
    let background_object = DrawObject {
        mesh: scene.objects.first().map_or(&EMPTY_MESH, |o| o.mesh),
        brdf: scene.objects.first().map_or(&default_brdf, |o| o.brdf),
        fresnel: scene
            .objects
            .first()
            .map_or(&default_fresnel, |o| o.fresnel),
        view_blur: ViewBlur::default(),
    };
    let background_frame = upload(
        gpu,
        "background uniforms",
        std::slice::from_ref(&uniforms(&background_object)),
        BufferUsage::UNIFORM,
    )?;
    let background_knots = upload(
        gpu,
        "background knots",
        &shading::fresnel_knots(background_object.fresnel),
        BufferUsage::STORAGE,
    )?;
    let background_set = bind(
        pipelines.background.layout(),
        &background_frame,
        &background_knots,
    )?;

    let color = gpu.create_image(ImageDesc::color_target("color", width, height, samples))?;
    let resolve = if samples > 1 {
        Some(gpu.create_image(ImageDesc::color_target("resolve", width, height, 1))?)
    } else {
        None
    };
    let depth = gpu.create_image(ImageDesc::depth_target("depth", width, height, samples))?;
    let output = resolve.as_ref().unwrap_or(&color);
    let readback = gpu.create_buffer(BufferDesc::readback("readback", output.byte_size()))?;

    let clear_color = match scene.background {
        Background::Transparent | Background::Environment => [0.0, 0.0, 0.0, 0.0],
        Background::Color([r, g, b]) => [r, g, b, 1.0],
    };
    let undefined = ImageUse::new(Access::Nothing, Layout::Undefined);
    let color_attachment = ImageUse::new(Access::ColorAttachmentWrite, Layout::ColorAttachment);
    let depth_attachment = ImageUse::new(Access::DepthAttachmentWrite, Layout::DepthAttachment);
    let transfer_src = ImageUse::new(Access::TransferRead, Layout::TransferSrc);
    gpu.submit_and_wait(|rec| {
        rec.image_barrier(&color, undefined, color_attachment);
        if let Some(resolve) = &resolve {
            rec.image_barrier(resolve, undefined, color_attachment);
        }
        rec.image_barrier(&depth, undefined, depth_attachment);
        rec.begin_rendering(&RenderTargets {
            color: &color,
            resolve: resolve.as_ref(),
            depth: &depth,
            clear_color,
        });
        if scene.background == Background::Environment {
            rec.bind_graphics(&pipelines.background, &background_set);
            rec.draw(3);
        }
        for object in &objects {
            rec.bind_graphics(&pipelines.lacquer, &object.lacquer_set);
            rec.bind_mesh_buffers(&object.vertices, &object.indices);
            rec.draw_indexed(object.index_count);
        }
        rec.end_rendering();
        rec.image_barrier(output, color_attachment, transfer_src);
        rec.copy_image_to_buffer(output, &readback);
        rec.memory_barrier(Access::TransferWrite, Access::HostRead);
        Ok(())
    })?;
    let pixels: Vec<[f32; 4]> = readback.read()?;
    Ok(HdrImage {
        width,
        height,
        pixels,
    })
}

/// A mapped buffer holding `data`.
fn upload<T: bytemuck::Pod>(
    gpu: &GpuContext,
    name: &str,
    data: &[T],
    usage: BufferUsage,
) -> Result<Buffer> {
    let mut buffer = gpu.create_buffer(BufferDesc::upload(
        name,
        std::mem::size_of_val(data) as u64,
        usage,
    ))?;
    buffer.write(data)?;
    Ok(buffer)
}

static EMPTY_MESH: Mesh = Mesh {
    positions: Vec::new(),
    normals: Vec::new(),
    indices: Vec::new(),
};

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
