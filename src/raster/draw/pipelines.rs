//! The pipeline table: every graphics pipeline the draws use, keyed by kind, sample count and the
//! environment's layer count, each built on first use (a command builds only the ones it draws
//! with) and kept; the descriptor-set layouts they declare, and the descriptor sets of one draw.

use super::frame::DrawBuffers;
use super::gpu_mesh::{VERTEX_ATTRIBUTES, VERTEX_STRIDE};
use crate::environment::brdf_quadrature::{BRDF_HIT_SAMPLES, BRDF_SAMPLES};
use crate::environment::gpu::GpuEnvironment;
use crate::environment::EnvironmentModel;
use crate::gpu::shaders::interface::{
    DrawConstants, TraceOrigin, BACKGROUND_COLOR, BACKGROUND_ENVIRONMENT, ENV_IRRADIANCE_BINDING,
    ENV_LAYERS_BINDING, ENV_LAYER_TEXELS_BINDING, FRAME_BINDING, FRESNEL_KNOTS_BINDING,
    GBUFFER_NORMAL_BINDING, GBUFFER_POSITION_BINDING, MAX_ENV_LAYERS, OBJECT_GEOMETRY_BINDING,
    OBJECT_MATERIAL_BINDING, SCENE_TLAS_BINDING, SHADED_IMAGE_BINDING, SHADED_INTEGRAL_BINDING,
};
use crate::gpu::{
    AccelerationStructure, Binding, BindingKind, Buffer, DepthCompare, DepthTest, DescriptorSet,
    Format, GpuContext, GraphicsPipeline, GraphicsPipelineDesc, Image, PipelineLayout,
    RayTracingPipeline, RayTracingPipelineDesc, Resource, Sampler,
};
use crate::Result;
use std::collections::hash_map::Entry;
use std::collections::HashMap;
use std::sync::Arc;

/// The mesh and background passes' set: the frame and the environment (background.frag samples
/// it).
const GRAPHICS_BINDINGS: [Binding; 3] = [
    Binding::new(FRAME_BINDING, BindingKind::UniformBuffer),
    Binding::array(
        ENV_LAYERS_BINDING,
        BindingKind::SampledImage,
        MAX_ENV_LAYERS as u32,
    ),
    Binding::new(ENV_IRRADIANCE_BINDING, BindingKind::SampledImage),
];

/// The shading pass's set (coverage_body.glsl, shade_body.glsl): the frame, the Fresnel knots,
/// the environment (its layers also as texels, for the `brdf` model), the materials, the
/// G-buffer; in the ray-traced pipelines the draw's top-level structure and its objects' mesh
/// addresses; and in the ray-tracing pipeline's shading (shade_rt*.rgen) the image and the
/// integral image it writes. Each set is a prefix of this one.
const SHADE_BINDINGS_RAY_PIPELINE: [Binding; 12] = [
    Binding::new(FRAME_BINDING, BindingKind::UniformBuffer),
    Binding::new(FRESNEL_KNOTS_BINDING, BindingKind::UniformTexelBuffer),
    Binding::array(
        ENV_LAYERS_BINDING,
        BindingKind::SampledImage,
        MAX_ENV_LAYERS as u32,
    ),
    Binding::new(ENV_IRRADIANCE_BINDING, BindingKind::SampledImage),
    Binding::new(OBJECT_MATERIAL_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(GBUFFER_POSITION_BINDING, BindingKind::SampledImage),
    Binding::new(GBUFFER_NORMAL_BINDING, BindingKind::SampledImage),
    Binding::new(ENV_LAYER_TEXELS_BINDING, BindingKind::UniformTexelBuffer),
    Binding::new(SCENE_TLAS_BINDING, BindingKind::AccelerationStructure),
    Binding::new(OBJECT_GEOMETRY_BINDING, BindingKind::StorageBuffer),
    Binding::new(SHADED_IMAGE_BINDING, BindingKind::StorageImage),
    Binding::new(SHADED_INTEGRAL_BINDING, BindingKind::StorageImage),
];

/// The ray-traced shading pass's (shade_rt*.frag, and the coverage draw beside either path).
const SHADE_BINDINGS_TRACED: &[Binding] = SHADE_BINDINGS_RAY_PIPELINE.split_at(10).0;

/// [`SHADE_BINDINGS_TRACED`] without the acceleration structure.
const SHADE_BINDINGS: &[Binding] = SHADE_BINDINGS_RAY_PIPELINE.split_at(8).0;

/// The shading pass's bindings (coverage and shade pipelines share one set).
fn shade_bindings(ray_traced: bool) -> &'static [Binding] {
    match ray_traced {
        true => SHADE_BINDINGS_TRACED,
        false => SHADE_BINDINGS,
    }
}

/// The specialization constants of a shading pipeline that depend on the draw.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub(super) struct ShadeVariant {
    /// The environment (else a colour) fills uncovered samples.
    pub environment_background: bool,
    /// See [`fresnel_on_pow2_grid`].
    pub fresnel_pow2_grid: bool,
    /// SPEC §4's environment model.
    pub environment_model: EnvironmentModel,
    /// Rays are traced (SPEC §6): shade_rt*.frag and their bindings.
    pub ray_traced: bool,
    /// ... and shadow rays among them (`SHADOWS`).
    pub shadows: bool,
    /// ... and SPEC §6's integral (`INTEGRAL`: bounces ≥ 1).
    pub integral: bool,
}

/// Whether a table's knots (as the shader reads them, f32) lie at exactly i·step degrees from 0
/// with step a power of two, so that θ/step is exact and its integer part is the interval the
/// shader's search would find. The built-in tables (a knot per degree) do.
pub(super) fn fresnel_on_pow2_grid(knots: &[[f32; 4]]) -> bool {
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
pub(super) enum PipelineKind {
    /// The lacquer draw's geometry pass (gbuffer.frag), multisampled. `true`: it keeps each
    /// sample's triangle for the ray-traced shading pass (gbuffer_rt.frag).
    GBuffer(bool),
    /// The shading pass's first draw (coverage_body.glsl), single-sampled, reading a G-buffer
    /// of the key's sample count. First field: the environment is the background (then it
    /// writes colour). The second field: the shading pass traces rays, so the set (shared with Shade) has the
    /// acceleration structure too.
    Coverage(bool, bool),
    /// The shading pass's second draw (shade_body.glsl); keyed like Coverage.
    Shade(ShadeVariant),
    /// The benchmark's forward draw (trivial.frag).
    Trivial,
    /// The background of a forward draw.
    Background,
}

/// One pipeline of the table.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub(super) struct PipelineKey {
    pub kind: PipelineKind,
    /// The G-buffer's (or the forward target's) MSAA samples.
    pub samples: u32,
    /// K of the bound environment: a specialization constant.
    pub layer_count: u32,
}

impl PipelineKey {
    fn constants(&self) -> DrawConstants {
        let variant = match self.kind {
            PipelineKind::Shade(variant) => variant,
            PipelineKind::Coverage(environment_background, ray_traced) => ShadeVariant {
                environment_background,
                ray_traced,
                ..ShadeVariant::default()
            },
            _ => ShadeVariant::default(),
        };
        DrawConstants {
            env_layer_count: self.layer_count,
            sample_count: self.samples,
            background_kind: match variant.environment_background {
                true => BACKGROUND_ENVIRONMENT,
                false => BACKGROUND_COLOR,
            },
            fresnel_pow2_grid: u32::from(variant.fresnel_pow2_grid),
            env_samples: BRDF_SAMPLES,
            env_hit_samples: BRDF_HIT_SAMPLES,
            shadows: u32::from(variant.shadows),
            integral: u32::from(variant.integral),
        }
    }

    /// How the pipeline is built.
    fn desc<'a>(&self, constants: &'a DrawConstants) -> GraphicsPipelineDesc<'a> {
        use crate::gpu::shaders::*;
        let multisampled = self.samples > 1;
        match self.kind {
            PipelineKind::GBuffer(ray_traced) => self.mesh(
                "gbuffer",
                match ray_traced {
                    true => GBUFFER_RT_FRAG,
                    false => GBUFFER_FRAG,
                },
                &GBUFFER_FORMATS,
                constants,
            ),
            PipelineKind::Trivial => self.mesh("trivial", TRIVIAL_FRAG, &COLOR_FORMAT, constants),
            // Writes 0 (covered) or 1 (the clear value, passing as equal so the background colour
            // is written too) into the coverage depth.
            PipelineKind::Coverage(_, ray_traced) => self.full_screen(
                "coverage",
                if multisampled {
                    COVERAGE_MS_FRAG
                } else {
                    COVERAGE_FRAG
                },
                (shade_bindings(ray_traced), 1),
                Some(DepthTest {
                    compare: DepthCompare::LessOrEqual,
                    write: true,
                }),
                constants,
            ),
            // 1 > 0 passes where a sample is covered; early, so uncovered blocks are skipped.
            PipelineKind::Shade(variant) => self.full_screen(
                "shade",
                // The model is compiled in (a define), not specialized: BENCHMARKS.md.
                match (variant.environment_model, variant.ray_traced, multisampled) {
                    (EnvironmentModel::Paper, false, false) => SHADE_FRAG,
                    (EnvironmentModel::Paper, false, true) => SHADE_MS_FRAG,
                    (EnvironmentModel::Paper, true, false) => SHADE_RT_FRAG,
                    (EnvironmentModel::Paper, true, true) => SHADE_RT_MS_FRAG,
                    (EnvironmentModel::Brdf, false, false) => SHADE_BRDF_FRAG,
                    (EnvironmentModel::Brdf, false, true) => SHADE_BRDF_MS_FRAG,
                    (EnvironmentModel::Brdf, true, false) => SHADE_RT_BRDF_FRAG,
                    (EnvironmentModel::Brdf, true, true) => SHADE_RT_BRDF_MS_FRAG,
                },
                (shade_bindings(variant.ray_traced), 1),
                Some(DepthTest {
                    compare: DepthCompare::Greater,
                    write: false,
                }),
                constants,
            ),
            PipelineKind::Background => self.full_screen(
                "background",
                BACKGROUND_FRAG,
                (&GRAPHICS_BINDINGS, self.samples),
                None,
                constants,
            ),
        }
    }

    /// A pipeline drawing the meshes (mesh.vert) into targets of the key's sample count.
    fn mesh<'a>(
        &self,
        name: &'static str,
        fragment_spirv: &'static [u8],
        color_formats: &'static [Format],
        constants: &'a DrawConstants,
    ) -> GraphicsPipelineDesc<'a> {
        GraphicsPipelineDesc {
            name,
            vertex_spirv: crate::gpu::shaders::MESH_VERT,
            fragment_spirv,
            bindings: &GRAPHICS_BINDINGS,
            vertex_stride: VERTEX_STRIDE,
            vertex_attributes: &VERTEX_ATTRIBUTES,
            color_formats,
            depth_format: Some(Format::Depth32Float),
            samples: self.samples,
            depth_test: Some(DepthTest {
                compare: DepthCompare::Less,
                write: true,
            }),
            fragment_constants: constants.words(),
            written_colors: color_formats.len(),
        }
    }

    /// A pipeline drawing background.vert's full-screen triangle (at depth 1) with `bindings`
    /// into a target of `samples`.
    fn full_screen<'a>(
        &self,
        name: &'static str,
        fragment_spirv: &'static [u8],
        (bindings, samples): (&'static [Binding], u32),
        depth_test: Option<DepthTest>,
        constants: &'a DrawConstants,
    ) -> GraphicsPipelineDesc<'a> {
        let ray_traced = match self.kind {
            PipelineKind::Coverage(_, ray_traced) => ray_traced,
            PipelineKind::Shade(variant) => variant.ray_traced,
            _ => false,
        };
        let color_formats: &'static [Format] = match ray_traced {
            true => &TRACED_COLOR_FORMATS,
            false => &COLOR_FORMAT,
        };
        GraphicsPipelineDesc {
            name,
            vertex_spirv: crate::gpu::shaders::BACKGROUND_VERT,
            fragment_spirv,
            bindings,
            vertex_stride: VERTEX_STRIDE,
            vertex_attributes: &[],
            color_formats,
            depth_format: Some(Format::Depth32Float),
            samples,
            depth_test,
            fragment_constants: constants.words(),
            written_colors: match self.kind {
                // A colour background is the clear colour: coverage.frag writes only depth.
                PipelineKind::Coverage(false, _) => 0,
                // It writes the background, never the integral image (its clear value stays
                // where no shade draw writes: `NO_INTEGRAL`).
                PipelineKind::Coverage(true, _) => 1,
                _ => color_formats.len(),
            },
        }
    }
}

const GBUFFER_FORMATS: [Format; 2] = [Format::Rgba32Float, Format::Rgba32Float];
const COLOR_FORMAT: [Format; 1] = [Format::Rgba32Float];
/// A ray-traced shading pass's targets: the image and the integral image (targets.rs).
const TRACED_COLOR_FORMATS: [Format; 2] = [Format::Rgba32Float, Format::Rgba32Float];

/// Every pipeline built so far.
#[derive(Default)]
pub(super) struct PipelineTable {
    pipelines: HashMap<PipelineKey, Arc<GraphicsPipeline>>,
    /// The ray-tracing pipelines' shading (shade_rt*.rgen), keyed like `PipelineKind::Shade`.
    ray_pipelines: HashMap<PipelineKey, Arc<RayTracingPipeline>>,
}

impl PipelineTable {
    /// The pipeline of `key`, built now if this is its first use.
    pub fn get(&mut self, gpu: &GpuContext, key: PipelineKey) -> Result<Arc<GraphicsPipeline>> {
        let pipeline = match self.pipelines.entry(key) {
            Entry::Occupied(entry) => entry.into_mut(),
            Entry::Vacant(entry) => entry.insert(Arc::new(Self::build(gpu, key)?)),
        };
        Ok(Arc::clone(pipeline))
    }

    /// Builds the pipeline of `key` (without keeping it: [`insert`](Self::insert)).
    pub fn build(gpu: &GpuContext, key: PipelineKey) -> Result<GraphicsPipeline> {
        let constants = key.constants();
        Ok(gpu.create_graphics_pipeline(&key.desc(&constants))?)
    }

    /// Whether the table holds the pipeline of `key`.
    pub fn has(&self, key: &PipelineKey) -> bool {
        self.pipelines.contains_key(key)
    }

    /// Keeps `pipeline` as the one of `key` (unless the table has one already).
    pub fn insert(&mut self, key: PipelineKey, pipeline: GraphicsPipeline) {
        self.pipelines
            .entry(key)
            .or_insert_with(|| Arc::new(pipeline));
    }

    /// The ray-tracing pipeline that shades `variant` (ray-traced) on a device without ray
    /// queries, built now if this is its first use: `key.kind` must be `PipelineKind::Shade`.
    pub fn ray_pipeline(
        &mut self,
        gpu: &GpuContext,
        key: PipelineKey,
    ) -> Result<Arc<RayTracingPipeline>> {
        let pipeline = match self.ray_pipelines.entry(key) {
            Entry::Occupied(entry) => entry.into_mut(),
            Entry::Vacant(entry) => {
                use crate::gpu::shaders::*;
                let PipelineKind::Shade(variant) = key.kind else {
                    return Err(crate::Error::invalid(
                        "ray-tracing pipeline",
                        format!("{:?}", key.kind),
                        "only the shading pass has one",
                    ));
                };
                let constants = key.constants();
                let raygen_spirv = match (variant.environment_model, key.samples > 1) {
                    (EnvironmentModel::Paper, false) => SHADE_RT_RGEN,
                    (EnvironmentModel::Paper, true) => SHADE_RT_MS_RGEN,
                    (EnvironmentModel::Brdf, false) => SHADE_RT_BRDF_RGEN,
                    (EnvironmentModel::Brdf, true) => SHADE_RT_BRDF_MS_RGEN,
                };
                let pipeline = gpu.create_ray_tracing_pipeline(&RayTracingPipelineDesc {
                    name: "shade (ray-tracing pipeline)",
                    raygen_spirv,
                    miss_spirv: TRACE_MISS_RMISS,
                    closest_hit_spirv: TRACE_HIT_RCHIT,
                    bindings: &SHADE_BINDINGS_RAY_PIPELINE,
                    push_constant_size: std::mem::size_of::<TraceOrigin>() as u32,
                    raygen_constants: constants.words(),
                })?;
                entry.insert(Arc::new(pipeline))
            }
        };
        Ok(Arc::clone(pipeline))
    }
}

// Descriptor sets name the environment's images (and the shading pass the targets), which may
// differ from the last draw's; they are cheap (one small pool each), so they are made per draw.

/// The environment layers as the sampler array binding wants them: unused array slots repeat the
/// last layer, since every element needs a valid descriptor.
fn layer_images(environment: &GpuEnvironment) -> Vec<&Image> {
    let mut layer_images: Vec<&Image> = environment.layers.iter().collect();
    if let Some(&last) = layer_images.last() {
        layer_images.resize(MAX_ENV_LAYERS, last);
    }
    layer_images
}

/// A set of [`GRAPHICS_BINDINGS`]: `frame` and the environment.
pub(super) fn graphics_set(
    gpu: &GpuContext,
    pipeline: &GraphicsPipeline,
    frame: &Buffer,
    environment: &GpuEnvironment,
    sampler: &Sampler,
) -> Result<DescriptorSet> {
    Ok(gpu.create_descriptor_set(
        pipeline.layout(),
        &[
            (FRAME_BINDING, Resource::Buffer(frame)),
            (
                ENV_LAYERS_BINDING,
                Resource::SampledImages(layer_images(environment), sampler),
            ),
            (
                ENV_IRRADIANCE_BINDING,
                Resource::SampledImage(&environment.irradiance, sampler),
            ),
        ],
    )?)
}

/// What a ray-traced shading pass's set adds.
#[derive(Clone, Copy)]
pub(super) struct TracedResources<'a> {
    /// The draw's top-level structure and its objects' mesh addresses.
    pub scene: (&'a AccelerationStructure, &'a Buffer),
    /// The image and the integral image a ray-tracing pipeline writes (None: the fragment
    /// shading pass's set, or the coverage draw's).
    pub storage: Option<(&'a Image, &'a Image)>,
}

/// A set of [`SHADE_BINDINGS`]: the draw's buffers, the environment (`layer_texels`: its
/// [`GpuEnvironment::layer_texels`] in the `brdf` model, any texel buffer in the `paper` model,
/// which never reads it) and the G-buffer; with `traced` (the top-level structure and the
/// objects' mesh addresses), of [`SHADE_BINDINGS_TRACED`]; with its `storage` too (the image and
/// the integral image), of [`SHADE_BINDINGS_RAY_PIPELINE`].
pub(super) fn shade_set(
    gpu: &GpuContext,
    layout: &PipelineLayout,
    buffers: &DrawBuffers,
    (environment, layer_texels): (&GpuEnvironment, &Buffer),
    sampler: &Sampler,
    (position, normal): (&Image, &Image),
    traced: Option<TracedResources<'_>>,
) -> Result<DescriptorSet> {
    let mut resources = vec![
        (FRAME_BINDING, Resource::Buffer(&buffers.scene_frame)),
        (FRESNEL_KNOTS_BINDING, Resource::TexelBuffer(&buffers.knots)),
        (
            ENV_LAYERS_BINDING,
            Resource::SampledImages(layer_images(environment), sampler),
        ),
        (
            ENV_IRRADIANCE_BINDING,
            Resource::SampledImage(&environment.irradiance, sampler),
        ),
        (
            OBJECT_MATERIAL_BINDING,
            Resource::TexelBuffer(&buffers.materials),
        ),
        (
            GBUFFER_POSITION_BINDING,
            Resource::SampledImage(position, sampler),
        ),
        (
            GBUFFER_NORMAL_BINDING,
            Resource::SampledImage(normal, sampler),
        ),
        (
            ENV_LAYER_TEXELS_BINDING,
            Resource::UintTexelBuffer(layer_texels),
        ),
    ];
    if let Some(TracedResources {
        scene: (scene, geometry),
        ..
    }) = traced
    {
        resources.push((SCENE_TLAS_BINDING, Resource::AccelerationStructure(scene)));
        resources.push((OBJECT_GEOMETRY_BINDING, Resource::Buffer(geometry)));
    }
    if let Some((image, integral)) = traced.and_then(|t| t.storage) {
        resources.push((SHADED_IMAGE_BINDING, Resource::StorageImage(image)));
        resources.push((SHADED_INTEGRAL_BINDING, Resource::StorageImage(integral)));
    }
    Ok(gpu.create_descriptor_set(layout, &resources)?)
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
