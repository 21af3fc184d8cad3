//! `shikki bench [--json] [--quick]`: runs `crate::bench` and prints the table (or JSON); the
//! arguments are declared in `args.rs`.

use super::args::BenchArgs;
use crate::bench::{self, BenchConfig};
use crate::{Error, Result};

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
