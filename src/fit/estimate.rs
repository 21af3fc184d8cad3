//! The whole fit of paper §3, in order: select rows → check every term has data → separation and
//! m with weights 1/y² → again with weights 1/model² → diffuse laws → Fresnel table → material.
//!
//! Weights: goniometer noise is roughly proportional to the signal, so every row is weighted by
//! 1/σ² with σ ∝ its value: the specular peak (hundreds of times the diffuse level on smooth
//! lacquer) and the diffuse floor then count alike. The first pass takes σ from the measured
//! value; a second pass takes it from the first pass's model, which removes the bias that weights
//! from noisy values carry (low readings would count more). Owns the pipeline and the "too few
//! data" checks; the maths is in [`super::separation`] and [`super::diffuse`].

use super::data::{goniometer_angles, in_plane_theta_o, Measurement, Measurements};
use super::diffuse::{
    check_lacquer_ratios, eval_law, fit_diffuse, DiffuseFit, DiffuseSums, Normalisation,
};
use super::separation::{
    BeckmannSearch, LinearSolution, RowGeometry, Separation, BECKMANN_M_RANGE, FRESNEL_KNOTS,
};
use crate::model::brdf::{lacquer_brdf, view_dependent_diffuse, BrdfParams};
use crate::model::{FresnelTable, LacquerMaterial};
use crate::{Error, Result};
use std::f64::consts::PI;

/// Rows with the light or the viewer beyond this angle from the normal are not fitted: there the
/// goniometer's spot is elongated, the clamp max(a + b·N·V, 0) may act, and 1/(N·V·N·L) amplifies
/// every error.
pub const GRAZING_LIMIT_DEG: f64 = 87.0;
/// A row is "near the mirror direction" when its half-vector is within this angle of the normal.
pub const NEAR_MIRROR_DEG: f64 = 10.0;
/// The fewest near-mirror rows that fix m.
pub const MIN_NEAR_MIRROR_ROWS: usize = 5;

/// What the fit may be told.
#[derive(Clone, Debug, Default)]
pub struct FitOptions {
    /// Take the normalisation f(1) = a + b and g(r_min) from this material (and β_*, IOR, which
    /// reflectance data cannot show); None: f(1) = g(1) = 1.
    pub reference: Option<LacquerMaterial>,
}

/// One fitted row: the measurement, the separation's parts and the final material's prediction.
#[derive(Clone, Debug)]
pub struct FittedRow {
    /// Index into [`Measurements::rows`].
    pub index: usize,
    pub geometry: RowGeometry,
    pub measured: [f64; 3],
    /// Measured minus the fitted specular part: the separated diffuse part.
    pub separated_diffuse: [f64; 3],
    /// Measured minus the fitted diffuse part: the separated specular part.
    pub separated_specular: [f64; 3],
    /// π·f_diff and π·f_spec of the final material at this row (its board's r).
    pub model_diffuse: [f64; 3],
    pub model_specular: [f64; 3],
}

/// Everything the fit found, for the material file and the report.
#[derive(Clone, Debug)]
pub struct FitResult {
    /// The fitted material (without `fresnel_file`: the table is [`FitResult::fresnel`]).
    pub material: LacquerMaterial,
    /// The Fresnel table, clamped to [0, 1].
    pub fresnel: FresnelTable,
    /// Per knot and channel: the data's weight on the knot; 0 where no row reaches it.
    pub fresnel_information: Vec<[f64; 3]>,
    /// Per knot and channel: F's standard error per unit relative noise
    /// ([`super::separation::LinearSolution::fresnel_unit_error`]).
    pub fresnel_unit_error: Vec<[f64; 3]>,
    /// Fresnel values the clamp to [0, 1] changed.
    pub fresnel_clamped: usize,
    /// J(m) on the first pass's grid over the whole search range (for the report's plot).
    pub beckmann_grid: Vec<(f64, f64)>,
    pub diffuse: DiffuseFit,
    pub normalisation: Normalisation,
    pub rows: Vec<FittedRow>,
    /// Rows left out as grazing.
    pub grazing_rows: usize,
    /// RMS of (measured − model)/model over the fitted rows and channels: the noise estimate.
    pub relative_rms: f64,
    /// Things a user should know (kept law, clamps, extrapolate_g).
    pub notes: Vec<String>,
}

/// A Fresnel knot counts as measured when rows reach it and they alone fix it to ±1 per unit
/// relative noise (±0.01 at 1 % noise); elsewhere the table is interpolated. The flag says the
/// data determine the knot; how closely is its standard error (the report lists both): at 2 %
/// noise on the synth grid ≤ 0.0022 up to 80°, 0.0097 at 83°.
pub const MEASURED_UNIT_ERROR: f64 = 1.0;

impl FitResult {
    /// Whether the data determine the Fresnel table at whole degree `knot` (every channel).
    pub fn fresnel_measured(&self, knot: usize) -> bool {
        (0..3).all(|c| {
            self.fresnel_information[knot][c] > 0.0
                && self.fresnel_unit_error[knot][c] <= MEASURED_UNIT_ERROR
        })
    }
}

/// Fits the lacquer model to `data`. Where every angle is within π/2 degrees of the normal the
/// angles were likely written in radians: a failure says so, and a fit that succeeds notes it.
pub fn fit_measurements(data: &Measurements, options: &FitOptions) -> Result<FitResult> {
    let radians = angles_look_like_radians(data);
    match fit(data, options) {
        Ok(mut fit) => {
            if radians {
                fit.notes.push(RADIANS_HINT.into());
            }
            Ok(fit)
        }
        Err(Error::InvalidParameter {
            field,
            value,
            reason,
        }) if radians => Err(Error::InvalidParameter {
            field,
            value,
            reason: format!("{reason}. Hint: {RADIANS_HINT}"),
        }),
        Err(e) => Err(e),
    }
}

const RADIANS_HINT: &str = "every θ_i and θ_o is within π/2 ≈ 1.5708 of 0, so the angles look \
    like radians; the angle columns are in degrees (theta_i_deg, theta_o_deg, phi_deg): multiply \
    them by 180/π ≈ 57.2958";

/// Whether every row's light and viewer lie within π/2 *degrees* of the normal (and some not on
/// it): no goniophotometer measures so, but θ in radians reads so as degrees.
fn angles_look_like_radians(data: &Measurements) -> bool {
    let limit = std::f64::consts::FRAC_PI_2.to_radians().cos();
    let within = |v: glam::DVec3| v.z >= limit;
    let on_normal = |v: glam::DVec3| v.x == 0.0 && v.y == 0.0;
    !data.rows.is_empty()
        && data.rows.iter().all(|r| within(r.light) && within(r.view))
        && !data
            .rows
            .iter()
            .all(|r| on_normal(r.light) && on_normal(r.view))
}

/// The fit itself.
fn fit(data: &Measurements, options: &FitOptions) -> Result<FitResult> {
    let normalisation = normalisation(options.reference.as_ref())?;
    let limit = GRAZING_LIMIT_DEG.to_radians().cos();
    let selected: Vec<usize> = (0..data.rows.len())
        .filter(|&i| data.rows[i].light.z >= limit && data.rows[i].view.z >= limit)
        .collect();
    let rows: Vec<_> = selected.iter().map(|&i| data.rows[i].clone()).collect();
    let geometry: Vec<RowGeometry> = rows
        .iter()
        .map(|r| RowGeometry::new(r.light, r.view))
        .collect();
    check_enough_data(data, &rows, &geometry)?;
    let ratios: Vec<f64> = data.samples.iter().map(|s| s.lacquer_ratio).collect();
    check_lacquer_ratios(&ratios)?;

    // Pass 1: σ from the measured values; pass 2: σ from pass 1's model.
    let floor = value_floor(&rows);
    let weights_of = |value: &dyn Fn(usize, usize) -> f64| -> Vec<[f64; 3]> {
        (0..rows.len())
            .map(|i| std::array::from_fn(|c| 1.0 / value(i, c).max(floor[c]).powi(2)))
            .collect()
    };
    let weights = weights_of(&|i, c| rows[i].reflectance[c]);
    let first = search(
        &rows,
        &geometry,
        &weights,
        data.samples.len(),
        BECKMANN_M_RANGE,
        41,
    )?;
    let predicted: Vec<[f64; 3]> = rows
        .iter()
        .zip(&geometry)
        .map(|(row, geo)| {
            let (d, s) = first.solution.parts(row.sample, geo);
            std::array::from_fn(|c| d[c] + s[c])
        })
        .collect();
    let weights = weights_of(&|i, c| predicted[i][c]);
    // The reweighting moves m by about the noise's effect (well under 10 %): search near it.
    let m1 = first.solution.beckmann_m;
    let near = (m1 / 1.25, (m1 * 1.25).min(BECKMANN_M_RANGE.1));
    let BeckmannSearch { solution, .. } =
        search(&rows, &geometry, &weights, data.samples.len(), near, 9)?;

    let mut sums = vec![[DiffuseSums::default(); 3]; data.samples.len()];
    for ((row, geo), w) in rows.iter().zip(&geometry).zip(&weights) {
        let (_, specular) = solution.parts(row.sample, geo);
        for c in 0..3 {
            sums[row.sample][c].add(w[c], geo.nv, row.reflectance[c] - specular[c]);
        }
    }
    let diffuse = fit_diffuse(&sums, &ratios, &normalisation)?;

    let mut notes = data.notes.clone();
    let mut clamped = 0;
    let table: Vec<[f64; 3]> = solution
        .fresnel
        .iter()
        .map(|f| {
            f.map(|v| {
                let kept = v.clamp(0.0, 1.0);
                clamped += usize::from(kept != v);
                kept
            })
        })
        .collect();
    if clamped > 0 {
        notes.push(format!(
            "{clamped} Fresnel value(s) outside [0, 1] were clamped (noise where few rows reach)"
        ));
    }
    let angles: Vec<f64> = (0..FRESNEL_KNOTS).map(|k| k as f64).collect();
    let fresnel = FresnelTable::new(angles, table)?;
    if !diffuse.lacquer_law_fitted {
        notes.push(
            "one lacquer ratio in the data: g(r) is not fitted; it keeps the normalisation's law"
                .into(),
        );
    }
    let r_min = ratios.iter().copied().fold(f64::INFINITY, f64::min);
    let material = assemble_material(options, solution.beckmann_m, &diffuse, r_min, &mut notes)?;

    let fitted = fitted_rows(
        &selected, &rows, &geometry, &solution, &material, &fresnel, &ratios,
    )?;
    let relative_rms = relative_rms(&fitted);
    Ok(FitResult {
        material,
        fresnel,
        fresnel_information: solution.fresnel_information.clone(),
        fresnel_unit_error: solution.fresnel_unit_error.clone(),
        fresnel_clamped: clamped,
        beckmann_grid: first.grid,
        diffuse,
        normalisation,
        rows: fitted,
        grazing_rows: data.rows.len() - selected.len(),
        relative_rms,
        notes,
    })
}

/// The conventions of [`Normalisation`] from the reference, or f(1) = g(1) = 1 with the paper's
/// g shape (used only when g cannot be fitted).
fn normalisation(reference: Option<&LacquerMaterial>) -> Result<Normalisation> {
    match reference {
        Some(reference) => {
            let f_at_normal = reference.diffuse_a + reference.diffuse_b;
            // A validated material has finite a and b, so this also excludes NaN.
            if f_at_normal <= 0.0 {
                return Err(Error::invalid(
                    "reference a + b",
                    f_at_normal,
                    "f(1) = a + b of the --normalise-like material must be > 0 to scale f by it",
                ));
            }
            Ok(Normalisation {
                f_at_normal,
                lacquer_law: reference.lacquer_law,
            })
        }
        None => {
            let paper = LacquerMaterial::default().lacquer_law;
            let at_one = eval_law(paper, 1.0);
            Ok(Normalisation {
                f_at_normal: 1.0,
                lacquer_law: paper.map(|c| c / at_one),
            })
        }
    }
}

/// Every term needs data of its own kind; say which term lacks it.
fn check_enough_data(
    data: &Measurements,
    rows: &[Measurement],
    geometry: &[RowGeometry],
) -> Result<()> {
    if data.rows.is_empty() {
        return Err(Error::invalid(
            "data",
            "0 rows",
            "there are no measurements to fit; give a file with measured rows",
        ));
    }
    if rows.is_empty() {
        return Err(Error::invalid(
            "data",
            format!("{} rows, all grazing", data.rows.len()),
            format!(
                "no row has both the light and the viewer within {GRAZING_LIMIT_DEG}° of the \
                 normal; measure at smaller angles"
            ),
        ));
    }
    // All-zero data "fitted" m = 1 and k_d = 0 with a relative residual of 1: nothing to fit.
    if rows.iter().all(|r| r.reflectance.iter().all(|&v| v == 0.0)) {
        return Err(Error::invalid(
            "data",
            format!("{} rows, every R, G and B 0", rows.len()),
            "the measurements hold no reflected light to fit; check that the file's R, G, B \
             columns hold the reflectance factors (π·f_r)",
        ));
    }
    for (s, sample) in data.samples.iter().enumerate() {
        // (N·V to 1e-9, the first such row): f depends on N·V alone.
        let mut views: Vec<(f64, &Measurement)> = rows
            .iter()
            .zip(geometry)
            .filter(|(r, _)| r.sample == s)
            .map(|(r, g)| ((g.nv * 1e9).round() / 1e9, r))
            .collect();
        views.sort_by(|a, b| a.0.total_cmp(&b.0));
        views.dedup_by(|a, b| a.0 == b.0);
        if views.len() < 2 {
            let angles = views.iter().map(|(_, row)| shown_view_angle(row));
            return Err(Error::invalid(
                format!("data for f(N·V) of sample `{}`", sample.name),
                format!(
                    "{} viewing angle(s) ({})",
                    views.len(),
                    angles.collect::<Vec<_>>().join(", ")
                ),
                "too few to fit a and b: measure each board at 2 or more viewing angles θ_o",
            ));
        }
    }
    let near: Vec<usize> = (0..rows.len())
        .filter(|&i| geometry[i].tilt_deg < NEAR_MIRROR_DEG)
        .collect();
    if near.len() < MIN_NEAR_MIRROR_ROWS {
        return Err(Error::invalid(
            "data for the specular lobe (Beckmann m)",
            format!("{} row(s) near the mirror direction", near.len()),
            format!(
                "too few: measure {MIN_NEAR_MIRROR_ROWS} or more rows whose half-vector is within \
                 {NEAR_MIRROR_DEG}° of the normal (θ_o near θ_i at φ = 0)"
            ),
        ));
    }
    let mut incidences: Vec<f64> = near
        .iter()
        .map(|&i| (rows[i].light.z.acos().to_degrees() * 10.0).round() / 10.0)
        .collect();
    incidences.sort_by(f64::total_cmp);
    incidences.dedup();
    if incidences.len() < 2 {
        return Err(Error::invalid(
            "data for the Fresnel table",
            format!("near-mirror rows at 1 incidence angle ({}°)", incidences[0]),
            "too few: measure the mirror direction at 2 or more incidence angles θ_i (e.g. 0..80° \
             in steps of 10°)",
        ));
    }
    Ok(())
}

/// A row's viewing angle as the file gives it: signed in the plane of incidence (θ_o = −85 is on
/// the light's side, and was shown as 85.0°), with its azimuth out of it.
fn shown_view_angle(row: &Measurement) -> String {
    match in_plane_theta_o(row.light, row.view, 1e-6) {
        Some(theta_o) => format!("{theta_o:.1}°"),
        None => {
            let (_, theta_o, phi) = goniometer_angles(row.light, row.view);
            format!("{theta_o:.1}° at φ = {phi:.1}°")
        }
    }
}

/// Per channel: 1e-3 of the median value. Weights 1/max(value, floor)² so that a zero reading
/// (a black board's blue channel, say) does not get an infinite weight.
fn value_floor(rows: &[Measurement]) -> [f64; 3] {
    std::array::from_fn(|c| {
        let mut values: Vec<f64> = rows.iter().map(|r| r.reflectance[c]).collect();
        values.sort_by(f64::total_cmp);
        let median = values.get(values.len() / 2).copied().unwrap_or(0.0);
        (1e-3 * median).max(1e-12)
    })
}

fn search(
    rows: &[Measurement],
    geometry: &[RowGeometry],
    weights: &[[f64; 3]],
    sample_count: usize,
    range: (f64, f64),
    grid: usize,
) -> Result<BeckmannSearch> {
    Separation {
        rows,
        geometry,
        weights,
        sample_count,
    }
    .search_beckmann_m(range, grid)
    .ok_or_else(|| {
        Error::invalid(
            "data",
            format!("{} rows", rows.len()),
            "the diffuse and specular parts cannot be separated: the least-squares system is \
             singular for every m; measure more viewing angles per board and near-mirror rows",
        )
    })
}

/// The fitted parameters in a material: β_*, IOR (not measurable from reflectance) from the
/// reference, else from the preset whose m is nearest (smooth 0.05, rough 0.2, in log m).
fn assemble_material(
    options: &FitOptions,
    beckmann_m: f64,
    diffuse: &DiffuseFit,
    r_min: f64,
    notes: &mut Vec<String>,
) -> Result<LacquerMaterial> {
    let mut material = match &options.reference {
        Some(reference) => reference.clone(),
        None => {
            let smooth = (beckmann_m / 0.05).ln().abs() < (beckmann_m / 0.2).ln().abs();
            let name = if smooth { "smooth" } else { "rough" };
            notes.push(format!(
                "beta_normal, beta_grazing, beta_power, ior_a and ior_b are not measured by the \
                 fit: they are the `{name}` preset's"
            ));
            LacquerMaterial::preset(name)?
        }
    };
    material.beckmann_m = beckmann_m;
    material.diffuse_a = diffuse.diffuse_a;
    material.diffuse_b = diffuse.diffuse_b;
    material.lacquer_law = diffuse.lacquer_law;
    material.lacquer_ratio = r_min;
    material.albedo = diffuse.albedo;
    material.extrapolate_g = false;
    material.fresnel_file = None;
    if material.albedo.iter().any(|k| !(0.0..=1.0).contains(k)) {
        let [r, g, b] = material.albedo;
        return Err(Error::invalid(
            "fitted kd",
            format!("{r},{g},{b}"),
            "is outside [0, 1]: check that the data are reflectance factors π·f_r (1 = a white \
             Lambertian diffuser), or choose another split of k_d·g·f with --normalise-like",
        ));
    }
    if let Err(Error::InvalidParameter { field, .. }) = material.validate() {
        if field == "r" {
            material.extrapolate_g = true;
            notes.push(format!(
                "the fitted g(r) turns upward before r = {r_min} (r* = {:.3}): extrapolate_g = true",
                material.lacquer_ratio_max()
            ));
        }
    }
    material.validate()?;
    Ok(material)
}

/// The rows with their separated parts and the final material's prediction (the model's own
/// [`lacquer_brdf`], so the report checks what the renderer will draw).
fn fitted_rows(
    selected: &[usize],
    rows: &[Measurement],
    geometry: &[RowGeometry],
    solution: &LinearSolution,
    material: &LacquerMaterial,
    fresnel: &FresnelTable,
    ratios: &[f64],
) -> Result<Vec<FittedRow>> {
    let base = material.brdf_params()?;
    let params: Vec<BrdfParams> = ratios
        .iter()
        .map(|&r| BrdfParams {
            lacquer_g: eval_law(material.lacquer_law, r),
            ..base
        })
        .collect();
    Ok(rows
        .iter()
        .zip(geometry)
        .zip(selected)
        .map(|((row, geo), &index)| {
            let p = &params[row.sample];
            let total = lacquer_brdf(p, fresnel, glam::DVec3::Z, row.view, row.light);
            let model_diffuse = view_dependent_diffuse(p, geo.nv).map(|v| v * PI);
            let (sep_d, sep_s) = solution.parts(row.sample, geo);
            FittedRow {
                index,
                geometry: *geo,
                measured: row.reflectance,
                separated_diffuse: std::array::from_fn(|c| row.reflectance[c] - sep_s[c]),
                separated_specular: std::array::from_fn(|c| row.reflectance[c] - sep_d[c]),
                model_diffuse,
                model_specular: std::array::from_fn(|c| total[c] * PI - model_diffuse[c]),
            }
        })
        .collect())
}

/// RMS of (measured − model)/model over rows and channels.
fn relative_rms(rows: &[FittedRow]) -> f64 {
    let mut sum = 0.0;
    let mut count = 0usize;
    for row in rows {
        for c in 0..3 {
            let model = row.model_diffuse[c] + row.model_specular[c];
            if model > 0.0 {
                sum += ((row.measured[c] - model) / model).powi(2);
                count += 1;
            }
        }
    }
    (sum / count.max(1) as f64).sqrt()
}
