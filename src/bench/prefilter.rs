//! Prefilter benchmark (the logic of benches/prefilter.rs, as a library stage): face N, K layers
//! plus irradiance of builtin:studio, the GPU compute prefilter (wall clock per run, and the sum of
//! its timestamped passes) against the CPU oracle on every core (rayon), same parameters.

use crate::environment::EnvironmentLight;
use serde::Serialize;

use super::{BenchConfig, Stat, Target};
use crate::environment::gpu::GpuPrefilter;
use crate::environment::load::{load_environment, BUILTIN_STUDIO};
use crate::environment::{prefilter_cpu, PrefilterParams};
use crate::gpu::GpuContext;
use crate::Result;

/// The targets (BENCHMARKS.md, "Targets"): GPU ≥ 4 × faster than the CPU oracle, and ≤ 1 s
/// for face 512, K = 8.
pub const SPEEDUP_LIMIT: f64 = 4.0;
pub const SECONDS_LIMIT: f64 = 1.0;

#[derive(Clone, Debug, Serialize)]
pub struct PrefilterBench {
    pub face_size: u32,
    pub layers: u32,
    pub source: String,
    pub cpu_threads: usize,
    /// One GPU prefilter call, upload to sampled images (s, wall clock).
    pub gpu_wall: Stat,
    /// Sum of the timestamped GPU passes (s).
    pub gpu_passes: Stat,
    /// GPU time of each pass in the last run (s): equirect→cube, mips, layers 1..K, irradiance,
    /// copy to images.
    pub gpu_pass_breakdown: Vec<(String, f64)>,
    /// The driver has the quirk `late_timestamps_after_graphics` and a graphics pass ran before
    /// this stage: `gpu_passes` and `gpu_pass_breakdown` are shifted by a pass (`gpu_wall` is
    /// right).
    pub timestamps_late: bool,
    /// The CPU oracle on all cores (s, wall clock).
    pub cpu_oracle: Stat,
    /// cpu_oracle.median / gpu_wall.median.
    pub speedup: f64,
    pub speedup_target: Target,
    pub time_target: Target,
}

pub fn run(gpu: &GpuContext, config: &BenchConfig) -> Result<PrefilterBench> {
    let source = load_environment(BUILTIN_STUDIO)?.image;
    let params = PrefilterParams {
        face_size: config.prefilter_face,
        layers: config.prefilter_layers,
        beta_min: 0.02,
        beta_max: 1.0,
        layer_texel: 1.0,
        small_layer_texel: 1.0,
        fine_layers: 0,
        blur_net_of_read: false,
        supersample_scale: 1,
    };
    params.validate()?;
    let prefilter = GpuPrefilter::new(gpu)?;
    let (mut wall, mut passes) = (Vec::new(), Vec::new());
    let mut breakdown = Vec::new();
    for run in 0..=config.runs {
        let start = std::time::Instant::now();
        let (env, t) = prefilter.run_timed(gpu, &source, &params, EnvironmentLight::default())?;
        let seconds = start.elapsed().as_secs_f64();
        drop(env);
        if run == 0 {
            continue; // warm-up
        }
        wall.push(seconds);
        passes.push(
            t.equirect_to_cube
                + t.mip_chain
                + t.layers.iter().sum::<f64>()
                + t.irradiance
                + t.copy_to_images,
        );
        breakdown = vec![
            ("equirect_to_cube".to_string(), t.equirect_to_cube),
            ("mip_chain".to_string(), t.mip_chain),
        ];
        breakdown.extend(
            t.layers
                .iter()
                .enumerate()
                .map(|(k, s)| (format!("layer_{}", k + 1), *s)),
        );
        breakdown.push(("irradiance".to_string(), t.irradiance));
        breakdown.push(("copy_to_images".to_string(), t.copy_to_images));
    }
    let mut cpu = Vec::new();
    for run in 0..=config.runs {
        let start = std::time::Instant::now();
        let env = prefilter_cpu(&source, &params, EnvironmentLight::default())?;
        let seconds = start.elapsed().as_secs_f64();
        drop(env);
        if run > 0 {
            cpu.push(seconds);
        }
    }
    let (gpu_wall, cpu_oracle) = (Stat::of(wall), Stat::of(cpu));
    let speedup = cpu_oracle.median / gpu_wall.median;
    let time_target = Target::at_most(
        &format!(
            "prefilter: GPU seconds for face {}, K = {}",
            params.face_size, params.layers
        ),
        gpu_wall.median,
        SECONDS_LIMIT,
    );
    Ok(PrefilterBench {
        face_size: params.face_size,
        layers: params.layers,
        source: BUILTIN_STUDIO.into(),
        cpu_threads: rayon::current_num_threads(),
        speedup,
        speedup_target: Target::at_least(
            "prefilter: CPU oracle time / GPU time",
            speedup,
            SPEEDUP_LIMIT,
        ),
        time_target,
        gpu_wall,
        gpu_passes: Stat::of(passes),
        gpu_pass_breakdown: breakdown,
        timestamps_late: false,
        cpu_oracle,
    })
}
