//! What a caller hands the draw and gets back: the scene, the settings and options, the timings;
//! and the checks a draw makes of them before touching the device.

use crate::environment::gpu::GpuEnvironment;
use crate::environment::params::{EnvironmentModel, ViewBlur};
use crate::gpu::shaders::interface::{MAX_ENV_LAYERS, MAX_LIGHTS, MAX_SAMPLES};
use crate::gpu::GpuContext;
use crate::model::{BrdfParams, FresnelTable};
use crate::raster::camera::Camera;
use crate::raster::lights::Light;
use crate::raster::mesh::Mesh;
use crate::{Error, Result};

/// Sample counts the renderer offers (`--samples 1|4`; lavapipe supports exactly these).
pub const SUPPORTED_SAMPLES: [u32; 2] = [1, MAX_SAMPLES];

/// Most Fresnel knots of one draw, all objects together: the shaders receive each table's first
/// knot as an f32 (`ObjectMaterial::fresnel_first`), exact below 2^24.
pub const MAX_DRAW_KNOTS: usize = 1 << 24;

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

impl Background {
    /// The colour the draw's targets are cleared to: the background where it is a colour (or
    /// transparent); the environment one is drawn.
    pub(crate) fn clear_color(self) -> [f32; 4] {
        match self {
            Background::Transparent | Background::Environment => [0.0; 4],
            Background::Color([r, g, b]) => [r, g, b, 1.0],
        }
    }
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
    /// How the environment lights them (SPEC §4).
    pub environment_model: EnvironmentModel,
    /// Light between objects (SPEC §6) by ray queries; `None`: every object shaded as if alone.
    /// Needs a device with ray queries ([`RayQuery`](crate::gpu::RayQuery)); refused without.
    pub ray_tracing: Option<RayTracing>,
    pub background: Background,
}

impl DrawScene<'_> {
    /// Whether the shading pass runs the `brdf` model's quadrature, which reads the directional
    /// albedo knots, the layer texels and the bright split's lights: as the environment term
    /// (`brdf`), or for the control variate of the light between objects (a draw that estimates
    /// its integral: `integral_environment` in lacquer_shade.glsl).
    pub fn reads_brdf_quadrature(&self) -> bool {
        self.environment_model == EnvironmentModel::Brdf
            || self.ray_tracing.is_some_and(|rt| rt.bounces > 0)
    }
}

/// Most bounces of SPEC §6's integral.
pub const MAX_BOUNCES: u32 = 4;
/// Most rays per shaded point.
pub const MAX_RAYS: u32 = 4096;

/// SPEC §6 as one draw traces it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RayTracing {
    /// Lights with visibility (shadow rays), at the shaded points and at every bounce.
    pub shadows: bool,
    /// Depth of the integral's recursion (0: lights with visibility only).
    pub bounces: u32,
    /// Rays per shaded point (1..=MAX_RAYS).
    pub rays: u32,
    /// Seeds the sample sequence: the same seed gives the same image.
    pub seed: u32,
    /// Filter the integral's estimate (denoise.rs) where `rays` is low enough for it to help.
    pub denoise: bool,
}

impl RayTracing {
    /// Whether the shading pass traces any ray.
    pub fn traces(&self) -> bool {
        self.shadows || self.bounces > 0
    }
}

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

/// How [`LacquerRenderer::render_meshes`](super::LacquerRenderer::render_meshes) draws.
#[derive(Clone, Copy, Debug, Default)]
pub struct DrawOptions {
    pub shading: MeshShading,
    /// Record timestamp queries and return [`DrawTimings`].
    pub timed: bool,
    /// Denoise on the host (`denoise::denoise`, the twin) instead of the device (tests compare
    /// the two).
    pub denoise_on_host: bool,
}

/// GPU time of one draw's passes from timestamp queries, in seconds.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct DrawTimings {
    /// The drawing: for the lacquer draw the G-buffer pass and the shading pass; for the forward
    /// draw the background (if any), the mesh draws, the end of the pass and the MSAA resolve.
    pub pass: f64,
    /// The image (shaded or resolved) → readback buffer.
    pub copy_out: f64,
    /// From the first command to the last (with the denoise's).
    pub total: f64,
    /// The denoise on the device (raster/draw/denoise.rs), after the strips.
    pub denoise: f64,
}

impl std::ops::AddAssign for DrawTimings {
    fn add_assign(&mut self, strip: DrawTimings) {
        self.pass += strip.pass;
        self.copy_out += strip.copy_out;
        self.total += strip.total;
        self.denoise += strip.denoise;
    }
}

/// Refuses, before any device work, a draw the device or the shaders cannot take.
pub(crate) fn validate(
    gpu: &GpuContext,
    scene: &DrawScene<'_>,
    settings: &RenderSettings,
) -> Result<()> {
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
            format!(
                "valid sample counts are {} and {}",
                SUPPORTED_SAMPLES[0], SUPPORTED_SAMPLES[1]
            ),
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
    if let Some(rt) = scene.ray_tracing {
        validate_ray_tracing(gpu, scene, &rt)?;
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
    for (index, object) in scene.objects.iter().enumerate() {
        // Named by the object: a placement that overflowed f32 showed as "invalid mesh.positions"
        // with nothing to say which object's transform did it.
        object.mesh.validate().map_err(|e| match e {
            Error::InvalidParameter {
                field,
                value,
                reason,
            } => Error::invalid(format!("object.{index} {field}"), value, reason),
            other => other,
        })?;
    }
    Ok(())
}

/// A ray-traced draw: a device with ray queries, bounces and rays in range, and triangle indices
/// the G-buffer holds exactly (as f32, below 2^24).
fn validate_ray_tracing(gpu: &GpuContext, scene: &DrawScene<'_>, rt: &RayTracing) -> Result<()> {
    if !gpu.info().ray_query.is_enabled() {
        return Err(Error::invalid(
            "ray_tracing",
            true,
            format!(
                "light between objects needs ray queries; {} has: {}. Draw with ray tracing off",
                gpu.info().name,
                gpu.info().ray_query.summary()
            ),
        ));
    }
    if rt.bounces > MAX_BOUNCES {
        return Err(Error::invalid(
            "bounces",
            rt.bounces,
            format!("bounces must be 0..={MAX_BOUNCES}"),
        ));
    }
    if !(1..=MAX_RAYS).contains(&rt.rays) {
        return Err(Error::invalid(
            "rays",
            rt.rays,
            format!("rays must be 1..={MAX_RAYS}"),
        ));
    }
    for object in scene.objects {
        let triangles = object.mesh.triangle_count();
        if triangles >= 1 << 24 {
            return Err(Error::invalid(
                "mesh",
                triangles,
                "a ray-traced mesh has at most 16,777,215 triangles (2^24 - 1); split it or \
                 render with ray tracing off",
            ));
        }
    }
    Ok(())
}
