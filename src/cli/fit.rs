//! `shikki fit` and `shikki synth` (filled in by the measurement work).

use crate::Result;
use clap::Args;

#[derive(Debug, Args)]
pub struct FitArgs {}

#[derive(Debug, Args)]
pub struct SynthArgs {}

pub fn run_fit(_args: FitArgs) -> Result<()> {
    Ok(())
}

pub fn run_synth(_args: SynthArgs) -> Result<()> {
    Ok(())
}
