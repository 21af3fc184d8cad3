//! The command line: argument parsing and dispatch only; rendering lives in the library.
//!
//! Every failure prints `error: …` (with its causes) to stderr and exits with code 1; clap's own
//! usage errors exit with 2.

mod args;
mod bench;
mod commands;
mod directions;
mod fit;
mod mesh_cmd;
mod scene_cmd;

use clap::Parser;
use std::process::ExitCode;

pub use args::{parse_size, parse_vec3, Cli, Command};

/// The CLI's GPU: the context from the environment (`SHIKKI_VALIDATION`, `SHIKKI_DEVICE`,
/// `SHIKKI_PIPELINE_CACHE`), whose pipeline cache is saved when the command is done, so the next
/// run starts without compiling shaders.
pub(crate) struct CliGpu(crate::gpu::GpuContext);

/// Opens the GPU; where ray queries are off, says so once on stderr (which feature is missing
/// and what to install).
pub(crate) fn open_gpu() -> crate::Result<CliGpu> {
    open_gpu_tracing(true)
}

/// [`open_gpu`] for work that traces rays (`traces`) or not. Without rays the device is opened
/// without its ray-tracing extensions, and nothing is said: NVIDIA's driver holds ~140 MiB more
/// host memory with the ray-tracing pipeline enabled, traced or not (an H200 with driver 580:
/// 360 against 216 MB peak for the default scene at 1024² without rays; BENCHMARKS.md).
pub(crate) fn open_gpu_tracing(traces: bool) -> crate::Result<CliGpu> {
    if let Some(problem) = crate::gpu::ContextOptions::ray_tracing_env_problem() {
        return Err(problem);
    }
    let mut options = crate::gpu::ContextOptions::from_env();
    if !traces {
        options.ray_tracing = crate::gpu::RayTracingChoice::Off;
    }
    let gpu = crate::gpu::GpuContext::new(&options)?;
    static RAY_QUERY_WARNING: std::sync::Once = std::sync::Once::new();
    if let Some(warning) = gpu.info().ray_query.warning(&gpu.info().name) {
        if traces {
            RAY_QUERY_WARNING.call_once(|| eprintln!("warning: {warning}"));
        }
    }
    Ok(CliGpu(gpu))
}

/// The library returns warnings; the CLI prints each as `warning: …` on stderr (except a lack
/// of ray queries, which [`open_gpu`] said once already).
pub(crate) fn print_warnings(warnings: impl IntoIterator<Item = crate::Warning>) {
    for warning in warnings {
        if !matches!(warning, crate::Warning::NoRayQueries { .. }) {
            eprintln!("warning: {warning}");
        }
    }
}

/// Removes an earlier run's output at `path` after a failure, and says so on stderr: it would
/// pass for this run's. Only a regular file is removed (`output::atomic::discard_stale_output`);
/// the caller decides that `path` is one this command writes.
pub(crate) fn remove_earlier_output(path: &std::path::Path) {
    if let Ok(true) = crate::output::atomic::discard_stale_output(path) {
        eprintln!(
            "removed {} from an earlier run: it is not this run's output",
            path.display()
        );
    }
}

impl std::ops::Deref for CliGpu {
    type Target = crate::gpu::GpuContext;
    fn deref(&self) -> &Self::Target {
        &self.0
    }
}

impl Drop for CliGpu {
    fn drop(&mut self) {
        if let Err(e) = self.0.save_pipeline_cache() {
            eprintln!("warning: {e}");
        }
    }
}

/// Runs the CLI with the process arguments.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = commands::run(cli);
    // `shikki bench` measures its child renders' peak memory this way (VmHWM at exit).
    if std::env::var_os(crate::bench::startup::REPORT_PEAK_MEMORY).is_some_and(|v| v == "1") {
        if let Some(kib) = crate::bench::startup::peak_rss_kib() {
            eprintln!("{}{kib}", crate::bench::startup::PEAK_MEMORY_PREFIX);
        }
    }
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            let message = err.to_string();
            eprintln!("error: {message}");
            let mut source = std::error::Error::source(&err);
            while let Some(cause) = source {
                // Errors that quote their cause (`cannot read PATH: CAUSE`) say it once.
                let text = cause.to_string();
                if !message.contains(&text) {
                    eprintln!("  caused by: {text}");
                }
                source = cause.source();
            }
            ExitCode::FAILURE
        }
    }
}
