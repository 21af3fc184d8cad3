//! Prefilter time for face 512, K = 8 (issue 7): the GPU compute pipeline vs the CPU oracle on
//! all cores, same input, same parameters, for three sources: builtin:studio (1024 × 512, the
//! headline figure), the real courtyard HDRI of assets/env (1024 × 512) and
//! studio doubled to 2048 × 1024 (pixel-replicated: same content, the 4 × 4 box filter of step 1).
//! Medians of repeated runs after a warm-up — wall clock and each pass's GPU timestamps — and
//! their ratio, all measured in one run. `cargo bench --bench prefilter`;
//! `SHIKKI_BENCH_RUNS=n` sets the runs, `SHIKKI_BENCH_CPU=0` skips the oracle (GPU-only tuning).

use shikki::environment::gpu::{GpuPrefilter, PrefilterTimings};
use shikki::environment::load::load_environment;
use shikki::environment::EnvironmentLight;
use shikki::environment::{oracle, Equirect, PrefilterParams};
use shikki::gpu::{ContextOptions, GpuContext};
use std::time::Instant;

fn median(mut samples: Vec<f64>) -> f64 {
    samples.sort_by(f64::total_cmp);
    samples[samples.len() / 2]
}

/// CPU time of this process so far, all threads (s): lavapipe's work, unlike the wall clock,
/// does not grow when other processes share the cores. From /proc (Linux); None elsewhere.
fn process_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the parenthesised command name; utime and stime are fields 14 and 15.
    let rest = stat.get(stat.rfind(')')? + 2..)?;
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0) // USER_HZ, 100 on Linux
}

/// `source` with every pixel repeated 2 × 2.
fn doubled(source: &Equirect) -> Equirect {
    let (w, h) = (source.width * 2, source.height * 2);
    let mut pixels = Vec::with_capacity((w * h) as usize);
    for y in 0..h {
        for x in 0..w {
            pixels.push(source.get(x / 2, y / 2));
        }
    }
    Equirect {
        width: w,
        height: h,
        pixels,
    }
}

/// Per-pass medians over the runs.
fn median_timings(all: &[PrefilterTimings]) -> PrefilterTimings {
    let of = |f: &dyn Fn(&PrefilterTimings) -> f64| median(all.iter().map(f).collect());
    PrefilterTimings {
        equirect_to_cube: of(&|t| t.equirect_to_cube),
        mip_chain: of(&|t| t.mip_chain),
        layers: (0..all[0].layers.len())
            .map(|k| of(&|t| t.layers[k]))
            .collect(),
        irradiance: of(&|t| t.irradiance),
        copy_to_images: of(&|t| t.copy_to_images),
    }
}

fn bench(
    gpu: &GpuContext,
    prefilter: &GpuPrefilter,
    name: &str,
    source: &Equirect,
    runs: usize,
    with_cpu: bool,
) -> Result<(), Box<dyn std::error::Error>> {
    let params = PrefilterParams {
        face_size: 512,
        layers: 8,
        beta_min: 0.02,
        beta_max: 1.0,
        layer_texel: 1.0,
        small_layer_texel: 1.0,
        fine_layers: 0,
        blur_net_of_read: false,
        supersample_scale: 1,
    };
    let mut gpu_times = Vec::new();
    let mut cpu_seconds = Vec::new();
    let mut timings = Vec::new();
    for run in 0..=runs {
        let cpu_before = process_cpu_seconds();
        let start = Instant::now();
        let (env, t) = prefilter.run_timed(gpu, source, &params, EnvironmentLight::default())?;
        let seconds = start.elapsed().as_secs_f64();
        let cpu = cpu_before.zip(process_cpu_seconds()).map(|(a, b)| b - a);
        drop(env);
        if run > 0 {
            gpu_times.push(seconds); // run 0 is the warm-up
            cpu_seconds.extend(cpu);
            timings.push(t);
        }
    }
    let g = median(gpu_times);
    let t = median_timings(&timings);
    println!(
        "{name} ({}x{}), face 512, K = 8:",
        source.width, source.height
    );
    println!("  GPU wall clock (median of {runs}): {g:.3} s");
    if !cpu_seconds.is_empty() {
        println!(
            "  GPU run's process CPU time (median; all lavapipe threads): {:.3} s",
            median(cpu_seconds)
        );
    }
    println!(
        "  GPU passes (median timestamps, s): equirect→cube {:.4}, mips {:.4}, layers {}, \
         irradiance {:.4}, copies {:.4}; sum {:.3}",
        t.equirect_to_cube,
        t.mip_chain,
        t.layers
            .iter()
            .map(|s| format!("{s:.4}"))
            .collect::<Vec<_>>()
            .join(" "),
        t.irradiance,
        t.copy_to_images,
        t.equirect_to_cube
            + t.mip_chain
            + t.layers.iter().sum::<f64>()
            + t.irradiance
            + t.copy_to_images
    );
    if with_cpu {
        let cpu_runs = runs.min(3);
        let mut cpu_times = Vec::new();
        for run in 0..=cpu_runs {
            let start = Instant::now();
            let env = oracle::prefilter_cpu(source, &params, EnvironmentLight::default())?;
            let seconds = start.elapsed().as_secs_f64();
            drop(env);
            if run > 0 {
                cpu_times.push(seconds);
            }
        }
        let c = median(cpu_times);
        println!("  CPU oracle (median of {cpu_runs}): {c:.3} s");
        println!("  GPU speed-up: {:.2}x", c / g);
    }
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let runs: usize = std::env::var("SHIKKI_BENCH_RUNS")
        .ok()
        .and_then(|s| s.parse().ok())
        .unwrap_or(5)
        .max(1);
    let with_cpu = std::env::var("SHIKKI_BENCH_CPU").map_or(true, |v| v != "0");
    let gpu = GpuContext::new(&ContextOptions::default())?;
    let prefilter = GpuPrefilter::new(&gpu)?;
    println!(
        "GPU: {} ({}), shaderFloat64 {}; CPU oracle on {} threads",
        gpu.info().name,
        gpu.info().driver_info,
        gpu.info().shader_float64,
        rayon::current_num_threads()
    );
    let studio = load_environment("builtin:studio")?.image;
    bench(&gpu, &prefilter, "builtin:studio", &studio, runs, with_cpu)?;
    let courtyard = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/env/courtyard.hdr");
    let source = load_environment(courtyard)?.image;
    bench(&gpu, &prefilter, "courtyard.hdr", &source, runs, with_cpu)?;
    let large = doubled(&studio);
    bench(&gpu, &prefilter, "studio doubled", &large, runs, with_cpu)?;
    Ok(())
}
