//! Start-up benchmark: wall time from spawning `shikki render` (this executable, the default scene:
//! two bowls and a tray lit by the 1024 × 512 studio environment) to its exit with the image
//! written.
//!
//! - Cold: every cache empty, every run: shikki's (pipeline cache, prefiltered environments) and
//!   the driver's. Mesa keeps compiled shaders in its own on-disk cache (`MESA_SHADER_CACHE_DIR`,
//!   by default under `~/.cache`); on lavapipe that is where a warm start saves the LLVM
//!   compilation, since the Vulkan pipeline cache there is a bare header. The child gets a fresh
//!   one inside the scratch directory, so "cold" is a first run on a fresh machine (NVIDIA's
//!   driver, whose cache `__GL_SHADER_DISK_CACHE_PATH` names, gets the same directory).
//! - Driver cache only: shikki's caches empty, the driver's shader cache filled (shikki run before
//!   with another cache directory): what the prefiltered-environment cache alone saves.
//! - Warm: every cache filled by a first run.

use std::path::Path;
use std::process::Command;

use serde::Serialize;

use super::{BenchConfig, ScratchDir, Stat, Target};
use crate::{Error, Result};

/// The target (BENCHMARKS.md, "Targets"): warm start-up ≤ 50 % of cold.
pub const WARM_LIMIT: f64 = 0.5;

/// The environment variable a child `shikki` reads to print its peak resident memory at exit.
pub const REPORT_PEAK_MEMORY: &str = "SHIKKI_REPORT_PEAK_MEMORY";
/// The line prefix of that report on stderr.
pub const PEAK_MEMORY_PREFIX: &str = "shikki-peak-rss-kib=";

#[derive(Clone, Debug, Serialize)]
pub struct StartupBench {
    pub command: String,
    pub cold: Stat,
    /// shikki's caches empty, the driver's shader cache filled.
    pub driver_cache_only: Stat,
    pub warm: Stat,
    /// warm.median / cold.median.
    pub warm_over_cold: f64,
    pub target: Target,
}

/// What one child run reported.
pub(crate) struct ChildRun {
    pub seconds: f64,
    pub peak_rss_kib: Option<u64>,
}

/// The default scene without ray tracing: startup and memory measure the process around the
/// raster draw (the `rays` stage measures ray tracing, and its own child process).
pub(crate) fn render_args(config: &BenchConfig, out: &Path) -> Vec<String> {
    vec![
        "render".into(),
        "-o".into(),
        out.display().to_string(),
        "--size".into(),
        format!("{0}x{0}", config.startup_size),
        "--no-ray-tracing".into(),
    ]
}

/// Runs `shikki render` of the default scene at the startup size, with its caches in
/// `cache_dir` and Mesa's shader cache in `driver_cache_dir`.
pub(crate) fn run_child(
    config: &BenchConfig,
    cache_dir: &Path,
    driver_cache_dir: &Path,
) -> Result<ChildRun> {
    let out = cache_dir.join("startup.png");
    run_shikki(&render_args(config, &out), cache_dir, driver_cache_dir)
}

/// Runs this executable with `args` (a `shikki render`), its caches in `cache_dir` and Mesa's
/// shader cache in `driver_cache_dir`; fails with the child's stderr.
pub(crate) fn run_shikki(
    args: &[String],
    cache_dir: &Path,
    driver_cache_dir: &Path,
) -> Result<ChildRun> {
    let exe = std::env::current_exe().map_err(|source| Error::Read {
        path: "current executable".into(),
        source,
    })?;
    let start = std::time::Instant::now();
    let output = Command::new(&exe)
        .args(args)
        .env("SHIKKI_PIPELINE_CACHE", cache_dir.join("pipelines.bin"))
        .env_remove("SHIKKI_ENV_CACHE")
        .env("MESA_SHADER_CACHE_DIR", driver_cache_dir)
        .env_remove("MESA_SHADER_CACHE_DISABLE")
        // NVIDIA's driver keeps its compiled shaders in a cache of its own (by default under
        // ~/.cache/nvidia): the same directory, so that "cold" is cold there too.
        .env("__GL_SHADER_DISK_CACHE_PATH", driver_cache_dir)
        .env("__GL_SHADER_DISK_CACHE", "1")
        .env("__GL_SHADER_DISK_CACHE_SKIP_CLEANUP", "1")
        .env(REPORT_PEAK_MEMORY, "1")
        .output()
        .map_err(|source| Error::Read {
            path: exe.clone(),
            source,
        })?;
    let seconds = start.elapsed().as_secs_f64();
    let stderr = String::from_utf8_lossy(&output.stderr);
    if !output.status.success() {
        return Err(Error::invalid(
            "bench child render",
            exe.display(),
            format!("`shikki render` failed: {}", stderr.trim()),
        ));
    }
    let peak_rss_kib = stderr
        .lines()
        .find_map(|l| l.strip_prefix(PEAK_MEMORY_PREFIX))
        .and_then(|v| v.trim().parse().ok());
    Ok(ChildRun {
        seconds,
        peak_rss_kib,
    })
}

pub fn run(config: &BenchConfig) -> Result<StartupBench> {
    let (mut cold, mut driver_only, mut warm) = (Vec::new(), Vec::new(), Vec::new());
    for run in 0..=config.runs {
        // A fresh directory: nothing cached, not even by the driver.
        let scratch = ScratchDir::new("startup")?;
        let seconds = run_child(config, &scratch.0, &scratch.0.join("mesa"))?.seconds;
        if run > 0 {
            cold.push(seconds);
        }
    }
    let driver = ScratchDir::new("startup-driver")?;
    for run in 0..=config.runs {
        let scratch = ScratchDir::new("startup")?;
        // Run 0 fills the driver's cache.
        let seconds = run_child(config, &scratch.0, &driver.0)?.seconds;
        if run > 0 {
            driver_only.push(seconds);
        }
    }
    let scratch = ScratchDir::new("startup-warm")?;
    let mesa = scratch.0.join("mesa");
    run_child(config, &scratch.0, &mesa)?; // fills the caches (and warms the OS file cache)
    for _ in 0..config.runs {
        warm.push(run_child(config, &scratch.0, &mesa)?.seconds);
    }
    let (cold, driver_cache_only, warm) = (Stat::of(cold), Stat::of(driver_only), Stat::of(warm));
    let ratio = warm.median / cold.median;
    Ok(StartupBench {
        command: format!(
            "shikki {}",
            render_args(config, Path::new("OUT.png")).join(" ")
        ),
        cold,
        driver_cache_only,
        warm,
        warm_over_cold: ratio,
        target: Target::at_most("startup: warm / cold", ratio, WARM_LIMIT),
    })
}

/// Peak resident memory of this process so far (VmHWM), in KiB; Linux only.
pub fn peak_rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmHWM:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}
