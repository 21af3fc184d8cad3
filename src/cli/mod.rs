//! The command line: argument parsing and dispatch only; rendering lives in the library.
//!
//! Every failure prints `error: …` (with its causes) to stderr and exits with code 1; clap's own
//! usage errors exit with 2.

mod args;
mod commands;
mod directions;
mod fit;
mod scene_cmd;

use clap::Parser;
use std::process::ExitCode;

pub use args::{parse_size, parse_vec3, Cli, Command};

/// Runs the CLI with the process arguments.
pub fn main() -> ExitCode {
    let cli = Cli::parse();
    match commands::run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("error: {err}");
            let mut source = std::error::Error::source(&err);
            while let Some(cause) = source {
                eprintln!("  caused by: {cause}");
                source = cause.source();
            }
            ExitCode::FAILURE
        }
    }
}
