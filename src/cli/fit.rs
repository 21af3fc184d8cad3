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
    let named = args
        .normalise_like
        .as_deref()
        .map(material_named)
        .transpose()?;
    let fresnel_path = fresnel_path_beside(&args.output);
    let mut inputs = vec![args.data.clone()];
    if let Some((reference, file)) = &named {
        inputs.extend(file.iter().chain(&reference.fresnel_file).cloned());
    }
    let mut outputs = vec![
        Output::new("-o", &args.output, &args.output, "the material file"),
        Output::new(
            "-o",
            &args.output,
            &fresnel_path,
            "the material's Fresnel table (written beside it)",
        ),
    ];
    if let Some(dir) = &args.report {
        check_report_folder(dir)?;
        outputs.extend(
            report::report_files()
                .into_iter()
                .map(|name| Output::new("--report", dir, &dir.join(name), "the report file")),
        );
    }
    refuse_overwriting_inputs(&outputs, &inputs)?;

    let reference = named.map(|(material, _)| material);
    let data = read_measurements(&args.data)?;
    eprintln!(
        "read {} row(s) on {} board(s) from {}; fitting",
        data.rows.len(),
        data.samples.len(),
        args.data.display()
    );
    let fit = fit_measurements(&data, &FitOptions { reference })?;

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
        (Some(path), _) => {
            let material = load_material_file(path)?;
            let inputs: Vec<PathBuf> = std::iter::once(path)
                .chain(&material.fresnel_file)
                .cloned()
                .collect();
            let output = Output::new("-o", &args.output, &args.output, "the synthetic data");
            refuse_overwriting_inputs(&[output], &inputs)?;
            (material, path.display().to_string())
        }
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

/// A preset name (in any case), or else the path of a material TOML, which is returned too (it is
/// an input the outputs must not overwrite).
fn material_named(name: &str) -> Result<(LacquerMaterial, Option<PathBuf>)> {
    if PRESET_NAMES.iter().any(|p| p.eq_ignore_ascii_case(name)) {
        Ok((LacquerMaterial::preset(name)?, None))
    } else if Path::new(name).is_file() {
        let path = PathBuf::from(name);
        Ok((load_material_file(&path)?, Some(path)))
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

/// A file a command will write: the flag that decides where (and what it was given, for the
/// message), its path and what it is.
struct Output<'a> {
    flag: &'static str,
    given: &'a Path,
    path: PathBuf,
    what: &'a str,
}

impl<'a> Output<'a> {
    fn new(flag: &'static str, given: &'a Path, path: &Path, what: &'a str) -> Self {
        Output {
            flag,
            given,
            path: path.to_path_buf(),
            what,
        }
    }
}

/// Refuses, before anything is written, an output that is one of the inputs: written atomically,
/// it would replace the input (`fit boards.csv --report .` replaced the measurements with the
/// per-board table, `fit a.fresnel.csv -o a.toml` with the fitted Fresnel table).
fn refuse_overwriting_inputs(outputs: &[Output], inputs: &[PathBuf]) -> Result<()> {
    for output in outputs {
        if let Some(input) = inputs.iter().find(|i| same_file(&output.path, i)) {
            let fix = match output.flag {
                "--report" => "choose another --report folder, e.g. --report report/",
                _ => "choose another -o name, e.g. -o fitted.toml",
            };
            return Err(Error::invalid(
                output.flag,
                output.given.display(),
                format!(
                    "{} {} is the input {} (the same file); writing it would replace the input, \
                     so nothing was written: {fix}",
                    output.what,
                    output.path.display(),
                    input.display()
                ),
            ));
        }
    }
    Ok(())
}

/// Whether two paths name one existing file: the same device and inode on Unix, so hard links,
/// symbolic links and `./x` against `x` all count; the canonical paths elsewhere. Also the
/// render's rule for its output against its inputs (`scene_cmd`).
pub(super) fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(meta_a), Ok(meta_b)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        meta_a.dev() == meta_b.dev() && meta_a.ino() == meta_b.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (meta_a, meta_b);
        matches!(
            (std::fs::canonicalize(a), std::fs::canonicalize(b)),
            (Ok(x), Ok(y)) if x == y
        )
    }
}

/// The report folder may be missing (it is created) but not a file: found only after the
/// material was written, it left a half-done run.
fn check_report_folder(dir: &Path) -> Result<()> {
    match std::fs::metadata(dir) {
        Ok(meta) if !meta.is_dir() => Err(Error::invalid(
            "--report",
            dir.display(),
            "is a file, not a folder; name a folder for the report (it is created if missing)",
        )),
        _ => Ok(()),
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
