//! The GPU draw: a mesh shaded with the lacquer BRDF (lacquer.frag) into an offscreen HDR target,
//! resolved (MSAA) and read back as an [`HdrImage`].
//!
//! Per draw: upload mesh, uniforms and Fresnel knots → transition targets → render → resolve →
//! copy to a readback buffer → barrier to host. Pipelines are made once per sample count and kept.

use crate::gpu::{
    Access, Binding, BindingKind, BufferDesc, BufferUsage, Format, GpuContext, GraphicsPipeline,
    GraphicsPipelineDesc, ImageDesc, ImageUse, Layout, RenderTargets, Resource, VertexAttribute,
};
use crate::model::{BrdfParams, FresnelTable};
use crate::output::HdrImage;
use crate::raster::camera::Camera;
use crate::raster::lights::{Light, MAX_LIGHTS};
use crate::raster::mesh::Mesh;
use crate::shading::{self, FrameUniforms};
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

/// What one draw shows.
pub struct DrawScene<'a> {
    pub mesh: &'a Mesh,
    pub camera: &'a Camera,
    pub lights: &'a [Light],
    pub brdf: &'a BrdfParams,
    pub fresnel: &'a FresnelTable,
}

const BINDINGS: [Binding; 2] = [
    Binding::new(0, BindingKind::UniformBuffer),
    Binding::new(1, BindingKind::StorageBuffer),
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

/// The lacquer raster renderer; keeps its pipelines between draws.
#[derive(Default)]
pub struct LacquerRenderer {
    pipelines: HashMap<u32, GraphicsPipeline>,
}

impl LacquerRenderer {
    pub fn new() -> Self {
        Self::default()
    }

    fn pipeline(&mut self, gpu: &GpuContext, samples: u32) -> Result<&GraphicsPipeline> {
        match self.pipelines.entry(samples) {
            Entry::Occupied(entry) => Ok(entry.into_mut()),
            Entry::Vacant(entry) => {
                let pipeline = gpu.create_graphics_pipeline(&GraphicsPipelineDesc {
                    name: "lacquer",
                    vertex_spirv: crate::gpu::shaders::MESH_VERT,
                    fragment_spirv: crate::gpu::shaders::LACQUER_FRAG,
                    bindings: &BINDINGS,
                    vertex_stride: VERTEX_STRIDE,
                    vertex_attributes: &VERTEX_ATTRIBUTES,
                    color_format: Format::Rgba32Float,
                    depth_format: Format::Depth32Float,
                    samples,
                })?;
                Ok(entry.insert(pipeline))
            }
        }
    }

    /// Renders `scene` and reads the image back (linear radiance, alpha = coverage, row 0 top).
    pub fn render(
        &mut self,
        gpu: &GpuContext,
        scene: &DrawScene<'_>,
        settings: &RenderSettings,
    ) -> Result<HdrImage> {
        validate(gpu, scene, settings)?;
        let RenderSettings {
            width,
            height,
            samples,
        } = *settings;
        let pipeline = self.pipeline(gpu, samples)?;

        let vertices: Vec<[f32; 6]> = scene
            .mesh
            .positions
            .iter()
            .zip(&scene.mesh.normals)
            .map(|(p, n)| [p[0], p[1], p[2], n[0], n[1], n[2]])
            .collect();
        let mut vertex_buf = gpu.create_buffer(BufferDesc::upload(
            "mesh vertices",
            (vertices.len() * VERTEX_STRIDE as usize) as u64,
            BufferUsage::VERTEX,
        ))?;
        vertex_buf.write(&vertices)?;
        let mut index_buf = gpu.create_buffer(BufferDesc::upload(
            "mesh indices",
            (scene.mesh.indices.len() * 4) as u64,
            BufferUsage::INDEX,
        ))?;
        index_buf.write(&scene.mesh.indices)?;

        let frame = FrameUniforms::new(
            scene.camera,
            width,
            height,
            scene.mesh.bounding_radius(),
            scene.lights,
            scene.brdf,
            scene.fresnel,
        );
        let mut frame_buf = gpu.create_buffer(BufferDesc::upload(
            "frame uniforms",
            std::mem::size_of::<FrameUniforms>() as u64,
            BufferUsage::UNIFORM,
        ))?;
        frame_buf.write(std::slice::from_ref(&frame))?;
        let knots = shading::fresnel_knots(scene.fresnel);
        let mut knots_buf = gpu.create_buffer(BufferDesc::upload(
            "fresnel knots",
            (knots.len() * 16) as u64,
            BufferUsage::STORAGE,
        ))?;
        knots_buf.write(&knots)?;
        let set = gpu.create_descriptor_set(
            pipeline.layout(),
            &[
                (0, Resource::Buffer(&frame_buf)),
                (1, Resource::Buffer(&knots_buf)),
            ],
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

        let undefined = ImageUse::new(Access::Nothing, Layout::Undefined);
        let color_attachment = ImageUse::new(Access::ColorAttachmentWrite, Layout::ColorAttachment);
        let depth_attachment = ImageUse::new(Access::DepthAttachmentWrite, Layout::DepthAttachment);
        let transfer_src = ImageUse::new(Access::TransferRead, Layout::TransferSrc);
        let index_count = scene.mesh.indices.len() as u32;
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
                clear_color: [0.0, 0.0, 0.0, 0.0],
            });
            rec.bind_graphics(pipeline, &set);
            rec.bind_mesh_buffers(&vertex_buf, &index_buf);
            rec.draw_indexed(index_count);
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
    scene.camera.validate()?;
    for light in scene.lights {
        light.validate()?;
    }
    scene.mesh.validate()
}
