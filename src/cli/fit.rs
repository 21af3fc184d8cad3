//! `shikki fit` and `shikki synth`: file plumbing only; the arguments are declared in `args.rs`,
//! the fit, the formats and the report live in `crate::fit`, the material file in
//! `crate::model::material_file`.

use std::path::{Path, PathBuf};

use super::args::{FitArgs, SynthArgs};
use crate::fit::estimate::FitOptions;
use crate::fit::synth::{synthesize_csv, synthesize_merl, Noise, DEFAULT_RATIOS};
use crate::fit::{fit_measurements, read_measurements, report};
use crate::model::material_file::{load_material_file, material_to_toml};
use crate::model::{LacquerMaterial, PRESET_NAMES};
use crate::output::atomic::write_atomically;
use crate::{Error, Result};

pub fn run_fit(args: FitArgs) -> Result<()> {
    if !has_extension(&args.output, "toml") {
        return Err(Error::invalid(
            "-o",
            args.output.display(),
            "the material file must end in .toml, e.g. -o lacquer.toml",
        ));
    }
    let reference = args
        .normalise_like
        .as_deref()
        .map(material_named)
        .transpose()?;
    let data = read_measurements(&args.data)?;
    let fit = fit_measurements(&data, &FitOptions { reference })?;

    let fresnel_path = fresnel_path_beside(&args.output);
    let fresnel_name = fresnel_path
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    write_atomically(&fresnel_path, fit.fresnel.to_csv().as_bytes())?;
    let toml = format!(
        "# Fitted by `shikki fit` from {}: {} rows, relative RMS residual {:.4}.\n{}",
        args.data.display(),
        fit.rows.len(),
        fit.relative_rms,
        material_to_toml(&fit.material, Some(&fresnel_name))
    );
    write_atomically(&args.output, toml.as_bytes())?;
    let m = &fit.material;
    eprintln!(
        "fitted m = {:.5}, a = {:.5}, b = {:.5}, g = {:.5} {:+.5}·r {:+.6}·r², k_d = ({:.4}, {:.4}, \
         {:.4}); relative RMS residual {:.4}",
        m.beckmann_m,
        m.diffuse_a,
        m.diffuse_b,
        m.lacquer_law[0],
        m.lacquer_law[1],
        m.lacquer_law[2],
        m.albedo[0],
        m.albedo[1],
        m.albedo[2],
        fit.relative_rms
    );
    for note in &fit.notes {
        eprintln!("note: {note}");
    }
    eprintln!(
        "wrote {} and {}",
        args.output.display(),
        fresnel_path.display()
    );
    if let Some(dir) = &args.report {
        let files = report::write_report(dir, &data, &fit)?;
        eprintln!(
            "wrote the report ({} files) to {}",
            files.len(),
            dir.display()
        );
    }
    Ok(())
}

pub fn run_synth(args: SynthArgs) -> Result<()> {
    let (material, origin) = match (&args.material, &args.preset) {
        (Some(path), _) => (load_material_file(path)?, path.display().to_string()),
        (None, Some(name)) => (LacquerMaterial::preset(name)?, format!("preset {name}")),
        (None, None) => {
            return Err(Error::invalid(
                "material",
                "none",
                "give a material TOML or --preset NAME",
            ))
        }
    };
    let noise = Noise {
        relative: args.noise,
        seed: args.seed,
    };
    let bytes = if has_extension(&args.output, "binary") {
        let board = match args.ratios.as_deref() {
            None => material,
            Some([r]) => LacquerMaterial {
                lacquer_ratio: *r,
                ..material
            },
            Some(many) => {
                return Err(Error::invalid(
                    "--ratios",
                    format!("{many:?}"),
                    "a MERL file holds one board: give one ratio, or write a .csv for several",
                ))
            }
        };
        synthesize_merl(&board, noise)?
    } else if has_extension(&args.output, "csv") {
        let ratios = args.ratios.unwrap_or_else(|| DEFAULT_RATIOS.to_vec());
        synthesize_csv(&material, &ratios, noise, &origin)?.into_bytes()
    } else {
        return Err(Error::invalid(
            "-o",
            args.output.display(),
            "the output must end in .csv (goniophotometer CSV) or .binary (MERL BRDF)",
        ));
    };
    write_atomically(&args.output, &bytes)?;
    eprintln!(
        "wrote {} ({origin}, noise {}, seed {})",
        args.output.display(),
        args.noise,
        args.seed
    );
    Ok(())
}

/// A preset name, or else the path of a material TOML.
fn material_named(name: &str) -> Result<LacquerMaterial> {
    if PRESET_NAMES.contains(&name) {
        LacquerMaterial::preset(name)
    } else if Path::new(name).is_file() {
        load_material_file(Path::new(name))
    } else {
        Err(Error::invalid(
            "--normalise-like",
            name,
            format!(
                "is neither a preset ({}) nor an existing material TOML file",
                PRESET_NAMES.join(", ")
            ),
        ))
    }
}

/// `dir/name.toml` → `dir/name.fresnel.csv`.
fn fresnel_path_beside(material: &Path) -> PathBuf {
    let stem = material
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "material".into());
    material.with_file_name(format!("{stem}.fresnel.csv"))
}

fn has_extension(path: &Path, extension: &str) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| e.eq_ignore_ascii_case(extension))
}
