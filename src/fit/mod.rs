//! Fitting the lacquer model to measured data (paper §3), and synthetic data from the model.
//!
//! ```text
//!  csv (goniometer, RGB | spectral → RGB)  ─┐
//!  merl (.binary, isotropic BRDF)          ─┴─► Measurements (boards + rows, N = +Z)
//!        │
//!        ▼  estimate: select rows, check each term has data
//!  separation (variable projection: m, Fresnel table, per-board P + Q·N·V)
//!        ▼
//!  diffuse (f = a + b·N·V, per-board k_d, g(r), normalisation)  ──► LacquerMaterial + FresnelTable
//!        ▼
//!  report (residuals per term and board, CSV + markdown) + plots (PNG)
//!
//!  synth: LacquerMaterial ─► goniometer grid (+ noise) ─► CSV | MERL
//! ```
//!
//! Everything here is plain Rust on the model of `model/`; it must not touch the GPU, and it owns
//! no model maths (D, G, F and f_r come from `model::brdf`). docs/measurements.md documents the
//! formats and the method for users.

pub mod charts;
pub mod csv;
pub mod data;
pub mod diffuse;
pub mod estimate;
pub mod linalg;
pub mod merl;
pub mod plots;
pub mod polar;
pub mod report;
pub mod separation;
pub mod synth;

use std::path::Path;

pub use data::{Measurement, Measurements, Sample};
pub use estimate::{fit_measurements, FitOptions, FitResult};

use crate::{Error, Result};

/// Reads measurements by extension: `.csv` (goniometer) or `.binary` (MERL).
pub fn read_measurements(path: &Path) -> Result<Measurements> {
    match path.extension().and_then(|e| e.to_str()) {
        Some(e) if e.eq_ignore_ascii_case("csv") => csv::read_goniometer_csv(path),
        Some(e) if e.eq_ignore_ascii_case("binary") => merl::read_merl(path),
        _ => Err(Error::invalid(
            "data file",
            path.display(),
            "the extension must be .csv (goniophotometer CSV) or .binary (MERL BRDF)",
        )),
    }
}
