//! The GLSL BRDF (run in a compute shader) against the CPU model of SPEC §2, number by number.

use crate::common;

use common::{assert_no_validation_messages, validated_gpu, Rng};
use glam::DVec3;
use shikki::compute::BrdfEvaluator;
use shikki::gpu::GpuContext;
use shikki::model::{lacquer_brdf, BrdfParams, FresnelTable, LacquerMaterial, PRESET_NAMES};

/// A unit vector at angle acos(cos_theta) from `n`, at a random azimuth.
fn around(n: DVec3, cos_theta: f64, rng: &mut Rng) -> DVec3 {
    let (t, b) = n.any_orthonormal_pair();
    let phi = 2.0 * std::f64::consts::PI * rng.uniform();
    let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
    (n * cos_theta + (t * phi.cos() + b * phi.sin()) * sin_theta).normalize()
}

fn random_unit(rng: &mut Rng) -> DVec3 {
    let z = 2.0 * rng.uniform() - 1.0;
    around(DVec3::Z, z, rng)
}

/// A cosine in (0, 1]: half uniform, half concentrated at grazing (down to 1e-4), plus exact
/// mirror-ish configurations arise from the uniform half.
fn cosine(rng: &mut Rng) -> f64 {
    if rng.uniform() < 0.5 {
        rng.uniform().max(1e-6)
    } else {
        10f64.powf(-4.0 * rng.uniform())
    }
}

/// Direction triples: random N; V and L at random cosines (many grazing), some below the horizon,
/// and a quarter with L near V's mirror direction so the specular peak is well sampled.
fn direction_triples(count: usize, seed: u64) -> Vec<[DVec3; 3]> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|i| {
            let n = random_unit(&mut rng);
            let v = around(n, cosine(&mut rng), &mut rng);
            let l = match i % 8 {
                0 => around(n, -cosine(&mut rng), &mut rng), // below the horizon: f_r = 0
                1 | 2 => {
                    // near the mirror direction, within a few m of it
                    let mirror = (2.0 * n.dot(v) * n - v).normalize();
                    let spread = 0.3 * rng.uniform();
                    around(mirror, spread.cos(), &mut rng)
                }
                _ => around(n, cosine(&mut rng), &mut rng),
            };
            [n, v, l]
        })
        .collect()
}

/// The preset's parameters and table, and f_r of each triple on the GPU.
fn evaluate_preset(
    gpu: &GpuContext,
    evaluator: &BrdfEvaluator,
    preset: &str,
    triples: &[[DVec3; 3]],
) -> (BrdfParams, FresnelTable, Vec<[f32; 3]>) {
    let material = LacquerMaterial::preset(preset).unwrap();
    let params = material.brdf_params().unwrap();
    let fresnel = material.fresnel_table().unwrap();
    let values = evaluator.evaluate(gpu, &params, &fresnel, triples).unwrap();
    (params, fresnel, values)
}

#[test]
fn gpu_brdf_matches_cpu_model_for_every_preset() {
    let gpu = validated_gpu();
    let evaluator = BrdfEvaluator::new(&gpu).unwrap();
    let triples = direction_triples(12_000, 0x5eed_1ac9);
    for preset in PRESET_NAMES {
        let (params, fresnel, gpu_values) = evaluate_preset(&gpu, &evaluator, preset, &triples);
        assert_eq!(gpu_values.len(), triples.len());
        let mut compared = 0usize;
        let mut worst = (0.0f64, 0usize);
        for (i, (triple, got)) in triples.iter().zip(&gpu_values).enumerate() {
            // The CPU model sees exactly the f32 unit vectors the GPU saw.
            let [n, v, l] = triple.map(|d| d.normalize().as_vec3().as_dvec3());
            let want = lacquer_brdf(&params, &fresnel, n, v, l);
            for c in 0..3 {
                let got = f64::from(got[c]);
                assert!(got.is_finite(), "{preset}: row {i} channel {c} is {got}");
                // The bound: relative error ≤ 1e-4 wherever f_r > 1e-6. Below that the
                // value is below fp32's useful precision relative to the diffuse floor.
                if want[c] > 1e-6 {
                    compared += 1;
                    let rel = (got - want[c]).abs() / want[c];
                    if rel > worst.0 {
                        worst = (rel, i);
                    }
                } else {
                    assert!(
                        got.abs() <= 1e-6 + 1e-4 * want[c].abs(),
                        "{preset}: row {i}: gpu {got} where cpu {}",
                        want[c]
                    );
                }
            }
        }
        let (rel, i) = worst;
        eprintln!("{preset}: {compared} values compared, worst relative error {rel:.3e} (row {i})");
        assert!(
            compared > 20_000,
            "{preset}: too few values above 1e-6 ({compared})"
        );
        assert!(
            rel <= 1e-4,
            "{preset}: row {i} {:?}: relative error {rel:.3e} > 1e-4",
            triples[i]
        );
    }
    assert_no_validation_messages(&gpu);
}

/// N·V and N·L just above 0 and far below f32's useful range: nh⁴ and 4·nv·nl underflow there,
/// and the GPU returned NaN (0/0) for nv = nl = 6.1e-17 (an independent audit, 2026-12-06).
/// The f_r there is the diffuse term (f_spec is below e^-1e19), which the CPU model gives.
#[test]
fn gpu_brdf_is_finite_where_the_cosines_underflow() {
    let gpu = validated_gpu();
    let evaluator = BrdfEvaluator::new(&gpu).unwrap();
    let triples: Vec<[DVec3; 3]> = [6.123234e-17, 1e-20, 1e-30, 1e-37, 1e-44]
        .iter()
        .flat_map(|&t: &f64| {
            let n = DVec3::Y;
            // (Not the mirror pair V = (1, t, 0), L = (-1, t, 0): its f_spec, F·D/(4·nv·nl) with
            // h = N, is ~1e38 at t = 1e-20 and past f32's range below, inf on both sides.)
            [
                [n, DVec3::new(1.0, t, 0.0), DVec3::new(t, t, 1.0)],
                [n, DVec3::new(1.0, t, 0.0), DVec3::new(0.0, t, 1.0)],
                [n, DVec3::new(0.0, t, 1.0), DVec3::new(0.0, 1.0, 0.0)],
            ]
        })
        .collect();
    for preset in PRESET_NAMES {
        let (params, fresnel, gpu_values) = evaluate_preset(&gpu, &evaluator, preset, &triples);
        for (i, (triple, got)) in triples.iter().zip(&gpu_values).enumerate() {
            let [n, v, l] = triple.map(|d| d.normalize().as_vec3().as_dvec3());
            let want = lacquer_brdf(&params, &fresnel, n, v, l);
            for c in 0..3 {
                let got = f64::from(got[c]);
                // The same bound as the preset test above: 1e-4 relative, or 1e-6 absolute
                // below f_r = 1e-6.
                assert!(
                    got.is_finite() && (got - want[c]).abs() <= 1e-6 + 1e-4 * want[c].abs(),
                    "{preset}: row {i} {triple:?} channel {c}: gpu {got}, cpu {}",
                    want[c]
                );
            }
        }
    }
    assert_no_validation_messages(&gpu);
}
