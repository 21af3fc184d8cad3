//! The fit report: residuals per term and per board (CSV and markdown), the boards' k_d and g,
//! the Fresnel table with its standard errors, the m search, and the plots of [`super::plots`].
//!
//! Residuals are relative, (measured − model)/model, over (row, channel) pairs, because the data's
//! noise is taken as proportional to the signal: with 2 % noise every row-level term reads
//! ≈ 0.02. Owns the report's files and numbers; it fits nothing.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use super::data::Measurements;
use super::diffuse::eval_law;
use super::estimate::{FitResult, FittedRow};
use super::plots;
use super::separation::FRESNEL_KNOTS;
use crate::output::atomic::write_atomically;
use crate::Result;

/// A row is diffuse-dominated below this specular share of the model, specular-dominated above
/// [`SPECULAR_SHARE`].
pub const DIFFUSE_SHARE: f64 = 0.01;
pub const SPECULAR_SHARE: f64 = 0.5;

/// One line of the residual table.
#[derive(Clone, Debug, PartialEq)]
pub struct Residual {
    /// `total`, `diffuse`, `specular`, `f(N·V)` or `g(r)`.
    pub term: &'static str,
    /// A board's name, or `all`.
    pub sample: String,
    /// (row, channel) pairs (boards, for g).
    pub count: usize,
    pub rms: f64,
    pub max_abs: f64,
}

/// The residual table: every term for all boards, then per board.
pub fn residuals(data: &Measurements, fit: &FitResult) -> Vec<Residual> {
    let mut table = Vec::new();
    let boards: Vec<Option<usize>> = std::iter::once(None)
        .chain((0..data.samples.len()).map(Some))
        .collect();
    for board in boards {
        let name = board.map_or("all".to_string(), |s| data.samples[s].name.clone());
        let rows: Vec<&FittedRow> = fit
            .rows
            .iter()
            .filter(|r| board.map_or(true, |s| data.rows[r.index].sample == s))
            .collect();
        for term in ROW_TERMS {
            let mut stats = Stats::default();
            for row in rows.iter().filter(|r| in_term(term, r)) {
                for c in 0..3 {
                    let (measured, model) = if term == "f(N·V)" {
                        let sample = data.rows[row.index].sample;
                        let k = fit.diffuse.board_albedo[sample][c];
                        let beta = fit.diffuse.beta;
                        (
                            row.separated_diffuse[c],
                            k * (1.0 + beta * (row.geometry.nv - 1.0)),
                        )
                    } else {
                        (
                            row.measured[c],
                            row.model_diffuse[c] + row.model_specular[c],
                        )
                    };
                    stats.add(measured, model);
                }
            }
            table.push(stats.residual(term, &name));
        }
        let mut g_stats = Stats::default();
        let norm = eval_law(fit.normalisation.lacquer_law, min_ratio(data));
        for (s, sample) in data.samples.iter().enumerate() {
            if board.map_or(true, |b| b == s) {
                let model = eval_law(fit.material.lacquer_law, sample.lacquer_ratio) / norm;
                g_stats.add(fit.diffuse.normalised_luminance[s], model);
            }
        }
        table.push(g_stats.residual("g(r)", &name));
    }
    table
}

/// Per knot and channel: F's standard error, σ̂ × the unit error, σ̂ the fit's relative RMS;
/// infinite where no row reaches the knot.
pub fn fresnel_std_errors(fit: &FitResult) -> Vec<[f64; 3]> {
    fit.fresnel_unit_error
        .iter()
        .zip(&fit.fresnel_information)
        .map(|(unit, info)| {
            std::array::from_fn(|c| {
                if info[c] > 0.0 {
                    fit.relative_rms * unit[c]
                } else {
                    f64::INFINITY
                }
            })
        })
        .collect()
}

/// The tables the report writes, before its figures and `report.md`.
const TABLE_FILES: [&str; 4] = ["residuals.csv", "boards.csv", "fresnel.csv", "m_search.csv"];

/// The markdown page, written last.
const PAGE_FILE: &str = "report.md";

/// Every file name [`write_report`] writes into its folder (the CLI checks them against the
/// inputs before anything is written).
pub fn report_files() -> Vec<&'static str> {
    TABLE_FILES
        .into_iter()
        .chain(plots::figure_names())
        .chain([PAGE_FILE])
        .collect()
}

/// Writes the report into `dir` (created if missing); returns the files written.
pub fn write_report(dir: &Path, data: &Measurements, fit: &FitResult) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| crate::Error::Write {
        path: dir.to_path_buf(),
        message: e.to_string(),
    })?;
    let residuals = residuals(data, fit);
    let mut written = Vec::new();
    let mut write = |name: &str, bytes: &[u8]| -> Result<()> {
        let path = dir.join(name);
        write_atomically(&path, bytes)?;
        written.push(path);
        Ok(())
    };
    let mut search = String::from("m,objective\n");
    for (m, j) in &fit.beckmann_grid {
        let _ = writeln!(search, "{m},{j}");
    }
    let tables = [
        residuals_csv(&residuals),
        boards_csv(data, fit),
        fresnel_csv(fit),
        search,
    ];
    for (name, table) in TABLE_FILES.iter().zip(&tables) {
        write(name, table.as_bytes())?;
    }
    let pictures = plots::render_all(data, fit)?;
    for (name, png) in &pictures {
        write(name, png)?;
    }
    let names: Vec<&str> = pictures.iter().map(|(n, _)| n.as_str()).collect();
    write(
        PAGE_FILE,
        markdown(data, fit, &residuals, &names).as_bytes(),
    )?;
    Ok(written)
}

fn residuals_csv(residuals: &[Residual]) -> String {
    let mut csv = String::from("term,sample,count,rms_relative,max_abs_relative\n");
    for r in residuals {
        let _ = writeln!(
            csv,
            "{},{},{},{},{}",
            r.term, r.sample, r.count, r.rms, r.max_abs
        );
    }
    csv
}

fn boards_csv(data: &Measurements, fit: &FitResult) -> String {
    let mut csv = String::from(
        "sample,r,albedo_r,albedo_g,albedo_b,kd_r,kd_g,kd_b,normalised_luminance,g_fitted\n",
    );
    for (s, sample) in data.samples.iter().enumerate() {
        let [ar, ag, ab] = fit.diffuse.board_albedo[s];
        let [kr, kg, kb] = fit.diffuse.board_kd[s];
        let g = eval_law(fit.material.lacquer_law, sample.lacquer_ratio);
        let _ = writeln!(
            csv,
            "{},{},{ar},{ag},{ab},{kr},{kg},{kb},{},{g}",
            sample.name, sample.lacquer_ratio, fit.diffuse.normalised_luminance[s]
        );
    }
    csv
}

fn fresnel_csv(fit: &FitResult) -> String {
    let errors = fresnel_std_errors(fit);
    let mut csv = String::from("angle_deg,r,g,b,measured,std_error_r,std_error_g,std_error_b\n");
    for (k, ([r, g, b], [er, eg, eb])) in fit.fresnel.rgb().iter().zip(&errors).enumerate() {
        let measured = fit.fresnel_measured(k);
        let _ = writeln!(csv, "{k},{r},{g},{b},{},{er},{eg},{eb}", u8::from(measured));
    }
    csv
}

fn markdown(
    data: &Measurements,
    fit: &FitResult,
    residuals: &[Residual],
    plots: &[&str],
) -> String {
    let m = &fit.material;
    let mut md = format!("# Lacquer fit of `{}`\n\n", data.source);
    let _ = writeln!(
        md,
        "{} rows on {} board(s); {} fitted, {} left out as grazing (beyond {}°).\n",
        data.rows.len(),
        data.samples.len(),
        fit.rows.len(),
        fit.grazing_rows,
        super::estimate::GRAZING_LIMIT_DEG
    );
    let _ = writeln!(md, "## Parameters\n\n| parameter | value |\n|---|---|");
    let [c0, c1, c2] = m.lacquer_law;
    let [kr, kg, kb] = m.albedo;
    for (name, value) in [
        ("m (Beckmann)", format!("{:.6}", m.beckmann_m)),
        (
            "a, b of f(N·V) = a + b·N·V",
            format!("{:.6}, {:.6}", m.diffuse_a, m.diffuse_b),
        ),
        ("c0, c1, c2 of g(r)", format!("{c0:.6}, {c1:.6}, {c2:.6}")),
        ("k_d (linear RGB)", format!("{kr:.6}, {kg:.6}, {kb:.6}")),
        ("r (least-lacquer board)", format!("{}", m.lacquer_ratio)),
        (
            "normalisation",
            format!(
                "f(1) = a + b = {:.6}; g(r_min) = {:.6}",
                fit.normalisation.f_at_normal,
                eval_law(fit.normalisation.lacquer_law, min_ratio(data))
            ),
        ),
        (
            "relative RMS residual (noise estimate)",
            format!("{:.4}", fit.relative_rms),
        ),
    ] {
        let _ = writeln!(md, "| {name} | {value} |");
    }
    let _ = writeln!(
        md,
        "\n## Residuals\n\nRelative, (measured − model)/model, over (row, channel) pairs; \
         `diffuse` rows have < 1 % specular, `specular` rows > 50 %; `f(N·V)` compares the \
         separated diffuse part with each board's own albedo times f; `g(r)` compares each \
         board's normalised luminance with g(r)/g(r_min).\n\n\
         | term | sample | count | RMS | max |\n|---|---|---|---|---|"
    );
    for r in residuals {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {:.4} | {:.4} |",
            r.term, r.sample, r.count, r.rms, r.max_abs
        );
    }
    let measured: Vec<usize> = (0..FRESNEL_KNOTS)
        .filter(|&k| fit.fresnel_measured(k))
        .collect();
    let _ = writeln!(
        md,
        "\n## Fresnel table\n\nWhole degrees 0..90 in `fresnel.csv`; the data reach {} of the 91 \
         angles (up to {}°); the others are interpolated with the least curvature, towards \
         F(90°) = 1 at grazing.\n",
        measured.len(),
        measured.last().copied().unwrap_or(0)
    );
    if !fit.notes.is_empty() {
        let _ = writeln!(md, "## Notes\n");
        for note in &fit.notes {
            let _ = writeln!(md, "- {note}");
        }
        md.push('\n');
    }
    let _ = writeln!(md, "## Plots\n");
    for name in plots {
        let _ = writeln!(md, "![{name}]({name})");
    }
    md
}

fn min_ratio(data: &Measurements) -> f64 {
    data.samples
        .iter()
        .map(|s| s.lacquer_ratio)
        .fold(f64::INFINITY, f64::min)
}

/// The specular share of a row's model (luminance-weighted).
fn share(row: &FittedRow) -> f64 {
    let d = super::data::luminance(row.model_diffuse);
    let s = super::data::luminance(row.model_specular);
    if d + s > 0.0 {
        s / (d + s)
    } else {
        0.0
    }
}

/// The row-level terms of the residual table.
const ROW_TERMS: [&str; 4] = ["total", "diffuse", "specular", "f(N·V)"];

/// Whether a row counts towards a row-level term.
fn in_term(term: &str, row: &FittedRow) -> bool {
    match term {
        "diffuse" | "f(N·V)" => share(row) < DIFFUSE_SHARE,
        "specular" => share(row) > SPECULAR_SHARE,
        _ => true,
    }
}

/// Running sums of relative residuals.
#[derive(Default)]
struct Stats {
    count: usize,
    sum2: f64,
    max_abs: f64,
}

impl Stats {
    fn add(&mut self, measured: f64, model: f64) {
        if model > 0.0 {
            let e = (measured - model) / model;
            self.count += 1;
            self.sum2 += e * e;
            self.max_abs = self.max_abs.max(e.abs());
        }
    }

    fn residual(&self, term: &'static str, sample: &str) -> Residual {
        Residual {
            term,
            sample: sample.to_string(),
            count: self.count,
            rms: (self.sum2 / self.count.max(1) as f64).sqrt(),
            max_abs: self.max_abs,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stats_are_relative_rms_and_max() {
        // Residuals +10 % and −20 %: RMS √((0.01 + 0.04)/2) = √0.025, max 0.2 (hand values).
        let mut s = Stats::default();
        s.add(1.1, 1.0);
        s.add(1.6, 2.0);
        s.add(5.0, 0.0); // no model value: not counted
        let r = s.residual("total", "all");
        assert_eq!(r.count, 2);
        assert!((r.rms - 0.025f64.sqrt()).abs() < 1e-15 && (r.max_abs - 0.2).abs() < 1e-15);
    }
}
