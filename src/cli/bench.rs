//! `shikki bench [--json] [--quick]`: runs `crate::bench` and prints the table (or JSON).

use clap::Args;

use crate::bench::{self, BenchConfig, Stage};
use crate::{Error, Result};

#[derive(Debug, Args)]
pub struct BenchArgs {
    /// Print one JSON object (machine, driver, every median, ratio and target verdict) on stdout;
    /// the table then goes to stderr.
    #[arg(long)]
    pub json: bool,
    /// Small sizes and two runs per figure: checks that every stage works (CI smoke run); the
    /// figures are not meaningful.
    #[arg(long)]
    pub quick: bool,
    /// Timed runs per figure, after one warm-up run (default 5, 2 with --quick).
    #[arg(long)]
    pub runs: Option<usize>,
    /// Render benchmark image side in pixels (default 1024).
    #[arg(long = "render-size")]
    pub render_size: Option<u32>,
    /// Prefilter face size (default 512).
    #[arg(long = "face-size")]
    pub face_size: Option<u32>,
    /// Prefilter layer count K (default 8).
    #[arg(long)]
    pub layers: Option<u32>,
    /// Batch benchmark: number of jobs (default 64).
    #[arg(long = "batch-jobs")]
    pub batch_jobs: Option<usize>,
    /// Batch benchmark image side (default 512).
    #[arg(long = "batch-size")]
    pub batch_size: Option<u32>,
    /// Start-up and memory benchmark image side (default 1024).
    #[arg(long = "startup-size")]
    pub startup_size: Option<u32>,
    /// Run only these stages (comma-separated; default all).
    #[arg(long, value_enum, value_delimiter = ',')]
    pub only: Vec<Stage>,
}

impl BenchArgs {
    fn config(&self) -> BenchConfig {
        let mut c = if self.quick {
            BenchConfig::quick()
        } else {
            BenchConfig::full()
        };
        c.runs = self.runs.unwrap_or(c.runs);
        c.render_size = self.render_size.unwrap_or(c.render_size);
        c.prefilter_face = self.face_size.unwrap_or(c.prefilter_face);
        c.prefilter_layers = self.layers.unwrap_or(c.prefilter_layers);
        c.batch_jobs = self.batch_jobs.unwrap_or(c.batch_jobs);
        c.batch_size = self.batch_size.unwrap_or(c.batch_size);
        c.startup_size = self.startup_size.unwrap_or(c.startup_size);
        if !self.only.is_empty() {
            c.stages = self.only.clone();
        }
        c
    }
}

pub fn run_bench(args: BenchArgs) -> Result<()> {
    let config = args.config();
    config.validate()?;
    if cfg!(debug_assertions) && !args.quick {
        eprintln!("warning: a debug build's figures are not meaningful; use `cargo run --release -- bench`");
    }
    let gpu = super::open_gpu()?;
    let report = bench::run(&gpu, &config, &mut |stage| eprintln!("bench: {stage}"))?;
    gpu.check_validation()?;
    let table = bench::table::markdown(&report);
    let text = if args.json {
        eprintln!("{table}");
        serde_json::to_string_pretty(&report).map_err(|e| Error::Write {
            path: "stdout".into(),
            message: format!("cannot serialise the report: {e}"),
        })? + "\n"
    } else {
        table
    };
    super::commands::write_stdout(&text)
}
