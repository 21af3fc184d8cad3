//! The `brdf` environment model's quadrature (CPU) against the brute-force integral over every
//! pixel of the map (SPEC §4), on the shipped courtyard HDRI and a lattice of sphere normals.

use glam::DVec3;
use shikki::environment::brdf_definition::specular_integral_definition;
use shikki::environment::brdf_quadrature::{specular_quadrature, BrdfQuadrature};
use shikki::environment::{load_environment, prefilter_cpu, EnvironmentLight, PrefilterParams};
use shikki::model::{BrdfParams, FresnelTable};

fn params(m: f64) -> BrdfParams {
    BrdfParams {
        beckmann_m: m,
        diffuse_a: 0.01,
        diffuse_b: 0.96,
        lacquer_g: 1.0159,
        albedo: [0.5, 0.06, 0.03],
    }
}

/// Normals over the visible hemisphere of a sphere seen from +Z (a Fibonacci lattice down to
/// N·V = 0.03), V = +Z.
fn sphere_points(count: usize) -> Vec<(DVec3, DVec3)> {
    let golden = std::f64::consts::PI * (3.0 - 5.0_f64.sqrt());
    (0..count)
        .map(|i| {
            let z = 0.03 + 0.97 * (i as f64 + 0.5) / count as f64;
            let r = (1.0 - z * z).sqrt();
            let phi = golden * i as f64;
            (DVec3::new(r * phi.cos(), r * phi.sin(), z), DVec3::Z)
        })
        .collect()
}

/// Mean and p99 relative difference (green channel) of the quadrature from the reference.
fn errors(
    samples: u32,
    m: f64,
    reference: &[[f64; 3]],
    run: impl Fn(&BrdfQuadrature, DVec3, DVec3) -> [f64; 3],
) -> (f64, f64) {
    let q = BrdfQuadrature {
        samples,
        footprint: 1.0,
    };
    let mut rel: Vec<f64> = sphere_points(reference.len())
        .iter()
        .zip(reference)
        .map(|(&(n, v), want)| (run(&q, n, v)[1] - want[1]).abs() / want[1])
        .collect();
    rel.sort_by(f64::total_cmp);
    let mean = rel.iter().sum::<f64>() / rel.len() as f64;
    println!(
        "m {m}, {samples} samples: mean {mean:.4}, p99 {:.4}",
        rel[rel.len() * 99 / 100]
    );
    (mean, rel[rel.len() * 99 / 100])
}

/// The estimator is deterministic and converges to the integral as the samples grow. Measured
/// (mean, p99): m = 0.05: 2.9 %, 48 % at 64 samples; 0.63 %, 6.4 % at 1024; 0.30 %, 3.0 % at
/// 8192. m = 0.5: 7.6 %, 28 %; 0.65 %, 2.3 %; 0.25 %, 1.3 %. The bounds: each step must cut the
/// mean error, and at 8192 samples mean ≤ 0.5 % and p99 ≤ 5 % (the p99). At the sample
/// counts a render can afford the error is far above the 1 % mean: the courtyard's sun
/// is a small bright source the lobe samples find only by chance (see BENCHMARKS.md).
#[test]
fn quadrature_converges_to_the_brute_force_integral() {
    let path = concat!(env!("CARGO_MANIFEST_DIR"), "/assets/env/courtyard.hdr");
    let source = load_environment(path).unwrap().image;
    let prefilter = PrefilterParams::for_source_width(source.width);
    let env = prefilter_cpu(&source, &prefilter, EnvironmentLight::default()).unwrap();
    let fresnel = FresnelTable::dielectric(1.5, 0.0045).unwrap();
    for m in [0.05, 0.5] {
        let p = params(m);
        let reference: Vec<[f64; 3]> = sphere_points(120)
            .iter()
            .map(|&(n, v)| {
                let cells = if m < 0.1 { 3 } else { 1 };
                let light = EnvironmentLight::default();
                specular_integral_definition(&source, light, &p, &fresnel, n, v, cells)
            })
            .collect();
        let run = |q: &BrdfQuadrature, n, v| specular_quadrature(&env, q, &p, &fresnel, n, v);
        let steps: Vec<(f64, f64)> = [64, 1024, 8192]
            .into_iter()
            .map(|samples| errors(samples, m, &reference, run))
            .collect();
        assert!(
            steps[0].0 > steps[1].0 && steps[1].0 > steps[2].0,
            "m {m}: {steps:?}"
        );
        assert!(steps[2].0 <= 5e-3 && steps[2].1 <= 5e-2, "m {m}: {steps:?}");
        // Same inputs, same numbers: nothing random in the estimator.
        let (n, v) = sphere_points(120)[7];
        let q = BrdfQuadrature::default();
        assert_eq!(run(&q, n, v), run(&q, n, v));
    }
}
