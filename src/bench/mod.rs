//! # bench — `shikki bench`: every stage measured, medians and same-run ratios
//!
//! One file per measurement: [`render`] (lacquer draw vs the trivial-shader floor, GPU
//! timestamps), [`prefilter`] (GPU vs the CPU oracle), [`batch`] (images per second vs the GPU
//! render time), [`startup`] and [`memory`] (child `shikki render` processes), [`rays`] (light
//! between objects: ray tracing on against off, acceleration structures). [`machine`] names the
//! CPU and driver; [`table`] prints the human-readable table. Every figure is the median of
//! `runs` runs after one warm-up run; every ratio divides two medians of the same invocation.
//! Nothing here asserts a speed: targets are reported as verdicts, never enforced.

pub mod batch;
pub mod machine;
pub mod memory;
pub mod prefilter;
pub mod rays;
pub mod render;
pub mod startup;
pub mod table;

use serde::Serialize;

use crate::gpu::GpuContext;
use crate::{Error, Result};

/// What to measure and how big: [`BenchConfig::full`] is the configuration the targets name,
/// [`BenchConfig::quick`] a small one for CI smoke runs.
#[derive(Clone, Debug, Serialize)]
pub struct BenchConfig {
    /// Timed runs per figure (after one warm-up run).
    pub runs: usize,
    /// Render benchmark image side (square), MSAA samples.
    pub render_size: u32,
    pub render_samples: u32,
    /// Prefilter face size and layer count K.
    pub prefilter_face: u32,
    pub prefilter_layers: u32,
    /// Batch: number of jobs and image side.
    pub batch_jobs: usize,
    pub batch_size: u32,
    /// Startup and memory: the child render's image side.
    pub startup_size: u32,
    /// Stages to run (all by default); the others are reported as not run.
    pub stages: Vec<Stage>,
}

/// One measurement of the report.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, clap::ValueEnum)]
#[serde(rename_all = "lowercase")]
pub enum Stage {
    Render,
    Prefilter,
    Batch,
    Startup,
    Memory,
    /// Light between objects (ray queries).
    Rays,
}

impl Stage {
    pub const ALL: [Stage; 6] = [
        Stage::Render,
        Stage::Prefilter,
        Stage::Batch,
        Stage::Startup,
        Stage::Memory,
        Stage::Rays,
    ];
}

impl BenchConfig {
    pub fn full() -> Self {
        BenchConfig {
            runs: 5,
            render_size: 1024,
            render_samples: 4,
            prefilter_face: 512,
            prefilter_layers: 8,
            batch_jobs: 64,
            batch_size: 512,
            startup_size: 1024,
            stages: Stage::ALL.to_vec(),
        }
    }

    /// Tiny sizes and two runs: checks every part works, in seconds (not meaningful as figures).
    pub fn quick() -> Self {
        BenchConfig {
            runs: 2,
            render_size: 128,
            render_samples: 4,
            prefilter_face: 64,
            prefilter_layers: 4,
            batch_jobs: 4,
            batch_size: 64,
            startup_size: 64,
            stages: Stage::ALL.to_vec(),
        }
    }

    pub fn validate(&self) -> Result<()> {
        if self.runs == 0 || self.runs > 1000 {
            return Err(Error::invalid("--runs", self.runs, "must be 1..=1000"));
        }
        if self.batch_jobs == 0 || self.batch_jobs > 4096 {
            return Err(Error::invalid(
                "--batch-jobs",
                self.batch_jobs,
                "must be 1..=4096",
            ));
        }
        for (field, side) in [
            ("--render-size", self.render_size),
            ("--batch-size", self.batch_size),
            ("--startup-size", self.startup_size),
        ] {
            if !(8..=8192).contains(&side) {
                return Err(Error::invalid(field, side, "must be 8..=8192 pixels"));
            }
        }
        Ok(())
    }
}

/// The median and spread of repeated measurements, in seconds (or the unit named by the field).
#[derive(Clone, Debug, Default, Serialize)]
pub struct Stat {
    pub median: f64,
    pub min: f64,
    pub max: f64,
    pub samples: Vec<f64>,
}

impl Stat {
    pub fn of(mut samples: Vec<f64>) -> Stat {
        samples.sort_by(f64::total_cmp);
        let median = match samples.len() {
            0 => f64::NAN,
            n if n % 2 == 1 => samples[n / 2],
            n => 0.5 * (samples[n / 2 - 1] + samples[n / 2]),
        };
        Stat {
            median,
            min: samples.first().copied().unwrap_or(f64::NAN),
            max: samples.last().copied().unwrap_or(f64::NAN),
            samples,
        }
    }
}

/// One performance target (BENCHMARKS.md, "Targets"): the measured value against its limit.
#[derive(Clone, Debug, Serialize)]
pub struct Target {
    pub description: String,
    pub value: f64,
    /// `value <= limit` passes for "at most" targets, `value >= limit` for "at least" ones.
    pub limit: f64,
    pub at_least: bool,
    pub met: bool,
}

impl Target {
    pub fn at_most(description: &str, value: f64, limit: f64) -> Self {
        Target {
            description: description.into(),
            value,
            limit,
            at_least: false,
            met: value <= limit,
        }
    }

    pub fn at_least(description: &str, value: f64, limit: f64) -> Self {
        Target {
            description: description.into(),
            value,
            limit,
            at_least: true,
            met: value >= limit,
        }
    }
}

/// Everything `shikki bench --json` prints.
#[derive(Clone, Debug, Serialize)]
pub struct BenchReport {
    pub shikki_version: String,
    /// `release` or `debug`: debug figures are not meaningful.
    pub build_profile: String,
    pub config: BenchConfig,
    pub machine: machine::Machine,
    pub driver: machine::Driver,
    pub render: Option<render::RenderBench>,
    pub prefilter: Option<prefilter::PrefilterBench>,
    pub batch: Option<batch::BatchBench>,
    pub startup: Option<startup::StartupBench>,
    pub memory: Option<memory::MemoryBench>,
    pub rays: Option<rays::RaysBench>,
    pub targets: Vec<Target>,
}

/// Runs every measurement; `progress` receives one line per stage (stderr in the CLI).
pub fn run(
    gpu: &GpuContext,
    config: &BenchConfig,
    progress: &mut dyn FnMut(&str),
) -> Result<BenchReport> {
    config.validate()?;
    let wants = |stage| config.stages.contains(&stage);
    let mut stage = |name: &str, stage: Stage| {
        let run = wants(stage);
        if run {
            progress(name);
        }
        run
    };
    let render = match stage("render: lacquer vs trivial shader", Stage::Render) {
        true => Some(render::run(gpu, config)?),
        false => None,
    };
    let prefilter = match stage("prefilter: GPU vs CPU oracle", Stage::Prefilter) {
        true => Some(prefilter::PrefilterBench {
            timestamps_late: render.is_some() && gpu.quirks().late_timestamps_after_graphics,
            ..prefilter::run(gpu, config)?
        }),
        false => None,
    };
    let batch = match stage("batch", Stage::Batch) {
        true => Some(batch::run(gpu, config)?),
        false => None,
    };
    let startup = match stage("startup: cold and warm child processes", Stage::Startup) {
        true => Some(startup::run(config)?),
        false => None,
    };
    let memory = match stage(
        "memory: peak resident memory of a child render",
        Stage::Memory,
    ) {
        true => Some(memory::run(config)?),
        false => None,
    };
    // A device without ray queries has nothing to measure here: the stage reports as not run.
    let traced = gpu.info().ray_query.is_enabled();
    let rays = match traced && stage("rays: light between objects", Stage::Rays) {
        true => Some(rays::run(gpu, config)?),
        false => None,
    };
    let mut targets = Vec::new();
    if let Some(r) = &render {
        targets.push(r.target.clone());
        targets.push(r.models.target.clone());
    }
    if let Some(p) = &prefilter {
        targets.push(p.speedup_target.clone());
        targets.push(p.time_target.clone());
    }
    if let Some(b) = &batch {
        targets.push(b.target.clone());
    }
    if let Some(s) = &startup {
        targets.push(s.target.clone());
    }
    if let Some(m) = &memory {
        targets.push(m.target.clone());
    }
    if let Some(r) = &rays {
        targets.push(r.target.clone());
        targets.push(r.process_target.clone());
    }
    Ok(BenchReport {
        shikki_version: env!("CARGO_PKG_VERSION").to_string(),
        build_profile: if cfg!(debug_assertions) {
            "debug"
        } else {
            "release"
        }
        .to_string(),
        config: config.clone(),
        machine: machine::Machine::detect(),
        driver: machine::Driver::of(gpu),
        render,
        prefilter,
        batch,
        startup,
        memory,
        rays,
        targets,
    })
}

/// A directory under the system temp dir for one bench stage, removed by [`ScratchDir`]'s drop.
pub(crate) struct ScratchDir(pub std::path::PathBuf);

impl ScratchDir {
    pub fn new(stage: &str) -> Result<Self> {
        let dir = std::env::temp_dir().join(format!(
            "shikki-bench-{stage}-{}-{}",
            std::process::id(),
            std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map(|d| d.as_nanos())
                .unwrap_or(0)
        ));
        std::fs::create_dir_all(&dir).map_err(|e| Error::Write {
            path: dir.clone(),
            message: format!("cannot create a scratch directory: {e}"),
        })?;
        Ok(ScratchDir(dir))
    }
}

impl Drop for ScratchDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
