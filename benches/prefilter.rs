//! Prefilter time for face 512, K = 8 (issue 3): the GPU compute pipeline vs the CPU oracle on
//! all cores, same input (builtin:studio), same parameters. Medians of repeated runs after a
//! warm-up, and their ratio, measured in one run. `cargo bench --bench prefilter`.

use shikki::environment::gpu::GpuPrefilter;
use shikki::environment::load::load_environment;
use shikki::environment::{oracle, PrefilterParams};
use shikki::gpu::{ContextOptions, GpuContext};
use std::time::Instant;

fn median(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let runs: usize = std::env::var("SHIKKI_BENCH_RUNS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5);
    let source = load_environment("builtin:studio")?.image;
    let params = PrefilterParams {
        face_size: 512,
        layers: 8,
        beta_min: 0.02,
        beta_max: 1.0,
    };
    let gpu = GpuContext::new(&ContextOptions::default())?;
    let prefilter = GpuPrefilter::new(&gpu)?;
    let mut gpu_times = Vec::new();
    let mut last_timings = None;
    for run in 0..=runs {
        let start = Instant::now();
        let (env, timings) = prefilter.run_timed(&gpu, &source, &params, 1.0, 0.0)?;
        let seconds = start.elapsed().as_secs_f64();
        drop(env);
        if run > 0 {
            gpu_times.push(seconds); // run 0 is the warm-up
            last_timings = Some(timings);
        }
    }
    let mut cpu_times = Vec::new();
    for run in 0..=runs.min(3) {
        let start = Instant::now();
        let env = oracle::prefilter_cpu(&source, &params, 1.0, 0.0)?;
        let seconds = start.elapsed().as_secs_f64();
        drop(env);
        if run > 0 {
            cpu_times.push(seconds);
        }
    }
    let (g, c) = (median(gpu_times), median(cpu_times));
    println!(
        "prefilter face 512, K = 8, builtin:studio ({}x{}) on {} ({}), CPU oracle on {} threads",
        source.width,
        source.height,
        gpu.info().name,
        gpu.info().driver_info,
        rayon::current_num_threads()
    );
    println!("  GPU compute (median of {runs}): {g:.3} s");
    println!("  CPU oracle  (median of {}): {c:.3} s", runs.min(3));
    println!("  GPU speed-up: {:.2}x", c / g);
    if let Some(t) = last_timings {
        println!("  GPU passes (timestamps, last run): {t:?}");
    }
    Ok(())
}
