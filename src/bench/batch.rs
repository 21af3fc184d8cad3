//! Batch benchmark: a sweep of `batch_jobs` jobs (the bowl scene of the render benchmark, orbiting
//! camera) rendered to PNG by the library's batch runner, images per second of the whole run,
//! against the ceiling 1 / (GPU time of one image's submit) measured in the same invocation, a few
//! images after each batch run.

use serde::Serialize;

use super::{BenchConfig, ScratchDir, Stat, Target};
use crate::gpu::GpuContext;
use crate::raster::draw::{Background, DrawOptions};
use crate::scene::batch::{run_batch, BatchOptions, BatchPlan};
use crate::scene::SceneRenderer;
use crate::{Error, Result};

/// The target (BENCHMARKS.md, "Targets"): throughput ≥ 90 % of 1 / (GPU render time per image).
pub const EFFICIENCY_LIMIT: f64 = 0.9;

/// Timed single-image renders after each batch run.
const GPU_SAMPLES_PER_RUN: usize = 3;

#[derive(Clone, Debug, Serialize)]
pub struct BatchBench {
    pub jobs: usize,
    pub width: u32,
    pub height: u32,
    pub samples: u32,
    /// Wall time of one whole batch run, setup to contact sheet (s).
    pub run_wall: Stat,
    /// jobs / run_wall, per run (images per second).
    pub images_per_second: Stat,
    /// GPU time of one image's submit (barriers, passes, resolve, copy-out), from timestamps (s).
    pub gpu_per_image: Stat,
    /// 1 / gpu_per_image.median (images per second).
    pub gpu_ceiling: f64,
    /// images_per_second.median / gpu_ceiling.
    pub efficiency: f64,
    pub target: Target,
    /// Images per second of one run of the same batch with ray tracing on (shadows, the default
    /// bounces and rays); `None` on a device without ray queries.
    pub ray_traced_images_per_second: Option<f64>,
}

/// One run of the batch with ray tracing on (after the raster runs warmed the caches): jobs per
/// second.
fn ray_traced_rate(gpu: &GpuContext, config: &BenchConfig) -> Result<f64> {
    let scratch = ScratchDir::new("batch-rays")?;
    let plan = BatchPlan::parse(&jobs_toml(config, true), "bench batch", &scratch.0)?;
    let options = BatchOptions {
        force: true,
        ..BatchOptions::new(scratch.0.join("out"))
    };
    let start = std::time::Instant::now();
    let summary = run_batch(gpu, &plan, &options)?;
    let jobs = plan.jobs().len();
    if summary.failed > 0 || summary.rendered != jobs {
        return Err(Error::invalid(
            "bench batch",
            format!("{} of {jobs} rendered with ray tracing", summary.rendered),
            "every benchmark job must render; see the errors above",
        ));
    }
    Ok(jobs as f64 / start.elapsed().as_secs_f64())
}

fn jobs_toml(config: &BenchConfig, ray_tracing: bool) -> String {
    let step = 360.0 / config.batch_jobs as f64;
    let orbits: Vec<String> = (0..config.batch_jobs)
        .map(|i| format!("{:.4}", i as f64 * step))
        .collect();
    format!(
        r#"name = "job-{{job}}"
[scene.camera]
eye = [0.0, 2.2, 3.2]
target = [0.0, 0.3, 0.0]
fov_deg = 30
[[scene.object]]
mesh = "builtin:bowl"
material = {{ preset = "smooth-red" }}
[scene.environment]
source = "builtin:studio"
[scene.output]
size = "{size}x{size}"
samples = 4
background = "env"
[scene.render]
ray_tracing = {ray_tracing}
[sweep]
"camera.orbit_deg" = [{orbits}]
"#,
        size = config.batch_size,
        orbits = orbits.join(", "),
    )
}

pub fn run(gpu: &GpuContext, config: &BenchConfig) -> Result<BatchBench> {
    let scratch = ScratchDir::new("batch")?;
    // The raster path, as the batch always measured; one run with ray tracing follows.
    let plan = BatchPlan::parse(&jobs_toml(config, false), "bench batch", &scratch.0)?;
    let jobs = plan.jobs().len();
    let options = BatchOptions {
        force: true,
        ..BatchOptions::new(scratch.0.join("out"))
    };
    // The GPU time of one job's image (same scene, same renderer code path), measured between
    // the batch runs, so that a change in machine load hits both figures (the machine is shared,
    // and the two are divided).
    let scene = super::render::bowl_scene(config.batch_size, 4, Background::Environment)?;
    let mut renderer = SceneRenderer::new(gpu)?;
    let (mut wall, mut rate, mut per_image) = (Vec::new(), Vec::new(), Vec::new());
    for run in 0..=config.runs {
        let start = std::time::Instant::now();
        let summary = run_batch(gpu, &plan, &options)?;
        let seconds = start.elapsed().as_secs_f64();
        if summary.failed > 0 || summary.rendered != jobs {
            return Err(Error::invalid(
                "bench batch",
                format!("{} of {jobs} rendered", summary.rendered),
                "every benchmark job must render; see the errors above",
            ));
        }
        for _ in 0..GPU_SAMPLES_PER_RUN {
            let (_, timings) = renderer.render_with(
                gpu,
                &scene,
                DrawOptions {
                    timed: true,
                    ..DrawOptions::default()
                },
            )?;
            if let (true, Some(t)) = (run > 0, timings) {
                per_image.push(t.total);
            }
        }
        if run > 0 {
            wall.push(seconds);
            rate.push(jobs as f64 / seconds);
        }
    }
    let ray_traced = match gpu.info().ray_query.is_enabled() {
        true => Some(ray_traced_rate(gpu, config)?),
        false => None,
    };
    let gpu_per_image = Stat::of(per_image);
    let images_per_second = Stat::of(rate);
    let gpu_ceiling = 1.0 / gpu_per_image.median;
    let efficiency = images_per_second.median / gpu_ceiling;
    Ok(BatchBench {
        jobs,
        width: config.batch_size,
        height: config.batch_size,
        samples: 4,
        run_wall: Stat::of(wall),
        images_per_second,
        gpu_per_image,
        gpu_ceiling,
        efficiency,
        target: Target::at_least(
            "batch: images per second / (1 / GPU time per image)",
            efficiency,
            EFFICIENCY_LIMIT,
        ),
        ray_traced_images_per_second: ray_traced,
    })
}
