//! Render benchmark: the built-in bowl (~100k triangles) lit by the studio environment and the
//! three default lights, drawn with the lacquer shader and with trivial.frag (a constant colour:
//! the rasteriser's floor for the same geometry). GPU time of the mesh pass (draw + MSAA resolve)
//! from timestamp queries; the background is a cleared colour so the pass is the mesh alone.

use glam::DVec3;
use serde::Serialize;

use super::{BenchConfig, Stat, Target};
use crate::environment::EnvironmentModel;
use crate::gpu::GpuContext;
use crate::model::LacquerMaterial;
use crate::raster::draw::{Background, DrawOptions, MeshShading};
use crate::raster::{default_lights, BuiltinMesh, Camera};
use crate::scene::{
    EnvironmentSpec, MeshSource, OutputSpec, RenderSpec, Scene, SceneObject, SceneRenderer,
};
use crate::Result;

/// The target (BENCHMARKS.md, "Targets"): lacquer draw ≤ 2 × the trivial draw of the same
/// geometry.
pub const RATIO_LIMIT: f64 = 2.0;

/// The target of issue 16: the `brdf` environment model's draw ≤ 1.5 × the `paper` model's, on
/// the default scene.
pub const BRDF_MODEL_LIMIT: f64 = 1.5;

/// The default scene drawn in both environment models, interleaved (GPU time of the draw).
#[derive(Clone, Debug, Serialize)]
pub struct ModelBench {
    pub width: u32,
    pub paper_gpu: Stat,
    pub brdf_gpu: Stat,
    /// brdf_gpu.median / paper_gpu.median.
    pub ratio: f64,
    pub target: Target,
}

#[derive(Clone, Debug, Serialize)]
pub struct RenderBench {
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    pub triangles: usize,
    pub lights: usize,
    /// GPU time of the lacquer draw: G-buffer pass and shading pass (s).
    pub lacquer_gpu: Stat,
    /// GPU time of the mesh pass with trivial.frag (s).
    pub trivial_gpu: Stat,
    /// Whole lacquer render call, uniforms to read-back (s, wall clock).
    pub lacquer_wall: Stat,
    /// Copy of the resolved image to the readback buffer (s, GPU).
    pub copy_out_gpu: Stat,
    /// lacquer_gpu.median / trivial_gpu.median.
    pub ratio: f64,
    pub target: Target,
    /// The default scene in the `paper` and `brdf` environment models.
    pub models: ModelBench,
}

/// The bowl scene of the render benchmark at `size`² (also used by the batch benchmark).
pub fn bowl_scene(size: u32, samples: u32, background: Background) -> Result<Scene> {
    Ok(Scene {
        camera: Camera {
            eye: DVec3::new(0.0, 2.2, 3.2),
            target: DVec3::new(0.0, 0.3, 0.0),
            up: DVec3::Y,
            fov_deg: 30.0,
        },
        objects: vec![SceneObject {
            mesh: MeshSource::Builtin(BuiltinMesh::Bowl),
            transform: glam::DMat4::IDENTITY,
            material: LacquerMaterial::preset("smooth-red")?,
        }],
        lights: default_lights(),
        environment: EnvironmentSpec::named(crate::environment::load::BUILTIN_STUDIO),
        // The raster path alone: the `rays` stage measures ray tracing.
        render: RenderSpec {
            ray_tracing: false,
            ..RenderSpec::default()
        },
        output: OutputSpec {
            width: size,
            height: size,
            samples,
            background,
            ..OutputSpec::default()
        },
    })
}

pub fn run(gpu: &GpuContext, config: &BenchConfig) -> Result<RenderBench> {
    let scene = bowl_scene(
        config.render_size,
        config.render_samples,
        Background::Color([0.0; 3]),
    )?;
    let mut renderer = SceneRenderer::new(gpu)?;
    let mut lacquer = Vec::new();
    let mut trivial = Vec::new();
    let mut wall = Vec::new();
    let mut copy_out = Vec::new();
    // Interleaved, so a change in machine load affects both shaders alike; run 0 is the warm-up
    // (pipelines, environment prefilter, mesh upload, targets).
    for run in 0..=config.runs {
        for shading in [MeshShading::Lacquer, MeshShading::Trivial] {
            let start = std::time::Instant::now();
            let (_, timings) = renderer.render_with(
                gpu,
                &scene,
                DrawOptions {
                    shading,
                    timed: true,
                    ..DrawOptions::default()
                },
            )?;
            let seconds = start.elapsed().as_secs_f64();
            let Some(t) = timings else { continue };
            if run == 0 {
                continue;
            }
            match shading {
                MeshShading::Lacquer => {
                    lacquer.push(t.pass);
                    wall.push(seconds);
                    copy_out.push(t.copy_out);
                }
                MeshShading::Trivial => trivial.push(t.pass),
            }
        }
    }
    let (lacquer, trivial) = (Stat::of(lacquer), Stat::of(trivial));
    let ratio = lacquer.median / trivial.median;
    let models = models(gpu, &mut renderer, config)?;
    Ok(RenderBench {
        width: config.render_size,
        height: config.render_size,
        samples: config.render_samples,
        triangles: BuiltinMesh::Bowl.mesh().triangle_count(),
        lights: scene.lights.len(),
        lacquer_gpu: lacquer,
        trivial_gpu: trivial,
        lacquer_wall: Stat::of(wall),
        copy_out_gpu: Stat::of(copy_out),
        ratio,
        target: Target::at_most(
            "render: lacquer draw / trivial-shader draw",
            ratio,
            RATIO_LIMIT,
        ),
        models,
    })
}

/// The default scene at the render size in each environment model, interleaved; run 0 warms up.
fn models(
    gpu: &GpuContext,
    renderer: &mut SceneRenderer,
    config: &BenchConfig,
) -> Result<ModelBench> {
    let mut scene = crate::scene::default_scene();
    scene.output.width = config.render_size;
    scene.output.height = config.render_size;
    scene.render.ray_tracing = false;
    let (mut paper, mut brdf) = (Vec::new(), Vec::new());
    for run in 0..=config.runs {
        for model in EnvironmentModel::ALL {
            scene.render.environment_model = model;
            let options = DrawOptions {
                shading: MeshShading::Lacquer,
                timed: true,
                ..DrawOptions::default()
            };
            let (_, timings) = renderer.render_with(gpu, &scene, options)?;
            let Some(t) = timings else { continue };
            if run == 0 {
                continue;
            }
            match model {
                EnvironmentModel::Paper => paper.push(t.pass),
                EnvironmentModel::Brdf => brdf.push(t.pass),
            }
        }
    }
    let (paper, brdf) = (Stat::of(paper), Stat::of(brdf));
    let ratio = brdf.median / paper.median;
    Ok(ModelBench {
        width: config.render_size,
        paper_gpu: paper,
        brdf_gpu: brdf,
        ratio,
        target: Target::at_most(
            "render: brdf environment model / paper model, default scene",
            ratio,
            BRDF_MODEL_LIMIT,
        ),
    })
}
