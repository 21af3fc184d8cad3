//! The fit recovers the model it is given (issue 6, acceptance): noiseless goniometer data and a
//! MERL file from the `smooth` and `rough` presets come back to 1e-3; with 2 % noise over three
//! seeds, m within 5 %, a and b within 0.02, g(r) within 2 % over [1, 5], the Fresnel knots
//! flagged measured within 4 of their standard errors (and the figures docs/measurements.md
//! states), and the report's residuals are of the noise's size. Spectral CSV columns go through SPEC §3's
//! path and fit like RGB.

use shikki::fit::estimate::{FitResult, MEASURED_UNIT_ERROR};
use shikki::fit::merl::{parse_merl, MERL_PHI_D_STRIDE};
use shikki::fit::report::{fresnel_std_errors, residuals};
use shikki::fit::synth::{goniometer_grid, synthesize, synthesize_merl, Noise, DEFAULT_RATIOS};
use shikki::fit::{csv, fit_measurements, FitOptions, Measurements};
use shikki::model::fresnel::{dielectric_reflectance, lacquer_ior};
use shikki::model::{FresnelTable, LacquerMaterial};

/// The issue's noiseless bound.
const NOISELESS: f64 = 1e-3;

fn fit_with_reference(data: &Measurements, truth: &LacquerMaterial) -> FitResult {
    let options = FitOptions {
        reference: Some(truth.clone()),
    };
    fit_measurements(data, &options).expect("the fit succeeds")
}

/// Fresnel knots the data determine (rows reach them and fix them on their own).
fn measured_knots(fit: &FitResult) -> Vec<usize> {
    (0..=90).filter(|&k| fit.fresnel_measured(k)).collect()
}

/// Every parameter of SPEC §2 and the Fresnel table at the measured knots, within `bound`.
fn assert_recovered(name: &str, fit: &FitResult, truth: &LacquerMaterial, bound: f64) {
    let m = &fit.material;
    let pairs = [
        ("m", m.beckmann_m, truth.beckmann_m),
        ("a", m.diffuse_a, truth.diffuse_a),
        ("b", m.diffuse_b, truth.diffuse_b),
        ("c0", m.lacquer_law[0], truth.lacquer_law[0]),
        ("c1", m.lacquer_law[1], truth.lacquer_law[1]),
        ("c2", m.lacquer_law[2], truth.lacquer_law[2]),
        ("kd.r", m.albedo[0], truth.albedo[0]),
        ("kd.g", m.albedo[1], truth.albedo[1]),
        ("kd.b", m.albedo[2], truth.albedo[2]),
    ];
    for (what, got, want) in pairs {
        eprintln!(
            "{name}: {what} = {got:.9} (true {want}, error {:.1e})",
            (got - want).abs()
        );
        assert!(
            (got - want).abs() <= bound,
            "{name}: {what} = {got}, expected {want}"
        );
    }
    let table = truth.fresnel_table().unwrap();
    let knots = measured_knots(fit);
    // The goniometer grid reaches θ = acos(V·H) up to ≈ 83°; the table must be measured there.
    assert!(
        knots.len() >= 80,
        "{name}: only {} measured knots",
        knots.len()
    );
    let worst = knots
        .iter()
        .flat_map(|&k| (0..3).map(move |c| (k, c)))
        .map(|(k, c)| (fit.fresnel.rgb()[k][c] - table.rgb()[k][c]).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "{name}: Fresnel worst error over {} knots {worst:.1e}",
        knots.len()
    );
    assert!(worst <= bound, "{name}: Fresnel error {worst}");
}

#[test]
fn noiseless_goniometer_data_recover_smooth_and_rough() {
    for preset in ["smooth", "rough"] {
        let truth = LacquerMaterial::preset(preset).unwrap();
        let clean = Noise {
            relative: 0.0,
            seed: 0,
        };
        let (data, _) = synthesize(&truth, &DEFAULT_RATIOS, clean).unwrap();
        let fit = fit_with_reference(&data, &truth);
        assert_recovered(preset, &fit, &truth, NOISELESS);
        // Without noise the model reproduces every row: relative RMS at rounding level
        // (1e-6 leaves room for the golden section's √ε resolution of m and β).
        assert!(fit.relative_rms < 1e-6, "{preset}: {}", fit.relative_rms);
    }
}

#[test]
fn default_normalisation_keeps_the_product_and_sets_f_and_g_to_one() {
    // Without a reference the split of k_d·g·f is f(1) = 1 and g(1) = 1; the product — what
    // renders — is the source's at every r and N·V (1e-6: √ε resolution of β, see above).
    let truth = LacquerMaterial::preset("rough-red").unwrap();
    let clean = Noise {
        relative: 0.0,
        seed: 0,
    };
    let (data, _) = synthesize(&truth, &DEFAULT_RATIOS, clean).unwrap();
    let fit = fit_measurements(&data, &FitOptions::default()).unwrap();
    let m = &fit.material;
    assert!((m.diffuse_a + m.diffuse_b - 1.0).abs() < 1e-12);
    let g = |law: [f64; 3], r: f64| law[0] + r * (law[1] + law[2] * r);
    assert!((g(m.lacquer_law, 1.0) - 1.0).abs() < 1e-6);
    for r in [1.0, 2.5, 5.0] {
        for nv in [0.1, 0.5, 1.0] {
            for c in 0..3 {
                let fitted = m.albedo[c] * g(m.lacquer_law, r) * (m.diffuse_a + m.diffuse_b * nv);
                let source = truth.albedo[c]
                    * g(truth.lacquer_law, r)
                    * (truth.diffuse_a + truth.diffuse_b * nv);
                assert!(
                    (fitted / source - 1.0).abs() < 1e-6,
                    "r {r} nv {nv}: {fitted} vs {source}"
                );
            }
        }
    }
    assert!((m.beckmann_m - 0.2).abs() < NOISELESS);
}

#[test]
fn two_percent_noise_over_three_seeds_stays_within_the_issue_bounds() {
    for preset in ["smooth", "rough", "smooth-red", "rough-red"] {
        let truth = LacquerMaterial::preset(preset).unwrap();
        for seed in [1, 2, 3] {
            let noise = Noise {
                relative: 0.02,
                seed,
            };
            let (data, _) = synthesize(&truth, &DEFAULT_RATIOS, noise).unwrap();
            let fit = fit_with_reference(&data, &truth);
            let m = &fit.material;
            let name = format!("{preset} seed {seed}");
            let m_error = (m.beckmann_m / truth.beckmann_m - 1.0).abs();
            let (a_error, b_error) = (
                (m.diffuse_a - truth.diffuse_a).abs(),
                (m.diffuse_b - truth.diffuse_b).abs(),
            );
            let g = |law: [f64; 3], r: f64| law[0] + r * (law[1] + law[2] * r);
            let g_error = (0..=40)
                .map(|i| 1.0 + 0.1 * f64::from(i))
                .map(|r| (g(m.lacquer_law, r) / g(truth.lacquer_law, r) - 1.0).abs())
                .fold(0.0, f64::max);
            eprintln!(
                "{name}: m {:.2e} rel, a {a_error:.1e}, b {b_error:.1e}, g {g_error:.1e} rel",
                m_error
            );
            assert!(m_error <= 0.05, "{name}: m = {}", m.beckmann_m);
            assert!(
                a_error <= 0.02 && b_error <= 0.02,
                "{name}: a, b = {}, {}",
                m.diffuse_a,
                m.diffuse_b
            );
            assert!(g_error <= 0.02, "{name}: g off by {g_error}");

            // Fresnel at the knots the report flags measured (fresnel.csv's `measured` = 1). The
            // flag's rule bounds each one's standard error by 1 per unit noise, 0.02 here, and
            // knots 81–83°, which few rows reach, come near it (0.0097), so the flag promises a
            // knot within a few of its own standard errors, not a fixed figure: 4 (the worst of
            // the six fits is 3.3; the seeds are fixed, so this is deterministic). The figures
            // docs/measurements.md states are checked too: ≤ 0.02 over every measured knot
            // (0.0197 measured), ≤ 0.005 over 0..=80° (0.0049 measured).
            let table = truth.fresnel_table().unwrap();
            let errors = fresnel_std_errors(&fit);
            let knots = measured_knots(&fit);
            assert!(
                (0..=83).all(|k| knots.contains(&k)),
                "{name}: measured knots {knots:?}"
            );
            let (mut worst, mut worst_to_80, mut worst_sigmas) = (0.0f64, 0.0f64, 0.0f64);
            for &k in &knots {
                let (fitted, truth) = (fit.fresnel.rgb()[k], table.rgb()[k]);
                for ((got, want), sigma) in fitted.iter().zip(truth).zip(errors[k]) {
                    let error = (got - want).abs();
                    assert!(sigma <= 0.02 * MEASURED_UNIT_ERROR, "{name}: knot {k}");
                    worst = worst.max(error);
                    worst_sigmas = worst_sigmas.max(error / sigma);
                    if k <= 80 {
                        worst_to_80 = worst_to_80.max(error);
                    }
                }
            }
            eprintln!(
                "{name}: Fresnel worst {worst:.4} over {} measured knots ({worst_sigmas:.2} \
                 standard errors), {worst_to_80:.4} over 0..=80°",
                knots.len()
            );
            assert!(
                worst_sigmas <= 4.0,
                "{name}: {worst_sigmas} standard errors"
            );
            assert!(worst <= 0.02, "{name}: Fresnel off by {worst}");
            assert!(
                worst_to_80 <= 0.005,
                "{name}: Fresnel off by {worst_to_80} to 80°"
            );

            // The report's row-level residuals read the noise: 2 % ± 0.3 % for every term over
            // all boards (thousands of values each, so the RMS of N(0, 0.02²) is 0.02 ± 0.0003).
            for r in residuals(&data, &fit).iter().filter(|r| r.sample == "all") {
                if r.term != "g(r)" {
                    assert!(
                        (r.rms - 0.02).abs() < 0.003 && r.count > 1000,
                        "{name}: {} residual {} over {}",
                        r.term,
                        r.rms,
                        r.count
                    );
                }
            }
        }
    }
}

#[test]
fn merl_file_from_the_model_fits_back() {
    // smooth: the sharp lobe is the harder case for MERL's θ_h sampling.
    let truth = LacquerMaterial::preset("smooth-red").unwrap();
    let bytes = synthesize_merl(
        &truth,
        Noise {
            relative: 0.0,
            seed: 0,
        },
    )
    .unwrap();
    let data = parse_merl(&bytes, "smooth.binary", MERL_PHI_D_STRIDE).unwrap();
    assert_eq!(data.samples.len(), 1);
    let fit = fit_with_reference(&data, &truth);
    // One board: g is not fitted but kept from the reference, so c0..c2 come back exactly.
    assert!(!fit.diffuse.lacquer_law_fitted);
    assert_recovered("MERL smooth-red", &fit, &truth, NOISELESS);
}

#[test]
fn spectral_columns_fit_like_rgb() {
    // smooth-black as spectra: flat k_d (0.02 at every λ is RGB 0.02 exactly) and the dielectric
    // F(λ, θ) of n(λ) = 1.5 + 0.0045/λ² at whole degrees, interpolated linearly in θ like the
    // table (the spectral path is linear, so these spectra map to exactly the model's RGB rows).
    let truth = LacquerMaterial::preset("smooth").unwrap();
    let params = truth.brdf_params().unwrap();
    let nm: Vec<f64> = (0..=80).map(|i| 380.0 + 5.0 * f64::from(i)).collect();
    let knot_spectrum = |k: usize| -> Vec<f64> {
        let cos = if k == 90 {
            0.0
        } else {
            (k as f64).to_radians().cos()
        };
        nm.iter()
            .map(|&l| dielectric_reflectance(cos, lacquer_ior(l, 1.5, 0.0045)))
            .collect()
    };
    let knots: Vec<Vec<f64>> = (0..=90).map(knot_spectrum).collect();
    let header: Vec<String> = nm.iter().map(|l| format!("{l}")).collect();
    let mut text = format!(
        "sample,r,theta_i_deg,theta_o_deg,phi_deg,{}\n",
        header.join(",")
    );
    for r in [1.0, 3.0, 5.0] {
        let g = truth.lacquer_law[0] + r * (truth.lacquer_law[1] + truth.lacquer_law[2] * r);
        // Every third grid point keeps the file small (4352 rows) and still covers the lobe.
        for [ti, to, phi] in goniometer_grid().into_iter().step_by(3) {
            let light = shikki::fit::data::light_direction(ti);
            let view = shikki::fit::data::view_direction(to, phi);
            let geo = shikki::fit::separation::RowGeometry::new(light, view);
            let s = geo.specular_per_fresnel(params.beckmann_m);
            let diffuse = 0.02 * (params.diffuse_a + params.diffuse_b * view.z).max(0.0) * g;
            let (lo, hi) = (&knots[geo.knot], &knots[geo.knot + 1]);
            let values: Vec<String> = (0..nm.len())
                .map(|i| {
                    let f = lo[i] + geo.knot_t * (hi[i] - lo[i]);
                    format!("{}", diffuse + f * s)
                })
                .collect();
            text.push_str(&format!("b{r},{r},{ti},{to},{phi},{}\n", values.join(",")));
        }
    }
    let data = csv::parse_goniometer_csv(&text, "spectral.csv").unwrap();
    let fit = fit_with_reference(&data, &truth);
    assert_recovered("spectral smooth", &fit, &truth, NOISELESS);
    // The table equals the default dielectric one, which is built by the same spectral path.
    assert_eq!(
        truth.fresnel_table().unwrap(),
        FresnelTable::dielectric(1.5, 0.0045).unwrap()
    );
}
