//! Memory benchmark: peak resident memory (VmHWM, reported by the child itself at exit) of
//! `shikki render` — the default scene with the 1024 × 512 studio environment — cold (prefilter
//! on the GPU) and warm (environment from the disk cache).

use serde::Serialize;

use super::startup::run_child;
use super::{BenchConfig, ScratchDir, Stat, Target};
use crate::{Error, Result};

/// The target (BENCHMARKS.md, "Targets"): ≤ 256 MiB.
pub const PEAK_LIMIT_MIB: f64 = 256.0;

#[derive(Clone, Debug, Serialize)]
pub struct MemoryBench {
    pub image_side: u32,
    /// Peak resident memory with empty caches (MiB).
    pub cold_peak_mib: Stat,
    /// Peak resident memory with the caches filled (MiB).
    pub warm_peak_mib: Stat,
    pub target: Target,
}

pub fn run(config: &BenchConfig) -> Result<MemoryBench> {
    let runs = config.runs.min(3);
    let mib = |kib: Option<u64>| {
        kib.map(|k| k as f64 / 1024.0).ok_or_else(|| {
            Error::invalid(
                "bench memory",
                "no report",
                "the child did not report its peak memory (needs Linux /proc/self/status)",
            )
        })
    };
    let (mut cold, mut warm) = (Vec::new(), Vec::new());
    for _ in 0..runs {
        let scratch = ScratchDir::new("memory")?;
        let mesa = scratch.0.join("mesa");
        cold.push(mib(run_child(config, &scratch.0, &mesa)?.peak_rss_kib)?);
        warm.push(mib(run_child(config, &scratch.0, &mesa)?.peak_rss_kib)?);
    }
    let (cold, warm) = (Stat::of(cold), Stat::of(warm));
    let worst = cold.median.max(warm.median);
    Ok(MemoryBench {
        image_side: config.startup_size,
        target: Target::at_most(
            "memory: peak resident MiB of `shikki render` (worse of cold and warm)",
            worst,
            PEAK_LIMIT_MIB,
        ),
        cold_peak_mib: cold,
        warm_peak_mib: warm,
    })
}
