//! Every bad-data case of issue 6 gives its exact message: missing columns, non-numeric cells,
//! NaN, negative values, angles out of range, too few data to fit a term (naming the term), and a
//! MERL file of the wrong size or kind.

use shikki::fit::csv::parse_goniometer_csv;
use shikki::fit::merl::{parse_merl, MERL_DIMS};
use shikki::fit::synth::{synthesize, Noise};
use shikki::fit::{fit_measurements, FitOptions, Measurements};
use shikki::model::LacquerMaterial;

const HEADER: &str = "sample,r,theta_i_deg,theta_o_deg,phi_deg,R,G,B";

/// The full error text of parsing `rows` after the RGB header.
fn csv_error(rows: &str) -> String {
    let text = format!("{HEADER}\n{rows}");
    match parse_goniometer_csv(&text, "data.csv") {
        Err(e) => e.to_string(),
        Ok(_) => panic!("expected an error for {rows:?}"),
    }
}

#[test]
fn missing_columns() {
    let err = parse_goniometer_csv(
        "sample,r,theta_i_deg,phi_deg,R,G,B\nA,1,0,0,1,1,1\n",
        "data.csv",
    )
    .unwrap_err()
    .to_string();
    assert_eq!(
        err,
        "data.csv:1: missing column `theta_o_deg`; the header must name sample, r, theta_i_deg, \
         theta_o_deg, phi_deg and then R,G,B or wavelengths in nm covering 380–780 (e.g. \
         380,390,…,780)"
    );
    let err = parse_goniometer_csv("sample,r,theta_i_deg,theta_o_deg,phi_deg,R,B\n", "data.csv")
        .unwrap_err()
        .to_string();
    assert!(
        err.starts_with("data.csv:1: missing column `G`; the header must name"),
        "{err}"
    );
    // A row with a cell missing.
    assert_eq!(
        csv_error("A,1,30,30,0,0.1,0.2,0.3\nA,1,30,31,0,0.1,0.2\n"),
        "data.csv:3: expected 8 cells separated by `,` as in the header, found 7"
    );
}

#[test]
fn non_numeric_cells() {
    assert_eq!(
        csv_error("A,1,30,abc,0,0.1,0.2,0.3\n"),
        "data.csv:2: `theta_o_deg` = `abc` is not a number"
    );
    assert_eq!(
        csv_error("A,1,30,30,0,0.1,,0.3\n"),
        "data.csv:2: `G` is empty; put a number there"
    );
}

#[test]
fn nan_and_infinity() {
    assert_eq!(
        csv_error("A,1,30,30,0,0.1,NaN,0.3\n"),
        "data.csv:2: `G` = `NaN` is not a finite number"
    );
    assert_eq!(
        csv_error("A,inf,30,30,0,0.1,0.2,0.3\n"),
        "data.csv:2: `r` = `inf` is not a finite number"
    );
}

#[test]
fn negative_values() {
    assert_eq!(
        csv_error("A,1,30,30,0,0.1,0.2,0.3\nA,1,30,40,0,-0.01,0.2,0.3\n"),
        "data.csv:3: `R` = -0.01 is negative; reflectance factors (π·f_r) are >= 0"
    );
}

#[test]
fn angles_out_of_range() {
    assert_eq!(
        csv_error("A,1,90,30,0,0.1,0.2,0.3\n"),
        "data.csv:2: `theta_i_deg` = 90 is outside [0, 90)"
    );
    assert_eq!(
        csv_error("A,1,-5,30,0,0.1,0.2,0.3\n"),
        "data.csv:2: `theta_i_deg` = -5 is outside [0, 90)"
    );
    assert_eq!(
        csv_error("A,1,30,-90,0,0.1,0.2,0.3\n"),
        "data.csv:2: `theta_o_deg` = -90 is outside (-90, 90)"
    );
    assert_eq!(
        csv_error("A,1,30,30,400,0.1,0.2,0.3\n"),
        "data.csv:2: `phi_deg` = 400 is outside [-360, 360]"
    );
}

#[test]
fn lacquer_ratio_below_one() {
    assert_eq!(
        csv_error("A,0.5,30,30,0,0.1,0.2,0.3\n"),
        "data.csv:2: `r` = 0.5 is below 1; r is the lacquer ratio relative to the least-lacquer \
         sample, which has r = 1"
    );
}

/// Noiseless synthetic data of rough-red on the standard grid, then `keep` filters the rows.
fn synthetic(ratios: &[f64], keep: impl Fn(&[f64; 3]) -> bool) -> Measurements {
    let material = LacquerMaterial::preset("rough-red").unwrap();
    let (mut data, angles) = synthesize(
        &material,
        ratios,
        Noise {
            relative: 0.0,
            seed: 0,
        },
    )
    .unwrap();
    data.rows = data
        .rows
        .into_iter()
        .zip(&angles)
        .filter(|(_, a)| keep(a))
        .map(|(r, _)| r)
        .collect();
    data
}

fn fit_error(data: &Measurements) -> String {
    match fit_measurements(data, &FitOptions::default()) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("expected the fit to fail"),
    }
}

#[test]
fn too_few_data_for_f_of_nv() {
    // Board 2 seen from one viewing angle only (θ_o = 30° in the plane).
    let mut data = synthetic(&[1.0, 3.0, 5.0], |_| true);
    let board2 = 1;
    let keep_view = shikki::fit::data::view_direction(30.0, 0.0);
    data.rows
        .retain(|r| r.sample != board2 || (r.view - keep_view).length() < 1e-12);
    assert_eq!(
        fit_error(&data),
        "invalid data for f(N·V) of sample `board-2` = 1 viewing angle(s) (30.0°): too few to fit \
         a and b: measure each board at 2 or more viewing angles θ_o"
    );
}

#[test]
fn too_few_data_for_the_specular_lobe() {
    // Only rows far from the mirror direction: in-plane on the light's side.
    let data = synthetic(&[1.0], |&[ti, to, phi]| {
        phi == 0.0 && to < 0.0 && ti >= 20.0
    });
    assert_eq!(
        fit_error(&data),
        "invalid data for the specular lobe (Beckmann m) = 0 row(s) near the mirror direction: \
         too few: measure 5 or more rows whose half-vector is within 10° of the normal (θ_o near \
         θ_i at φ = 0)"
    );
}

#[test]
fn too_few_data_for_the_fresnel_table() {
    // One incidence angle.
    let data = synthetic(&[1.0], |&[ti, _, _]| ti == 40.0);
    assert_eq!(
        fit_error(&data),
        "invalid data for the Fresnel table = near-mirror rows at 1 incidence angle (40°): too \
         few: measure the mirror direction at 2 or more incidence angles θ_i (e.g. 0..80° in \
         steps of 10°)"
    );
}

#[test]
fn too_few_data_for_g_of_r() {
    let data = synthetic(&[1.0, 2.0], |_| true);
    assert_eq!(
        fit_error(&data),
        "invalid data for g(r) = 2 lacquer ratios (1, 2): too few to fit c0, c1, c2: measure \
         boards at 3 or more lacquer ratios r, or fit one board at a time (g then keeps the \
         normalisation's law)"
    );
}

#[test]
fn grazing_rows_only() {
    let mut data = synthetic(&[1.0], |_| true);
    data.rows.truncate(3);
    for row in &mut data.rows {
        row.view = shikki::fit::data::view_direction(88.0, 0.0);
    }
    assert_eq!(
        fit_error(&data),
        "invalid data = 3 rows, all grazing: no row has both the light and the viewer within 87° \
         of the normal; measure at smaller angles"
    );
}

#[test]
fn merl_file_of_the_wrong_size_or_kind() {
    let mut bytes = Vec::new();
    for d in MERL_DIMS {
        bytes.extend_from_slice(&(d as i32).to_le_bytes());
    }
    bytes.extend_from_slice(&[0u8; 8 * 1000]);
    assert_eq!(
        parse_merl(&bytes, "gold.binary", 1)
            .unwrap_err()
            .to_string(),
        "invalid MERL file gold.binary = 8012 bytes: a MERL BRDF has exactly 34992012 bytes (a \
         12-byte header, then R, G and B blocks of 1458000 float64); the file is truncated or not \
         a MERL BRDF"
    );
    let mut other = Vec::new();
    for d in [90i32, 90, 360] {
        other.extend_from_slice(&d.to_le_bytes());
    }
    assert_eq!(
        parse_merl(&other, "gold.binary", 1)
            .unwrap_err()
            .to_string(),
        "invalid MERL file gold.binary = header 90 × 90 × 360: an isotropic MERL BRDF has the \
         header 90 × 90 × 180 (θ_h, θ_d, φ_d); this file is another kind of data"
    );
    assert!(parse_merl(&[1, 2], "tiny.binary", 1)
        .unwrap_err()
        .to_string()
        .starts_with("invalid MERL file tiny.binary = 2 bytes:"));
}

/// All-zero data was "fitted" (m = 1, k_d = 0, relative residual 1) and written, exit 0.
#[test]
fn data_without_light_is_refused() {
    let mut data = synthetic(&[1.0, 3.0, 5.0], |_| true);
    for row in &mut data.rows {
        row.reflectance = [0.0; 3];
    }
    let message = fit_error(&data);
    assert!(message.contains("no reflected light"), "{message}");
}
